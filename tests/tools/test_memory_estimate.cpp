// range_nlm_denoise's estimate of the memory a frame needs (what --memory-limit compares) against
// the peak resident set of real runs on a 1280 x 960 frame: for every parameter that changes the
// memory of a run, the estimate is at least the measured peak (above the tool's own, measured on a
// tiny frame) and not far above it.
#include "test_support.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <regex>
#include <string>
#include <vector>

#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

namespace fs = std::filesystem;
using namespace range_nlm;

namespace
{

class MemoryEstimate : public ::testing::Test
{
protected:
  static void SetUpTestSuite()
  {
    dir_ = fs::temp_directory_path() / ("range_nlm_memory_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    // Active-stereo noise: the automatic dilation filters the frame in phases, as a depth camera's.
    const std::string synth = "--noise stereo -q --output-dir ";
    const std::string big = (dir_ / "big").string(), tiny = (dir_ / "tiny").string();
    ASSERT_EQ(test::runTool("range_nlm_synth", synth + big + " --frames 3 --width 1280 --height 960").status, 0);
    ASSERT_EQ(test::runTool("range_nlm_synth", synth + tiny + " --frames 1 --width 32 --height 24").status, 0);
  }
  static void TearDownTestSuite() { fs::remove_all(dir_); }

  static std::string frame(const std::string& set, int k)
  {
    return (dir_ / set / "noisy" / ("frame_000" + std::to_string(k) + ".pcd")).string();
  }
  static std::vector<std::string> words(const std::string& text)
  {
    std::vector<std::string> out;
    std::string word;
    for (const char c : text + " ")
      if (c == ' ') {
        if (!word.empty())
          out.push_back(word);
        word.clear();
      } else {
        word += c;
      }
    return out;
  }
  /// The peak resident set, bytes, of range_nlm_denoise with `args`.
  static long long peakOf(const std::string& args)
  {
    std::vector<std::string> argv{std::string(RANGE_NLM_TOOLS_DIR) + "/range_nlm_denoise"};
    for (const std::string& w : words(args + " -q"))
      argv.push_back(w);
    const int pid = test::startProcess(argv, (dir_ / "run.log").string());
    int status = 0;
    rusage usage{};
    if (::wait4(pid, &status, 0, &usage) != pid || !WIFEXITED(status) || WEXITSTATUS(status) != 0) {
      ADD_FAILURE() << args << ":\n" << test::readBytes((dir_ / "run.log").string());
      return 0;
    }
    return static_cast<long long>(usage.ru_maxrss) * 1024;
  }
  /// The estimate, bytes, the tool gives for a frame of the run `args`: what it names when
  /// --memory-limit 1 refuses the frame (rounded up to MB).
  static long long estimateOf(const std::string& args)
  {
    const test::CommandResult r = test::runDenoise(args + " -q --memory-limit 1");
    std::smatch m;
    if (r.status != 1 || !std::regex_search(r.output, m, std::regex("needs about ([0-9]+) MB"))) {
      ADD_FAILURE() << args << ":\n" << r.output;
      return 0;
    }
    return std::stoll(m[1]) << 20;
  }
  static fs::path dir_;
};

fs::path MemoryEstimate::dir_;

} // namespace

TEST_F(MemoryEstimate, CoversTheMeasuredPeakOfEveryParameterThatChangesIt)
{
  if (test::kAddressSanitizer)
    GTEST_SKIP() << "AddressSanitizer's shadow memory and quarantine inflate the resident set";
  const std::string out = (dir_ / "out.pcd").string();
  const long long tool = peakOf(frame("tiny", 0) + " " + out);
  const std::string single = frame("big", 0) + " " + out + " ";
  const std::string directory =
      "--input-dir " + (dir_ / "big" / "noisy").string() + " --output-dir " + (dir_ / "out").string() + " ";
  const struct
  {
    std::string run, options;
  } runs[] = {{single, ""},
              {single, "--scales 3"},
              {single, "--uncertainty true"},
              {single, "--fill-holes 64"},
              {single, "--bandwidth-samples 100000"},
              {single, "--scales 3 --uncertainty true --fill-holes 64"},
              {directory, "--temporal-radius 1"},
              {directory, "--temporal-radius 1 --scales 3 --uncertainty true --fill-holes 64"}};
  for (const auto& run : runs) {
    fs::remove_all(dir_ / "out");
    const long long estimate = estimateOf(run.run + run.options);
    const long long frame_peak = peakOf(run.run + run.options) - tool;
    EXPECT_GE(estimate, frame_peak) << run.options << ": the estimate is below the measured peak";
    EXPECT_LE(estimate, frame_peak * 1.6) << run.options << ": the estimate is far above the measured peak";
    const std::string name = (run.run == single ? "frame " : "directory ") + run.options;
    std::printf("%-70s estimate %5lld MB, peak %5lld MB above the tool's %lld MB\n", name.c_str(), estimate >> 20,
                frame_peak >> 20, tool >> 20);
  }
}

// Each parameter that adds memory adds to the estimate, so that --memory-limit refuses a frame
// that the run would take past it.
TEST_F(MemoryEstimate, GrowsWithEveryParameterThatAddsMemory)
{
  const std::string single = frame("big", 0) + " " + (dir_ / "out.pcd").string() + " ";
  const long long plain = estimateOf(single);
  for (const char* options : {"--scales 2", "--uncertainty true", "--fill-holes 1", "--bandwidth-samples 100000",
                              "--pass radius=0 --pass radius=0"})
    EXPECT_GT(estimateOf(single + options), plain) << options;
  EXPECT_GT(estimateOf(single + "--scales 3 --uncertainty true --fill-holes 64"),
            estimateOf(single + "--scales 3 --uncertainty true"));
}

// The sample of the bandwidth estimate is bounded: 2^31 - 1 samples would take tens of GB.
TEST_F(MemoryEstimate, BandwidthSamplesBeyondTheirBoundAreAUsageError)
{
  const test::CommandResult r =
      test::runDenoise(frame("tiny", 0) + " " + (dir_ / "out.pcd").string() + " -q --bandwidth-samples 2147483647");
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_NE(r.output.find("bandwidth_samples = 2147483647 is invalid: must be at least 1, at most 100000"),
            std::string::npos)
      << r.output;
}
