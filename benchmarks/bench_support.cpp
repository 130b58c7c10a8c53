#include "bench_support.h"

#include <range_nlm/io/depth_image.h>
#include <range_nlm/io/pcd_file.h>
#include <range_nlm/parameter_registry.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <limits>
#include <random>
#include <sstream>
#include <stdexcept>
#include <thread>

#include <sched.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <unistd.h>

namespace range_nlm
{
namespace tools
{
namespace bench
{

namespace
{

void
writeAll(int fd, const std::string& text)
{
  const char* p = text.data();
  std::size_t left = text.size();
  while (left > 0) {
    const ssize_t n = ::write(fd, p, left);
    if (n < 0) {
      if (errno == EINTR)
        continue;
      return; // the parent is gone; nothing sensible is left to do
    }
    p += n;
    left -= static_cast<std::size_t>(n);
  }
}

std::string
readAll(int fd)
{
  std::string text;
  char buffer[4096];
  for (;;) {
    const ssize_t n = ::read(fd, buffer, sizeof buffer);
    if (n < 0) {
      if (errno == EINTR)
        continue;
      break;
    }
    if (n == 0)
      break;
    text.append(buffer, static_cast<std::size_t>(n));
  }
  return text;
}

/// Waits for child `pid` to end: its peak RSS goes into `result`; returns its wait status.
int
reap(pid_t pid, ChildResult& result)
{
  int status = 0;
  struct rusage usage;
  std::memset(&usage, 0, sizeof usage);
  pid_t waited;
  do
    waited = ::wait4(pid, &status, 0, &usage);
  while (waited < 0 && errno == EINTR);
  if (waited < 0)
    throw std::runtime_error(std::string("cannot wait for the measurement child: ") + std::strerror(errno));
  result.peak_rss_bytes = static_cast<std::uint64_t>(usage.ru_maxrss) * 1024u;
  return status;
}

std::string
signalText(int status)
{
  return "killed by signal " + std::to_string(WTERMSIG(status)) + " (" + strsignal(WTERMSIG(status)) + ")";
}

std::string
exitText(int status)
{
  return "measurement child exited with status " + std::to_string(WIFEXITED(status) ? WEXITSTATUS(status) : -1) +
         " without a result";
}

/// The whitespace-separated numbers of `text` appended to `values`, token by token with strtod
/// (operator>> does not read back the "nan" it writes); false with the bad token in `bad`.
bool
parseNumbers(const std::string& text, std::vector<double>& values, std::string& bad)
{
  std::istringstream numbers(text);
  std::string token;
  while (numbers >> token) {
    char* end = nullptr;
    const double v = std::strtod(token.c_str(), &end);
    if (end == token.c_str() || *end != '\0') {
      bad = token;
      return false;
    }
    values.push_back(v);
  }
  return true;
}

/// Process CPU time (user + system, all threads) in ms.
double
processCpuMs()
{
  struct rusage usage;
  if (::getrusage(RUSAGE_SELF, &usage) != 0)
    return std::numeric_limits<double>::quiet_NaN();
  const auto ms = [](const struct timeval& t) { return t.tv_sec * 1e3 + t.tv_usec * 1e-3; };
  return ms(usage.ru_utime) + ms(usage.ru_stime);
}

std::uint64_t
statusField(const char* key)
{
  std::ifstream status("/proc/self/status");
  std::string line;
  const std::size_t key_length = std::strlen(key);
  while (std::getline(status, line))
    if (line.compare(0, key_length, key) == 0 && line.size() > key_length && line[key_length] == ':') {
      std::istringstream fields(line.substr(key_length + 1));
      std::uint64_t kib = 0;
      fields >> kib;
      return kib * 1024u;
    }
  return 0;
}

} // namespace

ChildResult
runInChild(const std::function<std::vector<double>()>& work)
{
  std::cout.flush();
  std::cerr.flush();
  std::fflush(nullptr);
  int fds[2];
  if (::pipe(fds) != 0)
    throw std::runtime_error(std::string("cannot create a pipe for the measurement child: ") +
                             std::strerror(errno));
  const pid_t pid = ::fork();
  if (pid < 0) {
    const int error = errno;
    ::close(fds[0]);
    ::close(fds[1]);
    throw std::runtime_error(std::string("cannot fork the measurement child: ") + std::strerror(error));
  }
  if (pid == 0) {
    ::close(fds[0]);
    std::string payload;
    int status = 0;
    try {
      const std::vector<double> values = work();
      std::ostringstream out;
      out << "ok\n" << std::setprecision(17);
      for (double v : values)
        out << v << "\n";
      payload = out.str();
    } catch (const std::exception& e) {
      payload = std::string("error\n") + e.what();
      status = 3;
    } catch (...) {
      payload = "error\nunknown exception";
      status = 3;
    }
    writeAll(fds[1], payload);
    ::close(fds[1]);
    std::cout.flush();
    std::cerr.flush();
    std::fflush(nullptr);
    ::_exit(status); // no atexit handlers or static destructors of the parent's state
  }

  ::close(fds[1]);
  const std::string payload = readAll(fds[0]);
  ::close(fds[0]);
  ChildResult result;
  const int status = reap(pid, result);
  const std::size_t newline = payload.find('\n');
  const std::string head = payload.substr(0, newline);
  const std::string body = newline == std::string::npos ? std::string() : payload.substr(newline + 1);
  if (WIFSIGNALED(status)) {
    result.error = signalText(status);
    return result;
  }
  if (head == "error") {
    result.error = body.empty() ? "unknown error" : body;
    return result;
  }
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0 || head != "ok") {
    result.error = exitText(status);
    return result;
  }
  std::string bad;
  if (!parseNumbers(body, result.values, bad)) {
    result.error = "measurement child returned a malformed number '" + bad + "'";
    return result;
  }
  result.ok = true;
  return result;
}

std::uint64_t
residentBytes()
{
  return statusField("VmRSS");
}

std::uint64_t
peakResidentBytes()
{
  return statusField("VmHWM");
}

namespace
{
/// One line from `fd`, without its newline; false at the end of the stream before a newline.
bool
readLine(int fd, std::string& line)
{
  line.clear();
  for (;;) {
    char c;
    const ssize_t n = ::read(fd, &c, 1);
    if (n < 0 && errno == EINTR)
      continue;
    if (n <= 0)
      return false;
    if (c == '\n')
      return true;
    line.push_back(c);
  }
}

std::string
oneLine(std::string text)
{
  std::replace(text.begin(), text.end(), '\n', ' ');
  return text;
}

/// The child of one method in runInterleaved: prepares it, answers "ready", then times one call
/// per command byte 'c' and answers "<wall ms> <cpu ms>", until 'q' or the end of the commands.
[[noreturn]] void
serveCalls(const TimedMethod& method, int commands, int answers)
{
  int status = 0;
  try {
    const std::function<void()> call = method.prepare();
    writeAll(answers, "ready\n");
    for (;;) {
      char command = 0;
      const ssize_t n = ::read(commands, &command, 1);
      if (n < 0 && errno == EINTR)
        continue;
      if (n <= 0 || command != 'c')
        break;
      const double cpu = processCpuMs();
      const auto start = std::chrono::steady_clock::now();
      call();
      const double wall =
          std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
      std::ostringstream out;
      out << std::setprecision(17) << wall << ' ' << processCpuMs() - cpu << '\n';
      writeAll(answers, out.str());
    }
  } catch (const std::exception& e) {
    writeAll(answers, "error " + oneLine(e.what()) + "\n");
    status = 3;
  } catch (...) {
    writeAll(answers, "error unknown exception\n");
    status = 3;
  }
  std::cout.flush();
  std::cerr.flush();
  std::fflush(nullptr);
  ::_exit(status); // no atexit handlers or static destructors of the parent's state
}

bool
sendCommand(int fd, char command)
{
  for (;;) {
    const ssize_t n = ::write(fd, &command, 1);
    if (n == 1)
      return true;
    if (n < 0 && errno == EINTR)
      continue;
    return false; // the child is gone
  }
}
} // namespace

std::vector<ChildResult>
runInterleaved(const std::vector<TimedMethod>& methods)
{
  struct Child
  {
    pid_t pid = -1;
    int commands = -1, answers = -1;
    bool running = false;
    std::string error; // set when the child reported one
    std::vector<double> wall, cpu;
  };
  const std::size_t count = methods.size();
  std::vector<Child> children(count);
  std::vector<ChildResult> results(count);
  std::cout.flush();
  std::cerr.flush();
  std::fflush(nullptr);
  // A child that has died must not end the parent with SIGPIPE at its next command.
  struct sigaction ignore, previous;
  std::memset(&ignore, 0, sizeof ignore);
  ignore.sa_handler = SIG_IGN;
  ::sigaction(SIGPIPE, &ignore, &previous);
  const auto closeFd = [](int& fd) {
    if (fd >= 0)
      ::close(fd);
    fd = -1;
  };
  for (std::size_t k = 0; k < count; ++k) {
    int down[2], up[2];
    if (::pipe(down) != 0) {
      results[k].error = std::string("cannot create a pipe for the measurement child: ") + std::strerror(errno);
      continue;
    }
    if (::pipe(up) != 0) {
      results[k].error = std::string("cannot create a pipe for the measurement child: ") + std::strerror(errno);
      ::close(down[0]), ::close(down[1]);
      continue;
    }
    const pid_t pid = ::fork();
    if (pid < 0) {
      results[k].error = std::string("cannot fork the measurement child: ") + std::strerror(errno);
      ::close(down[0]), ::close(down[1]), ::close(up[0]), ::close(up[1]);
      continue;
    }
    if (pid == 0) {
      ::close(down[1]);
      ::close(up[0]);
      for (std::size_t j = 0; j < k; ++j) // the other children's pipes are not this one's
        closeFd(children[j].commands), closeFd(children[j].answers);
      serveCalls(methods[k], down[0], up[1]);
    }
    ::close(down[0]);
    ::close(up[1]);
    Child& c = children[k];
    c.pid = pid, c.commands = down[1], c.answers = up[0], c.running = true;
  }
  // A child's line was not a result: it reported an error or died (reason from its status).
  const auto failed = [](Child& c, bool complete, const std::string& line) {
    if (complete)
      c.error = line.compare(0, 6, "error ") == 0 ? line.substr(6)
                                                 : "measurement child returned a malformed result '" + line + "'";
    c.running = false;
  };
  std::string line;
  for (Child& c : children) {
    if (!c.running)
      continue;
    const bool complete = readLine(c.answers, line);
    if (!complete || line != "ready")
      failed(c, complete, line);
  }
  // One call of method k; false (and the child marked failed) if it gave no result.
  const auto call = [&](std::size_t k, std::vector<double>& result) {
    Child& c = children[k];
    const bool complete = sendCommand(c.commands, 'c') && readLine(c.answers, line);
    std::string bad;
    result.clear();
    if (complete && parseNumbers(line, result, bad) && result.size() == 2)
      return true;
    failed(c, complete, line);
    return false;
  };
  std::vector<double> result;
  for (int round = 0;; ++round) {
    bool any = false;
    // In the given order every round: methods next to each other in the list take their turns
    // next to each other in time.
    for (std::size_t k = 0; k < count; ++k) {
      Child& c = children[k];
      if (!c.running || round >= methods[k].runs)
        continue;
      any = true;
      std::this_thread::sleep_for(std::chrono::milliseconds(kSettleMs));
      if (methods[k].warmup && !call(k, result))
        continue;
      if (call(k, result))
        c.wall.push_back(result[0]), c.cpu.push_back(result[1]);
    }
    if (!any)
      break;
  }
  for (std::size_t k = 0; k < count; ++k) {
    Child& c = children[k];
    if (c.pid < 0)
      continue;
    if (c.running)
      sendCommand(c.commands, 'q');
    closeFd(c.commands);
    closeFd(c.answers);
    ChildResult& r = results[k];
    const int status = reap(c.pid, r);
    if (c.running && WIFEXITED(status) && WEXITSTATUS(status) == 0) {
      r.ok = true;
      r.values = c.wall;
      r.values.insert(r.values.end(), c.cpu.begin(), c.cpu.end());
    } else if (!c.error.empty()) {
      r.error = c.error;
    } else if (WIFSIGNALED(status)) {
      r.error = signalText(status);
    } else {
      r.error = exitText(status);
    }
  }
  ::sigaction(SIGPIPE, &previous, nullptr);
  return results;
}

double
median(std::vector<double> values)
{
  if (values.empty())
    throw std::invalid_argument("median of an empty sample");
  std::sort(values.begin(), values.end());
  const std::size_t n = values.size();
  return n % 2 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
}

MachineInfo
machineInfo()
{
  MachineInfo info;
  std::ifstream cpuinfo("/proc/cpuinfo");
  std::string line;
  while (std::getline(cpuinfo, line)) {
    const std::size_t colon = line.find(':');
    if (colon == std::string::npos)
      continue;
    std::string key = line.substr(0, colon);
    key.erase(key.find_last_not_of(" \t") + 1);
    if (key == "model name" || (info.cpu_model.empty() && (key == "Hardware" || key == "cpu model"))) {
      std::string value = line.substr(colon + 1);
      value.erase(0, value.find_first_not_of(" \t"));
      info.cpu_model = value;
      if (key == "model name")
        break;
    }
  }
  if (info.cpu_model.empty())
    info.cpu_model = "unknown (no model name in /proc/cpuinfo)";
  cpu_set_t set;
  CPU_ZERO(&set);
  if (::sched_getaffinity(0, sizeof set, &set) == 0)
    info.usable_cpus = CPU_COUNT(&set);
  const long online = ::sysconf(_SC_NPROCESSORS_ONLN);
  info.online_cpus = online > 0 ? static_cast<int>(online) : 0;
  if (info.usable_cpus == 0)
    info.usable_cpus = info.online_cpus;
  return info;
}

double
loadAverage()
{
  std::ifstream file("/proc/loadavg");
  double one_minute = -1.0;
  if (!(file >> one_minute))
    return -1.0;
  return one_minute;
}

std::string
jsonString(const std::string& text)
{
  std::string out = "\"";
  for (const char c : text) {
    switch (c) {
    case '"': out += "\\\""; break;
    case '\\': out += "\\\\"; break;
    case '\n': out += "\\n"; break;
    case '\t': out += "\\t"; break;
    case '\r': out += "\\r"; break;
    default:
      if (static_cast<unsigned char>(c) < 0x20) {
        char escaped[8];
        std::snprintf(escaped, sizeof escaped, "\\u%04x",
                      static_cast<unsigned>(static_cast<unsigned char>(c)));
        out += escaped;
      } else {
        out += c;
      }
    }
  }
  return out + "\"";
}

std::string
jsonNumber(double value)
{
  if (!std::isfinite(value))
    return "null";
  std::ostringstream out;
  out << std::setprecision(10) << value;
  return out.str();
}

pcl::PointCloud<pcl::PointXYZ>
cropCentre(const pcl::PointCloud<pcl::PointXYZ>& cloud, unsigned width, unsigned height,
           const std::string& what)
{
  if (!cloud.isOrganized() || cloud.width < width || cloud.height < height)
    throw std::invalid_argument(what + " is " + std::to_string(cloud.width) + " x " +
                                std::to_string(cloud.height) + ", too small for its centre " +
                                std::to_string(width) + " x " + std::to_string(height) + " crop");
  const unsigned u0 = (cloud.width - width) / 2, v0 = (cloud.height - height) / 2;
  pcl::PointCloud<pcl::PointXYZ> crop(width, height);
  bool dense = true;
  for (unsigned v = 0; v < height; ++v)
    for (unsigned u = 0; u < width; ++u) {
      const pcl::PointXYZ& p = cloud.at(u0 + u, v0 + v);
      crop.at(u, v) = p;
      dense = dense && std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z);
    }
  crop.is_dense = dense;
  crop.header = cloud.header;
  crop.sensor_origin_ = cloud.sensor_origin_;
  crop.sensor_orientation_ = cloud.sensor_orientation_;
  return crop;
}

pcl::PointCloud<pcl::PointXYZ>
withFreshNoise(const pcl::PointCloud<pcl::PointXYZ>& cloud, std::uint64_t seed)
{
  pcl::PointCloud<pcl::PointXYZ> noisy = cloud;
  std::mt19937_64 random(seed);
  std::normal_distribution<float> gauss(0.0f, 1.0f);
  const float ox = cloud.sensor_origin_[0], oy = cloud.sensor_origin_[1], oz = cloud.sensor_origin_[2];
  for (pcl::PointXYZ& p : noisy.points) {
    const float g = gauss(random); // drawn for every pixel: the noise field does not depend on holes
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
      continue;
    const float rx = p.x - ox, ry = p.y - oy, rz = p.z - oz;
    const float range = std::sqrt(rx * rx + ry * ry + rz * rz);
    if (!(range > 0.0f))
      continue;
    const float z = std::fabs(rz);
    const float sigma = 0.0012f + 0.0019f * (z - 0.4f) * (z - 0.4f);
    const float step = sigma * g / range;
    p.x += step * rx;
    p.y += step * ry;
    p.z += step * rz;
  }
  return noisy;
}

double
medianPixelSpacing(const pcl::PointCloud<pcl::PointXYZ>& cloud)
{
  std::vector<double> spacing;
  for (unsigned v = 0; v < cloud.height; ++v)
    for (unsigned u = 0; u + 1 < cloud.width; ++u) {
      const pcl::PointXYZ& a = cloud.at(u, v);
      const pcl::PointXYZ& b = cloud.at(u + 1, v);
      if (!std::isfinite(a.z) || !std::isfinite(b.z))
        continue;
      const double dx = a.x - b.x, dy = a.y - b.y, dz = a.z - b.z;
      spacing.push_back(std::sqrt(dx * dx + dy * dy + dz * dz));
    }
  return spacing.empty() ? 0.0 : median(std::move(spacing));
}

double
medianDepth(const pcl::PointCloud<pcl::PointXYZ>& cloud)
{
  std::vector<double> z;
  for (const pcl::PointXYZ& p : cloud.points)
    if (std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z))
      z.push_back(p.z);
  return z.empty() ? 0.0 : median(std::move(z));
}

namespace
{
/// The intrinsics of a real frame: for a depth PNG those of the intrinsics.txt beside it or in
/// its parent folder, else the defaults.
DepthIntrinsics
frameIntrinsics(const std::string& path)
{
  namespace fs = std::filesystem;
  DepthIntrinsics intrinsics;
  const fs::path beside = fs::path(path).parent_path() / "intrinsics.txt";
  const fs::path above = fs::path(path).parent_path().parent_path() / "intrinsics.txt";
  if (io::isDepthImagePath(path)) {
    if (fs::exists(beside))
      intrinsics = readIntrinsics(beside.string());
    else if (fs::exists(above))
      intrinsics = readIntrinsics(above.string());
  }
  return intrinsics;
}
} // namespace

pcl::PointCloud<pcl::PointXYZ>
loadXyzFrame(const std::string& path)
{
  return io::xyzFromBlob(io::loadFrame(path, frameIntrinsics(path)), path);
}

double
frameDepthScale(const std::string& path)
{
  return frameIntrinsics(path).depth_scale;
}

pcl::PointCloud<pcl::PointXYZ>
depthImageOutput(const pcl::PointCloud<pcl::PointXYZ>& input, const pcl::PointCloud<pcl::PointXYZ>& filtered,
                 double depth_scale, bool z_only)
{
  DepthClamping clamping;
  const DepthImage image = z_only ? cloudToDepthImage(filtered, depth_scale, &clamping)
                                  : cloudToDepthImage(input, filtered, depth_scale, &clamping);
  pcl::PointCloud<pcl::PointXYZ> out = filtered;
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (std::size_t i = 0; i < out.size(); ++i) {
    pcl::PointXYZ& o = out[i];
    if (image.values[i] == 0) {
      o.x = o.y = o.z = nan;
      continue;
    }
    // The ray of the input point (of the filtered one where the input has none).
    const pcl::PointXYZ& p = std::isfinite(input[i].z) && input[i].z != 0.0f ? input[i] : filtered[i];
    const double scale = image.values[i] / depth_scale / p.z;
    o.x = static_cast<float>(p.x * scale);
    o.y = static_cast<float>(p.y * scale);
    o.z = static_cast<float>(image.values[i] / depth_scale);
  }
  return out;
}

void
setRegistryField(const std::string& item, FilterParameters& p)
{
  const std::size_t eq = item.find('=');
  const ParameterEntry* entry = eq == std::string::npos ? nullptr : findParameter(item.substr(0, eq));
  if (!entry)
    throw std::invalid_argument("expected NAME=VALUE with NAME a field of FilterParameters (the field table of "
                                "docs/method.md), e.g. patch_edge_gate=0");
  setParameterFromText(*entry, p, item.substr(eq + 1));
  checkParameter(*entry, p);
}

} // namespace bench
} // namespace tools
} // namespace range_nlm
