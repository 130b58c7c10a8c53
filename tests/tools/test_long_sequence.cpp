// range_nlm_denoise over long sequences: memory is bounded by the temporal window, not by the
// length of the sequence.
#include "test_support.h"

#include <pcl/io/pcd_io.h>

#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <fcntl.h>
#include <filesystem>
#include <string>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>
#include <vector>

namespace fs = std::filesystem;
using namespace range_nlm;

namespace
{
/// The two sequence lengths compared. Under AddressSanitizer, which slows the filter down about
/// tenfold, the sequences are shorter; the growth they would show if frames were kept is still
/// far above the bound.
constexpr int kShortFrames = test::kAddressSanitizer ? 40 : 100;
constexpr int kLongFrames = test::kAddressSanitizer ? 120 : 300;
/// Peak resident memory of one run, in KiB. Measured for 64 x 48 frames with --temporal-radius 1:
/// 28 MiB in a Release build (of which the frames held are a few hundred KiB, the rest is code and
/// PCL's libraries), 105 MiB with AddressSanitizer (shadow memory, allocator) and a 1 MiB quarantine.
constexpr long kPeakBoundKiB = test::kAddressSanitizer ? 192 * 1024 : 48 * 1024;
/// Allowed difference between the short and the long sequence. Were frames kept, 80 more frames
/// of 64 x 48 would add over 6 MiB (a 36 KiB input blob plus a 48 KiB PointXYZ cloud each, at
/// least), 200 more over 16 MiB.
constexpr long kGrowthBoundKiB = 3 * 1024;

struct MeasuredRun
{
  int status = -1;
  long peak_kib = 0;
};

/// Runs the tool (output discarded) and reads the child's peak RSS from wait4().
MeasuredRun
runMeasured(const std::vector<std::string>& args)
{
  std::vector<std::string> all{std::string(RANGE_NLM_TOOLS_DIR) + "/range_nlm_denoise"};
  all.insert(all.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (std::string& a : all)
    argv.push_back(&a[0]);
  argv.push_back(nullptr);
  const pid_t pid = ::fork();
  if (pid == 0) {
    const int fd = ::open("/dev/null", O_WRONLY);
    ::dup2(fd, 1);
    ::dup2(fd, 2);
    if (test::kAddressSanitizer) // freed memory must not pile up in the quarantine during this test
      ::setenv("ASAN_OPTIONS", "quarantine_size_mb=1:detect_leaks=0", 1);
    ::execv(argv[0], argv.data());
    ::_exit(127);
  }
  MeasuredRun run;
  int status = 0;
  struct rusage usage = {};
  if (::wait4(pid, &status, 0, &usage) == pid) {
    run.status = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    run.peak_kib = usage.ru_maxrss; // KiB on Linux
  }
  return run;
}

std::string
frameName(int k)
{
  char name[16];
  std::snprintf(name, sizeof name, "f%03d.pcd", k);
  return name;
}
} // namespace

TEST(LongSequence, PeakMemoryStaysBoundedAndDoesNotGrowWithTheSequence)
{
  const fs::path root = fs::temp_directory_path() / ("range_nlm_long_" + std::to_string(::getpid()));
  fs::remove_all(root);
  fs::create_directories(root / "all");
  fs::create_directories(root / "short");
  for (int k = 0; k < kLongFrames; ++k) {
    auto cloud = test::makeCloud(64, 48, test::step(20 + k % 20, 1.0, 1.25), 0.004, 1000 + k);
    test::punchHoles(cloud, 0.02, 2000 + k);
    const fs::path path = root / "all" / frameName(k);
    pcl::io::savePCDFileBinary(path.string(), cloud);
    if (k < kShortFrames)
      fs::create_hard_link(path, root / "short" / frameName(k));
  }
  auto measure = [&](const std::string& in, const std::string& out) {
    return runMeasured({"--input-dir", (root / in).string(), "--output-dir", (root / out).string(),
                        "--temporal-radius", "1", "--search-window", "5", "--patch", "3", "--threads", "1",
                        "--quiet"});
  };
  const MeasuredRun short_run = measure("short", "out_short");
  const MeasuredRun long_run = measure("all", "out_long");
  ASSERT_EQ(short_run.status, 0);
  ASSERT_EQ(long_run.status, 0);
  int outputs = 0;
  for (const auto& entry : fs::directory_iterator(root / "out_long"))
    outputs += entry.path().extension() == ".pcd";
  EXPECT_EQ(outputs, kLongFrames);
  RecordProperty("peak_kib_short", std::to_string(short_run.peak_kib));
  RecordProperty("peak_kib_long", std::to_string(long_run.peak_kib));
  std::printf("peak RSS: %ld KiB for %d frames, %ld KiB for %d frames\n", short_run.peak_kib, kShortFrames,
              long_run.peak_kib, kLongFrames);
  EXPECT_GT(long_run.peak_kib, 0);
  EXPECT_LT(long_run.peak_kib, kPeakBoundKiB);
  EXPECT_LT(long_run.peak_kib - short_run.peak_kib, kGrowthBoundKiB)
      << "peak memory grows with the sequence: " << short_run.peak_kib << " KiB for " << kShortFrames
      << " frames, " << long_run.peak_kib << " KiB for " << kLongFrames;
  fs::remove_all(root);
}
