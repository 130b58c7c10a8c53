// How range_nlm_denoise marks the points the hole filling gave a range (tools/cli/frame_output.cpp):
// a uint8 PCD field `filled` (appended, the other fields' bytes kept), a mask PNG beside a depth
// PNG, and nothing at all when the hole filling is off.
#include "cli/frame_output.h"
#include "test_support.h"

#include <range_nlm/io/depth_image.h>

#include <pcl/io/pcd_io.h>

#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <limits>
#include <unistd.h>

namespace fs = std::filesystem;
using namespace range_nlm;

namespace
{
class FilledOutput : public ::testing::Test
{
protected:
  void SetUp() override
  {
    dir_ = fs::temp_directory_path() /
           ("range_nlm_filled_" + std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()) + "_" +
            std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }

  /// A noisy tilted plane, 48 x 36, with a 4 x 4 hole inside and an intensity per point.
  pcl::PointCloud<pcl::PointXYZI> frame() const
  {
    const auto xyz =
        test::makeCloud(48, 36, [](double x, double y, int, int) { return 1.2 / (1.0 - 0.2 * x + 0.1 * y); }, 0.002, 4);
    pcl::PointCloud<pcl::PointXYZI> c(48, 36);
    const float nan = std::numeric_limits<float>::quiet_NaN();
    for (int v = 0; v < 36; ++v)
      for (int u = 0; u < 48; ++u) {
        pcl::PointXYZI& p = c(u, v);
        p.x = xyz(u, v).x, p.y = xyz(u, v).y, p.z = xyz(u, v).z, p.intensity = float(u + 100 * v);
        if (u >= 22 && u < 26 && v >= 16 && v < 20)
          p.x = p.y = p.z = nan;
      }
    c.is_dense = false;
    return c;
  }
  fs::path dir_;
};
} // namespace

TEST_F(FilledOutput, MarkFilledAppendsAUint8FieldAndKeepsEveryOtherByte)
{
  pcl::PointCloud<pcl::PointXYZI> cloud = frame();
  pcl::PCLPointCloud2 blob;
  pcl::toPCLPointCloud2(cloud, blob);
  const pcl::PCLPointCloud2 before = blob;
  std::vector<unsigned char> filled(cloud.size(), 0);
  filled[5] = filled[700] = 1;
  tools::markFilled(blob, filled);
  ASSERT_EQ(blob.fields.size(), before.fields.size() + 1);
  EXPECT_EQ(blob.fields.back().name, "filled");
  EXPECT_EQ(blob.fields.back().datatype, pcl::PCLPointField::UINT8);
  ASSERT_EQ(blob.point_step, before.point_step + 1);
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    EXPECT_EQ(std::memcmp(&blob.data[i * blob.point_step], &before.data[i * before.point_step], before.point_step), 0);
    EXPECT_EQ(blob.data[i * blob.point_step + before.point_step], filled[i]) << i;
  }
  // A second mark keeps the first one's 1s.
  std::vector<unsigned char> more(cloud.size(), 0);
  more[6] = 1;
  tools::markFilled(blob, more);
  EXPECT_EQ(blob.fields.size(), before.fields.size() + 1);
  for (std::size_t i : {5u, 6u, 700u})
    EXPECT_EQ(blob.data[i * blob.point_step + before.point_step], 1) << i;
  EXPECT_THROW(tools::markFilled(blob, std::vector<unsigned char>(3, 0)), std::invalid_argument);
}

TEST_F(FilledOutput, ThePcdOutputMarksExactlyTheFilledPointsAndIsUnchangedWhenOff)
{
  const pcl::PointCloud<pcl::PointXYZI> in = frame();
  pcl::io::savePCDFileBinary(path("in.pcd"), in);
  const auto off = test::runDenoise(path("in.pcd") + " " + path("off.pcd") + " --threads 1");
  ASSERT_EQ(off.status, 0) << off.output;
  const auto zero = test::runDenoise(path("in.pcd") + " " + path("zero.pcd") + " --threads 1 --fill-holes 0");
  ASSERT_EQ(zero.status, 0) << zero.output;
  EXPECT_EQ(test::readBytes(path("off.pcd")), test::readBytes(path("zero.pcd")));
  EXPECT_EQ(test::readBytes(path("off.pcd")).find("filled"), std::string::npos);

  const auto on = test::runDenoise(path("in.pcd") + " " + path("on.pcd") + " --threads 1 --fill-holes 6");
  ASSERT_EQ(on.status, 0) << on.output;
  pcl::PCLPointCloud2 blob;
  ASSERT_EQ(pcl::io::loadPCDFile(path("on.pcd"), blob), 0);
  ASSERT_EQ(blob.fields.back().name, "filled");
  pcl::PointCloud<pcl::PointXYZI> out, off_cloud;
  pcl::fromPCLPointCloud2(blob, out);
  ASSERT_EQ(pcl::io::loadPCDFile(path("off.pcd"), off_cloud), 0);
  std::size_t filled = 0;
  for (std::size_t i = 0; i < in.size(); ++i) {
    const std::uint8_t mark = blob.data[i * blob.point_step + blob.fields.back().offset];
    const bool hole = !std::isfinite(in[i].z);
    EXPECT_EQ(mark, hole ? 1 : 0) << i; // the 4 x 4 hole is filled, nothing else is marked
    EXPECT_EQ(out[i].intensity, in[i].intensity);
    if (!hole) // the measured points are the filter's, bit for bit
      EXPECT_EQ(std::memcmp(&out[i].x, &off_cloud[i].x, 3 * sizeof(float)), 0) << i;
    filled += mark;
  }
  EXPECT_EQ(filled, 16u);
}

TEST_F(FilledOutput, ADepthPngOutputGetsAMaskBesideIt)
{
  DepthImage depth;
  depth.width = 48, depth.height = 36;
  depth.values.assign(48 * 36, 1500);
  for (int v = 0; v < 36; ++v)
    for (int u = 0; u < 48; ++u)
      depth.values[v * 48 + u] = static_cast<std::uint16_t>(1500 + 7 * u + ((u * 7 + v * 13) % 5));
  for (int v = 10; v < 13; ++v)
    for (int u = 20; u < 23; ++u)
      depth.values[v * 48 + u] = 0;
  writeDepthPng(path("in.png"), depth);
  const auto r = test::runDenoise(path("in.png") + " " + path("out.png") +
                                  " --threads 1 --fill-holes 4 --depth-scale 1000 --fx 40 --fy 40 --cx 23.5 --cy 17.5");
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_EQ(tools::filledMaskPath(path("out.png")), path("out.filled-mask.png"));
  const DepthImage mask = readDepthPng(path("out.filled-mask.png"));
  const DepthImage out = readDepthPng(path("out.png"));
  ASSERT_EQ(mask.values.size(), depth.values.size());
  for (std::size_t i = 0; i < depth.values.size(); ++i) {
    EXPECT_EQ(mask.values[i], depth.values[i] == 0 ? 65535 : 0) << i;
    EXPECT_NE(out.values[i], 0) << i;
  }
  const auto off = test::runDenoise(path("in.png") + " " + path("plain.png") +
                                    " --threads 1 --depth-scale 1000 --fx 40 --fy 40 --cx 23.5 --cy 17.5");
  ASSERT_EQ(off.status, 0) << off.output;
  EXPECT_FALSE(fs::exists(path("plain.filled-mask.png")));
}
