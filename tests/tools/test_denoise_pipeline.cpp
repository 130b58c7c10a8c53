// range_nlm_denoise over a directory reads the next frame and writes the previous result while it
// filters: the outputs, the order of the messages and the frame each error names are those of
// frames read, filtered and written one at a time.
#include "test_support.h"

#include <pcl/io/pcd_io.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <unistd.h>
#include <vector>

namespace fs = std::filesystem;
using namespace range_nlm;

namespace
{

constexpr int kFrames = 10, kWidth = 64, kHeight = 48;
const std::string kOptions = "--search-window 5 --patch 3";

std::string
frameName(int k)
{
  char name[16];
  std::snprintf(name, sizeof name, "f%02d.pcd", k);
  return name;
}

/// Noisy frames of a step that moves a column per frame, with holes.
void
writeFrame(const fs::path& dir, int k)
{
  auto cloud = test::makeCloud(kWidth, kHeight, test::step(kWidth / 3 + k, 1.0, 1.3), 0.004, 700 + k);
  test::punchHoles(cloud, 0.03, 800 + k);
  pcl::io::savePCDFileBinary((dir / frameName(k)).string(), cloud);
}

/// A frame that cannot be read: its body cut in half.
void
truncateFrame(const fs::path& path)
{
  fs::resize_file(path, fs::file_size(path) / 2);
}

/// The lines of `output` that report a frame ("NAME: ..."), as the names, in order.
std::vector<std::string>
reportedFrames(const std::string& output)
{
  std::vector<std::string> names;
  std::istringstream lines(output);
  std::string line;
  while (std::getline(lines, line))
    if (line.size() > 5 && line.compare(0, 1, "f") == 0 && line.find(".pcd: ") != std::string::npos)
      names.push_back(line.substr(0, line.find(": ")));
  return names;
}

std::vector<std::string>
filesOf(const fs::path& dir)
{
  std::vector<std::string> names;
  for (const auto& entry : fs::directory_iterator(dir))
    names.push_back(entry.path().filename().string());
  std::sort(names.begin(), names.end());
  return names;
}

class DenoisePipeline : public ::testing::Test
{
protected:
  void SetUp() override
  {
    root_ = fs::temp_directory_path() / ("range_nlm_pipeline_" + std::to_string(::getpid()) + "_" +
                                         ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(root_);
    fs::create_directories(in());
    for (int k = 0; k < kFrames; ++k)
      writeFrame(in(), k);
  }
  void TearDown() override { fs::remove_all(root_); }
  fs::path in() const { return root_ / "in"; }

  fs::path root_;
};

} // namespace

// The oracle of a temporal run with radius 1: the output of frame t depends only on frames
// t - 1, t, t + 1, so a run over a directory of just those frames gives it. A bad frame in the
// middle is skipped (--keep-going) with an all-NaN stand-in, in the window runs as in the long one.
TEST_F(DenoisePipeline, TemporalRunWithBadFrameEqualsRunsOverEachWindow)
{
  constexpr int kBad = 4;
  truncateFrame(in() / frameName(kBad));
  const fs::path out = root_ / "out";
  const test::CommandResult r = test::runDenoise("--input-dir " + in().string() + " --output-dir " + out.string() +
                                                 " --temporal-radius 1 --keep-going " + kOptions);
  ASSERT_EQ(r.status, 3) << r.output;
  std::vector<std::string> expected_names;
  for (int k = 0; k < kFrames; ++k)
    if (k != kBad)
      expected_names.push_back(frameName(k));
  EXPECT_EQ(reportedFrames(r.output), expected_names) << r.output;
  EXPECT_EQ(filesOf(out), expected_names);
  EXPECT_NE(r.output.find("1 frame(s) could not be read and were skipped:\n  '" + (in() / frameName(kBad)).string() +
                          "': truncated PCD body"),
            std::string::npos)
      << r.output;

  for (int t = 0; t < kFrames; ++t) {
    if (t == kBad)
      continue;
    const fs::path window = root_ / ("window" + std::to_string(t)), window_out = root_ / ("window_out" + std::to_string(t));
    fs::create_directories(window);
    for (int k = std::max(0, t - 1); k <= std::min(kFrames - 1, t + 1); ++k)
      fs::copy_file(in() / frameName(k), window / frameName(k));
    const test::CommandResult w = test::runDenoise("--input-dir " + window.string() + " --output-dir " +
                                                   window_out.string() + " --temporal-radius 1 --keep-going --quiet " +
                                                   kOptions);
    ASSERT_EQ(w.status, std::abs(t - kBad) == 1 ? 3 : 0) << w.output;
    EXPECT_TRUE(test::readBytes((out / frameName(t)).string()) == test::readBytes((window_out / frameName(t)).string()))
        << frameName(t) << " differs from the run over its window";
  }
}

// Static: every output equals a single-frame run on that frame; the bad frame is reported by
// name, in its place, however far the reader has read ahead.
TEST_F(DenoisePipeline, StaticRunWithBadFrameEqualsSingleFrameRuns)
{
  constexpr int kBad = 3;
  truncateFrame(in() / frameName(kBad));
  const fs::path out = root_ / "out", single = root_ / "single";
  fs::create_directories(single);
  const test::CommandResult r =
      test::runDenoise("--input-dir " + in().string() + " --output-dir " + out.string() + " --keep-going " + kOptions);
  ASSERT_EQ(r.status, 3) << r.output;
  for (int k = 0; k < kFrames; ++k) {
    const std::string name = frameName(k);
    const test::CommandResult s =
        test::runDenoise((in() / name).string() + " " + (single / name).string() + " --quiet " + kOptions);
    if (k == kBad) {
      EXPECT_EQ(s.status, 1) << s.output;
      EXPECT_FALSE(fs::exists(out / name));
      continue;
    }
    ASSERT_EQ(s.status, 0) << s.output;
    EXPECT_TRUE(test::readBytes((out / name).string()) == test::readBytes((single / name).string()))
        << name << " differs from the single-frame run";
  }
}

// Without --keep-going the first bad frame stops the run, and it is the one named: the frame read
// ahead after it (bad too, in another way) is not reported, every frame before it is written and
// none after it.
TEST_F(DenoisePipeline, FirstUnreadableFrameIsTheOneReported)
{
  truncateFrame(in() / frameName(5));
  std::ofstream(in() / frameName(6), std::ios::trunc) << "not a PCD file\n";
  const fs::path out = root_ / "out";
  const test::CommandResult r =
      test::runDenoise("--input-dir " + in().string() + " --output-dir " + out.string() + " " + kOptions);
  EXPECT_EQ(r.status, 1) << r.output;
  EXPECT_NE(r.output.find("range_nlm_denoise: error: '" + (in() / frameName(5)).string() + "': truncated PCD body"),
            std::string::npos)
      << r.output;
  EXPECT_EQ(r.output.find(frameName(6)), std::string::npos) << r.output;
  const std::vector<std::string> before{frameName(0), frameName(1), frameName(2), frameName(3), frameName(4)};
  EXPECT_EQ(reportedFrames(r.output), before) << r.output;
  EXPECT_EQ(filesOf(out), before);
}

// An output that cannot be written in the middle of the run (its name is taken by a directory):
// the error names that output, every frame before it is complete and equal to a clean run's, no
// later frame is written (although the filter may have gone on to it) and no temporary file is
// left. Static and temporal.
TEST_F(DenoisePipeline, UnwritableOutputMidRunIsReportedWithItsName)
{
  constexpr int kBlocked = 5;
  for (const std::string extra : {"", "--temporal-radius 1"}) {
    SCOPED_TRACE(extra);
    const fs::path clean = root_ / "clean", out = root_ / "out";
    fs::remove_all(clean);
    fs::remove_all(out);
    const test::CommandResult c = test::runDenoise("--input-dir " + in().string() + " --output-dir " + clean.string() +
                                                   " --quiet " + kOptions + " " + extra);
    ASSERT_EQ(c.status, 0) << c.output;
    fs::create_directories(out / frameName(kBlocked));
    const test::CommandResult r = test::runDenoise("--input-dir " + in().string() + " --output-dir " + out.string() +
                                                   " " + kOptions + " " + extra);
    EXPECT_EQ(r.status, 1) << r.output;
    EXPECT_NE(r.output.find("range_nlm_denoise: error: '" + (out / frameName(kBlocked)).string() + "': is a directory"),
              std::string::npos)
        << r.output;
    std::vector<std::string> before;
    for (int k = 0; k < kBlocked; ++k)
      before.push_back(frameName(k));
    EXPECT_EQ(reportedFrames(r.output), before) << r.output;
    std::vector<std::string> files = before;
    files.push_back(frameName(kBlocked)); // the directory
    EXPECT_EQ(filesOf(out), files);
    for (const std::string& name : before)
      EXPECT_TRUE(test::readBytes((out / name).string()) == test::readBytes((clean / name).string()))
          << name << " differs from the clean run";
  }
}

// --memory-limit counts the frame read ahead and the frame written behind of a directory run: the
// same frame needs more there than in a single-frame run.
TEST_F(DenoisePipeline, MemoryLimitCountsTheFramesInFlight)
{
  auto needed = [](const std::string& output) {
    const std::string mark = "frame needs about ";
    const std::size_t at = output.find(mark);
    return at == std::string::npos ? -1L : std::stol(output.substr(at + mark.size()));
  };
  // A frame large enough for the difference to show in whole MB.
  const fs::path big = root_ / "big";
  fs::create_directories(big);
  auto cloud = test::makeCloud(1000, 1000, test::plane(Eigen::Vector3d(0, 0, 1), 1.0), 0.004, 1);
  pcl::io::savePCDFileBinary((big / "big.pcd").string(), cloud);
  const test::CommandResult single = test::runDenoise((big / "big.pcd").string() + " " +
                                                      (root_ / "single.pcd").string() + " --memory-limit 1");
  const test::CommandResult directory = test::runDenoise("--input-dir " + big.string() + " --output-dir " +
                                                         (root_ / "out").string() + " --memory-limit 1");
  ASSERT_EQ(single.status, 1) << single.output;
  ASSERT_EQ(directory.status, 1) << directory.output;
  ASSERT_GT(needed(single.output), 0) << single.output;
  EXPECT_GT(needed(directory.output), needed(single.output)) << single.output << directory.output;
}
