// Temporal denoising compared with what PCL users do today (a per-pixel running average or
// median over the last frames), on a generated sequence with a moving object
// (range_nlm_bench --temporal).
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
};

struct Row
{
  std::string method;
  SequenceMetrics metrics;
  double milliseconds_per_frame = 0.0;
};

/// Per-pixel running average (or median) of the last `window` frames; a pixel valid in none of
/// them stays NaN.
pcl::PointCloud<pcl::PointXYZ>
runningPixelFilter(const std::vector<pcl::PointCloud<pcl::PointXYZ>::ConstPtr>& last, bool median);

std::vector<Row>
run(const Options& options, std::ostream& log);

void
printTable(const std::vector<Row>& rows, const Options& options, std::ostream& out);
void
printJson(const std::vector<Row>& rows, std::ostream& out);

} // namespace temporal
} // namespace tools
} // namespace range_nlm
