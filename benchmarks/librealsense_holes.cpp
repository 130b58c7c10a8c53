#include "librealsense_holes.h"

#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace range_nlm
{
namespace tools
{
namespace librealsense
{

namespace
{
std::string
text(double v)
{
  std::ostringstream s;
  s << v;
  return s.str();
}

/// holes_fill_left: every row from its second column on.
void
fillFromLeft(std::uint16_t* p, int width, int height)
{
  for (int j = 0; j < height; ++j) {
    ++p;
    for (int i = 1; i < width; ++i) {
      if (!*p)
        *p = *(p - 1);
      ++p;
    }
  }
}

/// holes_fill_farest: rows 1 .. height - 2, columns 1 .. width - 1; the largest of the upper,
/// upper-left, left, lower-left and lower neighbours.
void
fillFarthest(std::uint16_t* image, int width, int height)
{
  std::uint16_t* p = image + width;
  for (int j = 1; j < height - 1; ++j) {
    ++p;
    for (int i = 1; i < width; ++i) {
      if (!*p) {
        std::uint16_t tmp = *(p - width);
        for (const std::uint16_t* q : {p - width - 1, p - 1, p + width - 1, p + width})
          if (*q > tmp)
            tmp = *q;
        *p = tmp;
      }
      ++p;
    }
  }
}

/// holes_fill_nearest: the same pixels and neighbours; starts from the upper neighbour (a hole
/// there starts it at 0) and takes any smaller one of the others that is not a hole.
void
fillNearest(std::uint16_t* image, int width, int height)
{
  std::uint16_t* p = image + width;
  for (int j = 1; j < height - 1; ++j) {
    ++p;
    for (int i = 1; i < width; ++i) {
      if (!*p) {
        std::uint16_t tmp = *(p - width);
        for (const std::uint16_t* q : {p - width - 1, p - 1, p + width - 1, p + width})
          if (*q && *q < tmp)
            tmp = *q;
        *p = tmp;
      }
      ++p;
    }
  }
}
} // namespace

const char*
toString(HoleFillingMode mode)
{
  switch (mode) {
  case HoleFillingMode::fill_from_left:
    return "Fill from Left";
  case HoleFillingMode::farthest_from_around:
    return "Farest from around";
  case HoleFillingMode::nearest_from_around:
    return "Nearest from around";
  }
  return "?";
}

void
HoleFillingParameters::validate() const
{
  const int m = static_cast<int>(mode);
  if (m < 0 || m > 2)
    throw std::invalid_argument("librealsense hole-filling filter: mode " + std::to_string(m) +
                                " is outside 0 (fill from left) ... 2 (nearest from around)");
  if (!(depth_unit > 0.0) || !std::isfinite(depth_unit))
    throw std::invalid_argument("librealsense hole-filling filter: depth_unit " + text(depth_unit) +
                                " must be a positive number of metres");
}

HoleFillingFilter::HoleFillingFilter(const HoleFillingParameters& parameters) : parameters_(parameters)
{
  parameters_.validate();
}

void
HoleFillingFilter::process(std::uint16_t* depth, int width, int height) const
{
  if (width < 1 || height < 1)
    throw std::invalid_argument("librealsense hole-filling filter: the image is " + std::to_string(width) + " x " +
                                std::to_string(height) + " pixels");
  switch (parameters_.mode) {
  case HoleFillingMode::fill_from_left:
    fillFromLeft(depth, width, height);
    break;
  case HoleFillingMode::farthest_from_around:
    fillFarthest(depth, width, height);
    break;
  case HoleFillingMode::nearest_from_around:
    fillNearest(depth, width, height);
    break;
  }
}

pcl::PointCloud<pcl::PointXYZ>
HoleFillingFilter::filter(const pcl::PointCloud<pcl::PointXYZ>& in, const PinholeRays& rays) const
{
  if (in.height < 1 || in.width < 1 || std::size_t(in.width) * in.height != in.size())
    throw std::invalid_argument("librealsense hole-filling filter: the cloud is not organized (" +
                                std::to_string(in.width) + " x " + std::to_string(in.height) + ", " +
                                std::to_string(in.size()) + " points)");
  const double unit = parameters_.depth_unit;
  std::vector<std::uint16_t> depth(in.size(), 0);
  for (std::size_t i = 0; i < in.size(); ++i) {
    const pcl::PointXYZ& p = in[i];
    if (!std::isfinite(p.z))
      continue;
    auto where = [&] {
      return "pixel (" + std::to_string(i % in.width) + ", " + std::to_string(i / in.width) + ")";
    };
    if (!std::isfinite(p.x) || !std::isfinite(p.y))
      throw std::invalid_argument("librealsense hole-filling filter: " + where() + " has z " + text(p.z) +
                                  " but a non-finite x or y");
    const double units = std::round(double(p.z) / unit);
    if (units < 0.0 || units > 65535.0)
      throw std::invalid_argument("librealsense hole-filling filter: " + where() + " has z " + text(p.z) + " m, " +
                                  text(units) + " depth units of " + text(unit) +
                                  " m, outside a 16-bit depth image's 0 .. 65535 (choose a larger depth unit)");
    depth[i] = static_cast<std::uint16_t>(units);
  }
  const std::vector<std::uint16_t> before = depth;
  process(depth.data(), int(in.width), int(in.height));

  pcl::PointCloud<pcl::PointXYZ> out = in;
  bool dense = true;
  for (std::size_t i = 0; i < out.size(); ++i) {
    pcl::PointXYZ& q = out[i];
    if (before[i])
      continue; // measured: kept as it was (the filter never changes a non-zero depth)
    const int u = static_cast<int>(i % in.width), v = static_cast<int>(i / in.width);
    dense &= rays.place(q, u, v, double(depth[i]) * unit);
  }
  out.is_dense = dense;
  return out;
}

bool
PinholeRays::place(pcl::PointXYZ& q, int u, int v, double z) const
{
  if (!(z > 0.0)) {
    q.x = q.y = q.z = std::numeric_limits<float>::quiet_NaN();
    return false;
  }
  q.x = static_cast<float>((u - cx) / fx * z);
  q.y = static_cast<float>((v - cy) / fy * z);
  q.z = static_cast<float>(z);
  return true;
}

} // namespace librealsense
} // namespace tools
} // namespace range_nlm
