// Flat shading, mean-curvature colouring and before/after images of organized range frames.
#include <range_nlm/io/depth_image.h>
#include <range_nlm/eval/render.h>
#include <range_nlm/parameters.h>

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace range_nlm
{

namespace
{

std::string
numberText(double value)
{
  std::ostringstream s;
  s.precision(8);
  s << value;
  return s.str();
}

void
checkGrid(const Grid& grid, const char* what)
{
  if (grid.width <= 0 || grid.height <= 0 || grid.x.size() != grid.size() || grid.y.size() != grid.size() ||
      grid.z.size() != grid.size() || grid.valid.size() != grid.size())
    throw std::invalid_argument(std::string(what) + ": empty or inconsistent grid (" + std::to_string(grid.width) +
                                " x " + std::to_string(grid.height) + ")");
}

// Moreland's "cool to warm" diverging map, 33 samples at t = k / 32 (sRGB, 8 bit).
constexpr std::uint8_t kCoolWarm[33][3] = {
    {59, 76, 192},   {68, 90, 204},   {77, 104, 215},  {87, 117, 225},  {98, 130, 234},  {108, 142, 241},
    {119, 154, 247}, {130, 165, 251}, {141, 176, 254}, {152, 185, 255}, {163, 194, 255}, {174, 201, 253},
    {184, 208, 249}, {194, 213, 244}, {204, 217, 238}, {213, 219, 230}, {221, 221, 221}, {229, 216, 209},
    {236, 211, 197}, {241, 204, 185}, {245, 196, 173}, {247, 187, 160}, {247, 177, 148}, {247, 166, 135},
    {244, 154, 123}, {241, 141, 111}, {236, 127, 99},  {229, 112, 88},  {222, 96, 77},   {213, 80, 66},
    {203, 62, 56},   {192, 40, 47},   {180, 4, 38}};

} // namespace

RgbImage::RgbImage(int w, int h, const Rgb& fill) : width(w), height(h)
{
  const std::size_t n = static_cast<std::size_t>(std::max(w, 0)) * static_cast<std::size_t>(std::max(h, 0));
  rgb.resize(3 * n);
  for (std::size_t i = 0; i < n; ++i)
    std::copy(fill.begin(), fill.end(), rgb.begin() + 3 * i);
}

Rgb
RgbImage::at(int u, int v) const
{
  assert(u >= 0 && u < width && v >= 0 && v < height);
  const std::size_t i = 3 * (static_cast<std::size_t>(v) * width + u);
  return {rgb[i], rgb[i + 1], rgb[i + 2]};
}

void
RgbImage::set(int u, int v, const Rgb& colour)
{
  assert(u >= 0 && u < width && v >= 0 && v < height);
  const std::size_t i = 3 * (static_cast<std::size_t>(v) * width + u);
  rgb[i] = colour[0];
  rgb[i + 1] = colour[1];
  rgb[i + 2] = colour[2];
}

void
RenderParameters::validate() const
{
  auto window = [](const char* name, int value, int smallest) {
    if (value < smallest || value > 31 || value % 2 == 0)
      throw std::invalid_argument(std::string(name) + " must be odd and in " + std::to_string(smallest) +
                                  " ... 31 pixels, got " + std::to_string(value));
  };
  window("normal_window", normal_window, 3);
  window("curvature_window", curvature_window, 5);
  if (!(std::isfinite(max_depth_step) && max_depth_step > 0.0f))
    throw std::invalid_argument("max_depth_step must be a positive number, got " + numberText(max_depth_step));
  if (!(ambient >= 0.0f && ambient <= 1.0f))
    throw std::invalid_argument("ambient must be in 0 ... 1, got " + numberText(ambient));
  for (float c : viewpoint)
    if (!std::isfinite(c))
      throw std::invalid_argument("viewpoint must be finite, got a coordinate " + numberText(c));
  if (!(std::isfinite(curvature_limit) && curvature_limit >= 0.0f))
    throw std::invalid_argument("curvature_limit must be >= 0 (0 = automatic), got " + numberText(curvature_limit));
  if (!(percentile > 0.0f && percentile <= 100.0f))
    throw std::invalid_argument("percentile must be in (0, 100], got " + numberText(percentile));
  if (gap < 0 || gap > 1000)
    throw std::invalid_argument("gap must be in 0 ... 1000 pixels, got " + std::to_string(gap));
  if (threads < 0 || threads > FilterParameters::max_threads)
    throw std::invalid_argument("threads must be 0 (all) ... 1024, got " + std::to_string(threads));
}

Grid
gridFromCloud(const pcl::PointCloud<pcl::PointXYZ>& cloud)
{
  if (cloud.empty() || static_cast<std::size_t>(cloud.width) * cloud.height != cloud.size())
    throw std::invalid_argument("cloud of " + std::to_string(cloud.size()) + " points with width " +
                                std::to_string(cloud.width) + " and height " + std::to_string(cloud.height) +
                                " is empty or not organized");
  return Grid::fromInterleaved(&cloud[0].x, static_cast<int>(cloud.width), static_cast<int>(cloud.height),
                               sizeof(pcl::PointXYZ) / sizeof(float));
}

std::vector<float>
shadingIntensity(const Grid& grid, const RenderParameters& parameters)
{
  parameters.validate();
  checkGrid(grid, "shading");
  const NormalField normals = estimateNormals(grid, parameters.normal_window, parameters.viewpoint, parameters.threads);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  std::vector<float> intensity(grid.size(), nan);
  const Viewpoint& o = parameters.viewpoint;
  for (std::size_t i = 0; i < grid.size(); ++i) {
    if (!grid.valid[i] || !std::isfinite(normals.nx[i]))
      continue;
    float vx = 0.0f, vy = 0.0f, vz = 1.0f;
    if (parameters.light == Light::view_ray) {
      vx = o[0] - grid.x[i], vy = o[1] - grid.y[i], vz = o[2] - grid.z[i];
      const float length = std::sqrt(vx * vx + vy * vy + vz * vz);
      if (!(length > 0.0f))
        continue;
      vx /= length, vy /= length, vz /= length;
    }
    const float dot = std::fabs(normals.nx[i] * vx + normals.ny[i] * vy + normals.nz[i] * vz);
    intensity[i] = std::min(dot, 1.0f);
  }
  return intensity;
}

std::vector<float>
meanCurvature(const Grid& grid, const RenderParameters& parameters)
{
  parameters.validate();
  checkGrid(grid, "mean curvature");
  const int width = grid.width, height = grid.height;
  const int r = parameters.curvature_window / 2;
  const Viewpoint& o = parameters.viewpoint;
  std::vector<float> rho(grid.size(), 0.0f);
  for (std::size_t i = 0; i < grid.size(); ++i)
    if (grid.valid[i]) {
      const float dx = grid.x[i] - o[0], dy = grid.y[i] - o[1], dz = grid.z[i] - o[2];
      rho[i] = std::sqrt(dx * dx + dy * dy + dz * dz);
    }
  const float nan = std::numeric_limits<float>::quiet_NaN();
  std::vector<float> curvature(grid.size(), nan);
  const float step = parameters.max_depth_step;
  const int threads = threadCount(parameters.threads);
  (void)threads;

#pragma omp parallel for schedule(dynamic, 4) num_threads(threads)
  for (int v = 0; v < height; ++v) {
    // Offsets q_j = p_j - p_i of the neighbours that pass the depth-discontinuity test.
    std::vector<Eigen::Vector3d> offsets;
    offsets.reserve((2 * r + 1) * (2 * r + 1));
    for (int u = 0; u < width; ++u) {
      const int i = v * width + u;
      if (!grid.valid[i])
        continue;
      offsets.clear();
      Eigen::Vector3d sum = Eigen::Vector3d::Zero();
      for (int jv = std::max(0, v - r); jv <= std::min(height - 1, v + r); ++jv)
        for (int ju = std::max(0, u - r); ju <= std::min(width - 1, u + r); ++ju) {
          const int j = jv * width + ju;
          if (!grid.valid[j])
            continue;
          const int ring = std::max(std::abs(ju - u), std::abs(jv - v));
          if (std::fabs(rho[j] - rho[i]) > step * rho[i] * ring)
            continue;
          offsets.emplace_back(double(grid.x[j]) - grid.x[i], double(grid.y[j]) - grid.y[i],
                               double(grid.z[j]) - grid.z[i]);
          sum += offsets.back();
        }
      const std::size_t count = offsets.size();
      if (count < 10)
        continue;
      // Local frame: the least-squares plane of the same neighbours, its normal toward the viewer.
      const Eigen::Vector3d mean = sum / double(count);
      Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
      for (const Eigen::Vector3d& q : offsets)
        covariance += (q - mean) * (q - mean).transpose();
      const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(covariance);
      if (eigen.info() != Eigen::Success)
        continue;
      Eigen::Vector3d n = eigen.eigenvectors().col(0);
      const Eigen::Vector3d to_viewer(double(o[0]) - grid.x[i], double(o[1]) - grid.y[i], double(o[2]) - grid.z[i]);
      if (n.dot(to_viewer) < 0.0)
        n = -n;
      int k = 0; // the axis least aligned with n, made orthogonal to it
      for (int a = 1; a < 3; ++a)
        if (std::fabs(n[a]) < std::fabs(n[k]))
          k = a;
      const Eigen::Vector3d t1 = n.cross(Eigen::Vector3d::Unit(k)).normalized();
      const Eigen::Vector3d t2 = n.cross(t1);
      double spread = 0.0;
      for (const Eigen::Vector3d& q : offsets) {
        const double x = q.dot(t1), y = q.dot(t2);
        spread += x * x + y * y;
      }
      if (!(spread > 0.0))
        continue;
      // Fit in coordinates scaled to unit RMS spread, so the normal equations are well conditioned.
      const double s = std::sqrt(spread / double(count));
      Eigen::Matrix<double, 6, 6> normal_matrix = Eigen::Matrix<double, 6, 6>::Zero();
      Eigen::Matrix<double, 6, 1> rhs = Eigen::Matrix<double, 6, 1>::Zero();
      for (const Eigen::Vector3d& q : offsets) {
        const double x = q.dot(t1) / s, y = q.dot(t2) / s, h = q.dot(n) / s;
        Eigen::Matrix<double, 6, 1> phi;
        phi << x * x, x * y, y * y, x, y, 1.0;
        normal_matrix.selfadjointView<Eigen::Lower>().rankUpdate(phi);
        rhs += h * phi;
      }
      const Eigen::LDLT<Eigen::Matrix<double, 6, 6>> ldlt(normal_matrix.selfadjointView<Eigen::Lower>());
      if (ldlt.info() != Eigen::Success || !ldlt.isPositive() || !(ldlt.rcond() > 1e-10))
        continue;
      const Eigen::Matrix<double, 6, 1> c = ldlt.solve(rhs);
      const double a = c[0], b = c[1], cc = c[2], d = c[3], e = c[4];
      const double g = 1.0 + d * d + e * e;
      const double mean_curvature =
          -((1.0 + e * e) * 2.0 * a - 2.0 * d * e * b + (1.0 + d * d) * 2.0 * cc) / (2.0 * g * std::sqrt(g));
      const double value = mean_curvature / s;
      if (std::isfinite(value))
        curvature[i] = static_cast<float>(value);
    }
  }
  return curvature;
}

float
curvatureLimit(const std::vector<float>& curvature, float percentile)
{
  if (!(percentile > 0.0f && percentile <= 100.0f))
    throw std::invalid_argument("percentile must be in (0, 100], got " + numberText(percentile));
  std::vector<float> magnitude;
  magnitude.reserve(curvature.size());
  for (float h : curvature)
    if (std::isfinite(h))
      magnitude.push_back(std::fabs(h));
  if (magnitude.empty())
    return 1.0f;
  std::sort(magnitude.begin(), magnitude.end());
  const double position = double(percentile) / 100.0 * double(magnitude.size() - 1);
  const std::size_t lower = static_cast<std::size_t>(std::floor(position));
  const std::size_t upper = std::min(lower + 1, magnitude.size() - 1);
  const double fraction = position - double(lower);
  const double value = magnitude[lower] + fraction * (double(magnitude[upper]) - magnitude[lower]);
  return std::max(static_cast<float>(value), std::numeric_limits<float>::min());
}

Rgb
shade(float intensity, float ambient)
{
  const float clamped = std::isfinite(intensity) ? std::clamp(intensity, 0.0f, 1.0f) : 0.0f;
  const float level = 255.0f * (ambient + (1.0f - ambient) * clamped);
  const auto grey = static_cast<std::uint8_t>(std::clamp(std::lround(level), 0L, 255L));
  return {grey, grey, grey};
}

Rgb
coolWarm(float t)
{
  const float clamped = std::isfinite(t) ? std::clamp(t, 0.0f, 1.0f) : 0.5f;
  const float position = clamped * 32.0f;
  const int k = std::min(static_cast<int>(position), 31);
  const float f = position - float(k);
  Rgb colour;
  for (int c = 0; c < 3; ++c)
    colour[c] = static_cast<std::uint8_t>(
        std::lround((1.0f - f) * float(kCoolWarm[k][c]) + f * float(kCoolWarm[k + 1][c])));
  return colour;
}

Rgb
curvatureColour(float curvature, float limit)
{
  assert(limit > 0.0f);
  const float ratio = std::clamp(curvature / limit, -1.0f, 1.0f);
  return coolWarm(0.5f + 0.5f * ratio);
}

RgbImage
renderShaded(const Grid& grid, const RenderParameters& parameters)
{
  const std::vector<float> intensity = shadingIntensity(grid, parameters);
  RgbImage image(grid.width, grid.height, parameters.background);
  for (int v = 0; v < grid.height; ++v)
    for (int u = 0; u < grid.width; ++u) {
      const std::size_t i = static_cast<std::size_t>(v) * grid.width + u;
      if (!grid.valid[i])
        continue;
      image.set(u, v, std::isfinite(intensity[i]) ? shade(intensity[i], parameters.ambient) : parameters.no_estimate);
    }
  return image;
}

namespace
{
void
checkLimit(float limit)
{
  if (!(std::isfinite(limit) && limit > 0.0f))
    throw std::invalid_argument("curvature limit must be a positive number, got " + numberText(limit));
}
} // namespace

RgbImage
curvatureToImage(const Grid& grid, const std::vector<float>& curvature, float limit, const RenderParameters& parameters)
{
  checkLimit(limit);
  checkGrid(grid, "curvature image");
  if (curvature.size() != grid.size())
    throw std::invalid_argument("curvature image: " + std::to_string(curvature.size()) + " values for a grid of " +
                                std::to_string(grid.size()) + " points");
  RgbImage image(grid.width, grid.height, parameters.background);
  for (int v = 0; v < grid.height; ++v)
    for (int u = 0; u < grid.width; ++u) {
      const std::size_t i = static_cast<std::size_t>(v) * grid.width + u;
      if (!grid.valid[i])
        continue;
      image.set(u, v, std::isfinite(curvature[i]) ? curvatureColour(curvature[i], limit) : parameters.no_estimate);
    }
  return image;
}

RgbImage
renderCurvature(const Grid& grid, float limit, const RenderParameters& parameters)
{
  checkLimit(limit);
  const std::vector<float> curvature = meanCurvature(grid, parameters);
  return curvatureToImage(grid, curvature, limit, parameters);
}

RgbImage
sideBySide(const RgbImage& left, const RgbImage& right, int gap, const Rgb& gap_colour)
{
  if (left.height != right.height)
    throw std::invalid_argument("side by side: image heights differ (" + std::to_string(left.height) + " and " +
                                std::to_string(right.height) + ")");
  if (gap < 0)
    throw std::invalid_argument("side by side: gap must be >= 0, got " + std::to_string(gap));
  RgbImage image(left.width + gap + right.width, left.height, gap_colour);
  for (int v = 0; v < left.height; ++v) {
    const std::size_t row = static_cast<std::size_t>(v) * image.width;
    std::copy_n(left.rgb.begin() + 3 * static_cast<std::size_t>(v) * left.width, 3 * left.width,
                image.rgb.begin() + 3 * row);
    std::copy_n(right.rgb.begin() + 3 * static_cast<std::size_t>(v) * right.width, 3 * right.width,
                image.rgb.begin() + 3 * (row + left.width + gap));
  }
  return image;
}

BeforeAfterImage
renderBeforeAfter(const Grid& before, const Grid& after, RenderMode mode, const RenderParameters& parameters,
                  ScaleSource scale_source)
{
  parameters.validate();
  checkGrid(before, "before");
  checkGrid(after, "after");
  if (before.width != after.width || before.height != after.height)
    throw std::invalid_argument("before/after: frames differ in size (" + std::to_string(before.width) + " x " +
                                std::to_string(before.height) + " and " + std::to_string(after.width) + " x " +
                                std::to_string(after.height) + ")");
  BeforeAfterImage result;
  if (mode == RenderMode::shaded) {
    result.image = sideBySide(renderShaded(before, parameters), renderShaded(after, parameters), parameters.gap,
                              parameters.gap_colour);
    return result;
  }
  const std::vector<float> h_before = meanCurvature(before, parameters);
  const std::vector<float> h_after = meanCurvature(after, parameters);
  float limit = parameters.curvature_limit;
  if (!(limit > 0.0f)) {
    if (scale_source == ScaleSource::before) {
      limit = curvatureLimit(h_before, parameters.percentile);
    } else {
      std::vector<float> both(h_before);
      both.insert(both.end(), h_after.begin(), h_after.end());
      limit = curvatureLimit(both, parameters.percentile);
    }
  }
  result.curvature_limit = limit;
  result.image = sideBySide(curvatureToImage(before, h_before, limit, parameters),
                            curvatureToImage(after, h_after, limit, parameters), parameters.gap, parameters.gap_colour);
  return result;
}

pcl::PointCloud<pcl::PointXYZRGB>
colorizeByCurvature(const pcl::PointCloud<pcl::PointXYZ>& cloud, const RenderParameters& parameters, float* used_limit)
{
  parameters.validate();
  const Grid grid = gridFromCloud(cloud);
  const std::vector<float> curvature = meanCurvature(grid, parameters);
  const float limit =
      parameters.curvature_limit > 0.0f ? parameters.curvature_limit : curvatureLimit(curvature, parameters.percentile);
  if (used_limit != nullptr)
    *used_limit = limit;
  pcl::PointCloud<pcl::PointXYZRGB> coloured(cloud.width, cloud.height);
  coloured.header = cloud.header;
  coloured.sensor_origin_ = cloud.sensor_origin_;
  coloured.sensor_orientation_ = cloud.sensor_orientation_;
  const float nan = std::numeric_limits<float>::quiet_NaN();
  bool dense = true;
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    pcl::PointXYZRGB& p = coloured[i];
    if (!grid.valid[i]) {
      p.x = p.y = p.z = nan;
      p.r = p.g = p.b = 0;
      dense = false;
      continue;
    }
    p.x = cloud[i].x, p.y = cloud[i].y, p.z = cloud[i].z;
    const Rgb colour = std::isfinite(curvature[i]) ? curvatureColour(curvature[i], limit) : parameters.no_estimate;
    p.r = colour[0], p.g = colour[1], p.b = colour[2];
  }
  coloured.is_dense = dense;
  return coloured;
}

void
saveRgbPng(const std::string& path, const RgbImage& image)
{
  detail::PngPixels pixels;
  pixels.width = image.width;
  pixels.height = image.height;
  pixels.channels = 3;
  pixels.bit_depth = 8;
  pixels.bytes = image.rgb;
  detail::writePng(path, pixels);
}

} // namespace range_nlm
