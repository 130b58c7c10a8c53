// What range_nlm_denoise reports about frames and directories it cannot handle as asked: a frame
// written unchanged is not counted as filtered, a frame whose coordinates the float arithmetic
// cannot filter is reported as unfiltered (never "filtered" with its points unchanged), an input
// directory that cannot be listed says so and why, and a negative seed is refused by every tool.
#include "test_support.h"

#include <pcl/io/pcd_io.h>

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <limits>
#include <string>

#include <unistd.h>

namespace fs = std::filesystem;
using namespace range_nlm;

namespace
{

class ReportedProblems : public ::testing::Test
{
protected:
  void SetUp() override
  {
    dir_ = fs::temp_directory_path() / ("range_nlm_reported_" + std::to_string(::getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override
  {
    std::error_code ec;
    fs::permissions(dir_ / "locked", fs::perms::owner_all, ec);
    fs::remove_all(dir_);
  }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  /// A noisy 40 x 30 plane, its coordinates times `scale`.
  void writeFrame(const std::string& name, double scale = 1.0) const
  {
    auto cloud = test::makeCloud(40, 30, test::plane({0.1, 0.0, 1.0}, 1.0), 0.003, 11);
    for (auto& p : cloud)
      p.x = float(p.x * scale), p.y = float(p.y * scale), p.z = float(p.z * scale);
    ASSERT_EQ(pcl::io::savePCDFileBinary(path(name), cloud), 0);
  }
  fs::path dir_;
};

/// Valid points of `a` whose coordinates differ in `b` (the largest count if either cannot be read).
std::size_t
changedPoints(const std::string& a, const std::string& b)
{
  pcl::PointCloud<pcl::PointXYZ> before, after;
  if (pcl::io::loadPCDFile(a, before) != 0 || pcl::io::loadPCDFile(b, after) != 0 || before.size() != after.size())
    return std::numeric_limits<std::size_t>::max();
  std::size_t changed = 0;
  for (std::size_t i = 0; i < before.size(); ++i)
    changed += std::isfinite(before[i].z) &&
               !(before[i].x == after[i].x && before[i].y == after[i].y && before[i].z == after[i].z);
  return changed;
}

} // namespace

// A frame that could not be filtered is written unchanged and counted in "unfiltered", not in
// "frames_filtered".
TEST_F(ReportedProblems, FrameWrittenUnchangedIsNotCountedAsFiltered)
{
  fs::create_directories(dir_ / "in");
  writeFrame("in/a.pcd");
  pcl::PointCloud<pcl::PointXYZ> nan(40, 30);
  for (auto& p : nan)
    p.x = p.y = p.z = std::numeric_limits<float>::quiet_NaN();
  ASSERT_EQ(pcl::io::savePCDFileBinary(path("in/b.pcd"), nan), 0);
  const test::CommandResult r =
      test::runDenoise("--input-dir " + path("in") + " --output-dir " + path("out") + " --json --iterations 1");
  ASSERT_EQ(r.status, 0) << r.output;
  const nlohmann::json summary = test::jsonLine(r.output);
  EXPECT_EQ(summary["frames"], 2) << r.output;
  EXPECT_EQ(summary["unfiltered"], 1) << r.output;
  EXPECT_EQ(summary["frames_filtered"], 1) << r.output;
  EXPECT_EQ(summary["outputs"][1]["filtered"], false) << r.output;
}

// Coordinates scaled to 1e30 (or 1e-30) of a sensor's: their squares overflow (underflow) the
// float arithmetic. Such a frame is reported as not filtered, with a message naming the
// coordinates' magnitude, never as filtered with its points unchanged; a frame at an ordinary
// scale (1e3 or 1e-3 of metres: millimetres, kilometres) is filtered.
TEST_F(ReportedProblems, CoordinatesTheArithmeticCannotFilterAreReportedUnfiltered)
{
  const struct
  {
    double scale;
    const char* options;
  } runs[] = {
      {1e30, ""},
      {1e-30, ""},
      {1e20, ""},
      {1e-20, ""},
      {1e30, "--iterations 1 --dilation 2"}, // the phases of a dilation alone
      {1e-30, "--scales 2"},
  };
  for (const auto& run : runs) {
    SCOPED_TRACE(std::to_string(run.scale) + " " + run.options);
    writeFrame("far.pcd", run.scale);
    const test::CommandResult r =
        test::runDenoise(path("far.pcd") + " " + path("far_out.pcd") + " --json " + run.options);
    ASSERT_EQ(r.status, 0) << r.output;
    const nlohmann::json summary = test::jsonLine(r.output);
    const nlohmann::json& frame = summary["outputs"][0];
    EXPECT_EQ(frame["filtered"], false) << r.output;
    EXPECT_EQ(summary["unfiltered"], 1) << r.output;
    EXPECT_EQ(summary["frames_filtered"], 0) << r.output;
    EXPECT_NE(frame.value("reason", "").find("coordinates reach"), std::string::npos) << r.output;
    EXPECT_EQ(changedPoints(path("far.pcd"), path("far_out.pcd")), 0u);
  }
  for (const double scale : {1e3, 1e-3}) {
    SCOPED_TRACE(scale);
    writeFrame("near.pcd", scale);
    const test::CommandResult r = test::runDenoise(path("near.pcd") + " " + path("near_out.pcd") + " --json");
    ASSERT_EQ(r.status, 0) << r.output;
    const nlohmann::json summary = test::jsonLine(r.output);
    EXPECT_EQ(summary["outputs"][0]["filtered"], true) << r.output;
    EXPECT_TRUE(summary["outputs"][0]["distance_bandwidth"].is_number()) << r.output;
    EXPECT_GT(changedPoints(path("near.pcd"), path("near_out.pcd")), 0u);
  }
}

// An input directory that cannot be listed is not "a directory holding no frames": the message
// says it cannot be read, and why.
TEST_F(ReportedProblems, InputDirectoryThatCannotBeListedSaysWhy)
{
  // A path through a file: ENOTDIR.
  writeFrame("a.pcd");
  test::CommandResult r = test::runDenoise("--input-dir " + path("a.pcd/in") + " --output-dir " + path("out"));
  EXPECT_EQ(r.status, 1) << r.output;
  EXPECT_EQ(r.output,
            "range_nlm_denoise: error: cannot read input directory '" + path("a.pcd/in") + "': Not a directory\n");

  // A directory its user may not read: EACCES. Root reads it anyway, so where the test runs as
  // root the tool runs as the unprivileged user `nobody`.
  fs::create_directories(dir_ / "locked");
  writeFrame("locked/a.pcd");
  fs::permissions(dir_ / "locked", fs::perms::none);
  fs::permissions(dir_, fs::perms::all); // `nobody` reaches it
  std::string as_user;
  if (::geteuid() == 0) {
    if (test::runCommand("setpriv --reuid=nobody --regid=nogroup --clear-groups true").status != 0)
      GTEST_SKIP() << "runs as root and cannot run a command as the user nobody (setpriv), under which a "
                      "directory of mode 000 cannot be listed";
    as_user = "setpriv --reuid=nobody --regid=nogroup --clear-groups ";
  }
  r = test::runCommand(as_user + RANGE_NLM_TOOLS_DIR "/range_nlm_denoise --input-dir " + path("locked") +
                       " --output-dir " + path("locked_out"));
  EXPECT_EQ(r.status, 1) << r.output;
  EXPECT_EQ(r.output,
            "range_nlm_denoise: error: cannot read input directory '" + path("locked") + "': Permission denied\n");
  // Nothing inside it can be looked up either.
  r = test::runCommand(as_user + RANGE_NLM_TOOLS_DIR "/range_nlm_denoise --input-dir " + path("locked/sub") +
                       " --output-dir " + path("locked_out"));
  EXPECT_EQ(r.status, 1) << r.output;
  EXPECT_EQ(r.output,
            "range_nlm_denoise: error: cannot read input directory '" + path("locked/sub") + "': Permission denied\n");
}

// boost reads "-1" into an unsigned option as 2^64 - 1: every tool with a seed refuses a negative
// one (and anything else that is not a 64-bit unsigned integer), naming the option and the value.
TEST_F(ReportedProblems, NegativeSeedIsRefusedByEveryTool)
{
  writeFrame("in.pcd");
  for (const char* seed : {"-1", "-18446744073709551615", "18446744073709551616", "1e3"}) {
    SCOPED_TRACE(seed);
    const std::string refusal = std::string("the argument ('") + seed + "') for option '--seed' is invalid";
    test::CommandResult r = test::runDenoise(path("in.pcd") + " " + path("out.pcd") + " -q --seed " + seed);
    EXPECT_EQ(r.status, 2) << r.output;
    EXPECT_NE(r.output.find(refusal), std::string::npos) << r.output;
    EXPECT_FALSE(fs::exists(path("out.pcd")));
    r = test::runTool("range_nlm_synth", "--output-dir " + path("synth") + " --frames 1 --seed " + seed);
    EXPECT_EQ(r.status, 2) << r.output;
    EXPECT_NE(r.output.find(refusal), std::string::npos) << r.output;
    r = test::runDenoise(path("in.pcd") + " " + path("out.pcd") + " -q --pass seed=" + seed);
    EXPECT_EQ(r.status, 2) << r.output;
  }
  EXPECT_EQ(test::runDenoise(path("in.pcd") + " " + path("out.pcd") + " -q --seed 18446744073709551615").status, 0);
}
