#pragma once

#include <range_nlm/impl/nonlocal_means_filter.hpp>
#include <range_nlm/temporal_nonlocal_means_filter.h>

#include <stdexcept>
#include <string>

namespace range_nlm
{

template <typename PointT>
void
TemporalNonLocalMeansFilter<PointT>::setFrames(const std::deque<PointCloudConstPtr>& frames,
                                               std::size_t current)
{
  if (current >= frames.size())
    throw std::invalid_argument("range_nlm: current frame index " + std::to_string(current) +
                                " is outside the " + std::to_string(frames.size()) + " frames given");
  for (std::size_t k = 0; k < frames.size(); ++k) {
    if (!frames[k])
      throw std::invalid_argument("range_nlm: frame " + std::to_string(k) + " is null");
    // Refused here, where the caller hands the frames over, not at the next filter() call.
    const PointCloud& f = *frames[k];
    if (f.points.size() != static_cast<std::size_t>(f.width) * f.height)
      throw std::invalid_argument("range_nlm: frame " + std::to_string(k) + " of the temporal window holds " +
                                  std::to_string(f.points.size()) + " points but declares width x height = " +
                                  std::to_string(f.width) + " x " + std::to_string(f.height));
  }
  frames_ = frames;
  current_ = current;
  this->setInputCloud(frames[current]);
}

template <typename PointT>
void
TemporalNonLocalMeansFilter<PointT>::applyFilter(PointCloud& output)
{
  const PointCloud& input = *this->input_;
  // Without setFrames (or after setInputCloud with another cloud) the window is the input alone.
  const bool own_window = !frames_.empty() && frames_[current_].get() == &input;
  std::vector<Grid>& grids = workspace_.inputs();
  int center = 0;
  if (own_window) {
    grids.resize(frames_.size());
    for (std::size_t k = 0; k < frames_.size(); ++k) {
      const std::string what = "frame " + std::to_string(k) + " of the temporal window";
      toGrid(*frames_[k], grids[k], what.c_str());
    }
    center = static_cast<int>(current_);
  } else {
    grids.resize(1);
    toGrid(input, grids[0]);
  }
  std::vector<const Grid*> pointers;
  for (const Grid& g : grids)
    pointers.push_back(&g);
  const std::vector<unsigned char> active =
      detail::activeMask(this->indices_.get(), input.size(), this->use_indices_ && !this->fake_indices_);
  const Viewpoint viewpoint{input.sensor_origin_[0], input.sensor_origin_[1], input.sensor_origin_[2]};
  runFilter(pointers, center, parameters_, viewpoint, active, workspace_);
  frame_weights_ = workspace_.result().frame_weights;
  frame_bandwidths_ = workspace_.result().bandwidths;
  fromGrid(input, workspace_.result().output, output);
}

} // namespace range_nlm

/// Explicit instantiation for point type T: PCL_INSTANTIATE(TemporalNonLocalMeansFilter, types).
#define PCL_INSTANTIATE_TemporalNonLocalMeansFilter(T) template class range_nlm::TemporalNonLocalMeansFilter<T>;
