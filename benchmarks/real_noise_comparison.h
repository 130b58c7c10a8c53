// range_nlm_bench --real-noise: range_nlm against PCL's smoothers under realistic sensor noise.
// Generated scenes with the sensor noise models (ground truth: flat and feature RMSE), shipped
// real frames (residual of their planar regions, interior and border band) and static real
// sequences (temporal jitter of the frames filtered one by one).
#pragma once

#include <range_nlm/eval/metrics.h>
#include <range_nlm/parameters.h>

#include <ostream>
#include <string>
#include <vector>

namespace range_nlm
{
namespace tools
{
namespace real_noise
{

struct Options
{
  /// Frame size of the generated scenes.
  int width = 640, height = 480;
  /// Noise models of the generated scenes ("stereo", "kinect1", "tof", "kinect").
  std::vector<std::string> models{"stereo", "kinect1", "tof", "kinect"};
  /// Factors on each model's random error.
  std::vector<double> noise_scales{1.0, 2.0};
  /// Seeds of the generated scenes.
  std::vector<std::uint64_t> seeds{1, 2};
  /// Real frames (PCD or depth PNG with an intrinsics.txt beside it) for the planar residual.
  std::vector<std::string> real_frames;
  /// Static real sequences (each a list of frames) for the jitter.
  std::vector<std::vector<std::string>> static_sequences;
  /// If not empty: for each real frame a flat-shaded image raw | range_nlm default |
  /// FastBilateral (sigma_s 5, sigma_r 0.03) is written there as NAME.png.
  std::string render_dir;
  /// Include pcl::MovingLeastSquares (slow) in the generated scenes.
  bool include_mls = true;
  int threads = 0;
  /// If not empty: these settings (name, parameters) are compared instead of variants() (the
  /// default stays first, as the reference of the tally).
  std::vector<std::pair<std::string, FilterParameters>> settings;
};

/// The frames the comparison uses by default: the real frames under `data_dir` (the project's
/// data/) and, if `extra_dir` is not empty, those under it (same layout; e.g. a copy with the
/// RealSense D435 static triples), each found by name; missing ones are skipped.
void
addShippedFrames(Options& options, const std::string& data_dir, const std::string& extra_dir);

/// The static real sequences under `dir` (laid out like data/): the RealSense D435 triples
/// depth-images/realsense-d435-static/pose4/{3,4,5}_realsense_depth.png and pose5/{6,7,8}_...;
/// a pose with a frame missing is skipped, an empty `dir` gives none.
std::vector<std::vector<std::string>>
staticRealSequences(const std::string& dir);

/// The range_nlm settings compared: the default, the paper preset, the default without its
/// dilated passes (contiguous windows) and with a third pass.
std::vector<std::pair<std::string, FilterParameters>>
variants();

/// Runs the comparison; progress on `log`, the Markdown report on `report`, one JSON object on
/// `json` (may be the same stream as nothing else).
void
run(const Options& options, std::ostream& log, std::ostream& report, std::ostream* json);

} // namespace real_noise
} // namespace tools
} // namespace range_nlm
