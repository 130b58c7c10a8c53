// How results are written (tools/cli/frame_output.cpp): the per-point uncertainty as a PCD field
// and as a float image beside depth PNG output, through the library helpers and range_nlm_denoise.
#include "test_support.h"

#include "cli/frame_output.h"

#include <pcl/PCLPointCloud2.h>
#include <pcl/conversions.h>
#include <pcl/io/pcd_io.h>

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <unistd.h>

namespace fs = std::filesystem;
using namespace range_nlm;

namespace
{
class FrameOutput : public ::testing::Test
{
protected:
  void SetUp() override
  {
    dir_ = fs::temp_directory_path() /
           ("range_nlm_output_" + std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()) + "_" +
            std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }

  /// A noisy plane with a step and holes, 48 x 36, written as PCD.
  std::string writeFrame(const std::string& name)
  {
    auto c = test::makeCloud(48, 36, [](double, double, int u, int) { return u > 20 ? 1.0 : 1.1; }, 0.003, 3);
    test::punchHoles(c, 0.05, 4);
    pcl::io::savePCDFileBinary(path(name), c);
    return path(name);
  }
  fs::path dir_;
};

std::vector<std::string>
fieldNames(const std::string& pcd)
{
  pcl::PCLPointCloud2 blob;
  EXPECT_EQ(pcl::io::loadPCDFile(pcd, blob), 0) << pcd;
  std::vector<std::string> names;
  for (const pcl::PCLPointField& f : blob.fields)
    names.push_back(f.name);
  return names;
}

/// The float image of a PFM file (rows top to bottom) and its size.
std::vector<float>
readPfm(const std::string& path, int& width, int& height)
{
  std::ifstream in(path, std::ios::binary);
  std::string magic;
  double scale = 0.0;
  in >> magic >> width >> height >> scale;
  in.get(); // the single whitespace after the scale
  EXPECT_EQ(magic, "Pf");
  EXPECT_LT(scale, 0.0) << "little-endian";
  std::vector<float> bottom_up(static_cast<std::size_t>(width) * height);
  in.read(reinterpret_cast<char*>(bottom_up.data()), static_cast<std::streamsize>(bottom_up.size() * sizeof(float)));
  EXPECT_TRUE(in) << path;
  EXPECT_EQ(in.peek(), EOF) << "nothing after the pixels";
  std::vector<float> rows(bottom_up.size());
  for (int v = 0; v < height; ++v)
    std::memcpy(&rows[static_cast<std::size_t>(v) * width], &bottom_up[static_cast<std::size_t>(height - 1 - v) * width],
                width * sizeof(float));
  return rows;
}
} // namespace

TEST_F(FrameOutput, FloatFieldIsAppendedOrOverwritten)
{
  pcl::PointCloud<pcl::PointXYZ> c(3, 2);
  for (std::size_t i = 0; i < c.size(); ++i)
    c[i].x = float(i), c[i].y = 10.0f + i, c[i].z = 20.0f + i;
  pcl::PCLPointCloud2 blob;
  pcl::toPCLPointCloud2(c, blob);
  const std::uint32_t step = blob.point_step;
  tools::setFloatField(blob, "uncertainty", {0.5f, 1.5f, 2.5f, 3.5f, 4.5f, 5.5f});
  ASSERT_EQ(blob.fields.back().name, "uncertainty");
  EXPECT_EQ(blob.point_step, step + 4);
  EXPECT_EQ(blob.row_step, blob.point_step * 3);
  pcl::PointCloud<pcl::PointXYZ> back;
  pcl::fromPCLPointCloud2(blob, back);
  EXPECT_EQ(back[4].y, 14.0f);
  float value = 0.0f;
  std::memcpy(&value, &blob.data[4 * blob.point_step + blob.fields.back().offset], 4);
  EXPECT_EQ(value, 4.5f);
  tools::setFloatField(blob, "uncertainty", std::vector<float>(6, 7.0f)); // a second time: overwritten
  EXPECT_EQ(blob.point_step, step + 4);
  std::memcpy(&value, &blob.data[4 * blob.point_step + blob.fields.back().offset], 4);
  EXPECT_EQ(value, 7.0f);
  EXPECT_THROW(tools::setFloatField(blob, "uncertainty", {1.0f}), std::invalid_argument);
}

TEST_F(FrameOutput, FloatImageIsAPortableFloatMapTopRowFirstWhenRead)
{
  const std::vector<float> values{1, 2, 3, 4, 5, std::nanf("")};
  tools::writeFloatImage(path("u.pfm"), values, 3, 2);
  int w = 0, h = 0;
  const std::vector<float> read = readPfm(path("u.pfm"), w, h);
  EXPECT_EQ(w, 3);
  EXPECT_EQ(h, 2);
  EXPECT_EQ(read[0], 1.0f);
  EXPECT_EQ(read[4], 5.0f);
  EXPECT_TRUE(std::isnan(read[5]));
  EXPECT_EQ(tools::uncertaintyImagePath("out/frame.png"), "out/frame_uncertainty.pfm");
  EXPECT_THROW(tools::writeFloatImage(path("bad.pfm"), values, 4, 2), std::exception);
  EXPECT_FALSE(fs::exists(path("bad.pfm")));
}

TEST_F(FrameOutput, DenoiseWritesTheFieldOnlyWhenAsked)
{
  const std::string in = writeFrame("in.pcd");
  ASSERT_EQ(test::runDenoise("-q " + in + " " + path("off.pcd")).status, 0);
  const test::CommandResult on = test::runDenoise("-q --uncertainty true " + in + " " + path("on.pcd"));
  ASSERT_EQ(on.status, 0) << on.output;
  EXPECT_EQ(fieldNames(path("off.pcd")), (std::vector<std::string>{"x", "y", "z"}));
  EXPECT_EQ(fieldNames(path("on.pcd")), (std::vector<std::string>{"x", "y", "z", "uncertainty"}));
  // The same points either way; the field finite exactly where the point is, and below the noise.
  pcl::PointCloud<pcl::PointXYZ> off, with;
  pcl::io::loadPCDFile(path("off.pcd"), off);
  pcl::io::loadPCDFile(path("on.pcd"), with);
  pcl::PCLPointCloud2 blob;
  pcl::io::loadPCDFile(path("on.pcd"), blob);
  ASSERT_EQ(off.size(), with.size());
  for (std::size_t i = 0; i < off.size(); ++i) {
    EXPECT_EQ(std::memcmp(&off[i], &with[i], 3 * sizeof(float)), 0) << i;
    float sigma = 0.0f;
    std::memcpy(&sigma, &blob.data[i * blob.point_step + blob.fields.back().offset], sizeof sigma);
    EXPECT_EQ(std::isfinite(sigma), std::isfinite(with[i].z)) << i;
    if (std::isfinite(sigma)) {
      EXPECT_GE(sigma, 0.0f);
      EXPECT_LT(sigma, 0.006f);
    }
  }
}

TEST_F(FrameOutput, DenoiseWritesAFloatImageBesideDepthPng)
{
  const std::string in = writeFrame("in.pcd");
  const test::CommandResult r =
      test::runDenoise("-q --uncertainty true --line-of-sight " + in + " " + path("out.png"));
  ASSERT_EQ(r.status, 0) << r.output;
  int w = 0, h = 0;
  const std::vector<float> sigma = readPfm(path("out_uncertainty.pfm"), w, h);
  EXPECT_EQ(w, 48);
  EXPECT_EQ(h, 36);
  std::size_t finite = 0;
  for (float s : sigma)
    finite += std::isfinite(s);
  EXPECT_GT(finite, sigma.size() / 2);
  ASSERT_EQ(test::runDenoise("-q --line-of-sight " + in + " " + path("plain.png")).status, 0);
  EXPECT_FALSE(fs::exists(path("plain_uncertainty.pfm")));
}
