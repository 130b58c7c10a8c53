#pragma once

#include <range_nlm/nonlocal_means_filter.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <sstream>
#include <stdexcept>

namespace range_nlm
{
namespace detail
{

template <typename PointT>
Grid
toGrid(const pcl::PointCloud<PointT>& cloud, const char* what)
{
  if (!cloud.isOrganized() || cloud.width == 0 || cloud.height == 0) {
    std::ostringstream msg;
    msg << "range_nlm: the " << what << " is not organized (width " << cloud.width << ", height "
        << cloud.height << "); the filter needs a grid such as a depth-camera frame";
    throw std::invalid_argument(msg.str());
  }
  Grid grid(static_cast<int>(cloud.width), static_cast<int>(cloud.height));
  const std::ptrdiff_t n = static_cast<std::ptrdiff_t>(cloud.size());
  std::ptrdiff_t first_infinite = n;
#pragma omp parallel for schedule(static) reduction(min : first_infinite)
  for (std::ptrdiff_t i = 0; i < n; ++i) {
    const PointT& p = cloud[i];
    if (std::isinf(p.x) || std::isinf(p.y) || std::isinf(p.z))
      first_infinite = std::min(first_infinite, i);
    grid.x[i] = p.x;
    grid.y[i] = p.y;
    grid.z[i] = p.z;
  }
  if (first_infinite < n) {
    std::ostringstream msg;
    msg << "range_nlm: the " << what << " has an infinite coordinate at pixel (" << first_infinite % cloud.width
        << ", " << first_infinite / cloud.width << "); invalid points must be NaN";
    throw std::invalid_argument(msg.str());
  }
  grid.updateValidity();
  return grid;
}

template <typename PointT>
void
fromGrid(const pcl::PointCloud<PointT>& input, const Grid& grid, pcl::PointCloud<PointT>& output)
{
  if (&output != &input)
    output = input;
  bool dense = true;
  const std::ptrdiff_t n = static_cast<std::ptrdiff_t>(output.size());
#pragma omp parallel for schedule(static) reduction(&& : dense)
  for (std::ptrdiff_t i = 0; i < n; ++i) {
    PointT& p = output[i];
    p.x = grid.x[i];
    p.y = grid.y[i];
    p.z = grid.z[i];
    dense = dense && grid.valid[i];
  }
  output.is_dense = dense;
}

} // namespace detail

template <typename PointT>
void
NonLocalMeansFilter<PointT>::applyFilter(PointCloud& output)
{
  const PointCloud& input = *this->input_;
  const Grid grid = detail::toGrid(input);
  const std::vector<unsigned char> active =
      detail::activeMask(this->indices_.get(), input.size(), this->use_indices_ && !this->fake_indices_);
  const Viewpoint viewpoint{input.sensor_origin_[0], input.sensor_origin_[1], input.sensor_origin_[2]};
  const FilterRun run = runFilter({&grid}, 0, parameters_, viewpoint, active);
  bandwidths_ = run.bandwidths.front();
  detail::fromGrid(input, run.output, output);
}

} // namespace range_nlm
