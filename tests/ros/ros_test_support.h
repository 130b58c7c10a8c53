// A real ROS master for the tests, the processes they start, and organized frames as messages.
#pragma once

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/PointCloud2.h>

#include <cstdint>
#include <string>
#include <vector>

#include <sys/types.h>

namespace range_nlm
{
namespace test
{

/// A child process (own process group, killed with the test process if that dies first), its
/// stdout and stderr in a log file. The destructor stops it: SIGINT, then SIGKILL after 5 s.
class ChildProcess
{
public:
  ChildProcess(const std::vector<std::string>& argv, const std::string& log);
  ~ChildProcess();
  ChildProcess(const ChildProcess&) = delete;
  ChildProcess& operator=(const ChildProcess&) = delete;
  /// Still running?
  bool running();
  /// Waits up to `seconds` for the process to end: its exit status (128 + signal if killed by
  /// one), or -1 if it still runs.
  int waitExit(double seconds);
  void stop();
  const std::string& log() const { return log_; }
  pid_t pid() const { return pid_; }

private:
  pid_t pid_ = -1;
  int status_ = -1;
  std::string log_;
};

/// `rosmaster --core` on 127.0.0.1 with a free port, ROS_HOME and ROS_LOG_DIR in a fresh
/// temporary directory, ROS_MASTER_URI / ROS_IP / ROS_HOSTNAME in this process's environment
/// (children inherit them). Waits until the master answers.
class RosMaster
{
public:
  RosMaster();
  ~RosMaster();
  const std::string& directory() const { return directory_; }
  const std::string& uri() const { return uri_; }

private:
  std::string directory_;
  std::string uri_;
  ChildProcess* master_ = nullptr;
};

/// An organized cloud as a PointCloud2 with extra fields around x, y, z: x, y, z FLOAT32 at
/// 0, 4, 8, `intensity` FLOAT32 at 16 (= index / 2) and `ring` UINT16 at 20 (= index % 7);
/// point_step 24.
sensor_msgs::PointCloud2
toPointCloud2(const pcl::PointCloud<pcl::PointXYZ>& cloud, std::uint32_t stamp_sec, std::uint32_t stamp_nsec,
              const std::string& frame_id = "camera_depth_optical_frame");

/// x, y, z of a message written by toPointCloud2 (or any FLOAT32 x, y, z layout).
pcl::PointCloud<pcl::PointXYZ>
xyzOf(const sensor_msgs::PointCloud2& message);

/// Bitwise comparison of x, y, z (NaN equals NaN); "" if equal, else the first difference.
std::string
compareXyz(const pcl::PointCloud<pcl::PointXYZ>& actual, const pcl::PointCloud<pcl::PointXYZ>& expected);

/// "stamp SEC.NSEC" as the ROS glue prints it in log lines.
std::string
stampText(std::uint32_t sec, std::uint32_t nsec);

} // namespace test
} // namespace range_nlm
