#pragma once

#include <range_nlm/impl/grid_adaptor.hpp>
#include <range_nlm/temporal_stream.h>

#include <algorithm>
#include <cmath>
#include <chrono>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace range_nlm
{

template <typename PointT>
TemporalStream<PointT>::TemporalStream(int radius, TemporalWindow window, const FilterParameters& parameters)
    : radius_(radius), causal_(window != TemporalWindow::centred), recursive_(window == TemporalWindow::recursive),
      parameters_(parameters)
{
  if (radius < 0)
    throw std::invalid_argument("range_nlm: temporal radius " + std::to_string(radius) +
                                " is invalid: must be >= 0");
  parameters_.validate();
}

template <typename PointT>
int
TemporalStream<PointT>::historyLength() const
{
  return 2 * radius_ + 1;
}

template <typename PointT>
const Grid&
TemporalStream<PointT>::gridOf(std::size_t t, std::size_t position)
{
  HeldFrame& held = window_[t - first_];
  if (!held.converted) {
    const std::string what = "frame " + std::to_string(position) + " of the temporal window";
    toGrid(*held.cloud, held.grid, what.c_str());
    held.converted = true;
  }
  return held.grid;
}

template <typename PointT>
void
TemporalStream<PointT>::remember(std::size_t t, bool filtered)
{
  if (!recursive_ || radius_ == 0)
    return;
  const HeldFrame& held = window_[t - first_];
  if (filtered) {
    // The output as its cloud reads back: a point with a non-finite coordinate is invalid.
    start_grid_.assignValidated(workspace_.result().output);
  }
  const PointCloud& frame = *held.cloud;
  const Viewpoint viewpoint{frame.sensor_origin_[0], frame.sensor_origin_[1], frame.sensor_origin_[2]};
  // The frame's noise profile as the filter estimated (or carried) it for this frame, if it did,
  // and its analysis of the frame against the history (the run's first frame, where there was one).
  const NoiseProfile* profile = filtered ? &workspace_.currentProfile() : nullptr;
  const FrameOffset* change = filtered && !history_.empty() ? workspace_.frameChange(0) : nullptr;
  updateRunningAverage(history_, held.grid, filtered ? &start_grid_ : nullptr, viewpoint, historyLength(),
                       parameters_.search_window, parameters_.bandwidth_samples, parameters_.seed,
                       parameters_.threads, profile, change);
}

template <typename PointT>
void
TemporalStream<PointT>::RecycleOutput::operator()(PointCloud* cloud) const
{
  std::unique_ptr<PointCloud> owned(cloud);
  if (const std::shared_ptr<OutputPool> held = pool.lock()) {
    std::lock_guard<std::mutex> lock(held->mutex);
    if (held->spare.size() < 2)
      held->spare.push_back(std::move(owned));
  }
}

template <typename PointT>
typename TemporalStream<PointT>::CloudPtr
TemporalStream<PointT>::newOutput()
{
  std::unique_ptr<PointCloud> cloud;
  {
    std::lock_guard<std::mutex> lock(pool_->mutex);
    if (!pool_->spare.empty()) {
      cloud = std::move(pool_->spare.back());
      pool_->spare.pop_back();
    }
  }
  if (!cloud)
    cloud.reset(new PointCloud);
  return CloudPtr(cloud.release(), RecycleOutput{pool_});
}

template <typename PointT>
typename TemporalStream<PointT>::CloudPtr
TemporalStream<PointT>::filterAt(std::size_t t)
{
  last_outputs_.emplace_back();
  const CloudConstPtr& frame = window_[t - first_].cloud;
  if (recursive_ && !frame) { // a gap: the frames after it start a new history
    history_ = RunningAverage();
    return nullptr;
  }
  if (!window_[t - first_].wanted && !recursive_)
    return nullptr;
  const auto start = std::chrono::steady_clock::now();
  auto elapsed = [&start] {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  };
  // Recursive mode: the history (once there is one) and frame t; else frames lo .. hi.
  std::vector<const Grid*> grids;
  std::size_t current = 0;
  if (recursive_) {
    if (!history_.empty())
      grids.push_back(&history_.average);
    current = grids.size();
    grids.push_back(&gridOf(t, current));
  } else {
    const std::size_t lo = std::max(t >= static_cast<std::size_t>(radius_) ? t - radius_ : 0, first_);
    const std::size_t hi = causal_ ? t : std::min(t + radius_, pushed_ - 1);
    for (std::size_t k = lo; k <= hi; ++k)
      if (!window_[k - first_].cloud)
        throw std::invalid_argument("range_nlm: frame " + std::to_string(k) + " is null but frame " +
                                    std::to_string(t) + " is to be filtered with it");
    for (std::size_t k = lo; k <= hi; ++k)
      grids.push_back(&gridOf(k, k - lo));
    current = t - lo;
  }
  const Viewpoint viewpoint{frame->sensor_origin_[0], frame->sensor_origin_[1], frame->sensor_origin_[2]};
  CloudPtr out = newOutput();
  try {
    runFilter(grids, static_cast<int>(current), parameters_, viewpoint, {}, workspace_);
  } catch (const UnfilterableFrame& e) {
    // Passed through unchanged; a live stream must not stop at one covered or dropped frame.
    *out = *frame;
    last_weights_.clear();
    last_bandwidths_ = Bandwidths();
    last_outputs_.back().problem = e.what();
    last_outputs_.back().milliseconds = elapsed();
    remember(t, false);
    return out;
  }
  const FilterRun& run = workspace_.result();
  fromGrid(*frame, run.output, *out);
  last_weights_ = run.frame_weights;
  last_bandwidths_ = run.bandwidths[current];
  last_outputs_.back().bandwidths = last_bandwidths_;
  last_outputs_.back().outliers_moved = run.outliers_moved;
  last_outputs_.back().uncertainty = run.uncertainty;
  last_outputs_.back().filled = run.filled;
  remember(t, true);
  last_outputs_.back().milliseconds = elapsed();
  return out;
}

template <typename PointT>
void
TemporalStream<PointT>::dropBefore(std::size_t t)
{
  while (!window_.empty() && first_ < t) {
    if (window_.front().converted)
      spare_grid_ = std::move(window_.front().grid);
    window_.pop_front();
    ++first_;
  }
}

template <typename PointT>
std::vector<typename TemporalStream<PointT>::CloudPtr>
TemporalStream<PointT>::push(const CloudConstPtr& frame, bool wanted)
{
  if (!frame && wanted)
    throw std::invalid_argument("range_nlm: pushed frame is null");
  if (frame) {
    // Refused before anything changes, so that the caller can skip the frame and go on.
    if (frame->points.size() != static_cast<std::size_t>(frame->width) * frame->height)
      throw std::invalid_argument("range_nlm: frame " + std::to_string(pushed_) + " holds " +
                                  std::to_string(frame->points.size()) + " points but declares width x height = " +
                                  std::to_string(frame->width) + " x " + std::to_string(frame->height));
    // The first infinite coordinate in row order, whichever thread meets it.
    const std::ptrdiff_t n = static_cast<std::ptrdiff_t>(frame->points.size());
    std::ptrdiff_t infinite = n;
#pragma omp parallel for schedule(static) reduction(min : infinite) num_threads(threadCount(parameters_.threads))
    for (std::ptrdiff_t i = 0; i < n; ++i) {
      const PointT& p = frame->points[i];
      if (std::isinf(p.x) || std::isinf(p.y) || std::isinf(p.z))
        infinite = std::min(infinite, i);
    }
    if (infinite < n)
      throw std::invalid_argument("range_nlm: frame " + std::to_string(pushed_) +
                                  " has an infinite coordinate at pixel (" + std::to_string(infinite % frame->width) +
                                  ", " + std::to_string(infinite / frame->width) + "); invalid points must be NaN");
    checkViewpoint({frame->sensor_origin_[0], frame->sensor_origin_[1], frame->sensor_origin_[2]},
                   "the viewpoint (sensor origin) of frame " + std::to_string(pushed_));
    if (width_ == 0 && height_ == 0) {
      width_ = frame->width;
      height_ = frame->height;
    } else if (frame->width != width_ || frame->height != height_) {
      throw std::invalid_argument("range_nlm: frame " + std::to_string(pushed_) + " is " +
                                  std::to_string(frame->width) + " x " + std::to_string(frame->height) +
                                  " but the sequence is " + std::to_string(width_) + " x " +
                                  std::to_string(height_));
    }
  }
  window_.push_back({frame, wanted, false, std::move(spare_grid_)});
  spare_grid_ = Grid();
  last_outputs_.clear();
  ++pushed_;
  std::vector<CloudPtr> ready;
  // Frame t is ready once t + r (causal: t) has been pushed.
  const std::size_t lag = causal_ ? 0 : static_cast<std::size_t>(radius_);
  while (emitted_ + lag < pushed_) {
    ready.push_back(filterAt(emitted_));
    ++emitted_;
    const std::size_t keep_from =
        recursive_ ? emitted_ : emitted_ >= static_cast<std::size_t>(radius_) ? emitted_ - radius_ : 0;
    dropBefore(keep_from);
  }
  return ready;
}

template <typename PointT>
std::vector<typename TemporalStream<PointT>::CloudPtr>
TemporalStream<PointT>::flush()
{
  last_outputs_.clear();
  std::vector<CloudPtr> ready;
  while (emitted_ < pushed_) {
    ready.push_back(filterAt(emitted_));
    ++emitted_;
    const std::size_t keep_from =
        recursive_ ? emitted_ : emitted_ >= static_cast<std::size_t>(radius_) ? emitted_ - radius_ : 0;
    dropBefore(keep_from);
  }
  window_.clear();
  history_ = RunningAverage();
  first_ = pushed_;
  return ready;
}

template <typename PointT>
std::vector<typename pcl::PointCloud<PointT>::Ptr>
filterSequence(const std::vector<typename pcl::PointCloud<PointT>::ConstPtr>& frames, int radius,
               bool causal, const FilterParameters& parameters)
{
  return filterSequence<PointT>(frames, radius, causal ? TemporalWindow::causal : TemporalWindow::centred,
                                parameters);
}

template <typename PointT>
std::vector<typename pcl::PointCloud<PointT>::Ptr>
filterSequence(const std::vector<typename pcl::PointCloud<PointT>::ConstPtr>& frames, int radius,
               TemporalWindow window, const FilterParameters& parameters)
{
  TemporalStream<PointT> stream(radius, window, parameters);
  std::vector<typename pcl::PointCloud<PointT>::Ptr> out;
  for (const auto& frame : frames)
    for (auto& f : stream.push(frame))
      out.push_back(f);
  for (auto& f : stream.flush())
    out.push_back(f);
  return out;
}

} // namespace range_nlm

/// Explicit instantiation for point type T: PCL_INSTANTIATE(TemporalStream, types) and
/// PCL_INSTANTIATE(filterSequence, types).
#define PCL_INSTANTIATE_TemporalStream(T) template class range_nlm::TemporalStream<T>;
#define PCL_INSTANTIATE_filterSequence(T)                                                                         \
  template std::vector<pcl::PointCloud<T>::Ptr> range_nlm::filterSequence<T>(                                    \
      const std::vector<pcl::PointCloud<T>::ConstPtr>&, int, bool, const range_nlm::FilterParameters&);         \
  template std::vector<pcl::PointCloud<T>::Ptr> range_nlm::filterSequence<T>(                                    \
      const std::vector<pcl::PointCloud<T>::ConstPtr>&, int, range_nlm::TemporalWindow,                          \
      const range_nlm::FilterParameters&);
