// Accuracy metrics of filtered range frames against ground truth (see evaluation.h).
#include <range_nlm/eval/metrics.h>
#include <range_nlm/parameters.h>

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iomanip>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <utility>

namespace range_nlm
{
namespace
{

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kPi = 3.14159265358979323846;

template <typename T>
[[noreturn]] void
fail(const char* name, T value, const char* requirement)
{
  std::ostringstream msg;
  msg << "range_nlm: evaluation option " << name << " = " << value << " is invalid: " << requirement;
  throw std::invalid_argument(msg.str());
}

template <typename PointT>
void
checkOrganized(const pcl::PointCloud<PointT>& cloud, const std::string& what)
{
  if (cloud.width == 0 || cloud.height == 0 || std::size_t(cloud.width) * cloud.height != cloud.size())
    throw std::invalid_argument(what + " is not an organized cloud (width " + std::to_string(cloud.width) +
                                ", height " + std::to_string(cloud.height) + ", " +
                                std::to_string(cloud.size()) + " points)");
}

template <typename PointT>
void
checkSameSize(const pcl::PointCloud<pcl::PointNormal>& truth, const pcl::PointCloud<PointT>& other,
              const std::string& what)
{
  checkOrganized(other, what);
  if (other.width != truth.width || other.height != truth.height)
    throw std::invalid_argument(what + " is " + std::to_string(other.width) + " x " + std::to_string(other.height) +
                                " but the ground truth is " + std::to_string(truth.width) + " x " +
                                std::to_string(truth.height));
}

bool
isValid(const pcl::PointXYZ& p)
{
  return std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z);
}

bool
isValid(const pcl::PointNormal& p)
{
  return std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z) && std::isfinite(p.normal_x) &&
         std::isfinite(p.normal_y) && std::isfinite(p.normal_z);
}

/// Square dilation (Chebyshev radius r) of a binary mask, separable.
std::vector<unsigned char>
dilate(const std::vector<unsigned char>& mask, int width, int height, int r)
{
  if (r <= 0)
    return mask;
  std::vector<unsigned char> rows(mask.size(), 0), out(mask.size(), 0);
  for (int v = 0; v < height; ++v) {
    // Distance to the last set pixel on the left, swept both ways.
    const unsigned char* in = &mask[std::size_t(v) * width];
    unsigned char* o = &rows[std::size_t(v) * width];
    int last = -1000000;
    for (int u = 0; u < width; ++u) {
      if (in[u])
        last = u;
      if (u - last <= r)
        o[u] = 1;
    }
    last = 1000000;
    for (int u = width - 1; u >= 0; --u) {
      if (in[u])
        last = u;
      if (last - u <= r)
        o[u] = 1;
    }
  }
  for (int u = 0; u < width; ++u) {
    int last = -1000000;
    for (int v = 0; v < height; ++v) {
      if (rows[std::size_t(v) * width + u])
        last = v;
      if (v - last <= r)
        out[std::size_t(v) * width + u] = 1;
    }
    last = 1000000;
    for (int v = height - 1; v >= 0; --v) {
      if (rows[std::size_t(v) * width + u])
        last = v;
      if (last - v <= r)
        out[std::size_t(v) * width + u] = 1;
    }
  }
  return out;
}

/// Pixels whose truth differs between two frames (validity, or position beyond the tolerance).
std::vector<unsigned char>
changedPixels(const pcl::PointCloud<pcl::PointNormal>& a, const pcl::PointCloud<pcl::PointNormal>& b,
              double tolerance)
{
  std::vector<unsigned char> changed(a.size(), 0);
  const double tolerance_sq = tolerance * tolerance;
  for (std::size_t i = 0; i < a.size(); ++i) {
    const bool va = isValid(a[i]), vb = isValid(b[i]);
    if (va != vb) {
      changed[i] = 1;
    } else if (va) {
      const double dx = double(a[i].x) - b[i].x, dy = double(a[i].y) - b[i].y, dz = double(a[i].z) - b[i].z;
      changed[i] = dx * dx + dy * dy + dz * dz > tolerance_sq ? 1 : 0;
    }
  }
  return changed;
}

/// Everything measured on one frame.
struct FrameAnalysis
{
  FrameMetrics metrics;
  double flat_sq = 0.0, feature_sq = 0.0, flat_angle = 0.0, feature_angle = 0.0;
  /// Signed residual per pixel, NaN unless valid in truth and result.
  std::vector<float> residual;
  std::vector<unsigned char> feature;
};

double
rootMean(double sum, std::size_t count)
{
  return count ? std::sqrt(sum / double(count)) : kNaN;
}

double
mean(double sum, std::size_t count)
{
  return count ? sum / double(count) : kNaN;
}

FrameAnalysis
analyse(const pcl::PointCloud<pcl::PointNormal>& truth, const pcl::PointCloud<pcl::PointXYZ>& result,
        const pcl::PointCloud<pcl::PointXYZ>* input, const EvaluationOptions& options)
{
  checkOrganized(truth, "ground truth");
  checkSameSize(truth, result, "result");
  if (input)
    checkSameSize(truth, *input, "input");
  const int width = int(truth.width), height = int(truth.height);
  const std::size_t n = truth.size();

  FrameAnalysis a;
  a.feature = featureMask(truth, options);
  a.residual.assign(n, std::numeric_limits<float>::quiet_NaN());
  const Grid grid = Grid::fromInterleaved(reinterpret_cast<const float*>(result.points.data()), width, height,
                                          sizeof(pcl::PointXYZ) / sizeof(float));
  const NormalField normals = estimateNormals(grid, options.normal_window, options.viewpoint, options.threads);

  FrameMetrics& m = a.metrics;
  m.has_input = input != nullptr;
  for (std::size_t i = 0; i < n; ++i) {
    const pcl::PointNormal& g = truth[i];
    const bool result_valid = grid.valid[i] != 0;
    if (input) {
      const bool input_valid = isValid((*input)[i]);
      m.points_lost += input_valid && !result_valid;
      m.points_invented += !input_valid && result_valid;
    }
    if (!isValid(g))
      continue;
    ++m.truth_pixels;
    if (!result_valid) {
      ++m.missing_pixels;
      continue;
    }
    const double gn = std::sqrt(double(g.normal_x) * g.normal_x + double(g.normal_y) * g.normal_y +
                                double(g.normal_z) * g.normal_z);
    const double nx = g.normal_x / gn, ny = g.normal_y / gn, nz = g.normal_z / gn;
    const double r = (double(grid.x[i]) - g.x) * nx + (double(grid.y[i]) - g.y) * ny + (double(grid.z[i]) - g.z) * nz;
    a.residual[i] = float(r);
    const bool feature = a.feature[i] != 0;
    (feature ? a.feature_sq : a.flat_sq) += r * r;
    ++(feature ? m.feature_pixels : m.flat_pixels);
    if (std::isfinite(normals.nx[i])) {
      const double c = std::clamp(normals.nx[i] * nx + normals.ny[i] * ny + normals.nz[i] * nz, -1.0, 1.0);
      (feature ? a.feature_angle : a.flat_angle) += std::acos(c) * 180.0 / kPi;
      ++(feature ? m.feature_normal_pixels : m.flat_normal_pixels);
    }
  }
  m.flat_rmse = rootMean(a.flat_sq, m.flat_pixels);
  m.feature_rmse = rootMean(a.feature_sq, m.feature_pixels);
  m.flat_normal_error = mean(a.flat_angle, m.flat_normal_pixels);
  m.feature_normal_error = mean(a.feature_angle, m.feature_normal_pixels);
  return a;
}

std::string
number(double value, int precision = 6)
{
  if (!std::isfinite(value))
    return "null";
  std::ostringstream s;
  s << std::setprecision(precision) << value;
  return s.str();
}

/// Bytes of the well-formed UTF-8 sequence at text[i] (RFC 3629: no overlong forms, no
/// surrogates, nothing above U+10FFFF), 0 if there is none.
std::size_t
utf8Length(const std::string& text, std::size_t i)
{
  const auto byte = [&](std::size_t k) { return i + k < text.size() ? static_cast<unsigned char>(text[i + k]) : 0u; };
  const unsigned lead = byte(0);
  if (lead < 0x80)
    return 1;
  std::size_t length = 0;
  unsigned low = 0x80, high = 0xbf; // the range of the second byte
  if (lead >= 0xc2 && lead <= 0xdf)
    length = 2;
  else if (lead >= 0xe0 && lead <= 0xef) {
    length = 3;
    low = lead == 0xe0 ? 0xa0 : 0x80;
    high = lead == 0xed ? 0x9f : 0xbf;
  } else if (lead >= 0xf0 && lead <= 0xf4) {
    length = 4;
    low = lead == 0xf0 ? 0x90 : 0x80;
    high = lead == 0xf4 ? 0x8f : 0xbf;
  } else {
    return 0;
  }
  if (byte(1) < low || byte(1) > high)
    return 0;
  for (std::size_t k = 2; k < length; ++k)
    if (byte(k) < 0x80 || byte(k) > 0xbf)
      return 0;
  return length;
}

/// A JSON string literal of `text`; bytes that are not UTF-8 (a file name may hold any) become
/// U+FFFD, as the denoise tool's summary writes them, so that the output stays valid JSON.
std::string
jsonString(const std::string& text)
{
  std::string out = "\"";
  for (std::size_t i = 0; i < text.size();) {
    const std::size_t length = utf8Length(text, i);
    if (length == 0) {
      out += "\xef\xbf\xbd";
      ++i;
      continue;
    }
    if (length > 1) {
      out.append(text, i, length);
      i += length;
      continue;
    }
    const char c = text[i++];
    if (c == '"' || c == '\\') {
      out += '\\';
      out += c;
    } else if (static_cast<unsigned char>(c) < 0x20) {
      char buffer[8];
      std::snprintf(buffer, sizeof buffer, "\\u%04x", unsigned(static_cast<unsigned char>(c)));
      out += buffer;
    } else {
      out += c;
    }
  }
  return out + "\"";
}

/// The fields of a FrameMetrics as JSON members (no braces).
std::string
jsonMembers(const FrameMetrics& m)
{
  std::ostringstream s;
  s << "\"flat_rmse_mm\": " << number(m.flat_rmse * 1000.0) << ", \"feature_rmse_mm\": "
    << number(m.feature_rmse * 1000.0) << ", \"flat_normal_error_deg\": " << number(m.flat_normal_error)
    << ", \"feature_normal_error_deg\": " << number(m.feature_normal_error) << ", \"flat_pixels\": " << m.flat_pixels
    << ", \"feature_pixels\": " << m.feature_pixels << ", \"truth_pixels\": " << m.truth_pixels
    << ", \"missing_pixels\": " << m.missing_pixels << ", \"points_lost\": "
    << (m.has_input ? std::to_string(m.points_lost) : "null")
    << ", \"points_invented\": " << (m.has_input ? std::to_string(m.points_invented) : "null");
  return s.str();
}

std::string
cell(double value, int width, int precision)
{
  std::ostringstream s;
  s << std::setw(width);
  if (std::isfinite(value))
    s << std::fixed << std::setprecision(precision) << value;
  else
    s << "-";
  return s.str();
}

} // namespace

void
EvaluationOptions::validate() const
{
  if (feature_radius < 0)
    fail("feature_radius", feature_radius, "must be >= 0 pixels");
  if (!(std::isfinite(depth_jump) && depth_jump > 0.0))
    fail("depth_jump", depth_jump, "must be finite and > 0 (a fraction of the range)");
  if (!(crease_angle > 0.0 && crease_angle < 180.0))
    fail("crease_angle", crease_angle, "must be in (0, 180) degrees");
  if (normal_window < 3 || normal_window % 2 == 0)
    fail("normal_window", normal_window, "must be an odd number of pixels >= 3");
  if (!(std::isfinite(viewpoint[0]) && std::isfinite(viewpoint[1]) && std::isfinite(viewpoint[2])))
    fail("viewpoint", "(non-finite)", "must be finite");
  if (!(std::isfinite(change_tolerance) && change_tolerance >= 0.0))
    fail("change_tolerance", change_tolerance, "must be finite and >= 0 metres");
  if (threads < 0 || threads > FilterParameters::max_threads)
    fail("threads", threads, "must be 0 (all available) ... 1024");
}

std::vector<unsigned char>
featureMask(const pcl::PointCloud<pcl::PointNormal>& truth, const EvaluationOptions& options)
{
  options.validate();
  checkOrganized(truth, "ground truth");
  const int width = int(truth.width), height = int(truth.height);
  const std::size_t n = truth.size();
  std::vector<unsigned char> valid(n, 0);
  std::vector<double> range(n, 0.0);
  std::vector<Eigen::Vector3d> normal(n, Eigen::Vector3d::Zero());
  for (std::size_t i = 0; i < n; ++i) {
    const pcl::PointNormal& p = truth[i];
    if (!isValid(p))
      continue;
    const Eigen::Vector3d nv(p.normal_x, p.normal_y, p.normal_z);
    if (!(nv.norm() > 0.0))
      continue;
    valid[i] = 1;
    normal[i] = nv.normalized();
    range[i] = Eigen::Vector3d(double(p.x) - options.viewpoint[0], double(p.y) - options.viewpoint[1],
                               double(p.z) - options.viewpoint[2])
                   .norm();
  }
  const double cos_crease = std::cos(options.crease_angle * kPi / 180.0);
  std::vector<unsigned char> seed(n, 0);
  for (int v = 0; v < height; ++v)
    for (int u = 0; u < width; ++u) {
      const std::size_t i = std::size_t(v) * width + u;
      if (!valid[i])
        continue;
      for (int dv = -1; dv <= 1 && !seed[i]; ++dv)
        for (int du = -1; du <= 1; ++du) {
          const int nu = u + du, nv = v + dv;
          if ((du == 0 && dv == 0) || nu < 0 || nv < 0 || nu >= width || nv >= height)
            continue;
          const std::size_t j = std::size_t(nv) * width + nu;
          if (!valid[j] || std::abs(range[i] - range[j]) > options.depth_jump * std::min(range[i], range[j]) ||
              normal[i].dot(normal[j]) < cos_crease) {
            seed[i] = 1;
            break;
          }
        }
    }
  std::vector<unsigned char> mask = dilate(seed, width, height, options.feature_radius);
  for (std::size_t i = 0; i < n; ++i)
    mask[i] = mask[i] && valid[i];
  return mask;
}

FrameMetrics
evaluateFrame(const pcl::PointCloud<pcl::PointNormal>& truth, const pcl::PointCloud<pcl::PointXYZ>& result,
              const pcl::PointCloud<pcl::PointXYZ>* input, const EvaluationOptions& options)
{
  options.validate();
  return analyse(truth, result, input, options).metrics;
}

SequenceEvaluator::SequenceEvaluator(const EvaluationOptions& options) : options_(options)
{
  options_.validate();
}

FrameMetrics
SequenceEvaluator::add(const pcl::PointCloud<pcl::PointNormal>& truth, const pcl::PointCloud<pcl::PointXYZ>& result,
                       const pcl::PointCloud<pcl::PointXYZ>* input)
{
  const std::string frame = "frame " + std::to_string(frames_.size());
  if (!frames_.empty() && (int(truth.width) != width_ || int(truth.height) != height_))
    throw std::invalid_argument(frame + ": ground truth is " + std::to_string(truth.width) + " x " +
                                std::to_string(truth.height) + " but the sequence is " + std::to_string(width_) +
                                " x " + std::to_string(height_));
  FrameAnalysis a;
  try {
    a = analyse(truth, result, input, options_);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(frame + ": " + e.what());
  }
  const std::size_t n = truth.size();
  if (frames_.empty()) {
    width_ = int(truth.width);
    height_ = int(truth.height);
    mean_.assign(n, 0.0);
    m2_.assign(n, 0.0);
    static_.assign(n, 1);
    last_changed_.assign(n, 0);
  } else {
    const std::vector<unsigned char> changed = changedPixels(last_truth_, truth, options_.change_tolerance);
    // The previous frame is complete now that its successor is known.
    std::vector<unsigned char> both = last_changed_;
    for (std::size_t i = 0; i < n; ++i)
      both[i] = both[i] || changed[i];
    addMovingEdges(both, sums_.moving_sq, moving_pixels_);
    for (std::size_t i = 0; i < n; ++i)
      if (changed[i])
        static_[i] = 0;
    last_changed_ = changed;
  }
  // Welford update of the per-pixel residual statistics.
  const double count = double(frames_.size() + 1);
  for (std::size_t i = 0; i < n; ++i) {
    if (!static_[i])
      continue;
    if (!std::isfinite(a.residual[i])) {
      static_[i] = 0;
      continue;
    }
    const double r = a.residual[i];
    const double delta = r - mean_[i];
    mean_[i] += delta / count;
    m2_[i] += delta * (r - mean_[i]);
  }
  sums_.flat_sq += a.flat_sq;
  sums_.feature_sq += a.feature_sq;
  sums_.flat_angle += a.flat_angle;
  sums_.feature_angle += a.feature_angle;
  last_truth_ = truth;
  last_residual_ = std::move(a.residual);
  last_feature_ = std::move(a.feature);
  frames_.push_back(a.metrics);
  return a.metrics;
}

void
SequenceEvaluator::addMovingEdges(const std::vector<unsigned char>& changed, double& squares,
                                  std::size_t& pixels) const
{
  const std::vector<unsigned char> near = dilate(changed, width_, height_, options_.feature_radius);
  for (std::size_t i = 0; i < near.size(); ++i)
    if (near[i] && last_feature_[i] && std::isfinite(last_residual_[i])) {
      squares += double(last_residual_[i]) * last_residual_[i];
      ++pixels;
    }
}

SequenceMetrics
SequenceEvaluator::metrics() const
{
  SequenceMetrics s;
  s.frames = frames_;
  FrameMetrics& t = s.total;
  t.has_input = !frames_.empty();
  for (const FrameMetrics& f : frames_) {
    t.flat_pixels += f.flat_pixels;
    t.feature_pixels += f.feature_pixels;
    t.flat_normal_pixels += f.flat_normal_pixels;
    t.feature_normal_pixels += f.feature_normal_pixels;
    t.truth_pixels += f.truth_pixels;
    t.missing_pixels += f.missing_pixels;
    t.points_lost += f.points_lost;
    t.points_invented += f.points_invented;
    t.has_input = t.has_input && f.has_input;
  }
  if (!t.has_input)
    t.points_lost = t.points_invented = 0;
  t.flat_rmse = rootMean(sums_.flat_sq, t.flat_pixels);
  t.feature_rmse = rootMean(sums_.feature_sq, t.feature_pixels);
  t.flat_normal_error = mean(sums_.flat_angle, t.flat_normal_pixels);
  t.feature_normal_error = mean(sums_.feature_angle, t.feature_normal_pixels);

  double moving_sq = sums_.moving_sq;
  std::size_t moving_pixels = moving_pixels_;
  if (!frames_.empty())
    addMovingEdges(last_changed_, moving_sq, moving_pixels);
  s.moving_edge_rmse = rootMean(moving_sq, moving_pixels);
  s.moving_edge_pixels = moving_pixels;

  s.temporal_std = kNaN;
  if (frames_.size() >= 2) {
    double sum = 0.0;
    for (std::size_t i = 0; i < static_.size(); ++i)
      if (static_[i]) {
        sum += std::sqrt(m2_[i] / double(frames_.size() - 1));
        ++s.temporal_pixels;
      }
    s.temporal_std = mean(sum, s.temporal_pixels);
  }
  return s;
}

SequenceMetrics
evaluateSequence(const std::vector<pcl::PointCloud<pcl::PointNormal>>& truth,
                 const std::vector<pcl::PointCloud<pcl::PointXYZ>>& result,
                 const std::vector<pcl::PointCloud<pcl::PointXYZ>>& input, const EvaluationOptions& options)
{
  if (result.size() != truth.size())
    throw std::invalid_argument("the result has " + std::to_string(result.size()) + " frames but the ground truth has " +
                                std::to_string(truth.size()));
  if (!input.empty() && input.size() != truth.size())
    throw std::invalid_argument("the input has " + std::to_string(input.size()) + " frames but the ground truth has " +
                                std::to_string(truth.size()));
  SequenceEvaluator evaluator(options);
  for (std::size_t k = 0; k < truth.size(); ++k)
    evaluator.add(truth[k], result[k], input.empty() ? nullptr : &input[k]);
  return evaluator.metrics();
}

std::string
metricsTableHeader()
{
  std::ostringstream s;
  s << std::left << std::setw(24) << "frame" << std::right << std::setw(14) << "flat mm" << std::setw(14)
    << "feature mm" << std::setw(14) << "flat deg" << std::setw(14) << "feature deg" << std::setw(12) << "lost";
  return s.str();
}

std::string
metricsTableRow(const std::string& label, const FrameMetrics& m)
{
  std::ostringstream s;
  s << std::left << std::setw(24) << label << std::right << cell(m.flat_rmse * 1000.0, 14, 3)
    << cell(m.feature_rmse * 1000.0, 14, 3) << cell(m.flat_normal_error, 14, 2) << cell(m.feature_normal_error, 14, 2)
    << std::setw(12) << (m.has_input ? std::to_string(m.points_lost) : std::string("-"));
  return s.str();
}

std::string
toJson(const FrameMetrics& metrics)
{
  return "{" + jsonMembers(metrics) + "}";
}

std::string
toJson(const SequenceMetrics& metrics, const std::vector<std::string>& frame_names)
{
  std::ostringstream s;
  s << "{\"frame_count\": " << metrics.frames.size() << ", " << jsonMembers(metrics.total)
    << ", \"temporal_std_mm\": " << number(metrics.temporal_std * 1000.0)
    << ", \"temporal_pixels\": " << metrics.temporal_pixels
    << ", \"moving_edge_rmse_mm\": " << number(metrics.moving_edge_rmse * 1000.0)
    << ", \"moving_edge_pixels\": " << metrics.moving_edge_pixels << ", \"frames\": [";
  for (std::size_t k = 0; k < metrics.frames.size(); ++k) {
    s << (k ? ", " : "") << "{";
    if (k < frame_names.size())
      s << "\"name\": " << jsonString(frame_names[k]) << ", ";
    s << jsonMembers(metrics.frames[k]) << "}";
  }
  s << "]}";
  return s.str();
}

namespace
{

/// Running sums of points for an orthogonal least-squares plane fit.
struct PlaneSums
{
  std::size_t n = 0;
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  Eigen::Matrix3d outer = Eigen::Matrix3d::Zero();

  void add(const pcl::PointXYZ& p)
  {
    const Eigen::Vector3d q(p.x, p.y, p.z);
    ++n;
    sum += q;
    outer += q * q.transpose();
  }
  /// Plane through the centroid along the smallest eigenvector of the covariance, and the RMS
  /// orthogonal residual (sqrt of the smallest eigenvalue).
  Eigen::Vector4d fit(double* rms = nullptr) const
  {
    const Eigen::Vector3d c = sum / double(n);
    const Eigen::Matrix3d cov = outer / double(n) - c * c.transpose();
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(cov);
    Eigen::Vector3d normal = solver.eigenvectors().col(0);
    // Deterministic orientation: toward the sensor at the origin.
    if (normal.dot(c) > 0.0)
      normal = -normal;
    if (rms)
      *rms = std::sqrt(std::max(solver.eigenvalues()[0], 0.0));
    return Eigen::Vector4d(normal.x(), normal.y(), normal.z(), -normal.dot(c));
  }
};

/// Whether a plane is seen at more than 75 degrees from its normal (from its centroid): such a
/// plane nearly contains the lines of sight, so a thin strip of pixels at any depths fits it.
bool
grazing(const Eigen::Vector4d& plane, const PlaneSums& sums)
{
  const Eigen::Vector3d c = sums.sum / double(sums.n);
  return std::abs(plane.head<3>().dot(c.normalized())) < std::cos(75.0 * 3.14159265358979323846 / 180.0);
}

double
planeDistance(const Eigen::Vector4d& plane, const pcl::PointXYZ& p)
{
  return plane[0] * p.x + plane[1] * p.y + plane[2] * p.z + plane[3];
}

} // namespace

void
PlanarRegionOptions::validate() const
{
  if (min_region_pixels < 3)
    fail("min_region_pixels", min_region_pixels, "must be at least 3 pixels");
  if (border_band < 0)
    fail("border_band", border_band, "must be >= 0 pixels");
  if (block_size < 3)
    fail("block_size", block_size, "must be at least 3 pixels");
  if (!(std::isfinite(plane_distance) && plane_distance > 0.0))
    fail("plane_distance", plane_distance, "must be finite and > 0 metres");
}

namespace
{

/// A seed block of findPlanarRegions: its top-left pixel and how planar it is (rms / allowed).
struct Seed
{
  double score;
  int u0, v0;
};

/// Seed blocks: fully valid, planar within a third of the tolerance at their mean depth, not
/// grazing; the most planar first.
std::vector<Seed>
findSeedBlocks(const pcl::PointCloud<pcl::PointXYZ>& raw, const PlanarRegionOptions& options)
{
  const int width = int(raw.width), height = int(raw.height), b = options.block_size;
  std::vector<Seed> seeds;
  for (int v0 = 0; v0 + b <= height; v0 += b)
    for (int u0 = 0; u0 + b <= width; u0 += b) {
      PlaneSums sums;
      bool complete = true;
      for (int v = v0; v < v0 + b && complete; ++v)
        for (int u = u0; u < u0 + b; ++u) {
          const pcl::PointXYZ& p = raw[std::size_t(v) * width + u];
          if (!isValid(p)) {
            complete = false;
            break;
          }
          sums.add(p);
        }
      if (!complete)
        continue;
      double rms;
      const Eigen::Vector4d plane = sums.fit(&rms);
      const double z = sums.sum.z() / double(sums.n);
      const double allowed = options.plane_distance * z * z / 3.0;
      if (rms < allowed && !grazing(plane, sums))
        seeds.push_back({rms / allowed, u0, v0});
    }
  std::stable_sort(seeds.begin(), seeds.end(), [](const Seed& a, const Seed& c) { return a.score < c.score; });
  return seeds;
}

/// Grows the regions of findPlanarRegions from their seed blocks, one at a time.
class RegionGrower
{
public:
  RegionGrower(const pcl::PointCloud<pcl::PointXYZ>& raw, const PlanarRegionOptions& options, PlanarRegions& out)
      : raw_(raw), options_(options), out_(out), width_(int(raw.width)), height_(int(raw.height)),
        dropped_(raw.size(), 0)
  {
  }

  /// Grows a region from `seed` if its block is still free; keeps it if it is large and planar
  /// enough, else marks its pixels dropped.
  void grow(const Seed& seed)
  {
    if (!isFree(seed))
      return;
    const int id = int(out_.planes.size());
    PlaneSums sums;
    start(seed, id, sums);
    spread(id, sums);
    // Too small, or not planar after all (grown around a curved surface or over a crease).
    double rms;
    const Eigen::Vector4d plane = sums.fit(&rms);
    const double z = sums.sum.z() / double(sums.n);
    if (members_.size() < std::size_t(options_.min_region_pixels) ||
        rms >= options_.plane_distance * z * z / 3.0 || grazing(plane, sums)) {
      for (std::size_t i : members_) {
        out_.label[i] = -1;
        dropped_[i] = 1;
      }
      return;
    }
    out_.planes.push_back(plane);
    out_.sizes.push_back(members_.size());
  }

private:
  double tolerance(float z) const { return options_.plane_distance * double(z) * double(z); }

  /// Pixels of dropped regions may join later regions, but seed none (a seed inside would grow
  /// the same dropped region again).
  bool isFree(const Seed& seed) const
  {
    const int b = options_.block_size;
    bool free = true;
    for (int v = seed.v0; v < seed.v0 + b && free; ++v)
      for (int u = seed.u0; u < seed.u0 + b; ++u)
        free = free && out_.label[std::size_t(v) * width_ + u] == -1 && !dropped_[std::size_t(v) * width_ + u];
    return free;
  }

  void start(const Seed& seed, int id, PlaneSums& sums)
  {
    const int b = options_.block_size;
    members_.clear();
    queue_.clear();
    for (int v = seed.v0; v < seed.v0 + b; ++v)
      for (int u = seed.u0; u < seed.u0 + b; ++u) {
        const std::size_t i = std::size_t(v) * width_ + u;
        out_.label[i] = id;
        sums.add(raw_[i]);
        members_.push_back(i);
        queue_.push_back(i);
      }
  }

  /// Breadth-first over the 4-neighbours, refitting the plane each time the region doubles.
  void spread(int id, PlaneSums& sums)
  {
    Eigen::Vector4d plane = sums.fit();
    std::size_t refit_at = 2 * sums.n;
    for (std::size_t head = 0; head < queue_.size(); ++head) {
      const int u = int(queue_[head] % std::size_t(width_)), v = int(queue_[head] / std::size_t(width_));
      const int nu[4] = {u - 1, u + 1, u, u}, nv[4] = {v, v, v - 1, v + 1};
      for (int k = 0; k < 4; ++k) {
        if (nu[k] < 0 || nv[k] < 0 || nu[k] >= width_ || nv[k] >= height_)
          continue;
        const std::size_t j = std::size_t(nv[k]) * width_ + nu[k];
        if (!joins(plane, j, nu[k], nv[k]))
          continue;
        out_.label[j] = id;
        sums.add(raw_[j]);
        members_.push_back(j);
        queue_.push_back(j);
        if (sums.n >= refit_at) {
          plane = sums.fit();
          refit_at = 2 * sums.n;
        }
      }
    }
  }

  /// A pixel joins a region only if it is within the tolerance of the plane and the median of
  /// the distances of its valid 3x3 neighbours (at least 4) lies within a third of it: the
  /// median's noise is well below a point's, so regions stop at creases instead of creeping a
  /// noise width beyond them, and it ignores a minority of neighbours beyond a depth edge, so
  /// pixels at edges still join.
  bool joins(const Eigen::Vector4d& plane, std::size_t j, int u, int v) const
  {
    const pcl::PointXYZ& p = raw_[j];
    double median;
    return out_.label[j] == -1 && isValid(p) && !(std::abs(planeDistance(plane, p)) > tolerance(p.z)) &&
           medianDistance(plane, u, v, median) && !(3.0 * std::abs(median) > tolerance(p.z));
  }

  bool medianDistance(const Eigen::Vector4d& plane, int u, int v, double& median) const
  {
    double d[9];
    int n = 0;
    for (int dv = -1; dv <= 1; ++dv)
      for (int du = -1; du <= 1; ++du) {
        if (u + du < 0 || v + dv < 0 || u + du >= width_ || v + dv >= height_)
          continue;
        const pcl::PointXYZ& q = raw_[std::size_t(v + dv) * width_ + u + du];
        if (isValid(q))
          d[n++] = planeDistance(plane, q);
      }
    if (n < 4)
      return false;
    std::nth_element(d, d + n / 2, d + n);
    median = d[n / 2];
    return true;
  }

  const pcl::PointCloud<pcl::PointXYZ>& raw_;
  const PlanarRegionOptions& options_;
  PlanarRegions& out_;
  const int width_, height_;
  std::vector<unsigned char> dropped_;
  std::vector<std::size_t> members_, queue_;
};

/// Border band: region pixels within border_band of a pixel of the image outside the region.
void
markBorderBand(PlanarRegions& out, int border_band)
{
  const std::size_t size = out.label.size();
  for (int id = 0; id < int(out.planes.size()); ++id) {
    std::vector<unsigned char> outside(size);
    for (std::size_t i = 0; i < size; ++i)
      outside[i] = out.label[i] != id;
    const std::vector<unsigned char> near = dilate(outside, out.width, out.height, border_band);
    for (std::size_t i = 0; i < size; ++i)
      if (out.label[i] == id && near[i])
        out.border[i] = 1;
  }
}

} // namespace

PlanarRegions
findPlanarRegions(const pcl::PointCloud<pcl::PointXYZ>& raw, const PlanarRegionOptions& options)
{
  options.validate();
  checkOrganized(raw, "raw frame");
  PlanarRegions out;
  out.width = int(raw.width);
  out.height = int(raw.height);
  out.label.assign(raw.size(), -1);
  out.border.assign(raw.size(), 0);
  RegionGrower grower(raw, options, out);
  for (const Seed& seed : findSeedBlocks(raw, options))
    grower.grow(seed);
  markBorderBand(out, options.border_band);
  return out;
}

PlanarResidual
planarResidual(const PlanarRegions& regions, const pcl::PointCloud<pcl::PointXYZ>& frame)
{
  checkOrganized(frame, "frame");
  if (int(frame.width) != regions.width || int(frame.height) != regions.height)
    throw std::invalid_argument("range_nlm: frame is " + std::to_string(frame.width) + " x " +
                                std::to_string(frame.height) + " but the planar regions are of a " +
                                std::to_string(regions.width) + " x " + std::to_string(regions.height) + " frame");
  PlanarResidual r;
  r.regions = regions.planes.size();
  double interior_sq = 0.0, border_sq = 0.0;
  for (std::size_t i = 0; i < frame.size(); ++i) {
    const int id = regions.label[i];
    if (id < 0)
      continue;
    const pcl::PointXYZ& p = frame[i];
    if (!isValid(p)) {
      ++r.points_lost;
      continue;
    }
    const double e = planeDistance(regions.planes[std::size_t(id)], p);
    if (regions.border[i]) {
      border_sq += e * e;
      ++r.border_pixels;
    } else {
      interior_sq += e * e;
      ++r.interior_pixels;
    }
  }
  r.interior_rms = rootMean(interior_sq, r.interior_pixels);
  r.border_rms = rootMean(border_sq, r.border_pixels);
  return r;
}

void
JitterEvaluator::add(const pcl::PointCloud<pcl::PointXYZ>& frame)
{
  checkOrganized(frame, "frame " + std::to_string(frames_));
  if (frames_ == 0) {
    width_ = int(frame.width);
    height_ = int(frame.height);
    mean_.assign(frame.size(), 0.0);
    m2_.assign(frame.size(), 0.0);
    valid_.assign(frame.size(), 1);
  } else if (int(frame.width) != width_ || int(frame.height) != height_) {
    throw std::invalid_argument("range_nlm: frame " + std::to_string(frames_) + " is " +
                                std::to_string(frame.width) + " x " + std::to_string(frame.height) +
                                " but the sequence is " + std::to_string(width_) + " x " + std::to_string(height_));
  }
  ++frames_;
  for (std::size_t i = 0; i < frame.size(); ++i) {
    const pcl::PointXYZ& p = frame[i];
    if (!isValid(p)) {
      valid_[i] = 0;
      continue;
    }
    const double range = std::sqrt(double(p.x) * p.x + double(p.y) * p.y + double(p.z) * p.z);
    const double delta = range - mean_[i];
    mean_[i] += delta / double(frames_);
    m2_[i] += delta * (range - mean_[i]);
  }
}

TemporalJitter
JitterEvaluator::jitter() const
{
  TemporalJitter j;
  j.frames = frames_;
  std::vector<double> stds;
  if (frames_ >= 2)
    for (std::size_t i = 0; i < valid_.size(); ++i)
      if (valid_[i])
        stds.push_back(std::sqrt(m2_[i] / double(frames_ - 1)));
  j.pixels = stds.size();
  if (stds.empty()) {
    j.mean = j.median = kNaN;
    return j;
  }
  double sum = 0.0;
  for (double x : stds)
    sum += x;
  j.mean = sum / double(stds.size());
  const std::size_t mid = stds.size() / 2;
  std::nth_element(stds.begin(), stds.begin() + std::ptrdiff_t(mid), stds.end());
  j.median = stds[mid];
  if (stds.size() % 2 == 0)
    j.median = 0.5 * (j.median + *std::max_element(stds.begin(), stds.begin() + std::ptrdiff_t(mid)));
  return j;
}

TemporalJitter
temporalJitter(const std::vector<pcl::PointCloud<pcl::PointXYZ>>& frames)
{
  JitterEvaluator evaluator;
  for (const auto& f : frames)
    evaluator.add(f);
  return evaluator.jitter();
}

std::string
toJson(const PlanarResidual& r)
{
  std::ostringstream s;
  s << "{\"regions\": " << r.regions << ", \"interior_rms_mm\": " << number(r.interior_rms * 1000.0)
    << ", \"border_rms_mm\": " << number(r.border_rms * 1000.0) << ", \"interior_pixels\": " << r.interior_pixels
    << ", \"border_pixels\": " << r.border_pixels << ", \"points_lost\": " << r.points_lost << "}";
  return s.str();
}

std::string
toJson(const TemporalJitter& j)
{
  std::ostringstream s;
  s << "{\"frames\": " << j.frames << ", \"pixels\": " << j.pixels << ", \"mean_jitter_mm\": "
    << number(j.mean * 1000.0) << ", \"median_jitter_mm\": " << number(j.median * 1000.0) << "}";
  return s.str();
}

} // namespace range_nlm
