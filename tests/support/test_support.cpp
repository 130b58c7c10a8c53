#include "test_support.h"

#include <fstream>
#include <sstream>

#include <fcntl.h>
#include <unistd.h>
#include <stdexcept>

#include <pcl/common/centroid.h>
#include <pcl/features/normal_3d.h>

#include <cmath>
#include <cstdio>
#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <limits>
#include <random>

namespace range_nlm
{
namespace test
{

pcl::PointCloud<pcl::PointXYZ>
makeCloud(int w, int h, const DepthFunction& depth, double sigma, std::uint64_t seed, double focal)
{
  pcl::PointCloud<pcl::PointXYZ> cloud(w, h);
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> noise(0.0, 1.0);
  const double cx = (w - 1) / 2.0, cy = (h - 1) / 2.0;
  bool dense = true;
  for (int v = 0; v < h; ++v)
    for (int u = 0; u < w; ++u) {
      const double a = (u - cx) / focal, b = (v - cy) / focal;
      const double z = depth(a, b, u, v);
      pcl::PointXYZ& p = cloud.at(u, v);
      const double e = noise(rng);
      if (!std::isfinite(z)) {
        p.x = p.y = p.z = std::numeric_limits<float>::quiet_NaN();
        dense = false;
        continue;
      }
      // noise along the ray: scale the point by (r + e sigma) / r
      const Eigen::Vector3d q(a * z, b * z, z);
      const double r = q.norm();
      const Eigen::Vector3d n = q * ((r + sigma * e) / r);
      p.x = float(n.x()), p.y = float(n.y()), p.z = float(n.z());
    }
  cloud.is_dense = dense;
  return cloud;
}

DepthFunction
plane(const Eigen::Vector3d& n, double c)
{
  return [n, c](double a, double b, int, int) { return c / (n.x() * a + n.y() * b + n.z()); };
}

DepthFunction
step(int edge_u, double z0, double z1)
{
  return [=](double, double, int u, int) { return u < edge_u ? z0 : z1; };
}

DepthFunction
crease(int edge_u, double z0, double slope)
{
  // Surface z = z0 - slope |x - x_e| with x_e the column's x at depth z0 (a ridge toward the camera).
  return [=](double a, double, int u, int) {
    (void)u;
    (void)edge_u;
    // Solve z = z0 - slope * |a z - xe| with xe = 0 at the image centre (edge_u is the centre).
    const double s = a >= 0 ? 1.0 : -1.0;
    return z0 / (1.0 + slope * s * a);
  };
}

double
planeRmse(const pcl::PointCloud<pcl::PointXYZ>& cloud, const Eigen::Vector3d& n_in, double c)
{
  const double len = n_in.norm();
  const Eigen::Vector3d n = n_in / len;
  double sum = 0.0;
  std::size_t count = 0;
  for (const auto& p : cloud) {
    if (!std::isfinite(p.z))
      continue;
    const double e = n.dot(Eigen::Vector3d(p.x, p.y, p.z)) - c / len;
    sum += e * e;
    ++count;
  }
  return std::sqrt(sum / count);
}

pcl::PointCloud<pcl::PointXYZ>
referenceFilter(const pcl::PointCloud<pcl::PointXYZ>& cloud, int search, int patch, double d, double s)
{
  const int w = cloud.width, h = cloud.height;
  auto valid = [&](int u, int v) {
    return u >= 0 && v >= 0 && u < w && v < h && std::isfinite(cloud.at(u, v).z);
  };
  auto P = [&](int u, int v) {
    const auto& p = cloud.at(u, v);
    return Eigen::Vector3d(p.x, p.y, p.z);
  };
  pcl::PointCloud<pcl::PointXYZ> out = cloud;
  for (int v = 0; v < h; ++v)
    for (int u = 0; u < w; ++u) {
      if (!valid(u, v))
        continue;
      pcl::Indices ring;
      for (int dv = -1; dv <= 1; ++dv)
        for (int du = -1; du <= 1; ++du)
          if (valid(u + du, v + dv))
            ring.push_back((v + dv) * w + (u + du));
      Eigen::Vector4f plane;
      float curvature;
      if (ring.size() < 3 || !pcl::computePointNormal(cloud, ring, plane, curvature))
        continue;
      Eigen::Vector3d n(plane[0], plane[1], plane[2]);
      n.normalize();
      const Eigen::Vector3d pi = P(u, v);
      if (n.dot(-pi) < 0)
        n = -n;
      double num = 0, den = 0;
      for (int jv = v - search / 2; jv <= v + search / 2; ++jv)
        for (int ju = u - search / 2; ju <= u + search / 2; ++ju) {
          if (!valid(ju, jv))
            continue;
          double sim = 0;
          int pairs = 0;
          for (int ov = -patch / 2; ov <= patch / 2; ++ov)
            for (int ou = -patch / 2; ou <= patch / 2; ++ou)
              if (valid(u + ou, v + ov) && valid(ju + ou, jv + ov)) {
                const double t = (P(u + ou, v + ov) - P(ju + ou, jv + ov)).dot(n);
                sim += t * t;
                ++pairs;
              }
          if (pairs == 0)
            continue;
          sim /= pairs;
          const Eigen::Vector3d diff = pi - P(ju, jv);
          const double wgt = std::exp(-diff.squaredNorm() / (d * d)) * std::exp(-sim / (s * s));
          num += wgt * diff.dot(n);
          den += wgt;
        }
      const Eigen::Vector3d q = pi - n * (num / den);
      out.at(u, v).x = float(q.x());
      out.at(u, v).y = float(q.y());
      out.at(u, v).z = float(q.z());
    }
  return out;
}

CommandResult
runCommand(const std::string& command)
{
  CommandResult r;
  FILE* pipe = ::popen((command + " 2>&1").c_str(), "r");
  char buffer[4096];
  while (pipe && std::fgets(buffer, sizeof buffer, pipe))
    r.output += buffer;
  const int status = pipe ? ::pclose(pipe) : -1;
  r.status = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

CommandResult
runTool(const std::string& tool, const std::string& args)
{
  return runCommand(std::string(RANGE_NLM_TOOLS_DIR) + "/" + tool + " " + args);
}

CommandResult
runDenoise(const std::string& args)
{
  return runTool("range_nlm_denoise", args);
}

int
startProcess(const std::vector<std::string>& args, const std::string& log)
{
  std::vector<std::string> all = args;
  std::vector<char*> argv;
  for (std::string& a : all)
    argv.push_back(&a[0]);
  argv.push_back(nullptr);
  const pid_t pid = ::fork();
  if (pid == 0) {
    const int fd = ::open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    ::dup2(fd, 1);
    ::dup2(fd, 2);
    ::execv(argv[0], argv.data());
    ::_exit(127);
  }
  return pid;
}

std::string
readBytes(const std::string& path)
{
  std::ifstream in(path, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), {});
}

nlohmann::json
jsonLine(const std::string& output)
{
  std::istringstream lines(output);
  for (std::string line; std::getline(lines, line);)
    if (!line.empty() && line[0] == '{')
      return nlohmann::json::parse(line);
  throw std::runtime_error("no JSON object in the output: " + output);
}

void
punchHoles(pcl::PointCloud<pcl::PointXYZ>& cloud, double p, std::uint64_t seed)
{
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> uni(0.0, 1.0);
  for (auto& q : cloud)
    if (uni(rng) < p) {
      q.x = q.y = q.z = std::numeric_limits<float>::quiet_NaN();
      cloud.is_dense = false;
    }
}

int
freePort()
{
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  socklen_t length = sizeof address;
  const bool found = fd >= 0 && ::bind(fd, reinterpret_cast<sockaddr*>(&address), sizeof address) == 0 &&
                     ::getsockname(fd, reinterpret_cast<sockaddr*>(&address), &length) == 0;
  if (fd >= 0)
    ::close(fd);
  if (!found)
    throw std::runtime_error("cannot find a free port on 127.0.0.1");
  return ntohs(address.sin_port);
}

} // namespace test
} // namespace range_nlm
