// range_nlm_bench --generalisation: how range_nlm's settings, tuned on other noise, fare on
// spatially correlated noise. Generated scenes with the stereo sensor model over a grid of
// correlation lengths and noise strengths, scored against the truth (flat and feature RMSE) next
// to the best-balanced settings of pcl::FastBilateralFilter and pcl::MovingLeastSquares.
#pragma once

#include <range_nlm/parameters.h>

#include <ostream>
#include <string>
#include <vector>

namespace range_nlm
{
namespace tools
{
namespace generalisation
{

/// A range_nlm setting of the table: its name and its parameters.
struct Setting
{
  std::string name;
  FilterParameters parameters;
};

/// The setting "NAME=VALUE[,NAME=VALUE...]": the recommended parameters (or those of a preset,
/// with an item preset=NAME) with each named field of the parameter registry set, named by `spec`
/// itself. Throws std::invalid_argument naming the item and what is wrong with it (unknown field,
/// bad value, out of range).
Setting
settingFromText(const std::string& spec);

struct Options
{
  /// Frame size. At other sizes than 640x480 the focal lengths are scaled by width / 640, so that
  /// the frame shows the same scene.
  int width = 640, height = 480;
  /// Scenes ("boxes", "steps", "ridges"), each with its own seed (kFirstSeed + its place in the
  /// list of all three, so that a run of some of them scores the same cells).
  std::vector<std::string> scenes{"boxes", "steps", "ridges"};
  /// Factors on the stereo model's disparity noise.
  std::vector<double> noise_scales{0.5, 1.0, 2.0};
  /// Correlation lengths of the stereo noise, pixels.
  std::vector<double> correlation_lengths{0, 1, 2, 3, 4, 6, 8};
  /// range_nlm settings besides the default.
  std::vector<Setting> extra_settings;
  /// Noise scales of the cells in which pcl::MovingLeastSquares runs too. Its radius grid costs
  /// about three times everything else of a VGA cell, so by default only at scale 1 (the stereo
  /// model's own strength); elsewhere "(wins)" is against FastBilateral alone.
  std::vector<double> mls_noise_scales{1.0};
  int threads = 0;
};

/// The quick check: noise scale 1 only, correlation lengths 0, 2, 4 and 8, no MovingLeastSquares.
void
makeQuick(Options& options);

/// Runs the comparison: progress on `log`, the Markdown table and its summary on `report`, one
/// JSON object (every cell and the summary) on `json` if not null.
void
run(const Options& options, std::ostream& log, std::ostream& report, std::ostream* json);

} // namespace generalisation
} // namespace tools
} // namespace range_nlm
