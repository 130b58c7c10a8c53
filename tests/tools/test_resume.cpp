// --resume (tools/cli/resume.h): which outputs count as complete, against the size of the first
// input that can be read.
#include "cli/cli.h"
#include "cli/resume.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <unistd.h>
#include <vector>

using namespace range_nlm;
using namespace range_nlm::tools;
namespace fs = std::filesystem;

namespace
{

class Resume : public ::testing::Test
{
protected:
  void SetUp() override
  {
    dir_ = fs::temp_directory_path() / ("range_nlm_resume_" + std::to_string(::getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  std::string path(const std::string& name) const { return (dir_ / name).string(); }

  /// A width x height cloud of depths 1 m, written as binary PCD.
  std::string writeCloud(const std::string& name, unsigned width, unsigned height) const
  {
    pcl::PointCloud<pcl::PointXYZ> cloud(width, height, pcl::PointXYZ(0.1f, 0.2f, 1.0f));
    io::saveCloudAtomic(path(name), cloud);
    return path(name);
  }

  fs::path dir_;
};

} // namespace

TEST_F(Resume, AnOutputIsFinishedOnlyIfItIsAReadableFrameOfTheSize)
{
  const DepthIntrinsics intrinsics;
  const std::string complete = writeCloud("complete.pcd", 8, 6);
  EXPECT_TRUE(isFinishedOutput(complete, false, intrinsics, 8, 6));
  EXPECT_FALSE(isFinishedOutput(complete, false, intrinsics, 6, 8));
  EXPECT_FALSE(isFinishedOutput(path("missing.pcd"), false, intrinsics, 8, 6));

  // An interrupted write: the header and half of the points (the file goes on with padding
  // after the points, so the cut is made inside them).
  std::ifstream in(complete, std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::size_t body = bytes.find("DATA binary\n") + std::string("DATA binary\n").size();
  ASSERT_LT(body, bytes.size());
  std::ofstream(path("truncated.pcd"), std::ios::binary) << bytes.substr(0, body + 8 * 6 * 16 / 2);
  EXPECT_FALSE(isFinishedOutput(path("truncated.pcd"), false, intrinsics, 8, 6));
}

TEST_F(Resume, ADepthImageOutputIsCheckedAsOne)
{
  const DepthIntrinsics intrinsics;
  const pcl::PointCloud<pcl::PointXYZ> cloud(8, 6, pcl::PointXYZ(0.0f, 0.0f, 1.5f));
  saveDepthPng(path("out.png"), cloud, intrinsics.depth_scale);
  EXPECT_TRUE(isFinishedOutput(path("out.png"), true, intrinsics, 8, 6));
  EXPECT_FALSE(isFinishedOutput(path("out.png"), true, intrinsics, 8, 5));
  EXPECT_FALSE(isFinishedOutput(path("out.png"), false, intrinsics, 8, 6)); // not a PCD file
}

TEST_F(Resume, OutputsAreCheckedAgainstTheFirstInputThatCanBeRead)
{
  const std::vector<std::string> inputs = {path("missing.pcd"), writeCloud("in1.pcd", 8, 6),
                                           writeCloud("in2.pcd", 8, 6), writeCloud("in3.pcd", 8, 6)};
  fs::create_directories(dir_ / "out");
  const std::vector<std::string> outputs = {writeCloud("out/in0.pcd", 8, 6), writeCloud("out/in1.pcd", 8, 6),
                                            writeCloud("out/in2.pcd", 4, 3), path("out/in3.pcd")};
  FrameSize size;
  const std::vector<bool> finished =
      finishedOutputs(inputs, outputs, {0, 4}, false, DepthIntrinsics(), io::MemoryBudget(), size);
  // Output 0 is complete, but its input cannot be read: it is filtered (and reported) again.
  EXPECT_EQ(finished, (std::vector<bool>{false, true, false, false}));
  EXPECT_EQ(size.width, 8u);
  EXPECT_EQ(size.height, 6u);

  FrameSize shard_size;
  EXPECT_EQ(finishedOutputs(inputs, outputs, {1, 3}, false, DepthIntrinsics(), io::MemoryBudget(), shard_size),
            (std::vector<bool>{true, false}));
}
