// range_nlm_bench --accuracy-time: accuracy against time per frame of range_nlm's presets and of
// PCL's FastBilateralFilter and MovingLeastSquares on one generated frame (flat RMSE against its
// ground truth) and one real frame (residual to the planes of its planar regions), each method
// timed on the same machine in the same run. scripts/plot_accuracy_time.py draws its JSON.
#pragma once

#include <cstdint>
#include <ostream>
#include <string>
#include <vector>

namespace range_nlm
{
namespace tools
{
namespace accuracy_time
{

struct Options
{
  /// The generated frame: the boxes scene at this size, with this noise model
  /// (range_nlm_synth --noise) and seed.
  int width = 640, height = 480;
  std::string model = "stereo";
  std::uint64_t seed = 1;
  /// The real frame (organized PCD, or a depth PNG with an intrinsics.txt beside it); empty: none.
  std::string real_frame;
  /// Timed runs per method and frame, each after one untimed warm-up run; the median is reported.
  int runs = 3;
  /// Threads of range_nlm and MovingLeastSquares (0 = all cores); PCL's FastBilateralFilter
  /// has one.
  int threads = 0;
};

/// One method on one frame.
struct Row
{
  std::string frame;  // "generated: stereo, seed 1" or the real frame's file name
  std::string metric; // "flat RMSE against ground truth" or "residual to planes, interior"
  std::string family; // "range_nlm", "FastBilateral", "MLS"
  std::string setting;
  double accuracy_mm = 0.0; // the metric, millimetres (smaller is better)
  double median_ms = 0.0;   // wall time of one call, median of the timed runs
  std::vector<double> samples_ms;
  std::size_t points_lost = 0; // valid input points the method made invalid
};

/// Throws std::invalid_argument naming the field if `options` cannot run (runs < 1, a size below
/// 16 x 16, an unknown noise model, a real frame that does not exist).
void
validate(const Options& options);

/// Runs every method on each frame; progress on `log`. Per frame, a first row of family "input"
/// (setting "raw", no time) holds the metric of the unfiltered frame.
std::vector<Row>
run(const Options& options, std::ostream& log);

void
printTable(const std::vector<Row>& rows, const Options& options, std::ostream& out);
/// One JSON object: {"tool", "accuracy_time": {"runs", "threads", "rows": [{frame, metric,
/// family, setting, accuracy_mm, median_ms, samples_ms, points_lost}, ...]}}.
void
printJson(const std::vector<Row>& rows, const Options& options, std::ostream& out);

} // namespace accuracy_time
} // namespace tools
} // namespace range_nlm
