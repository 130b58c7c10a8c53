#include "quality_comparison.h"
#include "peers.h"

#include <range_nlm/eval/synthetic_scene.h>
#include <range_nlm/temporal_nonlocal_means_filter.h>

#include <pcl/filters/fast_bilateral_omp.h>
#include <pcl/search/kdtree.h>
#include <pcl/surface/mls.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <deque>
#include <iomanip>
#include <limits>
#include <map>
#include <sstream>

namespace range_nlm
{
namespace tools
{
namespace quality
{

using Cloud = pcl::PointCloud<pcl::PointXYZ>;

namespace
{
void
restoreInvalid(const Cloud& in, Cloud& out)
{
  const float nan = std::numeric_limits<float>::quiet_NaN();
  bool dense = true;
  for (std::size_t i = 0; i < in.size(); ++i) {
    const bool valid = std::isfinite(in[i].x) && std::isfinite(in[i].y) && std::isfinite(in[i].z);
    if (!valid)
      out[i].x = out[i].y = out[i].z = nan;
    dense = dense && valid;
  }
  out.is_dense = dense;
}

std::string
fixed(double v, int digits)
{
  std::ostringstream s;
  s << std::fixed << std::setprecision(digits) << v;
  return s.str();
}
} // namespace

Cloud
fastBilateral(const Cloud& in, float sigma_s, float sigma_r)
{
  const auto filter = bench::makeFastBilateral(sigma_s, sigma_r, 0);
  filter->setInputCloud(Cloud::ConstPtr(new Cloud(in)));
  Cloud out;
  filter->filter(out);
  restoreInvalid(in, out); // PCL writes a finite z into NaN pixels (PCL issue #1027)
  return out;
}

Cloud
movingLeastSquares(const Cloud& in, double radius, unsigned threads)
{
  const auto mls = bench::makeMovingLeastSquares(radius, threads);
  bench::setMlsInput(*mls, Cloud::ConstPtr(new Cloud(in)));
  Cloud projected;
  mls->process(projected);
  Cloud out = in;
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (auto& p : out)
    p.x = p.y = p.z = nan;
  const pcl::PointIndicesPtr correspondence = mls->getCorrespondingIndices();
  for (std::size_t k = 0; k < projected.size() && k < correspondence->indices.size(); ++k)
    out[correspondence->indices[k]] = projected[k];
  restoreInvalid(in, out);
  return out;
}

std::vector<std::pair<std::string, FilterParameters>>
rangeNlmVariants(bool include_levers)
{
  std::vector<std::pair<std::string, FilterParameters>> v;
  v.emplace_back("default", FilterParameters::recommended());
  v.emplace_back("preset paper (7x7 / 5x5, 3x3 normals)", FilterParameters::paper());
  if (!include_levers)
    return v;
  // The levers one by one, each added to the previous row.
  FilterParameters p = FilterParameters::paper();
  p.normal_window = 7;
  v.emplace_back("paper + 7x7 normals", p);
  p = FilterParameters::paper();
  p.normal_presmooth_window = 7;
  v.emplace_back("paper + normals from a pre-smoothed copy", p);
  p.bandwidth_model = BandwidthModel::range_adaptive;
  p.distance_scale = 1.5f;
  p.similarity_scale = 3.0f;
  v.emplace_back("  + range-adaptive robust d, s", p);
  p.normal_window = 7;
  p.normal_edge_gate = 3.0f;
  v.emplace_back("  + gated 7x7 normals", p);
  p.iterations = 2;
  v.emplace_back("  + 2 passes (normals re-estimated)", p);
  p.search_window = 9;
  p.patch_size = 3;
  v.emplace_back("  + 9x9 search, 3x3 patch", p);
  p.dilation = 0;
  p.cross_frame_bandwidth = CrossFrameBandwidth::guarded;
  v.emplace_back("  + automatic dilation, guarded cross-frame bandwidths", p);
  p.outlier_sigmas = 10.0f;
  v.emplace_back("  + isolated outliers moved onto their neighbours' surface", p);
  p.patch_edge_gate = 18.0f;
  v.emplace_back("  + gated patches", p);
  p.similarity_spread = 3.0f;
  v.emplace_back("  + s from the patch spread (first pass)", p);
  // The last lever row is the default itself, so that it cannot drift from it.
  v.emplace_back("  + automatic displacement, patch guide (= default)", FilterParameters::recommended());
  FilterParameters q = FilterParameters::recommended();
  q.displacement = Displacement::line_of_sight;
  v.emplace_back("default + line of sight", q);
  q = FilterParameters::recommended();
  q.max_displacement = 3.0f;
  v.emplace_back("default + displacement limit 3 sigma", q);
  q = FilterParameters::recommended();
  q.bandwidth_model = BandwidthModel::global;
  v.emplace_back("default with global (paper) d, s", q);
  q = FilterParameters::recommended();
  q.similarity_spread = 0.0f;
  v.emplace_back("default without s from the patch spread (similarity_spread 0)", q);
  return v;
}

Options
defaultOptions()
{
  Options o;
  o.scenarios.push_back(Scenario{"depth camera", "kinect", "boxes", 0.0, 1});
  o.scenarios.push_back(Scenario{"laser grade", "laser", "boxes", 0.0, 1});
  o.scenarios.push_back(Scenario{"depth camera, temporal r=1", "kinect", "boxes", 0.0, 3});
  o.scenarios.push_back(Scenario{"laser grade, temporal r=1", "laser", "boxes", 0.0, 3});
  // Steps, ridges and grooves of 2 - 5 mm: a few noise sigmas at laser grade.
  o.scenarios.push_back(Scenario{"small features, laser grade", "laser", "ridges", 0.0, 1});
  o.scenarios.push_back(Scenario{"small features, depth camera", "kinect", "ridges", 0.0, 1});
  return o;
}

namespace
{
std::vector<Method>
methodsFor(const Scenario& scenario, const Options& options)
{
  std::vector<Method> methods;
  const int threads = options.threads;
  for (const auto& [name, parameters] : rangeNlmVariants(options.include_levers)) {
    FilterParameters p = parameters;
    p.threads = threads;
    methods.push_back(Method{"range_nlm", name, [p](const std::vector<Cloud::ConstPtr>& frames, std::size_t c) {
                               TemporalNonLocalMeansFilter<pcl::PointXYZ> f;
                               f.setParameters(p);
                               f.setFrames(std::deque<Cloud::ConstPtr>(frames.begin(), frames.end()), c);
                               Cloud out;
                               f.filter(out);
                               return out;
                             }});
  }
  if (!options.include_peers)
    return methods;
  for (float sigma_s : {3.0f, 5.0f, 7.0f, 10.0f})
    for (float sigma_r : {0.01f, 0.03f, 0.05f, 0.1f})
      methods.push_back(Method{"pcl FastBilateralFilter",
                               "sigma_s " + fixed(sigma_s, 0) + ", sigma_r " + fixed(sigma_r, 2),
                               [=](const std::vector<Cloud::ConstPtr>& frames, std::size_t c) {
                                 return fastBilateral(*frames[c], sigma_s, sigma_r);
                               }});
  for (double radius : {0.01, 0.02, 0.03, 0.05})
    methods.push_back(Method{"pcl MovingLeastSquares", "order 2, radius " + fixed(radius, 2) + " m",
                             [=](const std::vector<Cloud::ConstPtr>& frames, std::size_t c) {
                               return movingLeastSquares(*frames[c], radius);
                             }});
  (void)scenario;
  return methods;
}
} // namespace

std::vector<Row>
run(const Options& options, std::ostream& log)
{
  std::vector<Row> rows;
  for (const Scenario& scenario : options.scenarios) {
    SceneOptions scene;
    scene.width = scenario.width;
    scene.height = scenario.height;
    scene.noise = noiseModelFromString(scenario.noise);
    scene.scene = sceneTypeFromString(scenario.scene);
    if (scenario.noise_scale > 0.0)
      scene.noise_scale = scenario.noise_scale;
    scene.frames = scenario.frames;
    scene.seed = scenario.seed;
    const std::vector<SyntheticFrame> sequence = renderSequence(scene);
    std::vector<Cloud::ConstPtr> frames;
    for (const auto& f : sequence)
      frames.emplace_back(new Cloud(f.noisy));
    const std::size_t centre = sequence.size() / 2;
    const auto& truth = sequence[centre].truth;
    EvaluationOptions eval;
    eval.threads = options.threads;
    rows.push_back(Row{scenario.name, "noisy input", "-", evaluateFrame(truth, *frames[centre], nullptr, eval), 0.0});
    for (const Method& m : methodsFor(scenario, options)) {
      const auto start = std::chrono::steady_clock::now();
      const Cloud result = m.apply(frames, centre);
      const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
      rows.push_back(Row{scenario.name, m.family, m.setting, evaluateFrame(truth, result, frames[centre].get(), eval), ms});
      const FrameMetrics& r = rows.back().metrics;
      log << scenario.name << " | " << m.family << " | " << m.setting << ": flat " << fixed(1000 * r.flat_rmse, 3)
          << " mm, feature " << fixed(1000 * r.feature_rmse, 3) << " mm, lost " << r.points_lost << " ("
          << fixed(ms, 0) << " ms)" << std::endl;
    }
  }
  return rows;
}

namespace
{
void
printRow(std::ostream& out, const std::string& family, const std::string& setting, const FrameMetrics& m,
         const std::string& note = "")
{
  out << "| " << family << " | " << setting << " | " << fixed(1000 * m.flat_rmse, 2) << " | "
      << fixed(1000 * m.feature_rmse, 2) << " | " << fixed(m.flat_normal_error, 1) << " | "
      << fixed(m.feature_normal_error, 1) << " | " << m.points_lost << " |" << note << "\n";
}
} // namespace

void
printTable(const std::vector<Row>& rows, std::ostream& out)
{
  std::vector<std::string> scenarios;
  for (const Row& r : rows)
    if (std::find(scenarios.begin(), scenarios.end(), r.scenario) == scenarios.end())
      scenarios.push_back(r.scenario);
  for (const std::string& scenario : scenarios) {
    out << "\n" << scenario << " (point-to-plane RMSE in mm against ground truth, mean normal error in degrees)\n\n";
    out << "| method | setting | flat RMSE | feature RMSE | flat normal | feature normal | points lost |\n";
    out << "|---|---|---|---|---|---|---|\n";
    std::map<std::string, std::pair<const Row*, const Row*>> best; // per peer family: best flat, best feature
    for (const Row& r : rows) {
      if (r.scenario != scenario)
        continue;
      if (r.family == "noisy input" || r.family == "range_nlm") {
        printRow(out, r.family, r.setting, r.metrics);
        continue;
      }
      auto& b = best[r.family];
      if (!b.first || r.metrics.flat_rmse < b.first->metrics.flat_rmse)
        b.first = &r;
      if (!b.second || r.metrics.feature_rmse < b.second->metrics.feature_rmse)
        b.second = &r;
    }
    for (const auto& [family, b] : best) {
      printRow(out, family, b.first->setting + " (best flat)", b.first->metrics);
      if (b.second != b.first)
        printRow(out, family, b.second->setting + " (best feature)", b.second->metrics);
    }
  }
}

void
printJson(const std::vector<Row>& rows, std::ostream& out)
{
  out << "{\"quality\": [";
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const Row& r = rows[i];
    out << (i ? ", " : "") << "{\"scenario\": \"" << r.scenario << "\", \"method\": \"" << r.family
        << "\", \"setting\": \"" << r.setting << "\", \"flat_rmse_mm\": " << 1000 * r.metrics.flat_rmse
        << ", \"feature_rmse_mm\": " << 1000 * r.metrics.feature_rmse
        << ", \"flat_normal_deg\": " << r.metrics.flat_normal_error
        << ", \"feature_normal_deg\": " << r.metrics.feature_normal_error
        << ", \"points_lost\": " << r.metrics.points_lost << ", \"ms\": " << r.milliseconds << "}";
  }
  out << "]}\n";
}

} // namespace quality
} // namespace tools
} // namespace range_nlm
