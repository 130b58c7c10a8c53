// 16-bit depth PNGs <-> organized clouds, the intrinsics reader and the libpng wrappers.
#include "test_support.h"

#include <range_nlm/io/depth_image.h>

#include <pcl/io/pcd_io.h>

#include <gtest/gtest.h>

#include <png.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include <sys/wait.h>
#include <unistd.h>

namespace fs = std::filesystem;
using namespace range_nlm;

namespace
{

const std::string kData = std::string(RANGE_NLM_SOURCE_DIR) + "/data/depth-images";
const std::string kTum = kData + "/tum-fr2-desk-pair/1_depth.png";
const std::string kTumIntrinsics = kData + "/tum-fr2-desk-pair/intrinsics.txt";
const std::string kRealSense = kData + "/realsense-d415-vcl3d/0_M11_depth_0.png";
const std::string kRealSenseIntrinsics = kData + "/realsense-d415-vcl3d/intrinsics.txt";

class DepthImageTest : public ::testing::Test
{
protected:
  void SetUp() override
  {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::temp_directory_path() /
           ("range_nlm_depth_" + std::string(info->name()) + "_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }

  fs::path dir_;
};

void
writeText(const std::string& path, const std::string& text)
{
  std::ofstream out(path, std::ios::binary);
  out << text;
}

std::string
readBytes(const std::string& path)
{
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

std::uint32_t
bigEndian32(const std::string& bytes, std::size_t at)
{
  return (std::uint32_t(std::uint8_t(bytes[at])) << 24) | (std::uint32_t(std::uint8_t(bytes[at + 1])) << 16) |
         (std::uint32_t(std::uint8_t(bytes[at + 2])) << 8) | std::uint32_t(std::uint8_t(bytes[at + 3]));
}

/// Expects `body` to throw std::invalid_argument whose message contains every one of `parts`.
template <typename Body>
void
expectInvalid(Body body, std::initializer_list<std::string> parts)
{
  try {
    body();
    ADD_FAILURE() << "no exception";
  } catch (const std::invalid_argument& e) {
    for (const std::string& part : parts)
      EXPECT_NE(std::string(e.what()).find(part), std::string::npos) << "message: " << e.what();
  }
}

} // namespace

TEST(DepthIntrinsics, DefaultsAreTheRosTumValues)
{
  const DepthIntrinsics d;
  EXPECT_EQ(d.fx, 525.0);
  EXPECT_EQ(d.fy, 525.0);
  EXPECT_EQ(d.cx, 319.5);
  EXPECT_EQ(d.cy, 239.5);
  EXPECT_EQ(d.depth_scale, 5000.0);
  EXPECT_NO_THROW(d.validate());
}

TEST(DepthIntrinsics, ValidateNamesTheField)
{
  DepthIntrinsics d;
  d.fy = -1.0;
  expectInvalid([&] { d.validate(); }, {"fy", "-1"});
  d = DepthIntrinsics();
  d.depth_scale = 0.0;
  expectInvalid([&] { d.validate(); }, {"depth_scale"});
  d = DepthIntrinsics();
  d.cx = std::nan("");
  expectInvalid([&] { d.validate(); }, {"cx"});
}

TEST(ReadIntrinsics, ShippedTumFile)
{
  const DepthIntrinsics d = readIntrinsics(kTumIntrinsics);
  EXPECT_DOUBLE_EQ(d.fx, 520.9);
  EXPECT_DOUBLE_EQ(d.fy, 521.0);
  EXPECT_DOUBLE_EQ(d.cx, 325.1);
  EXPECT_DOUBLE_EQ(d.cy, 249.7);
  // From "depth_m = value / 5000".
  EXPECT_DOUBLE_EQ(d.depth_scale, 5000.0);
}

TEST(ReadIntrinsics, ShippedRealSenseFileIsMillimetres)
{
  DepthIntrinsics defaults;
  defaults.depth_scale = 1.0; // must be replaced by the file's "millimetres"
  const DepthIntrinsics d = readIntrinsics(kRealSenseIntrinsics, defaults);
  EXPECT_DOUBLE_EQ(d.fx, 481.94012451171875);
  EXPECT_DOUBLE_EQ(d.fy, 481.94012451171875);
  EXPECT_DOUBLE_EQ(d.cx, 315.1639404296875);
  EXPECT_DOUBLE_EQ(d.cy, 174.9703826904297);
  EXPECT_DOUBLE_EQ(d.depth_scale, 1000.0);
}

TEST_F(DepthImageTest, IntrinsicsCommentsDefaultsAndExplicitScale)
{
  const std::string file = path("intrinsics.txt");
  writeText(file, "# a comment line\n\n  fx 600.5   # trailing comment\nfy\t601\n"
                  "depth_format uint16, value / 5000\ndepth_scale 1000\n");
  const DepthIntrinsics d = readIntrinsics(file);
  EXPECT_DOUBLE_EQ(d.fx, 600.5);
  EXPECT_DOUBLE_EQ(d.fy, 601.0);
  EXPECT_DOUBLE_EQ(d.cx, 319.5); // missing: default kept
  EXPECT_DOUBLE_EQ(d.cy, 239.5);
  EXPECT_DOUBLE_EQ(d.depth_scale, 1000.0); // an explicit depth_scale wins over depth_format
}

TEST_F(DepthImageTest, IntrinsicsErrorsNameFileAndLine)
{
  const std::string file = path("bad_intrinsics.txt");
  writeText(file, "fx 520\nfy 52O\n");
  expectInvalid([&] { readIntrinsics(file); }, {file, "line 2", "fy", "52O"});
  writeText(file, "fx -3\n");
  expectInvalid([&] { readIntrinsics(file); }, {file, "fx"});
  writeText(file, "width 640.5\n");
  expectInvalid([&] { readIntrinsics(file); }, {file, "width"});
  expectInvalid([&] { readIntrinsics(path("missing.txt")); }, {path("missing.txt")});
}

// A key the reader does not know is refused with its name and line: a misspelt depth_scale must
// not leave the default scale in place unnoticed.
TEST_F(DepthImageTest, UnknownIntrinsicsKeysAreRefusedByNameAndLine)
{
  const std::string file = path("intrinsics.txt");
  writeText(file, "fx 600\n# comment\nfy 600\ndepth_scal 1000\n");
  expectInvalid([&] { readIntrinsics(file); }, {file, "line 4", "unknown key 'depth_scal'"});
  writeText(file, "fx 600\nk1 0.12\n");
  expectInvalid([&] { readIntrinsics(file); }, {file, "line 2", "'k1'"});
}

// Every key of the intrinsics files shipped with the data (and the free-text keys they use:
// sensor, note, distortion, comments) is known; width and height are read.
TEST_F(DepthImageTest, EveryShippedIntrinsicsFileAndItsKeysAreAccepted)
{
  std::size_t files = 0;
  for (const auto& entry : fs::recursive_directory_iterator(std::string(RANGE_NLM_SOURCE_DIR) + "/data"))
    if (entry.path().filename() == "intrinsics.txt") {
      SCOPED_TRACE(entry.path().string());
      EXPECT_NO_THROW(readIntrinsics(entry.path().string()));
      ++files;
    }
  EXPECT_GE(files, 2u);
  const std::string file = path("intrinsics.txt");
  writeText(file, "# header\nwidth 1920\nheight 1080\nfx 1377.6\nfy 1375.7\ncx 936.5\ncy 537.5\n"
                  "depth_format uint16 PNG, millimetres, 0 = invalid\n"
                  "sensor Intel RealSense product id 0B07 (D435)\n"
                  "note the calibration_rs.yml files are a failed calibration - do not use\n"
                  "distortion Brown-Conrady rational: 0.54 -0.02 0.00002 -0.00007 -0.002 0.88 0.08 -0.01\n"
                  "comments free text\ncomment more text\nnotes and more\nsource where it came from\n");
  const DepthIntrinsics d = readIntrinsics(file);
  EXPECT_EQ(d.width, 1920);
  EXPECT_EQ(d.height, 1080);
  EXPECT_DOUBLE_EQ(d.depth_scale, 1000.0);
  EXPECT_EQ(d.source, file);
  const DepthIntrinsics tum = readIntrinsics(kTumIntrinsics);
  EXPECT_EQ(tum.width, 640);
  EXPECT_EQ(tum.height, 480);
}

// Intrinsics that give a size apply only to images of that size.
TEST_F(DepthImageTest, IntrinsicsOfAnotherSizeAreRefusedWithBothSizes)
{
  DepthImage image;
  image.width = 4;
  image.height = 3;
  image.values.assign(12, 5000);
  const std::string file = path("intrinsics.txt");
  writeText(file, "width 640\nheight 480\n");
  const DepthIntrinsics intrinsics = readIntrinsics(file);
  expectInvalid([&] { depthImageToCloud(image, intrinsics); }, {"4 x 3", "640 x 480", file});
  writeDepthPng(path("small.png"), image);
  expectInvalid([&] { loadDepthPng(path("small.png"), intrinsics); }, {path("small.png"), "4 x 3", "640 x 480"});
  writeText(file, "width 4\nheight 3\n");
  EXPECT_EQ(depthImageToCloud(image, readIntrinsics(file)).size(), 12u);
  EXPECT_EQ(depthImageToCloud(image, DepthIntrinsics()).size(), 12u); // no size given: any size
}

// Values a 16-bit image cannot hold: an error without a DepthClamping, clamped and counted with.
TEST(DepthImage, OutOfRangeDepthsAreClampedAndCountedWhenAsked)
{
  pcl::PointCloud<pcl::PointXYZ> cloud(4, 1);
  for (auto& p : cloud)
    p = pcl::PointXYZ(0.0f, 0.0f, 1.0f);
  cloud[1].z = 13.2f;    // 66000 at scale 5000
  cloud[2].z = 0.00005f; // 0.25
  cloud[3].x = cloud[3].y = cloud[3].z = std::nanf("");
  expectInvalid([&] { cloudToDepthImage(cloud, 5000.0); }, {"pixel (1, 0)"});
  DepthClamping clamping;
  const DepthImage image = cloudToDepthImage(cloud, 5000.0, &clamping);
  EXPECT_EQ(image.values, (std::vector<std::uint16_t>{5000, 65535, 1, 0}));
  EXPECT_EQ(clamping.above, 1u);
  EXPECT_EQ(clamping.below, 1u);
}

// A budget refuses a PNG from its header: the message names the file and the figure.
TEST_F(DepthImageTest, MemoryBudgetRefusesALargeImageFromItsHeader)
{
  DepthImage image;
  image.width = 200;
  image.height = 100;
  image.values.assign(20000, 1000);
  writeDepthPng(path("image.png"), image);
  io::MemoryBudget budget;
  budget.limit_bytes = 200 * 100 * 16 - 1; // one byte short of the cloud's points
  budget.setting = "--my-limit";
  expectInvalid([&] { readDepthPng(path("image.png"), budget); },
                {path("image.png"), "200 x 100 frame needs about 1 MB of memory", "--my-limit"});
  budget.limit_bytes = 200 * 100 * 16;
  EXPECT_EQ(readDepthPng(path("image.png"), budget).width, 200);
}

TEST(ReadDepthPng, TumFrameMatchesAnIndependentDecoder)
{
  const DepthImage image = readDepthPng(kTum);
  ASSERT_EQ(image.width, 640);
  ASSERT_EQ(image.height, 480);
  ASSERT_EQ(image.values.size(), 640u * 480u);
  // Values read with ImageMagick ("convert 1_depth.png -depth 16 txt:-").
  EXPECT_EQ(image.values[240 * 640 + 320], 8026);
  EXPECT_EQ(image.values[300 * 640 + 100], 7187);
  EXPECT_EQ(image.values[100 * 640 + 500], 29310);
  EXPECT_EQ(image.values[0], 0);
  std::size_t zeros = 0;
  for (std::uint16_t v : image.values)
    zeros += v == 0;
  EXPECT_EQ(zeros, 102341u);
}

TEST(DepthImageToCloud, KnownPixelMapsToKnownPoint)
{
  const DepthIntrinsics intrinsics = readIntrinsics(kTumIntrinsics);
  const pcl::PointCloud<pcl::PointXYZ> cloud = loadDepthPng(kTum, intrinsics);
  ASSERT_EQ(cloud.width, 640u);
  ASSERT_EQ(cloud.height, 480u);
  EXPECT_FALSE(cloud.is_dense);
  const double z = 8026.0 / 5000.0;
  const pcl::PointXYZ& p = cloud.at(320, 240);
  EXPECT_NEAR(p.z, z, 1e-6);
  EXPECT_NEAR(p.x, (320.0 - 325.1) * z / 520.9, 1e-6);
  EXPECT_NEAR(p.y, (240.0 - 249.7) * z / 521.0, 1e-6);
  const pcl::PointXYZ& q = cloud.at(500, 100);
  const double zq = 29310.0 / 5000.0;
  EXPECT_NEAR(q.x, (500.0 - 325.1) * zq / 520.9, 1e-5);
  EXPECT_NEAR(q.y, (100.0 - 249.7) * zq / 521.0, 1e-5);
  // Value 0 is a missing measurement: NaN in all three coordinates.
  const pcl::PointXYZ& hole = cloud.at(0, 0);
  EXPECT_TRUE(std::isnan(hole.x) && std::isnan(hole.y) && std::isnan(hole.z));
}

TEST(DepthImageToCloud, SmallImageByHand)
{
  DepthImage image;
  image.width = 3;
  image.height = 2;
  image.values = {1000, 0, 2000, 500, 1500, 65535};
  DepthIntrinsics intrinsics;
  intrinsics.fx = 100.0;
  intrinsics.fy = 200.0;
  intrinsics.cx = 1.0;
  intrinsics.cy = 0.5;
  intrinsics.depth_scale = 1000.0;
  const auto cloud = depthImageToCloud(image, intrinsics);
  ASSERT_EQ(cloud.width, 3u);
  ASSERT_EQ(cloud.height, 2u);
  EXPECT_FLOAT_EQ(cloud.at(0, 0).x, -0.01f); // (0 - 1) * 1 / 100
  EXPECT_FLOAT_EQ(cloud.at(0, 0).y, -0.0025f); // (0 - 0.5) * 1 / 200
  EXPECT_FLOAT_EQ(cloud.at(0, 0).z, 1.0f);
  EXPECT_TRUE(std::isnan(cloud.at(1, 0).x) && std::isnan(cloud.at(1, 0).y) && std::isnan(cloud.at(1, 0).z));
  EXPECT_FLOAT_EQ(cloud.at(2, 0).x, 0.02f);
  EXPECT_FLOAT_EQ(cloud.at(1, 1).x, 0.0f);
  EXPECT_FLOAT_EQ(cloud.at(1, 1).y, 0.00375f); // (1 - 0.5) * 1.5 / 200
  EXPECT_FLOAT_EQ(cloud.at(2, 1).z, 65.535f);

  const DepthImage back = cloudToDepthImage(cloud, 1000.0);
  EXPECT_EQ(back.values, image.values);
}

TEST(DepthImageToCloud, RejectsBadInput)
{
  DepthImage image;
  image.width = 2;
  image.height = 2;
  image.values = {1, 2, 3};
  expectInvalid([&] { depthImageToCloud(image, DepthIntrinsics()); }, {"2 x 2"});
  image.values = {1, 2, 3, 4};
  DepthIntrinsics bad;
  bad.fx = 0.0;
  expectInvalid([&] { depthImageToCloud(image, bad); }, {"fx"});
}

TEST(DepthMapToCloud, BackProjectsFloatDepthsAsTheUint16ImageIs)
{
  DepthImage image;
  image.width = 3;
  image.height = 2;
  image.values = {1000, 0, 2000, 1500, 1500, 65535};
  DepthIntrinsics intrinsics;
  intrinsics.fx = 100.0;
  intrinsics.fy = 200.0;
  intrinsics.cx = 1.0;
  intrinsics.cy = 0.5;
  intrinsics.depth_scale = 1000.0;
  const auto expected = depthImageToCloud(image, intrinsics);
  const std::vector<float> values(image.values.begin(), image.values.end());
  const auto cloud = depthMapToCloud(values, 3, 2, intrinsics);
  ASSERT_EQ(cloud.size(), expected.size());
  for (std::size_t i = 0; i < cloud.size(); ++i)
    for (int k = 0; k < 3; ++k) {
      const float a = cloud[i].data[k], b = expected[i].data[k];
      EXPECT_TRUE((std::isnan(a) && std::isnan(b)) || a == b) << "point " << i << " coordinate " << k;
    }
  // A negative or non-finite value is no measurement either.
  const auto holes = depthMapToCloud({-1.0f, std::nanf(""), INFINITY, 1.0f}, 2, 2, intrinsics);
  for (int i = 0; i < 3; ++i)
    EXPECT_TRUE(std::isnan(holes[i].x) && std::isnan(holes[i].y) && std::isnan(holes[i].z)) << i;
  EXPECT_FLOAT_EQ(holes[3].z, 0.001f);
  EXPECT_FALSE(holes.is_dense);
  expectInvalid([&] { depthMapToCloud({1.0f, 2.0f, 3.0f}, 2, 2, intrinsics); }, {"2 x 2"});
}

TEST(CloudToDepthValues, AreTheDepthsTheImageRounds)
{
  pcl::PointCloud<pcl::PointXYZ> cloud(3, 1);
  cloud[0] = pcl::PointXYZ(0.1f, 0.2f, 1.23456f);
  cloud[1] = pcl::PointXYZ(NAN, 0.0f, 1.0f); // invalid in any coordinate: NaN
  cloud[2] = pcl::PointXYZ(0.0f, 0.0f, 2.0f);
  const std::vector<double> values = cloudToDepthValues(cloud, 5000.0);
  ASSERT_EQ(values.size(), 3u);
  EXPECT_DOUBLE_EQ(values[0], double(1.23456f) * 5000.0);
  EXPECT_TRUE(std::isnan(values[1]));
  EXPECT_DOUBLE_EQ(values[2], 10000.0);
  const DepthImage image = cloudToDepthImage(cloud, 5000.0);
  EXPECT_EQ(image.values, (std::vector<std::uint16_t>{static_cast<std::uint16_t>(std::round(values[0])), 0, 10000}));
  expectInvalid([&] { cloudToDepthValues(cloud, -1.0); }, {"depth_scale"});
}

TEST(CloudToDepthImage, EveryUint16ValueSurvivesTheRoundTrip)
{
  DepthImage all;
  all.width = 256;
  all.height = 256;
  all.values.resize(65536);
  for (std::size_t i = 0; i < all.values.size(); ++i)
    all.values[i] = static_cast<std::uint16_t>(i);
  for (double scale : {5000.0, 1000.0, 4000.0, 1.0}) {
    DepthIntrinsics intrinsics;
    intrinsics.depth_scale = scale;
    const DepthImage back = cloudToDepthImage(depthImageToCloud(all, intrinsics), scale);
    EXPECT_EQ(back.values, all.values) << "depth scale " << scale;
  }
}

TEST(CloudToDepthImage, RefusesDepthsOutsideTheUint16Range)
{
  pcl::PointCloud<pcl::PointXYZ> cloud(2, 2);
  for (auto& p : cloud)
    p = pcl::PointXYZ(0.0f, 0.0f, 1.0f);
  cloud.at(1, 0).z = 14.0f; // 70000 at scale 5000
  expectInvalid([&] { cloudToDepthImage(cloud, 5000.0); }, {"pixel (1, 0)", "14", "13.107"});
  cloud.at(1, 0).z = -0.5f;
  expectInvalid([&] { cloudToDepthImage(cloud, 5000.0); }, {"pixel (1, 0)"});
  cloud.at(1, 0).z = 1e-5f; // would round to 0, which means "no measurement"
  expectInvalid([&] { cloudToDepthImage(cloud, 5000.0); }, {"pixel (1, 0)"});
  cloud.at(1, 0).z = 13.107f; // the largest depth at scale 5000
  EXPECT_EQ(cloudToDepthImage(cloud, 5000.0).values[1], 65535);
  expectInvalid([&] { cloudToDepthImage(cloud, 0.0); }, {"depth_scale"});
}

TEST_F(DepthImageTest, TumRoundTripIsBitExact)
{
  const DepthImage original = readDepthPng(kTum);
  const auto cloud = loadDepthPng(kTum, readIntrinsics(kTumIntrinsics));
  const std::string out = path("roundtrip.png");
  saveDepthPng(out, cloud, 5000.0);
  const DepthImage back = readDepthPng(out);
  EXPECT_EQ(back.width, original.width);
  EXPECT_EQ(back.height, original.height);
  EXPECT_EQ(back.values, original.values);
  // No temporary file is left behind.
  std::size_t files = 0;
  for (const auto& entry : fs::directory_iterator(dir_))
    files += entry.is_regular_file();
  EXPECT_EQ(files, 1u);
}

TEST_F(DepthImageTest, RealSenseRoundTripIsBitExact)
{
  const DepthImage original = readDepthPng(kRealSense);
  ASSERT_EQ(original.width, 640);
  ASSERT_EQ(original.height, 360);
  EXPECT_EQ(original.values[180 * 640 + 320], 1205); // ImageMagick
  const auto cloud = loadDepthPng(kRealSense, readIntrinsics(kRealSenseIntrinsics));
  EXPECT_NEAR(cloud.at(320, 180).z, 1.205f, 1e-6f);
  const std::string out = path("realsense.png");
  saveDepthPng(out, cloud, 1000.0);
  EXPECT_EQ(readDepthPng(out).values, original.values);
}

TEST_F(DepthImageTest, WrittenFileIsA16BitGreyPngOfTheRightSize)
{
  DepthImage image;
  image.width = 5;
  image.height = 3;
  image.values = {0, 1, 2, 255, 256, 4660, 65535, 65534, 1000, 0, 7, 8, 9, 10, 11};
  const std::string out = path("small.png");
  writeDepthPng(out, image);
  const std::string bytes = readBytes(out);
  ASSERT_GT(bytes.size(), 33u);
  EXPECT_EQ(bytes.substr(0, 8), std::string("\x89PNG\r\n\x1a\n", 8));
  EXPECT_EQ(bytes.substr(12, 4), "IHDR");
  EXPECT_EQ(bigEndian32(bytes, 16), 5u);    // width
  EXPECT_EQ(bigEndian32(bytes, 20), 3u);    // height
  EXPECT_EQ(std::uint8_t(bytes[24]), 16u); // bit depth
  EXPECT_EQ(std::uint8_t(bytes[25]), 0u);  // colour type: greyscale
  // libpng delivers the samples big-endian, as the PNG standard stores them.
  const detail::PngPixels pixels = detail::readPng(out);
  EXPECT_EQ(pixels.channels, 1);
  EXPECT_EQ(pixels.bit_depth, 16);
  ASSERT_EQ(pixels.bytes.size(), 30u);
  EXPECT_EQ(pixels.bytes[10], 0x12); // 4660 = 0x1234
  EXPECT_EQ(pixels.bytes[11], 0x34);
  EXPECT_EQ(readDepthPng(out).values, image.values);
}

TEST_F(DepthImageTest, ReadErrorsNameTheFile)
{
  expectInvalid([&] { readDepthPng(path("missing.png")); }, {path("missing.png")});

  const std::string text = path("text.png");
  writeText(text, "this is not an image at all");
  expectInvalid([&] { readDepthPng(text); }, {text, "not a PNG"});

  const std::string empty = path("empty.png");
  writeText(empty, "");
  expectInvalid([&] { readDepthPng(empty); }, {empty});

  const std::string truncated = path("truncated.png");
  const std::string tum = readBytes(kTum);
  writeText(truncated, tum.substr(0, tum.size() / 2));
  expectInvalid([&] { readDepthPng(truncated); }, {truncated, "damaged"});

  detail::PngPixels grey8;
  grey8.width = 4;
  grey8.height = 2;
  grey8.channels = 1;
  grey8.bit_depth = 8;
  grey8.bytes.assign(8, 100);
  const std::string eight = path("grey8.png");
  detail::writePng(eight, grey8);
  expectInvalid([&] { readDepthPng(eight); }, {eight, "8-bit greyscale", "16-bit"});

  detail::PngPixels rgb16 = grey8;
  rgb16.channels = 3;
  rgb16.bit_depth = 16;
  rgb16.bytes.assign(4 * 2 * 3 * 2, 7);
  const std::string colour = path("rgb16.png");
  detail::writePng(colour, rgb16);
  expectInvalid([&] { readDepthPng(colour); }, {colour, "16-bit RGB"});
}

namespace
{
/// A 4 x 2 PNG of `bit_depth` bits and `color_type` (PNG_COLOR_TYPE_*), pixels of zeros; a palette
/// image gets a palette of 2^bit_depth grey entries.
void
writeStoredPng(const std::string& path, int bit_depth, int color_type)
{
  std::FILE* file = std::fopen(path.c_str(), "wb");
  ASSERT_NE(file, nullptr);
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
  png_infop info = png_create_info_struct(png);
  ASSERT_TRUE(png && info);
  if (setjmp(png_jmpbuf(png))) {
    png_destroy_write_struct(&png, &info);
    std::fclose(file);
    FAIL() << "libpng failed writing " << path;
  }
  png_init_io(png, file);
  const png_uint_32 width = 4, height = 2;
  png_set_IHDR(png, info, width, height, bit_depth, color_type, PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT,
               PNG_FILTER_TYPE_DEFAULT);
  std::vector<png_color> palette(std::size_t(1) << bit_depth);
  for (std::size_t i = 0; i < palette.size(); ++i)
    palette[i].red = palette[i].green = palette[i].blue = static_cast<png_byte>(i);
  if (color_type == PNG_COLOR_TYPE_PALETTE)
    png_set_PLTE(png, info, palette.data(), static_cast<int>(palette.size()));
  png_write_info(png, info);
  std::vector<png_byte> row(width * 8 * 2, 0); // room for 16-bit RGBA
  for (png_uint_32 v = 0; v < height; ++v)
    png_write_row(png, row.data());
  png_write_end(png, nullptr);
  png_destroy_write_struct(&png, &info);
  std::fclose(file);
}
} // namespace

// A PNG that is not a depth image is named by its format as stored in the file, not by what
// libpng expands it to for reading (a palette image is not RGB, a 1-bit one not 8-bit).
TEST_F(DepthImageTest, OtherPngFormatsAreNamedAsStored)
{
  const struct
  {
    int bit_depth, color_type;
    const char* name;
  } formats[] = {{8, PNG_COLOR_TYPE_PALETTE, "8-bit palette"},
                 {4, PNG_COLOR_TYPE_PALETTE, "4-bit palette"},
                 {1, PNG_COLOR_TYPE_GRAY, "1-bit greyscale"},
                 {2, PNG_COLOR_TYPE_GRAY, "2-bit greyscale"},
                 {8, PNG_COLOR_TYPE_GRAY, "8-bit greyscale"},
                 {16, PNG_COLOR_TYPE_GRAY_ALPHA, "16-bit greyscale + alpha"},
                 {8, PNG_COLOR_TYPE_RGB, "8-bit RGB"},
                 {16, PNG_COLOR_TYPE_RGB_ALPHA, "16-bit RGBA"}};
  for (const auto& format : formats) {
    const std::string file =
        path("stored-" + std::to_string(format.bit_depth) + "-" + std::to_string(format.color_type) + ".png");
    writeStoredPng(file, format.bit_depth, format.color_type);
    try {
      readDepthPng(file);
      ADD_FAILURE() << format.name << " read as a depth image";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(std::string("(found ") + format.name + ")"), std::string::npos) << e.what();
    }
  }
}

TEST_F(DepthImageTest, WriteErrorsNameTheFile)
{
  pcl::PointCloud<pcl::PointXYZ> cloud(2, 2);
  for (auto& p : cloud)
    p = pcl::PointXYZ(0.0f, 0.0f, 1.0f);
  const std::string nowhere = path("no/such/dir/out.png");
  expectInvalid([&] { saveDepthPng(nowhere, cloud, 1000.0); }, {nowhere});
  cloud.at(0, 1).z = 100.0f;
  const std::string out = path("far.png");
  expectInvalid([&] { saveDepthPng(out, cloud, 1000.0); }, {out, "pixel (0, 1)"});
  EXPECT_FALSE(fs::exists(out));
  DepthImage inconsistent;
  inconsistent.width = 3;
  inconsistent.height = 3;
  inconsistent.values.assign(4, 1);
  expectInvalid([&] { writeDepthPng(out, inconsistent); }, {out});
}

// ---- depth PNGs through range_nlm_denoise -----------------------------------------------------

namespace
{
struct ToolResult
{
  int status = -1;
  std::string output;
};

ToolResult
runDenoise(const std::string& args)
{
  const test::CommandResult c = test::runTool("range_nlm_denoise", args);
  return ToolResult{c.status, c.output};
}

constexpr int kW = 64, kH = 48;
const char* const kIntrinsicsOptions = " --fx 60 --fy 60 --cx 31.5 --cy 23.5 --depth-scale 5000 --quiet";

/// A noisy fronto-parallel plane 1 m away, seen by a 64 x 48 camera with f = 60, a few holes.
DepthImage
noisyPlane(std::uint64_t seed)
{
  auto cloud = test::makeCloud(kW, kH, test::plane(Eigen::Vector3d(0, 0, 1), 1.0), 0.004, seed, 60.0);
  test::punchHoles(cloud, 0.05, seed + 100);
  return cloudToDepthImage(cloud, 5000.0);
}

double
spread(const DepthImage& image)
{
  double sum = 0.0, sum2 = 0.0;
  std::size_t n = 0;
  for (std::uint16_t v : image.values)
    if (v != 0) {
      sum += v, sum2 += double(v) * v;
      ++n;
    }
  const double mean = sum / n;
  return std::sqrt(sum2 / n - mean * mean);
}
} // namespace

TEST_F(DepthImageTest, DenoiseToolFiltersADepthPngSequence)
{
  fs::create_directories(dir_ / "in");
  const DepthImage a = noisyPlane(1), b = noisyPlane(2);
  writeDepthPng(path("in/frame_000.png"), a);
  writeDepthPng(path("in/frame_001.png"), b);
  const ToolResult r = runDenoise("--input-dir " + path("in") + " --output-dir " + path("out") +
                                  " --line-of-sight --temporal-radius 1" + kIntrinsicsOptions);
  ASSERT_EQ(r.status, 0) << r.output;
  const DepthImage fa = readDepthPng(path("out/frame_000.png"));
  const DepthImage fb = readDepthPng(path("out/frame_001.png"));
  ASSERT_EQ(fa.width, kW);
  ASSERT_EQ(fa.height, kH);
  for (std::size_t i = 0; i < a.values.size(); ++i) {
    EXPECT_EQ(fa.values[i] == 0, a.values[i] == 0) << "holes stay holes, pixel " << i;
    EXPECT_EQ(fb.values[i] == 0, b.values[i] == 0) << "holes stay holes, pixel " << i;
  }
  // Noise of 4 mm = 20 units; the plane is flat, so the spread must shrink.
  EXPECT_GT(spread(a), 15.0);
  EXPECT_LT(spread(fa), 0.5 * spread(a));
  EXPECT_LT(spread(fb), 0.5 * spread(b));
}

TEST_F(DepthImageTest, DenoiseToolWritesPcdFromPngWithTheIntrinsics)
{
  fs::create_directories(dir_ / "in");
  writeDepthPng(path("in/frame_000.png"), noisyPlane(3));
  writeText(path("intrinsics.txt"), "fx 60\nfy 60\ncx 31.5\ncy 23.5\ndepth_format uint16, value / 5000\n");
  ToolResult r = runDenoise("--input-dir " + path("in") + " --output-dir " + path("out") + " --output-format pcd" +
                            " --line-of-sight --quiet --intrinsics " + path("intrinsics.txt"));
  ASSERT_EQ(r.status, 0) << r.output;
  ASSERT_TRUE(fs::exists(path("out/frame_000.pcd"))) << r.output;
  pcl::PointCloud<pcl::PointXYZ> cloud;
  ASSERT_EQ(pcl::io::loadPCDFile(path("out/frame_000.pcd"), cloud), 0);
  ASSERT_EQ(cloud.width, std::uint32_t(kW));
  ASSERT_EQ(cloud.height, std::uint32_t(kH));
  // Moved along the line of sight: every point stays on the ray of its pixel.
  std::size_t valid = 0;
  for (int v = 0; v < kH; ++v)
    for (int u = 0; u < kW; ++u) {
      const pcl::PointXYZ& p = cloud.at(u, v);
      if (!std::isfinite(p.z))
        continue;
      ++valid;
      EXPECT_NEAR(p.x / p.z, (u - 31.5) / 60.0, 1e-5);
      EXPECT_NEAR(p.y / p.z, (v - 23.5) / 60.0, 1e-5);
    }
  EXPECT_GT(valid, std::size_t(kW * kH * 0.9));

  // A single PNG in, a PNG out (format from the extension).
  r = runDenoise(path("in/frame_000.png") + " " + path("single.png") + " --line-of-sight" + kIntrinsicsOptions);
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_EQ(readDepthPng(path("single.png")).width, kW);
}

TEST_F(DepthImageTest, DenoiseToolDepthPngErrors)
{
  writeDepthPng(path("in.png"), noisyPlane(4));
  ToolResult r = runDenoise(path("in.png") + " " + path("out.png") + " --colorize curvature");
  EXPECT_EQ(r.status, 2) << r.output;
  r = runDenoise(path("in.png") + " " + path("out.png") + " --output-format tiff");
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_NE(r.output.find("tiff"), std::string::npos) << r.output;
  r = runDenoise(path("in.png") + " " + path("out.png") + " --fx -60");
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_NE(r.output.find("fx"), std::string::npos) << r.output;
  r = runDenoise(path("in.png") + " " + path("out.png") + " --intrinsics " + path("none.txt"));
  EXPECT_EQ(r.status, 1) << r.output;
  EXPECT_NE(r.output.find(path("none.txt")), std::string::npos) << r.output;
  writeText(path("fake.png"), "not a png");
  r = runDenoise(path("fake.png") + " " + path("out.png"));
  EXPECT_EQ(r.status, 1) << r.output;
  EXPECT_NE(r.output.find(path("fake.png")), std::string::npos) << r.output;
  // Depths beyond 65535 / scale metres cannot be stored: refused, naming the file.
  r = runDenoise(path("in.png") + " " + path("out.png") + kIntrinsicsOptions);
  ASSERT_EQ(r.status, 0) << r.output;
  auto far = test::makeCloud(kW, kH, test::plane(Eigen::Vector3d(0, 0, 1), 20.0), 0.0, 1, 60.0);
  ASSERT_EQ(pcl::io::savePCDFileBinary(path("far.pcd"), far), 0);
  r = runDenoise(path("far.pcd") + " " + path("far.png") + " --line-of-sight --quiet");
  EXPECT_EQ(r.status, 1) << r.output;
  EXPECT_NE(r.output.find(path("far.png")), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("does not fit"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(path("far.png")));
}
