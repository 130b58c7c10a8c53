/// \file grid_adaptor.h
/// \brief Conversion between organized PCL clouds and the Grid the numeric kernel works on.
#pragma once

#include <range_nlm/core/grid.h>

#include <pcl/point_cloud.h>

namespace range_nlm
{

/// Copies x, y, z of an organized cloud into a Grid (point (u, v) at index v * width + u). A point
/// with a NaN coordinate becomes invalid, NaN in all of x, y and z. Throws std::invalid_argument,
/// naming `what` and the problem, if the cloud is not organized (height 1 or a size of 0), its
/// point count is not width x height, or it holds an infinite coordinate (an infinity is not an
/// invalid marker). PointT: any PCL point type whose first three floats are x, y, z.
template <typename PointT>
Grid
toGrid(const pcl::PointCloud<PointT>& cloud, const char* what = "input cloud");
/// The same into `grid`, reusing its storage when it has the cloud's size.
template <typename PointT>
void
toGrid(const pcl::PointCloud<PointT>& cloud, Grid& grid, const char* what = "input cloud");

/// `output` becomes `input` (header, sensor pose, size and every field) with x, y, z taken from
/// `grid`, which must have the input's size; is_dense is recomputed from the grid's valid points.
/// `output` may be `input` (in place); an output of the input's size keeps its storage.
template <typename PointT>
void
fromGrid(const pcl::PointCloud<PointT>& input, const Grid& grid, pcl::PointCloud<PointT>& output);

} // namespace range_nlm

#ifdef RANGE_NLM_HEADER_ONLY
#include <range_nlm/impl/grid_adaptor.hpp>
#endif
