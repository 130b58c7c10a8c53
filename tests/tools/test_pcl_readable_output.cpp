// Every kind of PCD file the tools write is read by PCL's own converter pcl_pcd2ply (pcl-tools):
// the fields are written packed, with no `_` padding fields, on which pcl_pcd2ply aborts.
#include "test_support.h"

#include <range_nlm/io/depth_image.h>

#include <pcl/io/pcd_io.h>
#include <pcl/point_types.h>

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <limits>
#include <string>
#include <vector>

#include <unistd.h>

namespace fs = std::filesystem;
using namespace range_nlm;

namespace
{
class PclReadableOutput : public ::testing::Test
{
protected:
  void SetUp() override
  {
    if (test::runCommand("command -v pcl_pcd2ply").status != 0)
      GTEST_SKIP() << "pcl_pcd2ply (Debian package pcl-tools) is not installed";
    dir_ = fs::temp_directory_path() /
           ("range_nlm_pcl_readable_" + std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()) +
            "_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    cloud_ = test::makeCloud(kWidth, kHeight, [](double, double, int u, int) { return u > 20 ? 1.0 : 1.1; }, 0.003, 3);
    // A 4 x 4 hole inside the frame, for --fill-holes.
    for (int v = 14; v < 18; ++v)
      for (int u = 10; u < 14; ++u)
        cloud_(u, v).x = cloud_(u, v).y = cloud_(u, v).z = std::numeric_limits<float>::quiet_NaN();
    cloud_.is_dense = false;
    pcl::io::savePCDFileBinary(path("in.pcd"), cloud_);
    pcl::PointCloud<pcl::PointXYZI> with_intensity(kWidth, kHeight);
    for (std::size_t i = 0; i < cloud_.size(); ++i) {
      with_intensity[i].x = cloud_[i].x, with_intensity[i].y = cloud_[i].y, with_intensity[i].z = cloud_[i].z;
      with_intensity[i].intensity = float(i);
    }
    with_intensity.is_dense = false;
    pcl::io::savePCDFileBinary(path("intensity.pcd"), with_intensity);
    writeDepthPng(path("in.png"), cloudToDepthImage(cloud_, 5000.0));
  }
  void TearDown() override
  {
    if (!dir_.empty())
      fs::remove_all(dir_);
  }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }

  /// pcl_pcd2ply converts `pcd`, exits 0, and its PLY holds every point of the frame.
  void expectConverts(const std::string& pcd) const
  {
    ASSERT_TRUE(fs::exists(pcd)) << pcd;
    const std::string ply = pcd.substr(0, pcd.size() - 4) + ".ply";
    const test::CommandResult r = test::runCommand("pcl_pcd2ply '" + pcd + "' '" + ply + "'");
    EXPECT_EQ(r.status, 0) << pcd << ":\n" << test::readBytes(pcd).substr(0, 300) << "\n" << r.output;
    const std::string header = test::readBytes(ply).substr(0, 1000);
    EXPECT_NE(header.find("element vertex " + std::to_string(kWidth * kHeight) + "\n"), std::string::npos)
        << ply << ":\n" << header;
    EXPECT_EQ(test::readBytes(pcd).substr(0, 400).find(" _"), std::string::npos) << "padding fields in " << pcd;
  }

  static constexpr int kWidth = 48;
  static constexpr int kHeight = 36;
  pcl::PointCloud<pcl::PointXYZ> cloud_;
  fs::path dir_;
};
} // namespace

TEST_F(PclReadableOutput, EveryPcdTheDenoiseToolWritesConverts)
{
  const std::vector<std::pair<std::string, std::string>> runs = {
      {"xyz.pcd", path("in.pcd")},
      {"xyzi.pcd", path("intensity.pcd")},
      {"uncertainty.pcd", path("in.pcd") + " --uncertainty true"},
      {"filled.pcd", path("in.pcd") + " --fill-holes 6"},
      {"filled_uncertainty.pcd", path("intensity.pcd") + " --fill-holes 6 --uncertainty true"},
      {"colorized.pcd", path("in.pcd") + " --colorize curvature"},
      {"colorized_uncertainty.pcd", path("in.pcd") + " --colorize curvature --uncertainty true"},
      {"depth.pcd", path("in.png")},
      {"depth_uncertainty.pcd", path("in.png") + " --uncertainty true"},
  };
  for (const auto& run : runs) {
    const std::string output = path(run.first);
    // The input first, the output second, then the options.
    const std::size_t space = run.second.find(' ');
    const std::string input = run.second.substr(0, space);
    const std::string options = space == std::string::npos ? "" : run.second.substr(space);
    const test::CommandResult r = test::runDenoise(input + " " + output + options + " --threads 1 -q");
    ASSERT_EQ(r.status, 0) << run.second << "\n" << r.output;
    expectConverts(output);
  }
}

TEST_F(PclReadableOutput, TheRenderToolsColouredPcdConverts)
{
  const test::CommandResult r =
      test::runTool("range_nlm_render", path("in.pcd") + " " + path("render.pcd") + " --mode curvature");
  ASSERT_EQ(r.status, 0) << r.output;
  expectConverts(path("render.pcd"));
}

TEST_F(PclReadableOutput, TheSynthToolsFramesConvert)
{
  const test::CommandResult r = test::runTool(
      "range_nlm_synth", "--output-dir " + path("synth") + " --frames 1 --width 48 --height 36");
  ASSERT_EQ(r.status, 0) << r.output;
  for (const std::string kind : {"noisy", "truth"})
    for (const auto& entry : fs::directory_iterator(path("synth/" + kind)))
      if (entry.path().extension() == ".pcd")
        expectConverts(entry.path().string());
}
