// range_nlm_bench --uncertainty-calibration: whether the per-point uncertainty
// (FilterParameters::uncertainty) is calibrated. Generated scenes of every sensor noise model are
// filtered by the default with the uncertainty on (a frame alone, and the middle frame of three);
// the points are binned by their predicted standard deviation (deciles) and, per bin, the RMS of
// the true error (along the direction the points move: the normal alone, the ray in temporal runs)
// is set against the RMS of the prediction, over all points and over flat and feature points
// apart.
#pragma once

#include <range_nlm/parameters.h>

#include <cstdint>
#include <ostream>
#include <string>
#include <vector>

namespace range_nlm
{
namespace tools
{
namespace uncertainty_calibration
{

struct Options
{
  /// Frame size of the generated scenes.
  int width = 640, height = 480;
  /// Noise models (range_nlm_synth --noise).
  std::vector<std::string> models{"kinect", "laser", "stripes", "stereo", "kinect1", "tof"};
  /// Scenes (range_nlm_synth --scene): boxes holds a panel with 3 mm ridges below the noise,
  /// steps does not.
  std::vector<std::string> scenes{"boxes", "steps"};
  /// Seed of the generated scenes.
  std::uint64_t seed = 1;
  /// Also the temporal run (middle frame of three, centred window of radius 1).
  bool temporal = true;
  /// Bins of equal point counts (10: deciles).
  int bins = 10;
  /// If not empty: the reliability diagram (predicted against actual RMS per bin, one colour per
  /// model, log-log) is written there as PNG.
  std::string plot;
  /// The filter's parameters (the uncertainty is switched on).
  FilterParameters parameters = FilterParameters::recommended();
  int threads = 0;
};

/// One bin: the RMS of the predicted standard deviations and of the true errors of its points.
struct Bin
{
  double predicted = 0.0, actual = 0.0;
  std::size_t points = 0;
  /// actual / predicted (NaN for an empty bin or a zero prediction).
  double ratio() const;
};

/// The points (where `selected` is nonzero and both values are finite) sorted by predicted
/// standard deviation and cut into `bins` bins of equal count (the last ones one point larger where
/// the count does not divide); each bin's RMS prediction and RMS error. Fewer points than bins give
/// one point per bin.
std::vector<Bin>
calibrationBins(const std::vector<float>& predicted, const std::vector<double>& error,
                const std::vector<unsigned char>& selected, int bins);

/// The bin whose ratio is farthest from 1 (on a log scale): its ratio. NaN without a bin.
double
worstRatio(const std::vector<Bin>& bins);

/// One model and run: the bins of all, flat and feature points.
struct Row
{
  std::string scene, model, run; // run: "alone" or "temporal"
  std::vector<Bin> all, flat, feature;
};

/// Filters every scene and bins its points; progress on `log`.
std::vector<Row>
run(const Options& options, std::ostream& log);

/// The Markdown table: per model and run, the worst ratio of all, flat and feature points and the
/// ratio of every decile of all points.
void
printTable(const std::vector<Row>& rows, std::ostream& out);
void
printJson(const std::vector<Row>& rows, std::ostream& out);

/// The reliability diagram of the rows' bins of all points as a PNG (see Options::plot).
void
plotReliability(const std::vector<Row>& rows, const std::string& path);

} // namespace uncertainty_calibration
} // namespace tools
} // namespace range_nlm
