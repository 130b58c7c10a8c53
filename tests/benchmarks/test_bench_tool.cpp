// range_nlm_bench end to end: the rows it times and its option checks; and the way it times
// methods in turns (bench_support).
#include "bench_support.h"
#include "test_support.h"

#include <gtest/gtest.h>

#include <csignal>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <memory>
#include <stdexcept>
#include <string>

#include <fcntl.h>
#include <unistd.h>

using namespace range_nlm;
namespace bench = range_nlm::tools::bench;

TEST(BenchTool, NoDirectTimesTheFastPathAndThePeersOnly)
{
  if (test::kAddressSanitizer)
    GTEST_SKIP() << "under AddressSanitizer Eigen's aligned allocator differs between this build and "
                    "Debian's PCL, so the cloud pcl::MovingLeastSquares resizes cannot be freed here";
  const test::CommandResult r =
      test::runTool("range_nlm_bench", "--config static --preset paper --runs 1 --no-direct --json");
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("\"method\": \"range_nlm fast\""), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("\"method\": \"pcl FastBilateralFilterOMP\""), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("\"method\": \"pcl MovingLeastSquares\""), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("range_nlm direct"), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("\"error\""), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("\"median_ms\": 0,"), std::string::npos) << r.output;
}

// The table starts with the default configuration as users run it: static on the VGA frame, then
// temporal (radius 1) on whole frames with the static filter on its centre frame in the same
// rounds; --breakdown gives their phases as runFilter reports them, the dilated passes included.
TEST(BenchTool, DefaultConfigurationsComeFirstWithTheirPhases)
{
  const test::CommandResult r = test::runTool("range_nlm_bench", "--config preset --runs 1 --breakdown --json");
  ASSERT_EQ(r.status, 0) << r.output;
  const std::size_t static_row = r.output.find("\"config\": \"static default 9x9/3x3 640x480\"");
  const std::size_t temporal_row = r.output.find("\"config\": \"temporal default 9x9/3x3 r=1 640x480\"");
  ASSERT_NE(static_row, std::string::npos) << r.output;
  ASSERT_NE(temporal_row, std::string::npos) << r.output;
  EXPECT_LT(static_row, temporal_row);
  // The first result is the default static filter.
  const std::size_t first = r.output.find("\"results\": [{\"method\": \"range_nlm fast\", \"config\": \"static default");
  EXPECT_NE(first, std::string::npos) << r.output;
  EXPECT_NE(r.output.find("\"method\": \"range_nlm temporal fast\", \"config\": \"temporal default"), std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("\"method\": \"range_nlm fast\", \"config\": \"temporal default"), std::string::npos)
      << r.output;
  EXPECT_EQ(r.output.find("7x7/5x5"), std::string::npos) << r.output; // no paper configuration
  EXPECT_NE(r.output.find("\"name\": \"dilation (automatic: estimate, split into phases, merge)\""), std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("\"name\": \"normals 7x7 gated\""), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("\"name\": \"neighbour frames (2)\""), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("preset temporal fast (radius 1) vs 1.3 x static"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("preset fast vs FastBilateralFilterOMP on the sequence's centre frame"), std::string::npos)
      << r.output;
  EXPECT_EQ(r.output.find("\"error\""), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("\"median_ms\": 0,"), std::string::npos) << r.output;
}

TEST(BenchTool, RejectsContradictoryDirectOptions)
{
  const test::CommandResult r = test::runTool("range_nlm_bench", "--all --no-direct");
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_NE(r.output.find("--all and --no-direct"), std::string::npos) << r.output;
}

// --parameter sets any field of the parameter registry on top of the preset; the notes name every
// field that differs from the preset, and a bad name or value is refused by name before timing.
TEST(BenchTool, ParameterOptionSetsARegistryFieldOrIsRefusedByName)
{
  const test::CommandResult bad_name = test::runTool("range_nlm_bench", "--parameter no_such_field=1");
  EXPECT_EQ(bad_name.status, 2) << bad_name.output;
  EXPECT_NE(bad_name.output.find("--parameter 'no_such_field=1'"), std::string::npos) << bad_name.output;
  const test::CommandResult bad_value = test::runTool("range_nlm_bench", "--parameter patch_edge_gate=-1");
  EXPECT_EQ(bad_value.status, 2) << bad_value.output;
  EXPECT_NE(bad_value.output.find("patch_edge_gate"), std::string::npos) << bad_value.output;
  EXPECT_NE(bad_value.output.find("-1"), std::string::npos) << bad_value.output;
  const test::CommandResult not_a_number = test::runTool("range_nlm_bench", "--parameter outlier_sigmas=many");
  EXPECT_EQ(not_a_number.status, 2) << not_a_number.output;
  EXPECT_NE(not_a_number.output.find("outlier_sigmas"), std::string::npos) << not_a_number.output;
  if (test::kAddressSanitizer)
    GTEST_SKIP() << "under AddressSanitizer Eigen's aligned allocator differs between this build and "
                    "Debian's PCL, so the cloud pcl::MovingLeastSquares resizes cannot be freed here";
  const test::CommandResult r = test::runTool(
      "range_nlm_bench", "--config static --preset paper --runs 1 --no-direct --parameter outlier_sigmas=7.5");
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("preset 'paper': outlier_sigmas 7.5"), std::string::npos) << r.output;
}

namespace
{
/// A method for runInterleaved whose every call appends `letter` to the file at `log` and whose
/// call number `fail_at` (1-based) fails: by an exception, or by SIGKILL with `kill`.
bench::TimedMethod
loggingMethod(const std::string& log, char letter, int runs, bool warmup, int fail_at = 0, bool kill = false)
{
  bench::TimedMethod m;
  m.runs = runs;
  m.warmup = warmup;
  m.prepare = [=] {
    auto calls = std::make_shared<int>(0);
    return std::function<void()>([=] {
      const int fd = ::open(log.c_str(), O_WRONLY | O_APPEND);
      if (fd < 0 || ::write(fd, &letter, 1) != 1)
        throw std::runtime_error("cannot append to " + log);
      ::close(fd);
      if (++*calls == fail_at) {
        if (kill)
          ::raise(SIGKILL);
        throw std::runtime_error(std::string("call ") + std::to_string(fail_at) + " of " + letter + " failed");
      }
    });
  };
  return m;
}
} // namespace

// The methods take turns in the order given, round by round: a turn is the warm-up call (if
// any) and the timed call. A method that throws or is killed drops out with that reason; the
// others keep their turns and return a wall and a CPU time per timed call.
TEST(BenchInterleaving, MethodsTakeTurnsAndAFailureStaysWithItsMethod)
{
  const std::string log =
      (std::filesystem::temp_directory_path() / ("range_nlm_turns_" + std::to_string(::getpid()) + ".log")).string();
  std::ofstream(log).close();
  std::vector<bench::TimedMethod> methods{
    loggingMethod(log, 'A', 3, true), loggingMethod(log, 'B', 2, false),
    loggingMethod(log, 'C', 2, true), loggingMethod(log, 'D', 2, true, 2, true),
    loggingMethod(log, 'E', 3, true, 3)};
  methods[2].prepare = []() -> std::function<void()> { throw std::runtime_error("C cannot be prepared"); };
  const std::vector<bench::ChildResult> r = bench::runInterleaved(methods);
  ASSERT_EQ(r.size(), methods.size());

  std::ifstream in(log);
  const std::string order((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_EQ(order, "AABDDEE" "AABE" "AA");
  ASSERT_TRUE(r[0].ok) << r[0].error;
  ASSERT_EQ(r[0].values.size(), 6u); // 3 wall times, then 3 CPU times
  ASSERT_TRUE(r[1].ok) << r[1].error;
  ASSERT_EQ(r[1].values.size(), 4u);
  for (int k : {0, 1}) {
    EXPECT_GT(r[k].peak_rss_bytes, 0u);
    for (double v : r[k].values)
      EXPECT_GE(v, 0.0);
  }
  EXPECT_FALSE(r[2].ok);
  EXPECT_EQ(r[2].error, "C cannot be prepared");
  EXPECT_FALSE(r[3].ok);
  EXPECT_NE(r[3].error.find("killed by signal 9"), std::string::npos) << r[3].error;
  EXPECT_FALSE(r[4].ok);
  EXPECT_EQ(r[4].error, "call 3 of E failed");
  std::remove(log.c_str());
}
