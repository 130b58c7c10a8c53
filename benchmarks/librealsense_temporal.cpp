#include "librealsense_temporal.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>

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
} // namespace

void
TemporalFilterParameters::validate() const
{
  if (!(alpha >= 0.0f && alpha <= 1.0f))
    throw std::invalid_argument("librealsense temporal filter: alpha " + text(alpha) + " is outside [0, 1]");
  if (delta < 1 || delta > 100)
    throw std::invalid_argument("librealsense temporal filter: delta " + std::to_string(delta) +
                                " is outside [1, 100] depth units");
  if (persistence < 0 || persistence > 8)
    throw std::invalid_argument("librealsense temporal filter: persistence " + std::to_string(persistence) +
                                " is outside [0, 8]");
  if (!(depth_unit > 0.0) || !std::isfinite(depth_unit))
    throw std::invalid_argument("librealsense temporal filter: depth_unit " + text(depth_unit) +
                                " must be a positive number of metres");
}

TemporalFilter::TemporalFilter(const TemporalFilterParameters& parameters) : parameters_(parameters)
{
  parameters_.validate();
  persistence_map_ = persistenceMap(parameters_.persistence);
}

std::array<std::uint8_t, 256>
TemporalFilter::persistenceMap(int persistence)
{
  // Credibility of a history byte whose bit 7 is the last frame and bit 0 the oldest.
  std::array<std::uint8_t, 256> map{};
  for (int i = 0; i < 256; ++i) {
    int valid[8]; // valid[k]: the frame k + 1 frames before this one
    for (int k = 0; k < 8; ++k)
      valid[k] = (i >> (7 - k)) & 1;
    auto sum = [&](int n) {
      int s = 0;
      for (int k = 0; k < n; ++k)
        s += valid[k];
      return s;
    };
    bool credible = false;
    switch (persistence) {
    case 1: credible = sum(8) >= 8; break;
    case 2: credible = sum(3) >= 2; break;
    case 3: credible = sum(4) >= 2; break;
    case 4: credible = sum(8) >= 2; break;
    case 5: credible = sum(2) >= 1; break;
    case 6: credible = sum(5) >= 1; break;
    case 7: credible = sum(8) >= 1; break;
    case 8: credible = true; break;
    default: break; // 0: no persistence
    }
    map[i] = credible ? 1 : 0;
  }
  // Rotated for each of the 8 phases of the history ring, as the source's credible_threshold.
  std::array<std::uint8_t, 256> credible{};
  for (int phase = 0; phase < 8; ++phase) {
    const unsigned mask = 1u << phase;
    for (int i = 0; i < 256; ++i) {
      const unsigned char pos = static_cast<unsigned char>((i << (8 - phase)) | (i >> phase));
      if (map[pos])
        credible[i] |= mask;
    }
  }
  return credible;
}

void
TemporalFilter::reset()
{
  std::fill(last_frame_.begin(), last_frame_.end(), 0);
  std::fill(history_.begin(), history_.end(), 0);
  std::fill(ray_x_.begin(), ray_x_.end(), 0.0f);
  std::fill(ray_y_.begin(), ray_y_.end(), 0.0f);
}

void
TemporalFilter::process(std::uint16_t* depth, int width, int height)
{
  if (width <= 0 || height <= 0)
    throw std::invalid_argument("librealsense temporal filter: frame size " + std::to_string(width) + " x " +
                                std::to_string(height) + " is not positive");
  if (width != width_ || height != height_) {
    // A new stream profile: the source reallocates (zeroes) the last frame and the history but
    // keeps counting frames.
    width_ = width;
    height_ = height;
    const std::size_t n = std::size_t(width) * std::size_t(height);
    last_frame_.assign(n, 0);
    history_.assign(n, 0);
    ray_x_.assign(n, 0.0f);
    ray_y_.assign(n, 0.0f);
  }
  const std::size_t pixels = last_frame_.size();
  const std::uint16_t delta_z = static_cast<std::uint16_t>(parameters_.delta);
  const unsigned char mask = static_cast<unsigned char>(1u << cur_frame_index_);
  const float alpha = parameters_.alpha;
  const float one_minus_alpha = 1.f - alpha;
  std::uint16_t* const frame = depth;
  std::uint16_t* const last = last_frame_.data();
  std::uint8_t* const history = history_.data();
  for (std::size_t i = 0; i < pixels; ++i) {
    const std::uint16_t cur_val = frame[i];
    const std::uint16_t prev_val = last[i];
    if (cur_val) {
      if (!prev_val) {
        last[i] = cur_val;
        history[i] = mask;
      } else {
        const std::uint16_t diff = static_cast<std::uint16_t>(std::fabs(cur_val - prev_val));
        if (diff < delta_z) {
          history[i] |= mask;
          const float filtered = alpha * cur_val + one_minus_alpha * prev_val;
          const std::uint16_t result = static_cast<std::uint16_t>(filtered);
          frame[i] = result;
          last[i] = result;
        } else {
          last[i] = cur_val;
          history[i] = mask;
        }
      }
    } else {
      if (prev_val) {
        const unsigned char classification = persistence_map_[history[i]];
        if (classification & mask)
          frame[i] = prev_val;
      }
      history[i] &= static_cast<unsigned char>(~mask);
    }
  }
  cur_frame_index_ = (cur_frame_index_ + 1) % 8;
}

pcl::PointCloud<pcl::PointXYZ>
TemporalFilter::filter(const pcl::PointCloud<pcl::PointXYZ>& in)
{
  if (in.height < 1 || in.width < 1 || std::size_t(in.width) * in.height != in.size())
    throw std::invalid_argument("librealsense temporal filter: the cloud is not organized (" +
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
      throw std::invalid_argument("librealsense temporal filter: " + where() + " has z " + text(p.z) +
                                  " but a non-finite x or y");
    const double units = std::round(double(p.z) / unit);
    if (units < 0.0 || units > 65535.0)
      throw std::invalid_argument("librealsense temporal filter: " + where() + " has z " + text(p.z) + " m, " +
                                  text(units) + " depth units of " + text(unit) +
                                  " m, outside a 16-bit depth image's 0 .. 65535 (choose a larger depth unit)");
    depth[i] = static_cast<std::uint16_t>(units);
  }
  const std::vector<std::uint16_t> before = depth;
  process(depth.data(), int(in.width), int(in.height));

  pcl::PointCloud<pcl::PointXYZ> out = in;
  const float nan = std::numeric_limits<float>::quiet_NaN();
  bool dense = true;
  for (std::size_t i = 0; i < out.size(); ++i) {
    pcl::PointXYZ& q = out[i];
    if (before[i]) {
      // The pixel's ray for later holes.
      ray_x_[i] = in[i].x / in[i].z;
      ray_y_[i] = in[i].y / in[i].z;
    }
    if (!depth[i]) {
      q.x = q.y = q.z = nan;
      dense = false;
      continue;
    }
    // The output image back along the pixel's ray. A point already at its depth (an input
    // quantized to the depth unit, the pixel unchanged) is kept bit for bit.
    const float z = static_cast<float>(double(depth[i]) * unit);
    if (depth[i] == before[i] && in[i].z == z)
      continue;
    q.x = ray_x_[i] * z;
    q.y = ray_y_[i] * z;
    q.z = z;
  }
  out.is_dense = dense;
  return out;
}

} // namespace librealsense
} // namespace tools
} // namespace range_nlm
