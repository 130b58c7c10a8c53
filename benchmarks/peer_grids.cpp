#include "peer_grids.h"
#include "quality_comparison.h"

#include <range_nlm/nonlocal_means_filter.h>

#include <cmath>
#include <iomanip>
#include <sstream>

namespace range_nlm
{
namespace tools
{
namespace peer_grids
{

std::string
fixed(double v, int digits)
{
  std::ostringstream s;
  s << std::fixed << std::setprecision(digits) << v;
  return s.str();
}

std::string
mm(double metres)
{
  return std::isfinite(metres) ? fixed(1000.0 * metres, 2) : "-";
}

Smoother
rangeNlm(const std::string& setting, const FilterParameters& parameters)
{
  return Smoother{"range_nlm", setting, [parameters](const Cloud& in) {
                    NonLocalMeansFilter<pcl::PointXYZ> f;
                    f.setParameters(parameters);
                    f.setInputCloud(Cloud::ConstPtr(new Cloud(in)));
                    Cloud out;
                    f.filter(out);
                    return out;
                  }};
}

Smoother
fastBilateral(float sigma_s, float sigma_r)
{
  return Smoother{"FastBilateral", "sigma_s " + fixed(sigma_s, 0) + ", sigma_r " + fixed(sigma_r, 2),
                  [=](const Cloud& in) { return quality::fastBilateral(in, sigma_s, sigma_r); }};
}

std::vector<Smoother>
fastBilateralGrid()
{
  std::vector<Smoother> s;
  for (float sigma_s : {3.0f, 5.0f, 7.0f, 10.0f, 15.0f})
    for (float sigma_r : {0.01f, 0.03f, 0.05f, 0.1f})
      s.push_back(fastBilateral(sigma_s, sigma_r));
  return s;
}

std::vector<Smoother>
mlsGrid(int threads)
{
  std::vector<Smoother> s;
  for (double radius : {0.02, 0.03, 0.05})
    s.push_back(Smoother{"MLS", "order 2, radius " + fixed(radius, 2) + " m",
                         [=](const Cloud& in) { return quality::movingLeastSquares(in, radius, unsigned(threads)); }});
  return s;
}

const ScoredRow*
bestBalanced(const std::vector<ScoredRow>& rows, const std::string& family)
{
  const ScoredRow* best = nullptr;
  for (const ScoredRow& r : rows)
    if (r.family == family && (!best || r.m.flat_rmse + r.m.feature_rmse < best->m.flat_rmse + best->m.feature_rmse))
      best = &r;
  return best;
}

bool
WinTally::add(const std::string& setting, const FrameMetrics& ours, const FrameMetrics& fast_bilateral,
              const FrameMetrics* mls)
{
  const auto beats = [&](const FrameMetrics& peer) {
    return ours.flat_rmse <= peer.flat_rmse && ours.feature_rmse <= peer.feature_rmse;
  };
  const bool win = beats(fast_bilateral) && (!mls || beats(*mls));
  Count& c = counts_[setting];
  c.won += win ? 1 : 0;
  c.scenes += 1;
  c.log_flat += std::log(ours.flat_rmse / fast_bilateral.flat_rmse);
  c.log_feature += std::log(ours.feature_rmse / fast_bilateral.feature_rmse);
  return win;
}

std::vector<WinTally::Summary>
WinTally::summaries(const std::vector<std::string>& settings) const
{
  std::vector<Summary> out;
  for (const std::string& setting : settings) {
    const auto it = counts_.find(setting);
    if (it == counts_.end() || it->second.scenes == 0)
      continue;
    const Count& c = it->second;
    out.push_back(Summary{setting, c.won, c.scenes, std::exp(c.log_flat / c.scenes),
                          std::exp(c.log_feature / c.scenes)});
  }
  return out;
}

void
WinTally::print(std::ostream& report, const std::vector<std::string>& settings, const std::string& scenes,
                const std::string& peers) const
{
  report << "| range_nlm setting | " << scenes << " won on both (vs " << peers
         << ") | flat RMSE / FastBilateral (geometric mean) | feature RMSE / FastBilateral |\n|---|---|---|---|\n";
  for (const Summary& s : summaries(settings))
    report << "| " << s.setting << " | " << s.won << " of " << s.scenes << " | " << fixed(s.flat_ratio, 2) << " | "
           << fixed(s.feature_ratio, 2) << " |\n";
}

} // namespace peer_grids
} // namespace tools
} // namespace range_nlm
