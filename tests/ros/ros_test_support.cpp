#include "ros_test_support.h"
#include "test_support.h"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <stdexcept>
#include <thread>

#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

namespace range_nlm
{
namespace test
{
namespace
{

/// Something accepts connections on 127.0.0.1:port.
bool
listening(int port)
{
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  address.sin_port = htons(static_cast<std::uint16_t>(port));
  const bool ok = ::connect(fd, reinterpret_cast<sockaddr*>(&address), sizeof address) == 0;
  ::close(fd);
  return ok;
}

} // namespace

ChildProcess::ChildProcess(const std::vector<std::string>& args, const std::string& log) : log_(log)
{
  std::vector<std::string> all = args;
  std::vector<char*> argv;
  for (std::string& a : all)
    argv.push_back(&a[0]);
  argv.push_back(nullptr);
  const pid_t parent = ::getpid();
  pid_ = ::fork();
  if (pid_ < 0)
    throw std::runtime_error("fork failed");
  if (pid_ == 0) {
    ::setpgid(0, 0);
    ::prctl(PR_SET_PDEATHSIG, SIGKILL); // the test process died: no orphan master or node
    if (::getppid() != parent)
      ::_exit(126);
    const int fd = ::open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    ::dup2(fd, 1);
    ::dup2(fd, 2);
    ::execvp(argv[0], argv.data());
    std::perror(argv[0]);
    ::_exit(127);
  }
  ::setpgid(pid_, pid_);
}

bool
ChildProcess::running()
{
  if (pid_ <= 0)
    return false;
  int status = 0;
  if (::waitpid(pid_, &status, WNOHANG) == pid_) {
    status_ = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
    pid_ = -1;
    return false;
  }
  return true;
}

int
ChildProcess::waitExit(double seconds)
{
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
  while (running() && std::chrono::steady_clock::now() < deadline)
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  return running() ? -1 : status_;
}

void
ChildProcess::stop()
{
  if (!running())
    return;
  ::kill(-pid_, SIGINT);
  for (int i = 0; i < 100; ++i) {
    int status = 0;
    if (::waitpid(pid_, &status, WNOHANG) == pid_) {
      pid_ = -1;
      return;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  ::kill(-pid_, SIGKILL);
  int status = 0;
  ::waitpid(pid_, &status, 0);
  pid_ = -1;
}

ChildProcess::~ChildProcess() { stop(); }

RosMaster::RosMaster()
{
  char dir[] = "/tmp/range_nlm_ros_XXXXXX";
  if (!::mkdtemp(dir))
    throw std::runtime_error("cannot create a temporary directory");
  directory_ = dir;
  ::setenv("ROS_HOME", directory_.c_str(), 1);
  ::setenv("ROS_LOG_DIR", (directory_ + "/log").c_str(), 1);
  ::setenv("ROS_IP", "127.0.0.1", 1);
  ::setenv("ROS_HOSTNAME", "127.0.0.1", 1);
  ::unsetenv("ROS_NAMESPACE");
  for (int attempt = 0; attempt < 3 && !master_; ++attempt) {
    const int port = freePort();
    uri_ = "http://127.0.0.1:" + std::to_string(port);
    auto* master = new ChildProcess({"rosmaster", "--core", "-p", std::to_string(port)},
                                    directory_ + "/rosmaster" + std::to_string(attempt) + ".log");
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(15);
    while (master->running() && !listening(port) && std::chrono::steady_clock::now() < deadline)
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    if (master->running() && listening(port))
      master_ = master;
    else
      delete master; // port taken in between, or no rosmaster: try again
  }
  if (!master_)
    throw std::runtime_error("rosmaster --core did not start (see " + directory_ + "/rosmaster*.log)");
  ::setenv("ROS_MASTER_URI", uri_.c_str(), 1);
}

RosMaster::~RosMaster()
{
  delete master_;
  std::error_code ec;
  if (!std::getenv("RANGE_NLM_KEEP_ROS_LOGS"))
    std::filesystem::remove_all(directory_, ec);
}

sensor_msgs::PointCloud2
toPointCloud2(const pcl::PointCloud<pcl::PointXYZ>& cloud, std::uint32_t sec, std::uint32_t nsec,
              const std::string& frame_id)
{
  sensor_msgs::PointCloud2 m;
  m.header.stamp.sec = sec;
  m.header.stamp.nsec = nsec;
  m.header.frame_id = frame_id;
  m.width = cloud.width;
  m.height = cloud.height;
  auto field = [&](const char* name, std::uint32_t offset, std::uint8_t type) {
    sensor_msgs::PointField f;
    f.name = name;
    f.offset = offset;
    f.datatype = type;
    f.count = 1;
    m.fields.push_back(f);
  };
  field("x", 0, sensor_msgs::PointField::FLOAT32);
  field("y", 4, sensor_msgs::PointField::FLOAT32);
  field("z", 8, sensor_msgs::PointField::FLOAT32);
  field("intensity", 16, sensor_msgs::PointField::FLOAT32);
  field("ring", 20, sensor_msgs::PointField::UINT16);
  m.point_step = 24;
  m.row_step = m.point_step * m.width;
  m.is_bigendian = false;
  m.data.assign(std::size_t(m.row_step) * m.height, 0xAB); // padding bytes must survive too
  bool dense = true;
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    std::uint8_t* p = &m.data[i * m.point_step];
    std::memcpy(p, &cloud[i].x, 4);
    std::memcpy(p + 4, &cloud[i].y, 4);
    std::memcpy(p + 8, &cloud[i].z, 4);
    const float intensity = float(i) / 2;
    const std::uint16_t ring = std::uint16_t(i % 7);
    std::memcpy(p + 16, &intensity, 4);
    std::memcpy(p + 20, &ring, 2);
    dense = dense && std::isfinite(cloud[i].z);
  }
  m.is_dense = dense;
  return m;
}

pcl::PointCloud<pcl::PointXYZ>
xyzOf(const sensor_msgs::PointCloud2& m)
{
  std::uint32_t offset[3] = {0, 0, 0};
  for (const auto& f : m.fields)
    for (int k = 0; k < 3; ++k)
      if (f.name == std::string(1, char('x' + k)))
        offset[k] = f.offset;
  pcl::PointCloud<pcl::PointXYZ> cloud(m.width, m.height);
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const std::uint8_t* p = &m.data[i * m.point_step];
    std::memcpy(&cloud[i].x, p + offset[0], 4);
    std::memcpy(&cloud[i].y, p + offset[1], 4);
    std::memcpy(&cloud[i].z, p + offset[2], 4);
  }
  return cloud;
}

std::string
compareXyz(const pcl::PointCloud<pcl::PointXYZ>& actual, const pcl::PointCloud<pcl::PointXYZ>& expected)
{
  if (actual.width != expected.width || actual.height != expected.height)
    return "size " + std::to_string(actual.width) + " x " + std::to_string(actual.height) + " vs " +
           std::to_string(expected.width) + " x " + std::to_string(expected.height);
  for (std::size_t i = 0; i < actual.size(); ++i)
    for (int k = 0; k < 3; ++k) {
      const float a = actual[i].data[k], e = expected[i].data[k];
      if (!(a == e || (std::isnan(a) && std::isnan(e))))
        return "point " + std::to_string(i) + " coordinate " + std::to_string(k) + ": " + std::to_string(a) +
               " vs " + std::to_string(e);
    }
  return "";
}

std::string
stampText(std::uint32_t sec, std::uint32_t nsec)
{
  char text[64];
  std::snprintf(text, sizeof text, "stamp %u.%09u", sec, nsec);
  return text;
}

} // namespace test
} // namespace range_nlm
