// Temporal denoising compared with what PCL and RealSense users do today (a per-pixel running
// average or median over the last frames, librealsense's temporal filter), on a generated
// sequence with a moving object and on static real sequences (range_nlm_bench
// --temporal-comparison).
#pragma once

#include <range_nlm/eval/metrics.h>

#include <ostream>
#include <string>
#include <vector>

namespace range_nlm
{
namespace tools
{
namespace temporal
{

struct Options
{
  int frames = 12;
  int width = 640, height = 480;
  std::string noise = "kinect";
  double motion_step = 0.01; // metres per frame of the moving box
  int window = 3;            // frames averaged by the running average / median
  std::uint64_t seed = 11;
  int threads = 0;
  /// Static real sequences (each a list of depth PNG or PCD frames) for the jitter table; none
  /// if empty.
  std::vector<std::vector<std::string>> static_sequences;
};

struct Row
{
  std::string method;
  SequenceMetrics metrics;
  double milliseconds_per_frame = 0.0;
};

/// Jitter of one method on one static real sequence.
struct JitterRow
{
  std::string method;
  /// Over the pixels valid in every raw frame (the same pixels for every method); a pixel a
  /// method leaves NaN in some frame is left out.
  TemporalJitter common;
  /// Over the pixels valid in every output frame of the method (holes it fills count).
  TemporalJitter own;
  /// The method's output for the last frame within the last raw frame's planar regions, against
  /// the raw frame's planes, and against planes refitted to the output in each region (the noise
  /// left on a plane, whatever offset the frames averaged in give it): the jitter is steadiness
  /// only (a filter that repeated its first output would have none).
  PlanarResidual last_frame;
  PlanarResidual last_frame_refit;
};

/// The jitter table of one static real sequence.
struct StaticSequenceResult
{
  std::string name;
  std::vector<std::string> frames;
  /// Pixels valid in every raw frame.
  std::size_t raw_pixels = 0;
  /// Planar regions found in the last raw frame.
  std::size_t regions = 0;
  std::vector<JitterRow> rows;
};

/// Per-pixel running average (or median) of the last `window` frames; a pixel valid in none of
/// them stays NaN.
pcl::PointCloud<pcl::PointXYZ>
runningPixelFilter(const std::vector<pcl::PointCloud<pcl::PointXYZ>::ConstPtr>& last, bool median);

std::vector<Row>
run(const Options& options, std::ostream& log);

/// The jitter of each static real sequence of `options`: raw; FastBilateral and range_nlm frame
/// by frame; range_nlm temporal (radius 1: centred, causal, recursive; centred and recursive
/// with the cross-frame bandwidths of a static camera); librealsense's temporal filter (causal;
/// its output for each frame of the sequence, starting cold on the first). Throws
/// std::invalid_argument naming the file if a frame cannot be read or differs in size.
std::vector<StaticSequenceResult>
runStatic(const Options& options, std::ostream& log);

void
printTable(const std::vector<Row>& rows, const std::vector<StaticSequenceResult>& real, const Options& options,
           std::ostream& out);
void
printJson(const std::vector<Row>& rows, const std::vector<StaticSequenceResult>& real, std::ostream& out);

} // namespace temporal
} // namespace tools
} // namespace range_nlm
