#pragma once

#include <range_nlm/grid_adaptor.h>

#include <cstddef>
#include <sstream>
#include <stdexcept>

namespace range_nlm
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
  if (cloud.points.size() != static_cast<std::size_t>(cloud.width) * cloud.height) {
    std::ostringstream msg;
    msg << "range_nlm: the " << what << " holds " << cloud.points.size() << " points but declares width x height = "
        << cloud.width << " x " << cloud.height;
    throw std::invalid_argument(msg.str());
  }
  // The points' x, y, z are the first three floats of every PCL point type that has them.
  const std::ptrdiff_t first_infinite = grid.assignInterleaved(
      &cloud.points[0].x, static_cast<int>(cloud.width), static_cast<int>(cloud.height), sizeof(PointT) / sizeof(float));
  if (first_infinite >= 0) {
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

} // namespace range_nlm

/// Explicit instantiation of the grid adaptor for point type T: PCL_INSTANTIATE(GridAdaptor, types).
#define PCL_INSTANTIATE_GridAdaptor(T)                                                                           \
  template range_nlm::Grid range_nlm::toGrid<T>(const pcl::PointCloud<T>&, const char*);                       \
  template void range_nlm::toGrid<T>(const pcl::PointCloud<T>&, range_nlm::Grid&, const char*);                \
  template void range_nlm::fromGrid<T>(const pcl::PointCloud<T>&, const range_nlm::Grid&, pcl::PointCloud<T>&);
