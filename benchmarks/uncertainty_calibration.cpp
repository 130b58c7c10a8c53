#include "uncertainty_calibration.h"
#include "bench_support.h"

#include <range_nlm/eval/metrics.h>
#include <range_nlm/eval/render.h>
#include <range_nlm/eval/synthetic_scene.h>
#include <range_nlm/nonlocal_means_filter.h>
#include <range_nlm/temporal_nonlocal_means_filter.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <iomanip>
#include <limits>
#include <numeric>
#include <sstream>

namespace range_nlm
{
namespace tools
{
namespace uncertainty_calibration
{

using Cloud = pcl::PointCloud<pcl::PointXYZ>;

double
Bin::ratio() const
{
  return points > 0 && predicted > 0.0 ? actual / predicted : std::numeric_limits<double>::quiet_NaN();
}

std::vector<Bin>
calibrationBins(const std::vector<float>& predicted, const std::vector<double>& error,
                const std::vector<unsigned char>& selected, int bins)
{
  std::vector<std::size_t> order;
  for (std::size_t i = 0; i < predicted.size() && i < error.size() && i < selected.size(); ++i)
    if (selected[i] && std::isfinite(predicted[i]) && std::isfinite(error[i]))
      order.push_back(i);
  // Ties broken by index, so that the bins do not depend on the sort's implementation.
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return predicted[a] < predicted[b] || (predicted[a] == predicted[b] && a < b);
  });
  const std::size_t count = std::min<std::size_t>(std::max(bins, 1), order.size());
  std::vector<Bin> out(count);
  for (std::size_t b = 0; b < count; ++b) {
    const std::size_t lo = b * order.size() / count, hi = (b + 1) * order.size() / count;
    double p2 = 0.0, e2 = 0.0;
    for (std::size_t k = lo; k < hi; ++k) {
      p2 += double(predicted[order[k]]) * predicted[order[k]];
      e2 += error[order[k]] * error[order[k]];
    }
    out[b].points = hi - lo;
    out[b].predicted = std::sqrt(p2 / double(hi - lo));
    out[b].actual = std::sqrt(e2 / double(hi - lo));
  }
  return out;
}

double
worstRatio(const std::vector<Bin>& bins)
{
  double worst = std::numeric_limits<double>::quiet_NaN();
  for (const Bin& b : bins) {
    const double r = b.ratio();
    if (std::isfinite(r) && r > 0.0 && !(std::fabs(std::log(r)) <= std::fabs(std::log(worst))))
      worst = r;
  }
  return worst;
}

namespace
{

/// The true error of each result point along the direction it moves: the point-to-plane
/// residual (p - truth) . n_truth of the frame filtered alone (it moves along its normal), the
/// distance along the ray (p - truth) . truth / |truth| in temporal runs (sensor at the origin);
/// NaN where either point is invalid.
std::vector<double>
trueErrors(const pcl::PointCloud<pcl::PointNormal>& truth, const Cloud& result, bool along_ray)
{
  std::vector<double> e(result.size(), std::numeric_limits<double>::quiet_NaN());
  for (std::size_t i = 0; i < result.size(); ++i) {
    const pcl::PointNormal& t = truth[i];
    const pcl::PointXYZ& p = result[i];
    if (!std::isfinite(t.x) || !std::isfinite(t.normal_x) || !std::isfinite(p.x))
      continue;
    const double dx = double(p.x) - t.x, dy = double(p.y) - t.y, dz = double(p.z) - t.z;
    if (along_ray) {
      const double len = std::sqrt(double(t.x) * t.x + double(t.y) * t.y + double(t.z) * t.z);
      e[i] = (dx * t.x + dy * t.y + dz * t.z) / len;
    } else {
      e[i] = dx * t.normal_x + dy * t.normal_y + dz * t.normal_z;
    }
  }
  return e;
}

Row
binned(const std::string& scene, const std::string& model, const std::string& run,
       const pcl::PointCloud<pcl::PointNormal>& truth, const Cloud& result, const std::vector<float>& sigma, int bins)
{
  const std::vector<double> error = trueErrors(truth, result, run == "temporal");
  const std::vector<unsigned char> feature = featureMask(truth);
  std::vector<unsigned char> all(result.size(), 1), flat(result.size());
  for (std::size_t i = 0; i < flat.size(); ++i)
    flat[i] = feature[i] ? 0 : 1;
  Row row;
  row.scene = scene;
  row.model = model;
  row.run = run;
  row.all = calibrationBins(sigma, error, all, bins);
  row.flat = calibrationBins(sigma, error, flat, bins);
  row.feature = calibrationBins(sigma, error, feature, bins);
  return row;
}

void
runScene(const Options& options, const std::string& scene_name, const std::string& model, std::ostream& log,
         std::vector<Row>& rows);

} // namespace

std::vector<Row>
run(const Options& options, std::ostream& log)
{
  std::vector<Row> rows;
  for (const std::string& scene_name : options.scenes)
    for (const std::string& model : options.models)
      runScene(options, scene_name, model, log, rows);
  return rows;
}

namespace
{
/// The rows of one scene and noise model: the frame alone and (Options::temporal) the middle
/// frame of three.
void
runScene(const Options& options, const std::string& scene_name, const std::string& model, std::ostream& log,
         std::vector<Row>& rows)
{
  {
    SceneOptions scene;
    scene.scene = sceneTypeFromString(scene_name);
    scene.width = options.width;
    scene.height = options.height;
    scene.noise = noiseModelFromString(model);
    scene.seed = options.seed;
    scene.frames = options.temporal ? 3 : 1;
    const std::vector<SyntheticFrame> frames = renderSequence(scene);
    FilterParameters p = options.parameters;
    p.threads = options.threads;
    p.uncertainty = true;
    {
      log << "uncertainty calibration: " << scene_name << ", " << model << ", a frame alone" << std::endl;
      NonLocalMeansFilter<pcl::PointXYZ> filter;
      filter.setParameters(p);
      filter.setInputCloud(Cloud::ConstPtr(new Cloud(frames.front().noisy)));
      Cloud out;
      filter.filter(out);
      rows.push_back(
          binned(scene_name, model, "alone", frames.front().truth, out, filter.getUncertainty(), options.bins));
    }
    if (options.temporal) {
      log << "uncertainty calibration: " << scene_name << ", " << model << ", middle frame of three" << std::endl;
      TemporalNonLocalMeansFilter<pcl::PointXYZ> filter;
      filter.setParameters(p);
      std::deque<Cloud::ConstPtr> window;
      for (const SyntheticFrame& f : frames)
        window.push_back(Cloud::ConstPtr(new Cloud(f.noisy)));
      filter.setFrames(window, 1);
      Cloud out;
      filter.filter(out);
      rows.push_back(
          binned(scene_name, model, "temporal", frames[1].truth, out, filter.getUncertainty(), options.bins));
    }
  }
}
} // namespace

namespace
{
std::string
ratioText(double r)
{
  if (!std::isfinite(r))
    return "-";
  std::ostringstream s;
  s << std::fixed << std::setprecision(2) << r;
  return s.str();
}
} // namespace

void
printTable(const std::vector<Row>& rows, std::ostream& out)
{
  out << "Per-point uncertainty: actual RMS error / predicted RMS standard deviation per decile of the prediction "
         "(1 = calibrated; within 0.75 ... 1.25 = within 25 %)\n\n";
  out << "| scene | model | run | worst, all | worst, flat | worst, feature | predicted RMS, deciles 1 / 5 / 10 (mm) | "
         "ratio per decile, all points |\n";
  out << "|---|---|---|---|---|---|---|---|\n";
  for (const Row& r : rows) {
    std::ostringstream deciles, range;
    for (std::size_t b = 0; b < r.all.size(); ++b)
      deciles << (b ? " " : "") << ratioText(r.all[b].ratio());
    if (!r.all.empty())
      range << std::fixed << std::setprecision(3) << 1000 * r.all.front().predicted << " / "
            << 1000 * r.all[r.all.size() / 2 - (r.all.size() > 1 ? 1 : 0)].predicted << " / "
            << 1000 * r.all.back().predicted;
    out << "| " << r.scene << " | " << r.model << " | " << r.run << " | " << ratioText(worstRatio(r.all)) << " | "
        << ratioText(worstRatio(r.flat)) << " | " << ratioText(worstRatio(r.feature)) << " | " << range.str() << " | "
        << deciles.str() << " |\n";
  }
}

void
printJson(const std::vector<Row>& rows, std::ostream& out)
{
  nlohmann::json all = nlohmann::json::array();
  const auto bins = [](const std::vector<Bin>& b) {
    nlohmann::json a = nlohmann::json::array();
    for (const Bin& x : b)
      a.push_back({{"predicted_mm", 1000 * x.predicted}, {"actual_mm", 1000 * x.actual}, {"points", x.points}});
    return a;
  };
  for (const Row& r : rows)
    all.push_back({{"scene", r.scene},
                   {"model", r.model},
                   {"run", r.run},
                   {"worst_ratio", {{"all", worstRatio(r.all)}, {"flat", worstRatio(r.flat)}, {"feature", worstRatio(r.feature)}}},
                   {"all", bins(r.all)},
                   {"flat", bins(r.flat)},
                   {"feature", bins(r.feature)}});
  out << nlohmann::json{{"tool", "range_nlm_bench"}, {"uncertainty_calibration", all}}.dump(1) << "\n";
}

namespace
{
/// A line from (x0, y0) to (x1, y1), `thick` pixels wide.
void
drawLine(RgbImage& img, double x0, double y0, double x1, double y1, const Rgb& c, int thick = 1)
{
  const int steps = static_cast<int>(std::max(std::fabs(x1 - x0), std::fabs(y1 - y0))) + 1;
  for (int s = 0; s <= steps; ++s) {
    const double t = double(s) / steps;
    const int x = static_cast<int>(std::lround(x0 + t * (x1 - x0))), y = static_cast<int>(std::lround(y0 + t * (y1 - y0)));
    for (int dy = -(thick / 2); dy <= thick / 2; ++dy)
      for (int dx = -(thick / 2); dx <= thick / 2; ++dx)
        if (x + dx >= 0 && x + dx < img.width && y + dy >= 0 && y + dy < img.height)
          img.set(x + dx, y + dy, c);
  }
}

/// A disc (filled) or ring of radius r.
void
drawMarker(RgbImage& img, double cx, double cy, int r, const Rgb& c, bool filled)
{
  for (int dy = -r; dy <= r; ++dy)
    for (int dx = -r; dx <= r; ++dx) {
      const int d2 = dx * dx + dy * dy, x = int(std::lround(cx)) + dx, y = int(std::lround(cy)) + dy;
      if (x < 0 || x >= img.width || y < 0 || y >= img.height || d2 > r * r || (!filled && d2 < (r - 1) * (r - 1)))
        continue;
      img.set(x, y, c);
    }
}
} // namespace

void
plotReliability(const std::vector<Row>& rows, const std::string& path)
{
  // Log-log axes over whole decades around every bin's values.
  double lo = std::numeric_limits<double>::infinity(), hi = 0.0;
  for (const Row& r : rows)
    for (const Bin& b : r.all)
      for (double v : {b.predicted, b.actual})
        if (v > 0.0)
          lo = std::min(lo, v), hi = std::max(hi, v);
  if (!(hi > 0.0))
    throw std::invalid_argument("uncertainty calibration: nothing to plot");
  const double d0 = std::floor(std::log10(lo)), d1 = std::ceil(std::log10(hi));
  const int size = 720, margin = 20;
  const double scale = (size - 2 * margin) / std::max(1.0, d1 - d0);
  const auto px = [&](double v) { return margin + (std::log10(v) - d0) * scale; };
  const auto py = [&](double v) { return size - margin - (std::log10(v) - d0) * scale; };
  RgbImage img(size, size, Rgb{255, 255, 255});
  // The band of +-25 % around the diagonal, light grey; decades as grid lines.
  for (int x = margin; x < size - margin; ++x) {
    const double v = std::pow(10.0, d0 + (x - margin) / scale);
    for (int y = int(py(1.25 * v)); y <= int(py(0.75 * v)); ++y)
      if (y >= margin && y < size - margin)
        img.set(x, y, Rgb{225, 225, 225});
  }
  for (double d = d0; d <= d1; d += 1.0) {
    const double v = std::pow(10.0, d);
    drawLine(img, px(v), margin, px(v), size - margin, Rgb{190, 190, 190});
    drawLine(img, margin, py(v), size - margin, py(v), Rgb{190, 190, 190});
  }
  drawLine(img, px(std::pow(10.0, d0)), py(std::pow(10.0, d0)), px(std::pow(10.0, d1)), py(std::pow(10.0, d1)),
           Rgb{0, 0, 0});
  const std::array<Rgb, 8> palette{Rgb{31, 119, 180}, Rgb{255, 127, 14}, Rgb{44, 160, 44}, Rgb{214, 39, 40},
                                   Rgb{148, 103, 189}, Rgb{140, 86, 75}, Rgb{227, 119, 194}, Rgb{127, 127, 127}};
  std::vector<std::string> models;
  for (const Row& r : rows)
    if (std::find(models.begin(), models.end(), r.model) == models.end())
      models.push_back(r.model);
  for (const Row& r : rows) {
    const std::size_t m = std::find(models.begin(), models.end(), r.model) - models.begin();
    const Rgb c = palette[m % palette.size()];
    const bool alone = r.run == "alone";
    for (std::size_t b = 0; b < r.all.size(); ++b) {
      const Bin& x = r.all[b];
      if (!(x.predicted > 0.0 && x.actual > 0.0))
        continue;
      if (b > 0 && r.all[b - 1].predicted > 0.0 && r.all[b - 1].actual > 0.0)
        drawLine(img, px(r.all[b - 1].predicted), py(r.all[b - 1].actual), px(x.predicted), py(x.actual), c,
                 alone ? 2 : 1);
      drawMarker(img, px(x.predicted), py(x.actual), 4, c, alone);
    }
  }
  saveRgbPng(path, img);
}

} // namespace uncertainty_calibration
} // namespace tools
} // namespace range_nlm
