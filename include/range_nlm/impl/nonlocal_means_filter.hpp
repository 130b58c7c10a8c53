#pragma once

#include <range_nlm/impl/grid_adaptor.hpp>
#include <range_nlm/nonlocal_means_filter.h>

#include <vector>

namespace range_nlm
{

template <typename PointT>
void
NonLocalMeansFilter<PointT>::applyFilter(PointCloud& output)
{
  const PointCloud& input = *this->input_;
  std::vector<Grid>& grids = workspace_.inputs();
  grids.resize(1);
  toGrid(input, grids[0]);
  const std::vector<unsigned char> active =
      detail::activeMask(this->indices_.get(), input.size(), this->use_indices_ && !this->fake_indices_);
  const Viewpoint viewpoint{input.sensor_origin_[0], input.sensor_origin_[1], input.sensor_origin_[2]};
  runFilter({&grids[0]}, 0, parameters_, viewpoint, active, workspace_);
  bandwidths_ = workspace_.result().bandwidths.front();
  fromGrid(input, workspace_.result().output, output);
}

} // namespace range_nlm

/// Explicit instantiation for point type T: PCL_INSTANTIATE(NonLocalMeansFilter, types).
#define PCL_INSTANTIATE_NonLocalMeansFilter(T) template class range_nlm::NonLocalMeansFilter<T>;
