#include "temporal_comparison.h"
#include "bench_support.h"
#include "librealsense_temporal.h"
#include "quality_comparison.h"

#include <range_nlm/nonlocal_means_filter.h>
#include <range_nlm/eval/synthetic_scene.h>
#include <range_nlm/temporal_stream.h>

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <deque>
#include <filesystem>
#include <functional>
#include <iomanip>
#include <limits>
#include <sstream>

namespace range_nlm
{
namespace tools
{
namespace temporal
{

using Cloud = pcl::PointCloud<pcl::PointXYZ>;

namespace
{
/// The settings of librealsense's temporal filter compared: its defaults, a heavier smoothing
/// (alpha 0.1) that shows the price of a long memory, and the widest edge threshold (delta 100
/// units), which lets noise larger than the default 20 units be averaged.
std::vector<librealsense::TemporalFilterParameters>
librealsenseSettings()
{
  librealsense::TemporalFilterParameters heavy, wide;
  heavy.alpha = 0.1f;
  wide.delta = 100; // the option's maximum: above the noise of far pixels
  return {librealsense::TemporalFilterParameters{}, heavy, wide};
}

std::string
librealsenseName(const librealsense::TemporalFilterParameters& p)
{
  std::ostringstream s;
  s << "librealsense temporal (alpha " << p.alpha << ", delta " << p.delta << ", persistency " << p.persistence
    << ")";
  return s.str();
}

/// One filter over the whole sequence, frame after frame.
std::vector<Cloud>
librealsenseSequence(const std::vector<Cloud::ConstPtr>& frames, const librealsense::TemporalFilterParameters& p)
{
  librealsense::TemporalFilter filter(p);
  std::vector<Cloud> out;
  for (const auto& f : frames)
    out.push_back(filter.filter(*f));
  return out;
}

std::vector<Cloud>
rangeNlmSequence(const std::vector<Cloud::ConstPtr>& frames, TemporalWindow window, const FilterParameters& p)
{
  std::vector<Cloud> out;
  for (const auto& f : filterSequence<pcl::PointXYZ>(frames, 1, window, p))
    out.push_back(*f);
  return out;
}

std::vector<Cloud>
perFrame(const std::vector<Cloud::ConstPtr>& frames, const FilterParameters& p)
{
  std::vector<Cloud> out;
  for (const auto& f : frames) {
    NonLocalMeansFilter<pcl::PointXYZ> filter;
    filter.setParameters(p);
    filter.setInputCloud(f);
    out.emplace_back();
    filter.filter(out.back());
  }
  return out;
}

const char*
windowName(TemporalWindow w)
{
  switch (w) {
  case TemporalWindow::centred: return "";
  case TemporalWindow::causal: return ", causal";
  case TemporalWindow::recursive: return ", recursive";
  }
  return "";
}

/// `frame` with the pixels outside `keep` set to NaN.
Cloud
masked(const Cloud& frame, const std::vector<unsigned char>& keep)
{
  Cloud out = frame;
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (std::size_t i = 0; i < out.size(); ++i)
    if (!keep[i])
      out[i].x = out[i].y = out[i].z = nan;
  out.is_dense = false;
  return out;
}

/// `regions` with each plane refitted (orthogonal least squares) to the valid points of `frame`
/// in the region; a region with fewer than 3 valid points keeps its plane.
PlanarRegions
refitPlanes(const PlanarRegions& regions, const Cloud& frame)
{
  const std::size_t n = regions.planes.size();
  std::vector<Eigen::Vector3d> sum(n, Eigen::Vector3d::Zero());
  std::vector<Eigen::Matrix3d> outer(n, Eigen::Matrix3d::Zero());
  std::vector<std::size_t> count(n, 0);
  for (std::size_t i = 0; i < frame.size(); ++i) {
    const int id = regions.label[i];
    const pcl::PointXYZ& p = frame[i];
    if (id < 0 || !(std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z)))
      continue;
    const Eigen::Vector3d q(p.x, p.y, p.z);
    sum[std::size_t(id)] += q;
    outer[std::size_t(id)] += q * q.transpose();
    ++count[std::size_t(id)];
  }
  PlanarRegions refit = regions;
  for (std::size_t k = 0; k < n; ++k) {
    if (count[k] < 3)
      continue;
    const Eigen::Vector3d centroid = sum[k] / double(count[k]);
    const Eigen::Matrix3d covariance = outer[k] / double(count[k]) - centroid * centroid.transpose();
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(covariance);
    const Eigen::Vector3d normal = solver.eigenvectors().col(0); // smallest eigenvalue
    refit.planes[k] = Eigen::Vector4d(normal.x(), normal.y(), normal.z(), -normal.dot(centroid));
  }
  return refit;
}

std::string
millimetres(double metres)
{
  std::ostringstream s;
  if (std::isfinite(metres))
    s << std::fixed << std::setprecision(2) << 1000.0 * metres;
  else
    s << "-";
  return s.str();
}
} // namespace

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
    const auto results = timed([&] { return perFrame(noisy, parameters); }, ms);
    evaluate("range_nlm per frame (static)", results, ms);
  }
  for (TemporalWindow window : {TemporalWindow::centred, TemporalWindow::causal, TemporalWindow::recursive}) {
    double ms = 0;
    const auto results = timed([&] { return rangeNlmSequence(noisy, window, parameters); }, ms);
    evaluate(std::string("range_nlm temporal, radius 1") + windowName(window), results, ms);
  }
  // The live preset, as a camera's stream runs it: per frame, and in the recursive window.
  FilterParameters live = FilterParameters::live();
  live.threads = options.threads;
  {
    double ms = 0;
    const auto results = timed([&] { return perFrame(noisy, live); }, ms);
    evaluate("range_nlm live per frame (static)", results, ms);
    const auto recursive = timed([&] { return rangeNlmSequence(noisy, TemporalWindow::recursive, live); }, ms);
    evaluate("range_nlm live temporal, radius 1, recursive", recursive, ms);
  }
  for (const auto& p : librealsenseSettings()) {
    double ms = 0;
    const auto results = timed([&] { return librealsenseSequence(noisy, p); }, ms);
    evaluate(librealsenseName(p), results, ms);
  }
  return rows;
}

std::vector<StaticSequenceResult>
runStatic(const Options& options, std::ostream& log)
{
  std::vector<StaticSequenceResult> results;
  FilterParameters parameters = FilterParameters::recommended();
  parameters.threads = options.threads;
  for (const std::vector<std::string>& sequence : options.static_sequences) {
    if (sequence.size() < 2)
      throw std::invalid_argument("a static sequence needs at least 2 frames, got " +
                                  std::to_string(sequence.size()) +
                                  (sequence.empty() ? std::string() : " (" + sequence.front() + ")"));
    StaticSequenceResult result;
    result.name = std::filesystem::path(sequence.front()).parent_path().filename().string();
    result.frames = sequence;
    std::vector<Cloud::ConstPtr> raw;
    for (const std::string& f : sequence)
      raw.emplace_back(new Cloud(bench::loadXyzFrame(f)));
    std::vector<unsigned char> keep(raw.front()->size(), 1);
    for (std::size_t k = 0; k < raw.size(); ++k) {
      const Cloud& frame = *raw[k];
      if (frame.width != raw.front()->width || frame.height != raw.front()->height)
        throw std::invalid_argument("'" + sequence[k] + "' is " + std::to_string(frame.width) + " x " +
                                    std::to_string(frame.height) + ", the sequence's first frame is " +
                                    std::to_string(raw.front()->width) + " x " + std::to_string(raw.front()->height));
      for (std::size_t i = 0; i < keep.size(); ++i) {
        const pcl::PointXYZ& p = frame[i];
        if (!(std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z)))
          keep[i] = 0;
      }
    }
    result.raw_pixels = std::size_t(std::count(keep.begin(), keep.end(), 1));
    const PlanarRegions regions = findPlanarRegions(*raw.back());
    result.regions = regions.planes.size();
    auto add = [&](const std::string& method, const std::vector<Cloud>& outputs) {
      JitterEvaluator common, own;
      for (const Cloud& c : outputs) {
        common.add(masked(c, keep));
        own.add(c);
      }
      result.rows.push_back(JitterRow{method, common.jitter(), own.jitter(), planarResidual(regions, outputs.back()),
                                      planarResidual(refitPlanes(regions, outputs.back()), outputs.back())});
      const JitterRow& r = result.rows.back();
      log << result.name << ": " << method << ": median jitter " << millimetres(r.common.median)
          << " mm over the raw frames' valid pixels, " << millimetres(r.own.median) << " mm over its own " << r.own.pixels
          << "; last frame to the raw planes " << millimetres(r.last_frame.interior_rms) << " / "
          << millimetres(r.last_frame.border_rms) << " mm, to its own " << millimetres(r.last_frame_refit.interior_rms)
          << " / " << millimetres(r.last_frame_refit.border_rms) << " mm" << std::endl;
    };
    {
      std::vector<Cloud> frames;
      for (const auto& f : raw)
        frames.push_back(*f);
      add("raw", frames);
    }
    for (auto [sigma_s, sigma_r] : {std::pair<float, float>{5.0f, 0.03f}, {15.0f, 0.05f}}) {
      std::vector<Cloud> frames;
      for (const auto& f : raw)
        frames.push_back(quality::fastBilateral(*f, sigma_s, sigma_r));
      std::ostringstream name;
      name << "FastBilateral per frame (sigma_s " << sigma_s << ", sigma_r " << sigma_r << ")";
      add(name.str(), frames);
    }
    // range_nlm's rows again as its depth-image output holds them (read back onto the rays).
    const double depth_scale = bench::frameDepthScale(sequence.front());
    auto add_with_png = [&](const std::string& method, const std::vector<Cloud>& outputs) {
      add(method, outputs);
      std::vector<Cloud> png;
      for (std::size_t k = 0; k < outputs.size(); ++k)
        png.push_back(bench::depthImageOutput(*raw[k], outputs[k], depth_scale));
      add(method + ", PNG output", png);
    };
    add_with_png("range_nlm per frame (default)", perFrame(raw, parameters));
    for (TemporalWindow window : {TemporalWindow::centred, TemporalWindow::causal, TemporalWindow::recursive})
      add_with_png(std::string("range_nlm temporal, radius 1") + windowName(window),
                   rangeNlmSequence(raw, window, parameters));
    // A camera known to be static (range_nlm_denoise --cross-frame temporal): the cross-frame
    // bandwidths always follow the frame-to-frame noise, where the guarded default takes
    // pose5's low-frequency offsets between frames for motion.
    FilterParameters static_camera = parameters;
    static_camera.cross_frame_bandwidth = CrossFrameBandwidth::temporal;
    for (TemporalWindow window : {TemporalWindow::centred, TemporalWindow::recursive})
      add_with_png(std::string("range_nlm temporal, radius 1") + windowName(window) + ", cross-frame temporal",
                   rangeNlmSequence(raw, window, static_camera));
    FilterParameters live = FilterParameters::live();
    live.threads = options.threads;
    add_with_png("range_nlm live per frame", perFrame(raw, live));
    add_with_png("range_nlm live temporal, radius 1, recursive",
                 rangeNlmSequence(raw, TemporalWindow::recursive, live));
    for (const auto& p : librealsenseSettings())
      add(librealsenseName(p), librealsenseSequence(raw, p));
    results.push_back(std::move(result));
  }
  return results;
}

void
printTable(const std::vector<Row>& rows, const std::vector<StaticSequenceResult>& real, const Options& options,
           std::ostream& out)
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
  if (real.empty())
    return;
  out << "\nStatic real sequences. Jitter: median per-pixel range jitter (sample std over the frames, mm) of each "
         "method's output for every frame of the sequence (the causal filters start cold on its first frame), over "
         "the pixels valid in every raw frame; in brackets over the pixels valid in every output frame of the "
         "method, and their number. Planes: the output for the last frame in the planar regions of the last raw "
         "frame, RMS distance to the raw frame's planes and to planes refitted to the output in each region "
         "(mm, interior of the regions)\n\n| method |";
  for (const StaticSequenceResult& r : real)
    out << " " << r.name << " jitter (" << r.frames.size() << " frames, " << r.raw_pixels << " px) | " << r.name
        << " planes: raw / refitted (" << r.regions << " regions) |";
  out << "\n|---|";
  for (std::size_t k = 0; k < real.size(); ++k)
    out << "---|---|";
  out << "\n";
  for (std::size_t m = 0; m < real.front().rows.size(); ++m) {
    out << "| " << real.front().rows[m].method << " |";
    for (const StaticSequenceResult& r : real) {
      const JitterRow& j = r.rows[m];
      out << " " << millimetres(j.common.median) << " (" << millimetres(j.own.median) << ", " << j.own.pixels
          << " px) | " << millimetres(j.last_frame.interior_rms) << " / " << millimetres(j.last_frame_refit.interior_rms)
          << " |";
    }
    out << "\n";
  }
}

void
printJson(const std::vector<Row>& rows, const std::vector<StaticSequenceResult>& real, std::ostream& out)
{
  out << "{\"temporal\": [";
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const Row& r = rows[i];
    out << (i ? ", " : "") << "{\"method\": " << bench::jsonString(r.method)
        << ", \"temporal_std_mm\": " << bench::jsonNumber(1000 * r.metrics.temporal_std)
        << ", \"moving_edge_rmse_mm\": " << bench::jsonNumber(1000 * r.metrics.moving_edge_rmse)
        << ", \"flat_rmse_mm\": " << bench::jsonNumber(1000 * r.metrics.total.flat_rmse)
        << ", \"feature_rmse_mm\": " << bench::jsonNumber(1000 * r.metrics.total.feature_rmse)
        << ", \"ms_per_frame\": " << bench::jsonNumber(r.milliseconds_per_frame) << "}";
  }
  out << "], \"real_static\": [";
  for (std::size_t s = 0; s < real.size(); ++s) {
    const StaticSequenceResult& r = real[s];
    out << (s ? ", " : "") << "{\"sequence\": " << bench::jsonString(r.name) << ", \"frames\": [";
    for (std::size_t k = 0; k < r.frames.size(); ++k)
      out << (k ? ", " : "") << bench::jsonString(r.frames[k]);
    out << "], \"raw_pixels\": " << r.raw_pixels << ", \"regions\": " << r.regions << ", \"rows\": [";
    for (std::size_t m = 0; m < r.rows.size(); ++m) {
      const JitterRow& j = r.rows[m];
      out << (m ? ", " : "") << "{\"method\": " << bench::jsonString(j.method)
          << ", \"median_jitter_mm\": " << bench::jsonNumber(1000 * j.common.median)
          << ", \"mean_jitter_mm\": " << bench::jsonNumber(1000 * j.common.mean)
          << ", \"pixels\": " << j.common.pixels
          << ", \"own_median_jitter_mm\": " << bench::jsonNumber(1000 * j.own.median)
          << ", \"own_mean_jitter_mm\": " << bench::jsonNumber(1000 * j.own.mean)
          << ", \"own_pixels\": " << j.own.pixels
          << ", \"last_frame_planes_interior_rms_mm\": " << bench::jsonNumber(1000 * j.last_frame.interior_rms)
          << ", \"last_frame_planes_border_rms_mm\": " << bench::jsonNumber(1000 * j.last_frame.border_rms)
          << ", \"last_frame_points_lost\": " << j.last_frame.points_lost
          << ", \"last_frame_refit_planes_interior_rms_mm\": " << bench::jsonNumber(1000 * j.last_frame_refit.interior_rms)
          << ", \"last_frame_refit_planes_border_rms_mm\": " << bench::jsonNumber(1000 * j.last_frame_refit.border_rms)
          << "}";
    }
    out << "]}";
  }
  out << "]}\n";
}

} // namespace temporal
} // namespace tools
} // namespace range_nlm
