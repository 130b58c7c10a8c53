// Quality comparison of range_nlm against the PCL filters a user would pick instead, on
// generated scenes with exact ground truth (range_nlm_bench --quality).
#pragma once

#include <range_nlm/eval/metrics.h>
#include <range_nlm/parameters.h>

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <functional>
#include <ostream>
#include <string>
#include <vector>

namespace range_nlm
{
namespace tools
{
namespace quality
{

/// PCL peers, with the invalid-pixel rule enforced afterwards (NaN in, NaN out).
pcl::PointCloud<pcl::PointXYZ>
fastBilateral(const pcl::PointCloud<pcl::PointXYZ>& in, float sigma_s, float sigma_r);
/// MovingLeastSquares (order 2, KdTree radius search over the finite points); each input point
/// is replaced by its projection, points MLS drops become NaN. `threads` 0 = all cores; the
/// result does not depend on it.
pcl::PointCloud<pcl::PointXYZ>
movingLeastSquares(const pcl::PointCloud<pcl::PointXYZ>& in, double radius, unsigned threads = 1);

/// A method with a name and parameter description, applied to a sequence (frames in time
/// order); returns the filtered centre frame.
struct Method
{
  std::string family;     // "range_nlm", "pcl FastBilateralFilter", ...
  std::string setting;    // the parameters, human readable
  std::function<pcl::PointCloud<pcl::PointXYZ>(const std::vector<pcl::PointCloud<pcl::PointXYZ>::ConstPtr>&,
                                               std::size_t centre)>
      apply;
};

struct Scenario
{
  std::string name;  // e.g. "depth camera, static"
  std::string noise; // kinect | laser | stripes
  std::string scene = "boxes"; // boxes | ridges (small features only)
  double noise_scale = 0.0; // 0 = the model's default
  int frames = 1;    // temporal scenarios: 3 (radius 1)
  int width = 640, height = 480;
  std::uint64_t seed = 7;
};

struct Row
{
  std::string scenario, family, setting;
  FrameMetrics metrics;
  double milliseconds = 0.0;
};

struct Options
{
  std::vector<Scenario> scenarios;
  bool include_peers = true;
  bool include_levers = true;
  int threads = 0;
};

Options
defaultOptions();

/// Runs every method on every scenario; prints progress to `log`.
std::vector<Row>
run(const Options& options, std::ostream& log);

/// The comparison table: per scenario the noisy input, the range_nlm rows and, per PCL family,
/// the best setting for flat RMSE and the best for feature RMSE (with their other figures).
void
printTable(const std::vector<Row>& rows, std::ostream& out);
void
printJson(const std::vector<Row>& rows, std::ostream& out);

/// The parameter sets range_nlm is measured with: the default, the paper preset and the levers
/// one by one (each a named FilterParameters).
std::vector<std::pair<std::string, FilterParameters>>
rangeNlmVariants(bool include_levers);

} // namespace quality
} // namespace tools
} // namespace range_nlm
