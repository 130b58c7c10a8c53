// range_nlm_denoise's depth-image output (tools/cli/frame_output.cpp): a PNG output is the
// library's encoding of the filtered frame, each point re-projected onto its pixel's ray
// (cloudToDepthImage(input, filtered, ...)), of the very points a PCD output holds -- in
// single-frame and temporal directory runs -- and the same bytes for any thread count.
#include "test_support.h"

#include <range_nlm/io/depth_image.h>

#include <pcl/io/pcd_io.h>

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <unistd.h>

namespace fs = std::filesystem;
using namespace range_nlm;
using Cloud = pcl::PointCloud<pcl::PointXYZ>;

namespace
{

constexpr int kWidth = 64, kHeight = 48;
constexpr double kFocal = 60.0, kScale = 5000.0;

class FrameOutput : public ::testing::Test
{
protected:
  void SetUp() override
  {
    dir_ = fs::temp_directory_path() / ("range_nlm_frame_output_" + std::to_string(::getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_ / "in");
    std::ofstream(path("intrinsics.txt")) << "fx " << kFocal << "\nfy " << kFocal << "\ncx " << (kWidth - 1) / 2.0
                                          << "\ncy " << (kHeight - 1) / 2.0 << "\ndepth_scale " << kScale
                                          << "\nwidth " << kWidth << "\nheight " << kHeight << "\n";
    DepthIntrinsics k;
    k.fx = k.fy = kFocal;
    k.cx = (kWidth - 1) / 2.0;
    k.cy = (kHeight - 1) / 2.0;
    k.depth_scale = kScale;
    intrinsics_ = k;
    // Three frames of a tilted plane with a step, new noise each.
    for (int f = 0; f < 3; ++f) {
      const Cloud cloud = test::makeCloud(
          kWidth, kHeight,
          [](double a, double b, int u, int) { return (u < 40 ? 1.2 : 1.5) / (1.0 + 0.4 * a - 0.2 * b); }, 0.006,
          20 + f, kFocal);
      writeDepthPng(path("in/" + std::to_string(f) + ".png"), cloudToDepthImage(cloud, kScale));
    }
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }

  /// range_nlm_denoise with `args` and the test's intrinsics; the test fails if it does.
  void denoise(const std::string& args) const
  {
    const test::CommandResult r = test::runDenoise(args + " --intrinsics " + path("intrinsics.txt") + " -q");
    ASSERT_EQ(r.status, 0) << r.output;
  }

  /// The PNG output `png` is the library's re-projected encoding of the PCD output `pcd` of the
  /// same run over the input frame `input`; returns the z of the PCD output encoded as it is.
  DepthImage expectPngOfPcd(const std::string& input, const std::string& png, const std::string& pcd) const
  {
    Cloud filtered;
    EXPECT_EQ(pcl::io::loadPCDFile(pcd, filtered), 0) << pcd;
    const DepthImage expected = cloudToDepthImage(loadDepthPng(input, intrinsics_), filtered, kScale);
    EXPECT_EQ(readDepthPng(png).values, expected.values) << png;
    return cloudToDepthImage(filtered, kScale);
  }

  fs::path dir_;
  DepthIntrinsics intrinsics_;
};

} // namespace

TEST_F(FrameOutput, PngOutputIsTheReprojectedPcdOutput)
{
  denoise(path("in/1.png") + " " + path("one.png"));
  denoise(path("in/1.png") + " " + path("one.pcd"));
  const DepthImage z_only = expectPngOfPcd(path("in/1.png"), path("one.png"), path("one.pcd"));
  // The frame filtered alone moved along its normals: its z alone is another image.
  EXPECT_NE(z_only.values, readDepthPng(path("one.png")).values);
}

TEST_F(FrameOutput, TemporalPngOutputsAreTheReprojectedPcdOutputs)
{
  for (const std::string mode : {"--temporal-radius 1", "--temporal-radius 1 --recursive"}) {
    const std::string png = path("png" + std::to_string(mode.size())), pcd = path("pcd" + std::to_string(mode.size()));
    denoise("--input-dir " + path("in") + " --output-dir " + png + " --output-format png " + mode);
    denoise("--input-dir " + path("in") + " --output-dir " + pcd + " --output-format pcd " + mode);
    for (int f = 0; f < 3; ++f) {
      SCOPED_TRACE(mode + ", frame " + std::to_string(f));
      expectPngOfPcd(path("in/" + std::to_string(f) + ".png"), png + "/" + std::to_string(f) + ".png",
                     pcd + "/" + std::to_string(f) + ".pcd");
    }
  }
}

TEST_F(FrameOutput, PngOutputIsTheSameForOneTwoAndThreeThreads)
{
  for (int threads : {1, 2, 3})
    denoise(path("in/0.png") + " " + path("t" + std::to_string(threads) + ".png") + " --threads " +
            std::to_string(threads));
  const std::string one = test::readBytes(path("t1.png"));
  ASSERT_FALSE(one.empty());
  EXPECT_EQ(test::readBytes(path("t2.png")), one);
  EXPECT_EQ(test::readBytes(path("t3.png")), one);
}
