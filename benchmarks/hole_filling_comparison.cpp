#include "hole_filling_comparison.h"

#include "bench_support.h"
#include "librealsense_holes.h"
#include "opencv_inpaint.h"

#include <range_nlm/nonlocal_means_filter.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <iomanip>
#include <limits>
#include <random>
#include <sstream>

namespace range_nlm
{
namespace tools
{
namespace holes
{
namespace
{
using Cloud = pcl::PointCloud<pcl::PointXYZ>;
using bench::jsonNumber;
using bench::jsonString;

void
makeHole(Cloud& cloud, std::size_t i)
{
  const float nan = std::numeric_limits<float>::quiet_NaN();
  cloud[i].x = cloud[i].y = cloud[i].z = nan;
}

/// The shadows of every left edge of a foreground in row v.
void
punchShadows(SyntheticFrame& frame, const SceneOptions& scene, const Options& options, int v,
             std::vector<HoleKind>& kind)
{
  const int w = static_cast<int>(frame.truth.width);
  const auto depth = [&](int u) { return frame.truth[std::size_t(v) * w + u].z; };
  for (int u = 1; u < w; ++u) {
    const float far = depth(u - 1), near = depth(u);
    if (!std::isfinite(far) || !std::isfinite(near) || !(far > 1.05f * near))
      continue;
    const double disparity = scene.fx * options.baseline * (1.0 / near - 1.0 / far);
    const int width = std::min(40, static_cast<int>(std::lround(disparity)));
    for (int k = u - width; k < u; ++k)
      if (k >= 0 && std::isfinite(depth(k)) && depth(k) > 1.05f * near) {
        const std::size_t i = std::size_t(v) * w + k;
        kind[i] = HoleKind::shadow;
        makeHole(frame.noisy, i);
      }
  }
}

double
elapsedMs(std::chrono::steady_clock::time_point start)
{
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

/// The score of `out` on the punched pixels; `filled_by_all` is cleared where `out` left a hole.
Score
score(const std::string& method, const Cloud& out, const SyntheticFrame& frame, const std::vector<HoleKind>& kind,
      std::vector<unsigned char>& filled_by_all)
{
  Score s;
  s.method = method;
  double shadow2 = 0.0, blob2 = 0.0;
  std::size_t gross = 0;
  std::vector<double> errors;
  for (std::size_t i = 0; i < kind.size(); ++i) {
    if (kind[i] == HoleKind::none || !std::isfinite(frame.truth[i].z))
      continue;
    const bool shadow = kind[i] == HoleKind::shadow;
    (shadow ? s.shadows : s.blobs) += 1;
    if (!std::isfinite(out[i].z)) {
      filled_by_all[i] = 0;
      continue;
    }
    const double e = double(out[i].z) - frame.truth[i].z;
    (shadow ? s.shadows_filled : s.blobs_filled) += 1;
    (shadow ? shadow2 : blob2) += e * e;
    gross += std::abs(e) > 0.03 * frame.truth[i].z;
    errors.push_back(std::abs(e));
  }
  s.shadow_rmse_mm = s.shadows_filled ? 1000.0 * std::sqrt(shadow2 / s.shadows_filled) : 0.0;
  s.blob_rmse_mm = s.blobs_filled ? 1000.0 * std::sqrt(blob2 / s.blobs_filled) : 0.0;
  const std::size_t filled = s.shadows_filled + s.blobs_filled;
  s.gross_share = filled ? double(gross) / filled : 0.0;
  s.median_error_mm = errors.empty() ? 0.0 : 1000.0 * bench::median(errors);
  return s;
}

/// The methods' outputs on one punched frame, in the order of the table.
std::vector<std::pair<std::string, Cloud>>
runMethods(const Cloud& noisy, const SceneOptions& scene, const Options& options, std::vector<double>& ms)
{
  std::vector<std::pair<std::string, Cloud>> outputs;
  librealsense::PinholeRays rays;
  rays.fx = scene.fx, rays.fy = scene.fy, rays.cx = scene.principalX(), rays.cy = scene.principalY();
  const Cloud::ConstPtr input(new Cloud(noisy));
  const auto filtered = [&](int fill_holes) {
    NonLocalMeansFilter<pcl::PointXYZ> filter;
    filter.setNumberOfThreads(options.threads);
    filter.setFillHoles(fill_holes);
    filter.setInputCloud(input);
    Cloud out;
    const auto start = std::chrono::steady_clock::now();
    filter.filter(out);
    ms.push_back(elapsedMs(start));
    return out;
  };
  outputs.emplace_back("range_nlm default, --fill-holes " + std::to_string(options.fill_holes),
                       filtered(options.fill_holes));
  const Cloud smooth = filtered(0);
  const double smooth_ms = ms.back();
  ms.pop_back();
  const librealsense::HoleFillingMode modes[] = {librealsense::HoleFillingMode::fill_from_left,
                                                 librealsense::HoleFillingMode::farthest_from_around,
                                                 librealsense::HoleFillingMode::nearest_from_around};
  for (const bool after_filter : {true, false}) {
    for (const auto mode : modes) {
      librealsense::HoleFillingParameters p;
      p.mode = mode;
      const auto start = std::chrono::steady_clock::now();
      Cloud out = librealsense::HoleFillingFilter(p).filter(after_filter ? smooth : noisy, rays);
      ms.push_back(elapsedMs(start) + (after_filter ? smooth_ms : 0.0));
      outputs.emplace_back(std::string(after_filter ? "range_nlm default + " : "raw + ") + "librealsense '" +
                               librealsense::toString(mode) + "'",
                           std::move(out));
    }
    for (const auto method : {opencv::InpaintMethod::telea, opencv::InpaintMethod::navier_stokes}) {
      const auto start = std::chrono::steady_clock::now();
      Cloud out = opencv::inpaintDepth(after_filter ? smooth : noisy, rays, method, options.inpaint_radius);
      ms.push_back(elapsedMs(start) + (after_filter ? smooth_ms : 0.0));
      outputs.emplace_back(std::string(after_filter ? "range_nlm default + " : "raw + ") + "OpenCV inpaint (" +
                               opencv::toString(method) + ")",
                           std::move(out));
    }
  }
  return outputs;
}
} // namespace

std::vector<HoleKind>
punchHoles(SyntheticFrame& frame, const SceneOptions& scene, const Options& options, std::uint64_t seed)
{
  const int w = static_cast<int>(frame.noisy.width), h = static_cast<int>(frame.noisy.height);
  std::vector<HoleKind> kind(frame.noisy.size(), HoleKind::none);
  for (int v = 0; v < h; ++v)
    punchShadows(frame, scene, options, v, kind);
  std::mt19937_64 rng(seed);
  std::uniform_int_distribution<int> column(0, w - 1), row(0, h - 1), radius(1, 5);
  for (int placed = 0, tries = 0; placed < options.blobs && tries < 100 * options.blobs; ++tries) {
    const int cu = column(rng), cv = row(rng), r = radius(rng);
    const int surface = frame.shape_index[std::size_t(cv) * w + cu];
    if (!std::isfinite(frame.noisy[std::size_t(cv) * w + cu].z))
      continue;
    ++placed;
    for (int v = std::max(0, cv - r); v <= std::min(h - 1, cv + r); ++v)
      for (int u = std::max(0, cu - r); u <= std::min(w - 1, cu + r); ++u) {
        const std::size_t i = std::size_t(v) * w + u;
        if ((u - cu) * (u - cu) + (v - cv) * (v - cv) <= r * r && frame.shape_index[i] == surface &&
            std::isfinite(frame.noisy[i].z)) {
          kind[i] = HoleKind::blob;
          makeHole(frame.noisy, i);
        }
      }
  }
  frame.noisy.is_dense = false;
  return kind;
}

std::vector<SceneResult>
run(const Options& options, std::ostream& log)
{
  std::vector<SceneResult> results;
  for (const SceneType scene_type : options.scenes)
    for (const NoiseModel noise : options.noises) {
      SceneOptions scene;
      scene.width = options.width;
      scene.height = options.height;
      scene.fx = scene.fy = 525.0 * options.width / 640.0;
      scene.scene = scene_type;
      scene.noise = noise;
      scene.seed = options.seed;
      SyntheticFrame frame = renderFrame(scene);
      const std::vector<HoleKind> kind = punchHoles(frame, scene, options, options.seed + 100);
      SceneResult result;
      result.name = std::string(toString(scene_type)) + " " + toString(noise);
      log << "hole filling: " << result.name << "\n" << std::flush;
      std::vector<double> ms;
      const auto outputs = runMethods(frame.noisy, scene, options, ms);
      std::vector<unsigned char> filled_by_all(kind.size(), 1);
      for (std::size_t k = 0; k < outputs.size(); ++k) {
        result.scores.push_back(score(outputs[k].first, outputs[k].second, frame, kind, filled_by_all));
        result.scores.back().milliseconds = ms[k];
      }
      for (std::size_t k = 0; k < outputs.size(); ++k) {
        double sum2 = 0.0;
        std::size_t n = 0;
        for (std::size_t i = 0; i < kind.size(); ++i)
          if (kind[i] != HoleKind::none && filled_by_all[i] && std::isfinite(frame.truth[i].z)) {
            const double e = double(outputs[k].second[i].z) - frame.truth[i].z;
            sum2 += e * e, ++n;
          }
        result.scores[k].common_rmse_mm = n ? 1000.0 * std::sqrt(sum2 / n) : 0.0;
        result.common = n;
      }
      results.push_back(std::move(result));
    }
  return results;
}

void
printTable(const std::vector<SceneResult>& results, const Options& options, std::ostream& out)
{
  out << "Hole filling on generated " << options.width << "x" << options.height
      << " scenes (shadows beside depth edges, blobs on surfaces), against ground truth\n";
  for (const SceneResult& r : results) {
    out << "\n" << r.name << " (" << r.common << " pixels filled by every method)\n";
    out << "| method | shadows filled | shadow RMSE mm | blobs filled | blob RMSE mm | gross | median error mm "
           "| common RMSE mm | ms |\n";
    out << "|---|---|---|---|---|---|---|---|---|\n";
    for (const Score& s : r.scores) {
      const auto share = [](std::size_t a, std::size_t b) {
        std::ostringstream t;
        t << std::fixed << std::setprecision(0) << (b ? 100.0 * a / b : 0.0) << " % of " << b;
        return t.str();
      };
      out << std::fixed << std::setprecision(1) << "| " << s.method << " | " << share(s.shadows_filled, s.shadows)
          << " | " << s.shadow_rmse_mm << " | " << share(s.blobs_filled, s.blobs) << " | " << s.blob_rmse_mm << " | "
          << 100.0 * s.gross_share << " % | " << std::setprecision(2) << s.median_error_mm << " | "
          << std::setprecision(1) << s.common_rmse_mm << " | " << std::setprecision(0) << s.milliseconds
          << " |\n";
    }
  }
}

void
printJson(const std::vector<SceneResult>& results, const Options& options, std::ostream& out)
{
  out << "{\"width\": " << options.width << ", \"height\": " << options.height
      << ", \"fill_holes\": " << options.fill_holes << ", \"scenes\": [";
  for (std::size_t k = 0; k < results.size(); ++k) {
    const SceneResult& r = results[k];
    out << (k ? ", " : "") << "{\"scene\": " << jsonString(r.name) << ", \"common\": " << r.common
        << ", \"methods\": [";
    for (std::size_t m = 0; m < r.scores.size(); ++m) {
      const Score& s = r.scores[m];
      out << (m ? ", " : "") << "{\"method\": " << jsonString(s.method) << ", \"shadows\": " << s.shadows
          << ", \"shadows_filled\": " << s.shadows_filled << ", \"shadow_rmse_mm\": " << jsonNumber(s.shadow_rmse_mm)
          << ", \"blobs\": " << s.blobs << ", \"blobs_filled\": " << s.blobs_filled
          << ", \"blob_rmse_mm\": " << jsonNumber(s.blob_rmse_mm) << ", \"gross_share\": " << jsonNumber(s.gross_share)
          << ", \"median_error_mm\": " << jsonNumber(s.median_error_mm)
          << ", \"common_rmse_mm\": " << jsonNumber(s.common_rmse_mm)
          << ", \"milliseconds\": " << jsonNumber(s.milliseconds) << "}";
    }
    out << "]}";
  }
  out << "]}\n";
}

} // namespace holes
} // namespace tools
} // namespace range_nlm
