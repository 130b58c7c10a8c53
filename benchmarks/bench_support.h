// Helpers of range_nlm_bench: isolated measurement in forked child processes (one piece of work,
// or several methods taking turns), statistics, machine description, JSON text, and the frame
// preparation (centre crop, fresh depth-camera noise) the benchmark configurations need.
#pragma once

#include <range_nlm/parameters.h>

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace range_nlm
{
namespace tools
{
namespace bench
{

/// Outcome of work run in a child process.
struct ChildResult
{
  /// True if the work returned normally; otherwise `error` says why (exception text, exit
  /// status or signal).
  bool ok = false;
  std::string error;
  /// The numbers the work returned.
  std::vector<double> values;
  /// Peak resident set size of the child in bytes: ru_maxrss reported by wait4 (Linux reports
  /// it in KiB). It includes what the child inherited from the parent at fork time.
  std::uint64_t peak_rss_bytes = 0;
};

/// Forks, runs `work` in the child and returns its numbers and peak RSS. Each measured method
/// gets its own address space, so one method's allocations never inflate another's peak, and a
/// crash is reported instead of ending the benchmark. The parent must not have started an
/// OpenMP thread pool (libgomp's pool does not survive fork); the children may.
ChildResult
runInChild(const std::function<std::vector<double>()>& work);

/// Current (VmRSS) or peak (VmHWM) resident set size of this process in bytes, from
/// /proc/self/status; 0 if unavailable.
std::uint64_t
residentBytes();
std::uint64_t
peakResidentBytes();

/// One method for runInterleaved: `prepare` runs once in the method's own child process (not
/// timed) and returns the call to time, `runs` times; with `warmup`, each timed call comes right
/// after an untimed one.
struct TimedMethod
{
  std::function<std::function<void()>()> prepare;
  int runs = 1;
  bool warmup = true;
};

/// Milliseconds the parent waits before each method's turn, so that the OpenMP threads of the
/// method before (libgomp's idle threads spin for up to about 10 ms before they sleep) have
/// stopped competing for the cores.
constexpr int kSettleMs = 20;

/// Times several methods, each in a child process of its own (its own address space and peak
/// memory, as with runInChild), in rounds: every round, each method with runs left takes one
/// turn, in the order given, an untimed warm-up call (if `warmup`) and then the timed call. A change of the
/// machine's speed while the benchmark runs (other work on a shared machine) then reaches every
/// method alike instead of whichever happened to be running; the warm-up call of each turn gives
/// the timed one the warm caches and threads that back-to-back calls have. Result k is method
/// k's: `values` holds the wall-clock milliseconds of its timed calls, then the process CPU
/// milliseconds of each (user + system, all threads; includes OpenMP's busy waiting);
/// `peak_rss_bytes` comes from wait4 when the child has ended. A method that fails (exception,
/// crash) drops out with its error and the others go on. The parent must not have started an
/// OpenMP thread pool (see runInChild).
std::vector<ChildResult>
runInterleaved(const std::vector<TimedMethod>& methods);

/// Median of a non-empty sample (mean of the two middle values for an even count).
double
median(std::vector<double> values);

/// The machine: CPU model name from /proc/cpuinfo and the number of logical CPUs this process
/// may run on (sched_getaffinity) and that the system has online.
struct MachineInfo
{
  std::string cpu_model;
  int usable_cpus = 0;
  int online_cpus = 0;
};
MachineInfo
machineInfo();

/// The 1-minute load average from /proc/loadavg (negative if unavailable): on a shared machine
/// it tells whether other work competed with the measurement.
double
loadAverage();

/// `text` as a JSON string literal, quotes included.
std::string
jsonString(const std::string& text);
/// A finite number as JSON (NaN and infinities become null).
std::string
jsonNumber(double value);

/// The centre `width` x `height` window of an organized cloud (sensor pose kept). Throws
/// std::invalid_argument naming `what` if the cloud is smaller than the window.
pcl::PointCloud<pcl::PointXYZ>
cropCentre(const pcl::PointCloud<pcl::PointXYZ>& cloud, unsigned width, unsigned height,
           const std::string& what);

/// A copy of `cloud` with fresh depth-camera noise added along each camera ray (from the
/// sensor origin): Gaussian with sigma(z) = 1.2 mm + 1.9 mm * (z - 0.4 m)^2, z in metres (the
/// Kinect axial model of docs/method.md, "Sensor noise models"). NaN points stay NaN.
/// Deterministic for a given seed.
pcl::PointCloud<pcl::PointXYZ>
withFreshNoise(const pcl::PointCloud<pcl::PointXYZ>& cloud, std::uint64_t seed);

/// Median distance between horizontally adjacent valid points: the pixel spacing of the
/// frame at its typical depth, in cloud units. 0 if no adjacent valid pair exists.
double
medianPixelSpacing(const pcl::PointCloud<pcl::PointXYZ>& cloud);

/// Median z of the valid points (0 if there is none).
double
medianDepth(const pcl::PointCloud<pcl::PointXYZ>& cloud);

/// A real frame as an organized XYZ cloud in metres: a PCD file, or a 16-bit depth PNG with the
/// intrinsics.txt beside it or in its parent folder (the default intrinsics if neither exists).
/// Throws std::invalid_argument naming the file if it cannot be read.
pcl::PointCloud<pcl::PointXYZ>
loadXyzFrame(const std::string& path);

/// The depth scale (values per metre) a depth-image output of the frame `path` is written with:
/// that of the intrinsics loadXyzFrame reads for a depth PNG, else range_nlm_denoise's default
/// (--depth-scale, DepthIntrinsics's 5000).
double
frameDepthScale(const std::string& path);

/// What a depth-image output holds of the filtered frame `filtered` of `input`, read back: the
/// 16-bit image at `depth_scale` (re-projected onto the rays, cloudToDepthImage(input, filtered,
/// ...), or with `z_only` the filtered z as it is), each value back-projected onto the ray of its
/// input point (as a reader with the frame's intrinsics does). Depths beyond the 16-bit range
/// are clamped as range_nlm_denoise clamps them.
pcl::PointCloud<pcl::PointXYZ>
depthImageOutput(const pcl::PointCloud<pcl::PointXYZ>& input, const pcl::PointCloud<pcl::PointXYZ>& filtered,
                 double depth_scale, bool z_only = false);

/// Sets one field of `p` from "NAME=VALUE", NAME a field of the parameter registry (the field
/// table of docs/method.md), and checks it against its range. Throws std::invalid_argument
/// saying what is wrong (no such field, a bad or out-of-range value).
void
setRegistryField(const std::string& item, FilterParameters& p);

} // namespace bench
} // namespace tools
} // namespace range_nlm
