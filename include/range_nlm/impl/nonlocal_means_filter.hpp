#pragma once

#include <range_nlm/nonlocal_means_filter.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace range_nlm
{
namespace detail
{

template <typename PointT>
void
toGrid(const pcl::PointCloud<PointT>& cloud, Grid& grid, const char* what)
{
  if (!cloud.isOrganized() || cloud.width == 0 || cloud.height == 0) {
    std::ostringstream msg;
    msg << "range_nlm: the " << what << " is not organized (width " << cloud.width << ", height "
        << cloud.height << "); the filter needs a grid such as a depth-camera frame";
    throw std::invalid_argument(msg.str());
  }
  const std::ptrdiff_t n = static_cast<std::ptrdiff_t>(cloud.size());
  grid.width = static_cast<int>(cloud.width);
  grid.height = static_cast<int>(cloud.height);
  // Every element is written below: resizing to the size it already has costs nothing.
  grid.x.resize(n);
  grid.y.resize(n);
  grid.z.resize(n);
  grid.valid.resize(n);
  // Branch-free on the bits of the coordinates (a branch per point mispredicts wherever valid and
  // invalid points alternate): |x| below the exponent's all-ones pattern is finite, equal to it is
  // infinite. The position of an infinity is looked for only once one was seen.
  const std::uint32_t nan_bits = 0x7fc00000u; // quiet NaN
  const std::uint32_t inf_bits = 0x7f800000u; // |x| of an infinity; finite below
  std::uint32_t infinite = 0;
  float* __restrict gx = grid.x.data();
  float* __restrict gy = grid.y.data();
  float* __restrict gz = grid.z.data();
  unsigned char* __restrict gv = grid.valid.data();
  const PointT* __restrict points = cloud.points.data();
#pragma omp parallel for simd schedule(static) reduction(| : infinite)
  for (std::ptrdiff_t i = 0; i < n; ++i) {
    const PointT& p = points[i];
    std::uint32_t bx, by, bz;
    std::memcpy(&bx, &p.x, sizeof bx);
    std::memcpy(&by, &p.y, sizeof by);
    std::memcpy(&bz, &p.z, sizeof bz);
    const std::uint32_t ax = bx & 0x7fffffffu, ay = by & 0x7fffffffu, az = bz & 0x7fffffffu;
    const std::uint32_t ok = std::uint32_t{ax < inf_bits} & std::uint32_t{ay < inf_bits} & std::uint32_t{az < inf_bits};
    infinite |= std::uint32_t{ax == inf_bits} | std::uint32_t{ay == inf_bits} | std::uint32_t{az == inf_bits};
    const std::uint32_t keep = 0u - ok;
    bx = (bx & keep) | (nan_bits & ~keep);
    by = (by & keep) | (nan_bits & ~keep);
    bz = (bz & keep) | (nan_bits & ~keep);
    std::memcpy(&gx[i], &bx, sizeof bx);
    std::memcpy(&gy[i], &by, sizeof by);
    std::memcpy(&gz[i], &bz, sizeof bz);
    gv[i] = static_cast<unsigned char>(ok);
  }
  std::ptrdiff_t first_infinite = n;
  for (std::ptrdiff_t i = 0; infinite && i < n; ++i)
    if (std::isinf(cloud[i].x) || std::isinf(cloud[i].y) || std::isinf(cloud[i].z)) {
      first_infinite = i;
      break;
    }
  if (first_infinite < n) {
    std::ostringstream msg;
    msg << "range_nlm: the " << what << " has an infinite coordinate at pixel (" << first_infinite % cloud.width
        << ", " << first_infinite / cloud.width << "); invalid points must be NaN";
    throw std::invalid_argument(msg.str());
  }
}

template <typename PointT>
Grid
toGrid(const pcl::PointCloud<PointT>& cloud, const char* what)
{
  Grid grid;
  toGrid(cloud, grid, what);
  return grid;
}

template <typename PointT>
void
fromGrid(const pcl::PointCloud<PointT>& input, const Grid& grid, pcl::PointCloud<PointT>& output)
{
  // An output of the input's size (a filter called again) keeps its storage; its points are
  // copied below, in parallel, together with the new coordinates.
  const bool copy_points = &output != &input && output.size() == input.size();
  if (&output != &input) {
    if (copy_points) {
      output.header = input.header;
      output.width = input.width;
      output.height = input.height;
      output.sensor_origin_ = input.sensor_origin_;
      output.sensor_orientation_ = input.sensor_orientation_;
    } else {
      output = input;
    }
  }
  unsigned dense = 1; // (an integer &, not &&: no branch per point)
  const std::ptrdiff_t n = static_cast<std::ptrdiff_t>(output.size());
#pragma omp parallel for schedule(static) reduction(& : dense)
  for (std::ptrdiff_t i = 0; i < n; ++i) {
    PointT& p = output[i];
    if (copy_points)
      p = input[i];
    p.x = grid.x[i];
    p.y = grid.y[i];
    p.z = grid.z[i];
    dense &= grid.valid[i];
  }
  output.is_dense = dense != 0;
}

} // namespace detail

template <typename PointT>
void
NonLocalMeansFilter<PointT>::applyFilter(PointCloud& output)
{
  const PointCloud& input = *this->input_;
  workspace_.inputs.resize(1);
  detail::toGrid(input, workspace_.inputs[0]);
  const std::vector<unsigned char> active =
      detail::activeMask(this->indices_.get(), input.size(), this->use_indices_ && !this->fake_indices_);
  const Viewpoint viewpoint{input.sensor_origin_[0], input.sensor_origin_[1], input.sensor_origin_[2]};
  runFilter({&workspace_.inputs[0]}, 0, parameters_, viewpoint, active, workspace_);
  bandwidths_ = workspace_.run.bandwidths.front();
  detail::fromGrid(input, workspace_.run.output, output);
}

} // namespace range_nlm
