/// \file evaluation.h
/// \brief Accuracy of a filtered organized range frame (or sequence) against exact ground truth:
/// point-to-plane RMSE and normal error in flat and feature regions, lost points, temporal
/// flicker of static surfaces and the error at the edges of moving objects. For real frames,
/// without ground truth: residuals to planes found in the raw frame, and the temporal jitter of
/// a static sequence.
///
/// Ground truth is a pcl::PointNormal cloud (exact points and unit normals, NaN where invalid),
/// as written by range_nlm_synth. The residual of pixel i is r_i = (p_result - p_truth) . n_truth,
/// metres. Lengths are metres, angles degrees.
#pragma once

#include <range_nlm/core/pipeline.h>

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <Eigen/Core>

#include <cstddef>
#include <string>
#include <vector>

namespace range_nlm
{

/// How regions are classified and normals estimated.
struct EvaluationOptions
{
  /// A truth pixel is a feature pixel when it lies within this Chebyshev distance, pixels, of a
  /// discontinuity or crease seed. >= 0, default 3.
  int feature_radius = 3;
  /// Depth discontinuity: a valid truth pixel whose 8-neighbour is invalid (inside the image), or
  /// whose range (distance from `viewpoint`) differs from a valid 8-neighbour's by more than this
  /// fraction of the smaller of the two. > 0, default 0.05 (5 cm at 1 m).
  double depth_jump = 0.05;
  /// Crease: a valid truth pixel whose normal differs from a valid 8-neighbour's by more than
  /// this angle, degrees. In (0, 180), default 20.
  double crease_angle = 20.0;
  /// Side of the grid window of the least-squares normals estimated on the result
  /// (range_nlm::estimateNormals), pixels. Odd, >= 3, default 5.
  int normal_window = 5;
  /// Sensor position; normals are oriented toward it and ranges measured from it.
  Viewpoint viewpoint = {0.0f, 0.0f, 0.0f};
  /// Truth points of consecutive frames closer than this, metres, count as unchanged (static).
  /// >= 0, default 1e-5.
  double change_tolerance = 1e-5;
  /// OpenMP threads of the normal estimation; 0 = all. 0 ... 1024.
  int threads = 0;

  /// Throws std::invalid_argument naming the first invalid option and its value.
  void validate() const;
};

/// Metrics of one frame, or pooled over the frames of a sequence. An RMSE or mean over no pixel
/// is NaN.
struct FrameMetrics
{
  /// Point-to-plane RMSE sqrt(mean r_i^2) over flat pixels valid in truth and result, metres.
  double flat_rmse = 0.0;
  /// The same over feature pixels, metres.
  double feature_rmse = 0.0;
  /// Mean angle between the result's estimated normals and the true normals, flat pixels, degrees.
  double flat_normal_error = 0.0;
  /// The same over feature pixels, degrees.
  double feature_normal_error = 0.0;
  /// Pixels in each RMSE.
  std::size_t flat_pixels = 0;
  std::size_t feature_pixels = 0;
  /// Pixels in each normal error (result normal could be estimated).
  std::size_t flat_normal_pixels = 0;
  std::size_t feature_normal_pixels = 0;
  /// Valid truth pixels, and among them those where the result is NaN.
  std::size_t truth_pixels = 0;
  std::size_t missing_pixels = 0;
  /// Whether the noisy input was given; the two counts below are 0 otherwise.
  bool has_input = false;
  /// Points valid in the input and NaN in the result.
  std::size_t points_lost = 0;
  /// Points NaN in the input and valid in the result (a filter must never invent points).
  std::size_t points_invented = 0;
};

/// Metrics of a sequence.
struct SequenceMetrics
{
  /// Per frame, in order.
  std::vector<FrameMetrics> frames;
  /// Pooled over all frames: RMSEs over all pixels of all frames, counts summed.
  FrameMetrics total;
  /// Mean over static pixels of the per-pixel sample standard deviation over the frames of the
  /// signed residual r_i, metres. Static pixels: valid in truth and result in every frame and
  /// whose truth never changes. NaN with fewer than two frames or no such pixel.
  double temporal_std = 0.0;
  std::size_t temporal_pixels = 0;
  /// Point-to-plane RMSE over moving-edge pixels, metres: feature pixels of frame k within
  /// `feature_radius` of a pixel whose truth differs from frame k-1 or k+1. NaN if none.
  double moving_edge_rmse = 0.0;
  std::size_t moving_edge_pixels = 0;
};

/// Classifies the valid truth pixels: 1 = feature (near a depth discontinuity or crease),
/// 0 = flat or invalid. Throws std::invalid_argument if the cloud is not organized.
std::vector<unsigned char>
featureMask(const pcl::PointCloud<pcl::PointNormal>& truth, const EvaluationOptions& options = {});

/// Metrics of one frame. `input` (the noisy frame the result was computed from) may be null; it
/// is used only for the lost/invented point counts. Throws std::invalid_argument if the clouds
/// are not organized or their sizes differ.
FrameMetrics
evaluateFrame(const pcl::PointCloud<pcl::PointNormal>& truth, const pcl::PointCloud<pcl::PointXYZ>& result,
              const pcl::PointCloud<pcl::PointXYZ>* input = nullptr, const EvaluationOptions& options = {});

/// Accumulates a sequence frame by frame, holding only per-pixel statistics and the last frame
/// (so long sequences need not be in memory at once).
class SequenceEvaluator
{
public:
  /// Throws std::invalid_argument if the options are invalid.
  explicit SequenceEvaluator(const EvaluationOptions& options = {});

  /// Adds the next frame and returns its metrics (as evaluateFrame). All frames must have the
  /// first frame's size; throws std::invalid_argument naming the frame otherwise.
  FrameMetrics add(const pcl::PointCloud<pcl::PointNormal>& truth, const pcl::PointCloud<pcl::PointXYZ>& result,
                   const pcl::PointCloud<pcl::PointXYZ>* input = nullptr);

  /// Metrics of the frames added so far.
  SequenceMetrics metrics() const;

private:
  /// Sums behind the pooled RMSEs and means.
  struct Sums
  {
    double flat_sq = 0.0, feature_sq = 0.0, flat_angle = 0.0, feature_angle = 0.0, moving_sq = 0.0;
  };
  /// Moving-edge contribution of the last frame added, given its change mask.
  void addMovingEdges(const std::vector<unsigned char>& changed, double& squares, std::size_t& pixels) const;

  EvaluationOptions options_;
  int width_ = 0, height_ = 0;
  std::vector<FrameMetrics> frames_;
  Sums sums_;
  std::size_t moving_pixels_ = 0;
  // Welford accumulators of the residual per pixel, and whether the pixel is still static.
  std::vector<double> mean_, m2_;
  std::vector<unsigned char> static_;
  // The last frame: truth, residuals, feature mask and change mask with respect to its predecessor.
  pcl::PointCloud<pcl::PointNormal> last_truth_;
  std::vector<float> last_residual_;
  std::vector<unsigned char> last_feature_, last_changed_;
};

/// Convenience: evaluates whole sequences; `input` may be empty (no lost-point counts) or hold
/// one frame per truth frame. Throws std::invalid_argument on count or size mismatches.
SequenceMetrics
evaluateSequence(const std::vector<pcl::PointCloud<pcl::PointNormal>>& truth,
                 const std::vector<pcl::PointCloud<pcl::PointXYZ>>& result,
                 const std::vector<pcl::PointCloud<pcl::PointXYZ>>& input = {},
                 const EvaluationOptions& options = {});

/// Header of the table printed by metricsTableRow (fixed-width columns, no trailing newline).
std::string
metricsTableHeader();
/// One row: label, flat / feature RMSE in mm, flat / feature normal error in degrees, points
/// lost ("-" without input). NaN prints as "-".
std::string
metricsTableRow(const std::string& label, const FrameMetrics& metrics);
/// One JSON object with the metrics in mm and degrees; NaN becomes null.
std::string
toJson(const FrameMetrics& metrics);
/// One JSON object: the pooled metrics, temporal std and moving-edge RMSE in mm, and "frames":
/// an array of per-frame objects, each with "name" taken from `frame_names` when given.
std::string
toJson(const SequenceMetrics& metrics, const std::vector<std::string>& frame_names = {});

/// How planar regions are found in a raw frame (findPlanarRegions).
struct PlanarRegionOptions
{
  /// Smallest region kept, pixels. >= 3, default 2000.
  int min_region_pixels = 2000;
  /// Width of the border band of a region, pixels: region pixels within this Chebyshev distance
  /// of a pixel (inside the image) outside the region. >= 0, default 3.
  int border_band = 3;
  /// Side of the square blocks whose plane fits seed the regions, pixels. >= 3, default 8.
  int block_size = 8;
  /// Largest distance of a point from its region's plane at a depth of 1 m, metres; scaled by
  /// z^2 (z in metres) because depth-camera error grows with z^2. A seed block's RMS residual
  /// must be below a third of it. > 0, default 0.01.
  double plane_distance = 0.01;

  /// Throws std::invalid_argument naming the first invalid option and its value.
  void validate() const;
};

/// Large planar regions of an organized frame.
struct PlanarRegions
{
  int width = 0, height = 0;
  /// Region of each pixel (index into planes), -1 for none.
  std::vector<int> label;
  /// 1 where a region pixel lies in its region's border band.
  std::vector<unsigned char> border;
  /// Plane of each region, fitted (least squares, orthogonal) on the raw region's points:
  /// n . p + d = 0 with |n| = 1, as (n_x, n_y, n_z, d).
  std::vector<Eigen::Vector4d> planes;
  /// Pixels of each region.
  std::vector<std::size_t> sizes;
};

/// Finds planar regions in a raw frame, deterministically: the valid pixels are split into blocks
/// of block_size^2; each block whose points all are valid and whose plane fit has an RMS
/// residual below plane_distance(z) / 3 is a seed; seeds are taken in order of increasing
/// residual (then scan order), and each grows over 4-connected unlabelled valid pixels within
/// plane_distance(z) of the region's plane (refitted whenever the region has doubled) for which
/// the median distance of their valid 3x3 neighbours (at least 4) is within plane_distance(z) / 3
/// (regions stop at creases, yet pixels beside a depth edge join). Regions
/// with fewer than min_region_pixels pixels, or whose final fit has an RMS residual of a third
/// of the tolerance at their mean depth or more, are dropped (their pixels may join later
/// regions but seed none). Seeds and regions whose plane is seen at more than 75 degrees from its normal are
/// not used: such a plane nearly contains the lines of sight and fits a strip at any depths.
/// Throws std::invalid_argument if the cloud is not organized or the options are invalid.
PlanarRegions
findPlanarRegions(const pcl::PointCloud<pcl::PointXYZ>& raw, const PlanarRegionOptions& options = {});

/// Residuals of a frame to the planes of the raw frame's regions.
struct PlanarResidual
{
  /// Regions the residuals are measured over.
  std::size_t regions = 0;
  /// RMS orthogonal distance to the region's plane over the interior (not border band) pixels
  /// valid in the frame, metres; NaN over none.
  double interior_rms = 0.0;
  /// The same over the border band pixels: bleeding across the regions' borders shows here.
  double border_rms = 0.0;
  std::size_t interior_pixels = 0;
  std::size_t border_pixels = 0;
  /// Region pixels (all valid in the raw frame) that are NaN in the frame.
  std::size_t points_lost = 0;
};

/// Residuals of `frame` (same size as the raw frame the regions came from) to their planes.
/// Throws std::invalid_argument if the sizes differ.
PlanarResidual
planarResidual(const PlanarRegions& regions, const pcl::PointCloud<pcl::PointXYZ>& frame);

/// Temporal jitter of a static sequence: the per-pixel sample standard deviation (n - 1) of the
/// range |p| over the frames, at pixels valid in every frame.
struct TemporalJitter
{
  std::size_t frames = 0;
  std::size_t pixels = 0;
  /// Mean and median over those pixels, metres; NaN with fewer than two frames or no pixel.
  double mean = 0.0;
  double median = 0.0;
};

/// Accumulates the jitter frame by frame (per-pixel Welford sums only).
class JitterEvaluator
{
public:
  /// Adds the next frame; all frames must have the first frame's size (std::invalid_argument
  /// naming the frame otherwise) and be organized.
  void add(const pcl::PointCloud<pcl::PointXYZ>& frame);
  TemporalJitter jitter() const;

private:
  int width_ = 0, height_ = 0;
  std::size_t frames_ = 0;
  std::vector<double> mean_, m2_;
  std::vector<unsigned char> valid_;
};

/// Convenience: the jitter of a whole sequence.
TemporalJitter
temporalJitter(const std::vector<pcl::PointCloud<pcl::PointXYZ>>& frames);

/// JSON object: regions, interior / border RMS in mm, pixel counts, points lost; NaN is null.
std::string
toJson(const PlanarResidual& residual);
/// JSON object: frames, pixels, mean / median jitter in mm; NaN is null.
std::string
toJson(const TemporalJitter& jitter);

} // namespace range_nlm
