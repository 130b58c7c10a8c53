#include "temporal_comparison.h"

#include <range_nlm/nonlocal_means_filter.h>
#include <range_nlm/eval/synthetic_scene.h>
#include <range_nlm/temporal_stream.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <deque>
#include <functional>
#include <iomanip>
#include <limits>

namespace range_nlm
{
namespace tools
{
namespace temporal
{

using Cloud = pcl::PointCloud<pcl::PointXYZ>;

Cloud
runningPixelFilter(const std::vector<Cloud::ConstPtr>& last, bool median)
{
  Cloud out = *last.back();
  const float nan = std::numeric_limits<float>::quiet_NaN();
  std::vector<float> xs, ys, zs;
  bool dense = true;
  for (std::size_t i = 0; i < out.size(); ++i) {
    xs.clear(), ys.clear(), zs.clear();
    for (const auto& frame : last) {
      const pcl::PointXYZ& p = (*frame)[i];
      if (std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z))
        xs.push_back(p.x), ys.push_back(p.y), zs.push_back(p.z);
    }
    pcl::PointXYZ& q = out[i];
    if (xs.empty()) {
      q.x = q.y = q.z = nan;
      dense = false;
      continue;
    }
    if (median) {
      // The median depth sample (whole point, so it stays on a measured ray).
      std::vector<std::size_t> order(zs.size());
      for (std::size_t k = 0; k < order.size(); ++k)
        order[k] = k;
      std::nth_element(order.begin(), order.begin() + order.size() / 2, order.end(),
                       [&](std::size_t a, std::size_t b) { return zs[a] < zs[b]; });
      const std::size_t m = order[order.size() / 2];
      q.x = xs[m], q.y = ys[m], q.z = zs[m];
    } else {
      double sx = 0, sy = 0, sz = 0;
      for (std::size_t k = 0; k < xs.size(); ++k)
        sx += xs[k], sy += ys[k], sz += zs[k];
      q.x = float(sx / xs.size()), q.y = float(sy / xs.size()), q.z = float(sz / xs.size());
    }
  }
  out.is_dense = dense;
  return out;
}

std::vector<Row>
run(const Options& options, std::ostream& log)
{
  SceneOptions scene;
  scene.width = options.width;
  scene.height = options.height;
  scene.noise = noiseModelFromString(options.noise);
  scene.frames = options.frames;
  scene.motion = Motion::moving_box;
  scene.motion_step = options.motion_step;
  scene.seed = options.seed;
  const std::vector<SyntheticFrame> sequence = renderSequence(scene);
  std::vector<Cloud::ConstPtr> noisy;
  std::vector<pcl::PointCloud<pcl::PointNormal>> truth;
  for (const auto& f : sequence) {
    noisy.emplace_back(new Cloud(f.noisy));
    truth.push_back(f.truth);
  }
  EvaluationOptions eval;
  eval.threads = options.threads;

  std::vector<Row> rows;
  auto evaluate = [&](const std::string& name, const std::vector<Cloud>& results, double ms) {
    SequenceEvaluator evaluator(eval);
    for (std::size_t k = 0; k < results.size(); ++k)
      evaluator.add(truth[k], results[k], noisy[k].get());
    rows.push_back(Row{name, evaluator.metrics(), ms / results.size()});
    const SequenceMetrics& m = rows.back().metrics;
    log << name << ": temporal std " << 1000 * m.temporal_std << " mm, moving edges " << 1000 * m.moving_edge_rmse
        << " mm" << std::endl;
  };
  auto timed = [](const std::function<std::vector<Cloud>()>& f, double& ms) {
    const auto start = std::chrono::steady_clock::now();
    std::vector<Cloud> r = f();
    ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    return r;
  };

  {
    std::vector<Cloud> raw;
    for (const auto& f : noisy)
      raw.push_back(*f);
    evaluate("noisy input", raw, 0.0);
  }
  for (bool median : {false, true}) {
    double ms = 0;
    const auto results = timed(
        [&] {
          std::vector<Cloud> out;
          for (std::size_t k = 0; k < noisy.size(); ++k) {
            const std::size_t lo = k + 1 >= static_cast<std::size_t>(options.window) ? k + 1 - options.window : 0;
            out.push_back(runningPixelFilter(std::vector<Cloud::ConstPtr>(noisy.begin() + lo, noisy.begin() + k + 1), median));
          }
          return out;
        },
        ms);
    evaluate(std::string("per-pixel running ") + (median ? "median" : "average") + " of " +
                 std::to_string(options.window) + " frames",
             results, ms);
  }
  FilterParameters parameters = FilterParameters::recommended();
  parameters.threads = options.threads;
  {
    double ms = 0;
    const auto results = timed(
        [&] {
          std::vector<Cloud> out;
          for (const auto& f : noisy) {
            NonLocalMeansFilter<pcl::PointXYZ> filter;
            filter.setParameters(parameters);
            filter.setInputCloud(f);
            out.emplace_back();
            filter.filter(out.back());
          }
          return out;
        },
        ms);
    evaluate("range_nlm per frame (static)", results, ms);
  }
  for (bool causal : {false, true}) {
    double ms = 0;
    const auto results = timed(
        [&] {
          std::vector<Cloud> out;
          for (const auto& f : filterSequence<pcl::PointXYZ>(noisy, 1, causal, parameters))
            out.push_back(*f);
          return out;
        },
        ms);
    evaluate(std::string("range_nlm temporal, radius 1") + (causal ? ", causal" : ""), results, ms);
  }
  return rows;
}

void
printTable(const std::vector<Row>& rows, const Options& options, std::ostream& out)
{
  out << "\nSequence of " << options.frames << " frames " << options.width << "x" << options.height << ", "
      << options.noise << " noise, a box moving " << 1000 * options.motion_step
      << " mm per frame (mm; temporal std over static pixels, RMSE within 3 px of the moving box's edges)\n\n";
  out << "| method | temporal std | moving-edge RMSE | flat RMSE | feature RMSE | ms/frame |\n";
  out << "|---|---|---|---|---|---|\n";
  out << std::fixed;
  for (const Row& r : rows)
    out << "| " << r.method << " | " << std::setprecision(2) << 1000 * r.metrics.temporal_std << " | "
        << 1000 * r.metrics.moving_edge_rmse << " | " << 1000 * r.metrics.total.flat_rmse << " | "
        << 1000 * r.metrics.total.feature_rmse << " | " << std::setprecision(0) << r.milliseconds_per_frame << " |\n";
}

void
printJson(const std::vector<Row>& rows, std::ostream& out)
{
  out << "{\"temporal\": [";
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const Row& r = rows[i];
    out << (i ? ", " : "") << "{\"method\": \"" << r.method << "\", \"temporal_std_mm\": " << 1000 * r.metrics.temporal_std
        << ", \"moving_edge_rmse_mm\": " << 1000 * r.metrics.moving_edge_rmse
        << ", \"flat_rmse_mm\": " << 1000 * r.metrics.total.flat_rmse
        << ", \"feature_rmse_mm\": " << 1000 * r.metrics.total.feature_rmse
        << ", \"ms_per_frame\": " << r.milliseconds_per_frame << "}";
  }
  out << "]}\n";
}

} // namespace temporal
} // namespace tools
} // namespace range_nlm
