/// \file nonlocal_means_filter.h
/// \brief Feature-preserving non-local denoising of one organized range frame (Schall, Belyaev,
/// Seidel 2006, Sec. 3.2; the decisions where the paper is loose are in docs/method.md) as a
/// pcl::Filter.
#pragma once

#include <range_nlm/core/pipeline.h>
#include <range_nlm/grid_adaptor.h>
#include <range_nlm/parameter_setters.h>

#include <pcl/filters/filter.h>

namespace range_nlm
{

/// Moves every valid point of an organized cloud along its normal n_i by
///   h_i = sum_j Phi_d Phi_s ((p_i - p_j) . n_i) / sum_j Phi_d Phi_s,  j in the S x S window,
/// Phi_d = exp(-|p_i - p_j|^2 / d^2), Phi_s = exp(-Sim(i, j) / s^2), Sim the mean squared height
/// difference of the P x P patches of i and j along n_i.
///
/// The pcl::Filter contract: output has the input's width, height, header, sensor pose and every
/// non-xyz field; only x, y, z move. NaN points stay NaN and never contribute. With setIndices
/// only the indexed points move. Filtering in place works. Bad input throws std::invalid_argument
/// with a message that names the problem.
template <typename PointT>
class NonLocalMeansFilter : public pcl::Filter<PointT>, public ParameterSetters
{
public:
  using PointCloud = typename pcl::Filter<PointT>::PointCloud;
  using Ptr = pcl::shared_ptr<NonLocalMeansFilter<PointT>>;
  using ConstPtr = pcl::shared_ptr<const NonLocalMeansFilter<PointT>>;

  NonLocalMeansFilter() { this->filter_name_ = "NonLocalMeansFilter"; }

  /// d used by the last filter() call (first iteration), cloud units.
  float getEstimatedDistanceBandwidth() const { return bandwidths_.distance; }
  /// s used by the last filter() call (first iteration), cloud units.
  float getEstimatedSimilarityBandwidth() const { return bandwidths_.similarity; }
  /// mu_d and sigma_s as estimated by the last filter() call.
  const Bandwidths& getBandwidths() const { return bandwidths_; }
  /// Isolated outliers moved onto their neighbours' surface by the last filter() call
  /// (FilterParameters::outlier_sigmas).
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

  Bandwidths bandwidths_;
  /// Buffers kept between filter() calls (frames of one size reuse them).
  FilterWorkspace workspace_;
};

namespace detail
{
/// Active mask from PCL indices (empty = all points); throws on an out-of-range index.
std::vector<unsigned char>
activeMask(const pcl::Indices* indices, std::size_t size, bool use_indices);
} // namespace detail

} // namespace range_nlm

#ifdef RANGE_NLM_HEADER_ONLY
#include <pcl/impl/pcl_base.hpp> // PCLBase's members, for point types PCL is not compiled for
#include <range_nlm/impl/nonlocal_means_filter.hpp>
#endif
