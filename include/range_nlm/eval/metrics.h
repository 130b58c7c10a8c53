/// \file evaluation.h
/// \brief Accuracy of a filtered organized range frame (or sequence) against exact ground truth:
/// point-to-plane RMSE and normal error in flat and feature regions, lost points, temporal
/// flicker of static surfaces and the error at the edges of moving objects.
///
/// Ground truth is a pcl::PointNormal cloud (exact points and unit normals, NaN where invalid),
/// as written by range_nlm_synth. The residual of pixel i is r_i = (p_result - p_truth) . n_truth,
/// metres. Lengths are metres, angles degrees.
#pragma once

#include <range_nlm/core/pipeline.h>

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

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
  /// OpenMP threads of the normal estimation; 0 = all. >= 0.
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

} // namespace range_nlm
