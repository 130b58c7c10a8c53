// Hole filling compared with what RealSense users run today (librealsense's hole-filling filter,
// its three modes, reimplemented in librealsense_holes.h) and with OpenCV's inpainting (both of
// its methods, opencv_inpaint.h), on generated scenes with holes punched where real depth cameras
// lose data, scored against ground truth (range_nlm_bench --hole-filling). PCL has no depth-image
// inpainting.
#pragma once

#include <range_nlm/eval/synthetic_scene.h>

#include <cstdint>
#include <ostream>
#include <string>
#include <vector>

namespace range_nlm
{
namespace tools
{
namespace holes
{

struct Options
{
  int width = 640, height = 480;
  std::vector<SceneType> scenes = {SceneType::boxes, SceneType::steps};
  std::vector<NoiseModel> noises = {NoiseModel::stereo, NoiseModel::kinect};
  std::uint64_t seed = 1;
  /// range_nlm's FilterParameters::fill_holes.
  int fill_holes = 24;
  /// Blobs punched per frame (dark or shiny patches), radius 1 .. 5 pixels.
  int blobs = 60;
  /// cv::inpaint's inpaintRadius, pixels.
  double inpaint_radius = 3.0;
  /// Baseline of the stereo shadows, metres (a RealSense D435's).
  double baseline = 0.05;
  int threads = 0;
};

/// Why a punched pixel has no measurement.
enum class HoleKind : unsigned char
{
  none = 0,
  /// Beside a foreground's left edge on the background, as wide as the disparity jump: the part
  /// of the background the second camera (to the right) cannot see.
  shadow = 1,
  /// A disc on one surface (the pixels of the disc that see the surface its centre sees): a dark
  /// or shiny patch that returns no signal.
  blob = 2
};

/// Punches the holes into `frame.noisy` (NaN in x, y and z) and returns what each pixel became:
/// shadows beside every depth edge where the depth grows by more than 5 % from a pixel to its
/// left neighbour, over round(fx B (1 / z_near - 1 / z_far)) pixels (at most 40) of the far side,
/// and `blobs` discs at random valid pixels. Deterministic for a given seed.
std::vector<HoleKind>
punchHoles(SyntheticFrame& frame, const SceneOptions& scene, const Options& options, std::uint64_t seed);

/// One method's score on the punched pixels of one frame.
struct Score
{
  std::string method;
  /// Punched pixels (with ground truth) of each kind, and of them those the method filled.
  std::size_t shadows = 0, blobs = 0, shadows_filled = 0, blobs_filled = 0;
  /// RMSE of the filled pixels' depth against the ground truth, millimetres, per kind.
  double shadow_rmse_mm = 0.0, blob_rmse_mm = 0.0;
  /// Filled pixels off their true depth by more than 3 % of it (the other side of an edge, or a
  /// surface bridged across it), share of the filled pixels.
  double gross_share = 0.0;
  /// Median absolute depth error of the filled pixels, millimetres.
  double median_error_mm = 0.0;
  /// RMSE over the pixels every method filled, millimetres.
  double common_rmse_mm = 0.0;
  double milliseconds = 0.0;
};

struct SceneResult
{
  std::string name;
  std::size_t common = 0;
  std::vector<Score> scores;
};

/// The methods on every scene and noise of `options`: range_nlm's default with fill_holes; the
/// default without it followed by each librealsense mode (the D400's chain: hole filling after
/// the spatial and temporal filters) and each OpenCV inpainting method; the same on the raw frame.
std::vector<SceneResult>
run(const Options& options, std::ostream& log);

void
printTable(const std::vector<SceneResult>& results, const Options& options, std::ostream& out);
void
printJson(const std::vector<SceneResult>& results, const Options& options, std::ostream& out);

} // namespace holes
} // namespace tools
} // namespace range_nlm
