/// \file temporal_nonlocal_means_filter.h
/// \brief Non-local denoising of one frame of a range sequence using its neighbouring frames
/// (Schall, Belyaev, Seidel 2006, Sec. 3.3) as a pcl::Filter.
#pragma once

#include <range_nlm/core/pipeline.h>
#include <range_nlm/parameter_setters.h>

#include <pcl/filters/filter.h>

#include <deque>

namespace range_nlm
{

/// Filters the current frame c of a window of frames k = c - a .. c + b of one size:
///   p'_i = p_i - n_i * sum_k Psi_k sum_{j in N_k} Phi_dk Phi_sk ((p_i - p_j) . n_i)
///                    / sum_k Psi_k sum_{j in N_k} Phi_dk Phi_sk
/// with Psi_k = Psi_dk Psi_sk, Psi_dk = (1/2)^|k - c|, Psi_sk = exp(-s_k^2 / max_k s_k^2), and the
/// similarity of patches of frame k with the patch of p_i in frame c projected on n_i of frame c.
/// Per-frame bandwidths d_k, s_k are estimated from each frame. A window of one frame gives the
/// static NonLocalMeansFilter result. The input cloud is the current frame.
template <typename PointT>
class TemporalNonLocalMeansFilter : public pcl::Filter<PointT>, public ParameterSetters
{
public:
  using PointCloud = typename pcl::Filter<PointT>::PointCloud;
  using PointCloudConstPtr = typename PointCloud::ConstPtr;
  using Ptr = pcl::shared_ptr<TemporalNonLocalMeansFilter<PointT>>;

  TemporalNonLocalMeansFilter() { this->filter_name_ = "TemporalNonLocalMeansFilter"; }

  /// The frames in time order and the index of the current one, which also becomes the input
  /// cloud. Throws std::invalid_argument if `current` is not an index of `frames`, a frame is
  /// null, or a frame's width x height is not its number of points.
  void setFrames(const std::deque<PointCloudConstPtr>& frames, std::size_t current);
  const std::deque<PointCloudConstPtr>& getFrames() const { return frames_; }
  /// Lets go of the frames and the input cloud (the filter's buffers stay for the next call).
  void clearFrames()
  {
    frames_.clear();
    current_ = 0;
    this->input_.reset();
  }
  std::size_t getCurrentFrameIndex() const { return current_; }

  /// Psi_k = Psi_dk * Psi_sk per frame of the last filter() call (0 for an all-NaN neighbour).
  const std::vector<float>& getFrameWeights() const { return frame_weights_; }
  /// Bandwidths per frame of the last filter() call.
  const std::vector<Bandwidths>& getFrameBandwidths() const { return frame_bandwidths_; }
  /// Isolated outliers of the current frame moved onto their neighbours' surface by the last
  /// filter() call (FilterParameters::outlier_sigmas).
  std::size_t getOutliersMoved() const { return workspace_.result().outliers_moved; }
  /// With FilterParameters::uncertainty (setEstimateUncertainty): the last filter() call's
  /// per-point uncertainty, organized like the output (index v * width + u): the standard
  /// deviation of each output point's error along its direction of movement, cloud units (metres),
  /// NaN for invalid points (docs/method.md, "Per-point uncertainty"). Empty when off.
  const std::vector<float>& getUncertainty() const { return workspace_.result().uncertainty; }
  /// Indices of the points the last filter() call filled (FilterParameters::fill_holes): they
  /// were invalid in the input and were given a range by the hole filling, not measured. Empty
  /// when the hole filling is off.
  pcl::Indices getFilledIndices() const
  {
    pcl::Indices indices;
    const std::vector<unsigned char>& filled = workspace_.result().filled;
    for (std::size_t i = 0; i < filled.size(); ++i)
      if (filled[i])
        indices.push_back(static_cast<pcl::index_t>(i));
    return indices;
  }

  /// Told where each phase of every filter() call begins and ends (see StageObserver, e.g. for
  /// progress or timing); null for none. Not owned.
  void setStageObserver(StageObserver* observer) { workspace_.setStageObserver(observer); }

protected:
  void applyFilter(PointCloud& output) override;

  std::deque<PointCloudConstPtr> frames_;
  std::size_t current_ = 0;
  std::vector<float> frame_weights_;
  std::vector<Bandwidths> frame_bandwidths_;
  /// Buffers kept between filter() calls (frames of one size reuse them).
  FilterWorkspace workspace_;
};

} // namespace range_nlm

#ifdef RANGE_NLM_HEADER_ONLY
#include <pcl/impl/pcl_base.hpp> // PCLBase's members, for point types PCL is not compiled for
#include <range_nlm/impl/temporal_nonlocal_means_filter.hpp>
#endif
