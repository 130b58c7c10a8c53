// Synthetic organized clouds and a naive reference of the filter formula for the tests.
#pragma once

#include <range_nlm/core/grid.h>

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include <cstdint>
#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

namespace range_nlm
{
namespace test
{

/// The message of the std::invalid_argument `f` throws, or "" if it throws none (any other
/// exception propagates and fails the test).
inline std::string
errorOf(const std::function<void()>& f)
{
  try {
    f();
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}


/// Depth (along +z) of a surface seen through pixel (u, v) of a w x h pinhole camera
/// (focal f pixels, centre (w-1)/2, (h-1)/2); NaN = no surface.
using DepthFunction = std::function<double(double x_over_z, double y_over_z, int u, int v)>;

/// Ray-cast organized cloud with Gaussian noise of `sigma` along each ray.
pcl::PointCloud<pcl::PointXYZ>
makeCloud(int w, int h, const DepthFunction& depth, double sigma, std::uint64_t seed, double focal = 300.0);

/// Plane n . p = c seen by the camera (n need not be normalised).
DepthFunction
plane(const Eigen::Vector3d& n, double c);
/// Step edge: depth z0 left of column `edge_u`, z1 from it on.
DepthFunction
step(int edge_u, double z0, double z1);
/// Crease (roof): two planes meeting along column `edge_u`, slopes +/- `slope` in z per unit x/z.
DepthFunction
crease(int edge_u, double z0, double slope);

/// Signed distance of each valid point to the plane n . p = c (n normalised inside), RMSE.
double
planeRmse(const pcl::PointCloud<pcl::PointXYZ>& cloud, const Eigen::Vector3d& n, double c);

/// Naive evaluation of the static filter formula (docs/method.md, "The static filter") in double
/// precision, with normals from pcl::computePointNormal over the 3x3 neighbourhood, oriented
/// toward the origin, and fixed bandwidths d, s. Invalid points stay NaN.
pcl::PointCloud<pcl::PointXYZ>
referenceFilter(const pcl::PointCloud<pcl::PointXYZ>& cloud, int search, int patch, double d, double s);

/// True in a build under AddressSanitizer (RANGE_NLM_SANITIZE), which slows the filter down
/// about tenfold and cannot free clouds that Debian's uninstrumented PCL libraries resized.
#if defined(__SANITIZE_ADDRESS__)
constexpr bool kAddressSanitizer = true;
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
constexpr bool kAddressSanitizer = true;
#else
constexpr bool kAddressSanitizer = false;
#endif
#else
constexpr bool kAddressSanitizer = false;
#endif

/// Exit status (-1 if it did not exit normally) and combined stdout + stderr of a command.
struct CommandResult
{
  int status = -1;
  std::string output;
};
/// Runs `command` through the shell with stderr folded into stdout.
CommandResult
runCommand(const std::string& command);
/// Runs the built tool `tool` (e.g. "range_nlm_denoise") with `args`.
CommandResult
runTool(const std::string& tool, const std::string& args);
/// Runs the built range_nlm_denoise with `args`.
CommandResult
runDenoise(const std::string& args);

/// Adds NaN holes: each point becomes NaN with probability p.
/// Starts `argv[0]` with the arguments `argv[1..]` in the background, its stdout and stderr into
/// the file `log`; returns its pid (reap it with waitpid or wait4).
int
startProcess(const std::vector<std::string>& argv, const std::string& log);

/// The whole contents of a file ("" if it cannot be read).
std::string
readBytes(const std::string& path);

/// The JSON object a tool printed with --json: the first line of `output` that starts with '{',
/// parsed (other lines are progress or messages on stderr). Throws if there is none or it does
/// not parse.
nlohmann::json
jsonLine(const std::string& output);

void
punchHoles(pcl::PointCloud<pcl::PointXYZ>& cloud, double p, std::uint64_t seed);

/// A TCP port on 127.0.0.1 that nothing listens on now (bound to port 0 and released), for the
/// tests that start real servers (rosmaster, slurmctld, slurmd). Throws std::runtime_error.
int
freePort();

} // namespace test
} // namespace range_nlm
