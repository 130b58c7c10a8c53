#include "accuracy_time.h"
#include "bench_support.h"
#include "peer_grids.h"

#include <range_nlm/eval/metrics.h>
#include <range_nlm/eval/synthetic_scene.h>
#include <range_nlm/parameters.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <functional>
#include <stdexcept>

namespace range_nlm
{
namespace tools
{
namespace accuracy_time
{

namespace
{
using Cloud = pcl::PointCloud<pcl::PointXYZ>;
using peer_grids::fixed;
using peer_grids::Smoother;

/// range_nlm's three presets, FastBilateral at the settings the real-frame comparison uses and
/// MovingLeastSquares' radius grid: each family a short curve of its own trade-off.
std::vector<Smoother>
methods(int threads)
{
  std::vector<Smoother> s;
  for (const char* name : {"default", "live", "paper"}) {
    FilterParameters p = FilterParameters::preset(name);
    p.threads = threads;
    s.push_back(peer_grids::rangeNlm(name, p));
  }
  for (const auto& [sigma_s, sigma_r] : {std::pair{5.0f, 0.03f}, {10.0f, 0.05f}, {15.0f, 0.05f}})
    s.push_back(peer_grids::fastBilateral(sigma_s, sigma_r));
  for (Smoother& m : peer_grids::mlsGrid(threads))
    s.push_back(std::move(m));
  return s;
}

/// One warm-up call, then `runs` timed calls; the last result and the times (ms).
Cloud
timed(const Smoother& s, const Cloud& input, int runs, std::vector<double>& samples)
{
  Cloud result = s.apply(input);
  for (int k = 0; k < runs; ++k) {
    const auto start = std::chrono::steady_clock::now();
    result = s.apply(input);
    samples.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count());
  }
  return result;
}

Row
named(const std::string& frame, const std::string& metric, const std::string& family, const std::string& setting)
{
  Row r;
  r.frame = frame;
  r.metric = metric;
  r.family = family;
  r.setting = setting;
  return r;
}

double
median(std::vector<double> v)
{
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

} // namespace

void
validate(const Options& o)
{
  if (o.runs < 1)
    throw std::invalid_argument("runs must be at least 1, got " + std::to_string(o.runs));
  if (o.width < 16 || o.height < 16)
    throw std::invalid_argument("frame size must be at least 16x16, got " + std::to_string(o.width) + "x" +
                                std::to_string(o.height));
  if (o.threads < 0)
    throw std::invalid_argument("threads must be 0 (all cores) or more, got " + std::to_string(o.threads));
  noiseModelFromString(o.model); // throws std::invalid_argument naming the model
  if (!o.real_frame.empty() && !std::filesystem::is_regular_file(o.real_frame))
    throw std::invalid_argument("real frame '" + o.real_frame + "' is not a file");
}

std::vector<Row>
run(const Options& o, std::ostream& log)
{
  validate(o);
  const std::vector<Smoother> all = methods(o.threads);
  std::vector<Row> rows;

  SceneOptions scene;
  scene.width = o.width;
  scene.height = o.height;
  scene.noise = noiseModelFromString(o.model);
  scene.seed = o.seed;
  const SyntheticFrame frame = renderFrame(scene);
  EvaluationOptions eval;
  eval.threads = o.threads;
  const std::string generated = "generated: boxes, " + o.model + " noise, seed " + std::to_string(o.seed);
  Row noisy = named(generated, "flat RMSE against ground truth", "input", "raw");
  noisy.accuracy_mm = 1e3 * evaluateFrame(frame.truth, frame.noisy, nullptr, eval).flat_rmse;
  rows.push_back(noisy);
  for (const Smoother& s : all) {
    Row r = named(generated, "flat RMSE against ground truth", s.family, s.setting);
    const Cloud result = timed(s, frame.noisy, o.runs, r.samples_ms);
    const FrameMetrics m = evaluateFrame(frame.truth, result, &frame.noisy, eval);
    r.accuracy_mm = 1e3 * m.flat_rmse;
    r.points_lost = m.points_lost;
    r.median_ms = median(r.samples_ms);
    log << generated << ": " << s.family << " " << s.setting << ": " << fixed(r.accuracy_mm, 2) << " mm, "
        << fixed(r.median_ms, 1) << " ms" << std::endl;
    rows.push_back(std::move(r));
  }

  if (!o.real_frame.empty()) {
    const Cloud raw = bench::loadXyzFrame(o.real_frame);
    const PlanarRegions regions = findPlanarRegions(raw);
    const std::string name = std::filesystem::path(o.real_frame).filename().string();
    Row before = named(name, "residual to planes, interior", "input", "raw");
    before.accuracy_mm = 1e3 * planarResidual(regions, raw).interior_rms;
    rows.push_back(before);
    for (const Smoother& s : all) {
      Row r = named(name, "residual to planes, interior", s.family, s.setting);
      const Cloud result = timed(s, raw, o.runs, r.samples_ms);
      const PlanarResidual p = planarResidual(regions, result);
      r.accuracy_mm = 1e3 * p.interior_rms;
      r.points_lost = p.points_lost;
      r.median_ms = median(r.samples_ms);
      log << name << ": " << s.family << " " << s.setting << ": " << fixed(r.accuracy_mm, 2) << " mm, "
          << fixed(r.median_ms, 1) << " ms" << std::endl;
      rows.push_back(std::move(r));
    }
  }
  return rows;
}

void
printTable(const std::vector<Row>& rows, const Options& o, std::ostream& out)
{
  out << "Accuracy against time per frame (median of " << o.runs << " runs after a warm-up, threads "
      << o.threads << "; FastBilateral single-threaded)\n\n"
      << "| frame | metric | method | setting | accuracy (mm) | ms per frame | points lost |\n"
      << "|---|---|---|---|---|---|---|\n";
  for (const Row& r : rows)
    out << "| " << r.frame << " | " << r.metric << " | " << r.family << " | " << r.setting << " | "
        << fixed(r.accuracy_mm, 2) << " | " << (r.samples_ms.empty() ? "-" : fixed(r.median_ms, 1)) << " | "
        << r.points_lost << " |\n";
}

void
printJson(const std::vector<Row>& rows, const Options& o, std::ostream& out)
{
  const bench::MachineInfo machine = bench::machineInfo();
  nlohmann::json a = nlohmann::json::array();
  for (const Row& r : rows)
    a.push_back({{"frame", r.frame},
                 {"metric", r.metric},
                 {"family", r.family},
                 {"setting", r.setting},
                 {"accuracy_mm", r.accuracy_mm},
                 {"median_ms", r.samples_ms.empty() ? nlohmann::json(nullptr) : nlohmann::json(r.median_ms)},
                 {"samples_ms", r.samples_ms},
                 {"points_lost", r.points_lost}});
  out << nlohmann::json{{"tool", "range_nlm_bench"},
                        {"accuracy_time",
                         {{"runs", o.runs},
                          {"threads", o.threads},
                          {"cpu_model", machine.cpu_model},
                          {"cpus", machine.usable_cpus},
                          {"load_average_end", bench::loadAverage()},
                          {"rows", a}}}}
             .dump(1)
      << "\n";
}

} // namespace accuracy_time
} // namespace tools
} // namespace range_nlm
