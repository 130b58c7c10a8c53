// range_nlm_denoise at the limits: frames whose header announces more memory than --memory-limit
// (decompression bombs) are refused quickly by name and figure, absurd thread counts are refused,
// depths a filtered 16-bit image cannot hold are clamped with a warning, and depth PNGs read with
// default intrinsics or with intrinsics of another size are reported.
#include "test_support.h"

#include <range_nlm/io/depth_image.h>

#include <pcl/io/pcd_io.h>

#include <gtest/gtest.h>
#include <png.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <string>
#include <vector>

#include <unistd.h>

namespace fs = std::filesystem;
using namespace range_nlm;

namespace
{

class Limits : public ::testing::Test
{
protected:
  void SetUp() override
  {
    dir_ = fs::temp_directory_path() / ("range_nlm_limits_" + std::to_string(::getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  fs::path dir_;
};

/// A width x height 16-bit greyscale PNG of zeros, written row by row (never held in memory):
/// deflate shrinks it about a thousandfold.
void
writeZeroPng(const std::string& path, std::uint32_t width, std::uint32_t height)
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
  png_set_compression_level(png, 9);
  png_set_filter(png, 0, PNG_FILTER_NONE);
  png_set_IHDR(png, info, width, height, 16, PNG_COLOR_TYPE_GRAY, PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT,
               PNG_FILTER_TYPE_DEFAULT);
  png_write_info(png, info);
  std::vector<png_byte> row(std::size_t(width) * 2, 0);
  for (std::uint32_t v = 0; v < height; ++v)
    png_write_row(png, row.data());
  png_write_end(png, nullptr);
  png_destroy_write_struct(&png, &info);
  std::fclose(file);
}

double
secondsOf(const std::function<void()>& f)
{
  const auto start = std::chrono::steady_clock::now();
  f();
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

} // namespace

// 20000 x 20000 16-bit pixels: a file of a few hundred kB that would need tens of GB. Refused from
// its header, in well under the time decoding it would take, with the file and the figure.
TEST_F(Limits, DecompressionBombPngIsRefusedFromItsHeader)
{
  const std::string bomb = path("bomb.png");
  writeZeroPng(bomb, 20000, 20000);
  EXPECT_LT(fs::file_size(bomb), 2u * 1024 * 1024);
  test::CommandResult r;
  const double seconds = secondsOf([&] { r = test::runDenoise(bomb + " " + path("out.png") + " -q"); });
  EXPECT_EQ(r.status, 1) << r.output;
  EXPECT_NE(r.output.find("'" + bomb + "'"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("memory"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("20000 x 20000"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("--memory-limit"), std::string::npos) << r.output;
  EXPECT_LT(seconds, 5.0);
  EXPECT_FALSE(fs::exists(path("out.png")));

  // With the check off and too little memory (address space limited to 700 MB, the 800 MB of
  // pixels do not fit), running out of memory still names the frame.
  if (!test::kAddressSanitizer) { // AddressSanitizer reserves terabytes of address space
    r = test::runCommand("ulimit -v 700000 && exec " + std::string(RANGE_NLM_TOOLS_DIR) + "/range_nlm_denoise " +
                         bomb + " " + path("out.png") + " -q --memory-limit 0");
    EXPECT_EQ(r.status, 1) << r.output;
    EXPECT_NE(r.output.find("'" + bomb + "': out of memory while reading the frame"), std::string::npos) << r.output;
    EXPECT_FALSE(fs::exists(path("out.png")));
  }

  // No limit: the same header passes the check (and decoding it is left untried here); a limit
  // refuses a VGA frame too, with the estimate in MB.
  const std::string milk = std::string(RANGE_NLM_SOURCE_DIR) + "/data/milk_cartoon_all_small_clorox.pcd";
  r = test::runDenoise(milk + " " + path("milk.pcd") + " -q --memory-limit 10");
  EXPECT_EQ(r.status, 1) << r.output;
  EXPECT_NE(r.output.find("'" + milk + "'"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("a 640 x 480 frame needs about"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("more than the limit of 10 MB"), std::string::npos) << r.output;
  r = test::runDenoise(milk + " " + path("milk.pcd") + " -q --memory-limit -1");
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_NE(r.output.find("--memory-limit"), std::string::npos) << r.output;
}

// A PCD header announcing 2^28 points in front of a small binary_compressed body.
TEST_F(Limits, PcdAnnouncingHugeFrameIsRefusedBeforeItsBodyIsRead)
{
  const std::string bomb = path("bomb.pcd");
  {
    std::ofstream out(bomb, std::ios::binary);
    out << "# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\n"
           "COUNT 1 1 1\nWIDTH 16384\nHEIGHT 16384\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 268435456\n"
           "DATA binary_compressed\n";
    out << std::string(64, '\0');
  }
  const test::CommandResult r = test::runDenoise(bomb + " " + path("out.pcd") + " -q");
  EXPECT_EQ(r.status, 1) << r.output;
  EXPECT_NE(r.output.find("'" + bomb + "'"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("16384 x 16384 frame needs about"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("memory"), std::string::npos) << r.output;
}

TEST_F(Limits, ThreadCountAboveTheMaximumIsAUsageError)
{
  const auto cloud = test::makeCloud(32, 24, test::plane({0.1, 0.0, 1.0}, 1.0), 0.002, 5);
  ASSERT_EQ(pcl::io::savePCDFileBinary(path("in.pcd"), cloud), 0);
  test::CommandResult r = test::runDenoise(path("in.pcd") + " " + path("out.pcd") + " -q --threads 100000");
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_NE(r.output.find("threads = 100000"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("1024"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(path("out.pcd")));
  r = test::runDenoise(path("in.pcd") + " " + path("out.pcd") + " -q --threads 1024");
  EXPECT_EQ(r.status, 0) << r.output;
}

// A slanted surface whose far part is at the sensor's largest value (65535, clipped like a real
// sensor's far range): filtering fits the ramp and carries some pixels past 65535. They are
// stored as 65535 with a warning giving their number; holes stay holes.
TEST_F(Limits, NearSaturatedDepthPngIsClampedWithAWarning)
{
  constexpr int w = 64, h = 48;
  DepthImage image;
  image.width = w;
  image.height = h;
  image.values.resize(std::size_t(w) * h);
  std::uint64_t state = 12345;
  for (int v = 0; v < h; ++v)
    for (int u = 0; u < w; ++u) {
      state = state * 6364136223846793005ull + 1442695040888963407ull;
      const double noise = double(state >> 40) / double(1ull << 24) * 160.0 - 80.0;
      const double value = 64800.0 + 30.0 * u + noise;
      image.values[std::size_t(v) * w + u] = std::uint16_t(std::min(65535.0, std::max(1.0, std::round(value))));
    }
  image.values[5 * w + 5] = 0; // a hole
  writeDepthPng(path("saturated.png"), image);
  const std::string options = " --fx 60 --fy 60 --cx 31.5 --cy 23.5 --depth-scale 5000 --line-of-sight";
  const test::CommandResult r = test::runDenoise(path("saturated.png") + " " + path("out.png") + options);
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("warning: '" + path("out.png") + "'"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("stored as 65535"), std::string::npos) << r.output;
  const DepthImage out = readDepthPng(path("out.png"));
  ASSERT_EQ(out.values.size(), image.values.size());
  std::size_t at_max = 0;
  for (std::size_t i = 0; i < out.values.size(); ++i) {
    EXPECT_EQ(out.values[i] == 0, image.values[i] == 0) << "pixel " << i;
    at_max += out.values[i] == 65535;
  }
  EXPECT_GT(at_max, 0u);
  // The warning's count is the number of pixels the filter carried past the range.
  const std::size_t count_at = r.output.find(" pixel(s) filtered to more than");
  ASSERT_NE(count_at, std::string::npos) << r.output;
  const std::size_t count_from = r.output.rfind(' ', count_at - 1) + 1;
  const std::size_t clamped = std::stoul(r.output.substr(count_from, count_at - count_from));
  EXPECT_GT(clamped, 0u);
  EXPECT_LE(clamped, at_max);
}

// Without --intrinsics, a depth PNG read with default values is reported once, naming the file
// and the defaults; not with an intrinsics file, nor when every value is given.
TEST_F(Limits, DefaultIntrinsicsAreReported)
{
  const auto cloud = test::makeCloud(64, 48, test::plane({0.0, 0.0, 1.0}, 1.0), 0.003, 9, 60.0);
  fs::create_directories(path("in"));
  writeDepthPng(path("in/a.png"), cloudToDepthImage(cloud, 5000.0));
  writeDepthPng(path("in/b.png"), cloudToDepthImage(cloud, 5000.0));
  test::CommandResult r = test::runDenoise("--input-dir " + path("in") + " --output-dir " + path("out") + " -q");
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("warning: '" + path("in/a.png") + "'"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("default intrinsics"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("depth-scale 5000"), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("'" + path("in/b.png") + "'"), std::string::npos) << "warned once: " << r.output;

  std::ofstream(path("intrinsics.txt")) << "width 64\nheight 48\nfx 60\nfy 60\ncx 31.5\ncy 23.5\ndepth_scale 5000\n";
  r = test::runDenoise(path("in/a.png") + " " + path("a.png") + " -q --intrinsics " + path("intrinsics.txt"));
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_EQ(r.output.find("warning"), std::string::npos) << r.output;
  r = test::runDenoise(path("in/a.png") + " " + path("a.png") +
                       " -q --fx 60 --fy 60 --cx 31.5 --cy 23.5 --depth-scale 5000");
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_EQ(r.output.find("warning"), std::string::npos) << r.output;
  // Only --depth-scale given: the focal lengths and centre are still defaults.
  r = test::runDenoise(path("in/a.png") + " " + path("a.png") + " -q --depth-scale 5000");
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("fx 525"), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("depth-scale 5000"), std::string::npos) << r.output;
}

// Intrinsics for 640 x 480 applied to a 64 x 48 image: refused, naming both files and sizes.
TEST_F(Limits, IntrinsicsOfAnotherImageSizeAreRefused)
{
  const auto cloud = test::makeCloud(64, 48, test::plane({0.0, 0.0, 1.0}, 1.0), 0.003, 9, 60.0);
  writeDepthPng(path("small.png"), cloudToDepthImage(cloud, 5000.0));
  const std::string tum = std::string(RANGE_NLM_SOURCE_DIR) + "/data/depth-images/tum-fr2-desk-pair/intrinsics.txt";
  const test::CommandResult r = test::runDenoise(path("small.png") + " " + path("out.png") + " -q --intrinsics " + tum);
  EXPECT_EQ(r.status, 1) << r.output;
  EXPECT_NE(r.output.find("'" + path("small.png") + "'"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("'" + tum + "'"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("64 x 48"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("640 x 480"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(path("out.png")));
}
