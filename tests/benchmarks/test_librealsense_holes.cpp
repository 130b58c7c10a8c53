// The reimplementation of librealsense's hole-filling filter (benchmarks/librealsense_holes.h)
// against the semantics of src/proc/hole-filling-filter.h: each mode's scan on a tiny image whose
// result is derived by hand, the pixels no mode touches, and the cloud adaptor.
#include "librealsense_holes.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <vector>

using range_nlm::tools::librealsense::HoleFillingFilter;
using range_nlm::tools::librealsense::HoleFillingMode;
using range_nlm::tools::librealsense::HoleFillingParameters;
using range_nlm::tools::librealsense::PinholeRays;
using Image = std::vector<std::uint16_t>;

namespace
{
// 4 x 4, 0 = hole: holes inside, in the first row and in the last row.
const Image kInput = {10, 20, 0,  40, //
                      50, 0,  0,  60, //
                      70, 0,  80, 90, //
                      11, 0,  13, 14};

Image
filled(HoleFillingMode mode, Image image = kInput, int width = 4, int height = 4)
{
  HoleFillingParameters p;
  p.mode = mode;
  HoleFillingFilter(p).process(image.data(), width, height);
  return image;
}
} // namespace

TEST(LibrealsenseHoles, TheDefaultIsFarthestFromAroundInMillimetres)
{
  const HoleFillingParameters p;
  EXPECT_EQ(p.mode, HoleFillingMode::farthest_from_around);
  EXPECT_DOUBLE_EQ(p.depth_unit, 0.001);
}

TEST(LibrealsenseHoles, FillFromLeftCopiesTheLeftNeighbourAlongEveryRowButTheFirstColumn)
{
  // Row 0: (2, 0) takes 20. Row 1: (1, 1) takes 50, then (2, 1) the 50 just written. Row 3: 11.
  EXPECT_EQ(filled(HoleFillingMode::fill_from_left), (Image{10, 20, 20, 40, //
                                                            50, 50, 50, 60, //
                                                            70, 70, 80, 90, //
                                                            11, 11, 13, 14}));
  // A hole in the first column stays.
  EXPECT_EQ(filled(HoleFillingMode::fill_from_left, {0, 5, 0, 0, 7, 0, 3, 0}, 4, 2),
            (Image{0, 5, 5, 5, 7, 7, 3, 3}));
}

TEST(LibrealsenseHoles, FarthestTakesTheLargestOfTheFiveNeighboursUpLeftAndDown)
{
  // (1, 1): max(up 20, up-left 10, left 50, down-left 70, down 0) = 70.
  // (2, 1): max(up 0, up-left 20, left 70 (just filled), down-left 0, down 80) = 80; its right
  //         neighbour 60 is not read.
  // (1, 2): max(70, 50, 70, 11, 0) = 70. The holes of the first and last rows stay.
  EXPECT_EQ(filled(HoleFillingMode::farthest_from_around), (Image{10, 20, 0,  40, //
                                                                  50, 70, 80, 60, //
                                                                  70, 70, 80, 90, //
                                                                  11, 0,  13, 14}));
}

TEST(LibrealsenseHoles, NearestStartsFromTheUpperNeighbourAndKeepsAHoleBelowAHole)
{
  // (1, 1): from up 20, the smaller up-left 10 wins; down is a hole and is skipped.
  // (2, 1): its upper neighbour is a hole: it starts at 0 and stays a hole (the source's quirk).
  // (1, 2): from up 10 (just filled); nothing smaller.
  EXPECT_EQ(filled(HoleFillingMode::nearest_from_around), (Image{10, 20, 0,  40, //
                                                                 50, 10, 0,  60, //
                                                                 70, 10, 80, 90, //
                                                                 11, 0,  13, 14}));
}

TEST(LibrealsenseHoles, BadParametersAndSizesAreRefused)
{
  HoleFillingParameters p;
  p.depth_unit = 0.0;
  EXPECT_THROW(HoleFillingFilter{p}, std::invalid_argument);
  p = {};
  p.mode = static_cast<HoleFillingMode>(3);
  EXPECT_THROW(HoleFillingFilter{p}, std::invalid_argument);
  Image one{0};
  EXPECT_THROW(HoleFillingFilter().process(one.data(), 0, 1), std::invalid_argument);
}

TEST(LibrealsenseHoles, TheCloudAdaptorPutsFilledPixelsOnTheirRaysAndKeepsMeasuredPoints)
{
  // 3 x 3 at 1.2 m and 1.5 m; the centre is a hole that farthest-from-around fills with 1.5 m.
  PinholeRays rays;
  rays.fx = rays.fy = 2.0;
  rays.cx = rays.cy = 1.0;
  pcl::PointCloud<pcl::PointXYZ> cloud(3, 3);
  for (int v = 0; v < 3; ++v)
    for (int u = 0; u < 3; ++u) {
      const float z = u == 0 ? 1.5f : 1.2003f; // off the millimetre grid: kept as it is
      cloud(u, v) = pcl::PointXYZ(float((u - 1.0) / 2.0 * z), float((v - 1.0) / 2.0 * z), z);
    }
  const float nan = std::numeric_limits<float>::quiet_NaN();
  cloud(1, 1) = pcl::PointXYZ(nan, nan, nan);
  cloud(2, 0) = pcl::PointXYZ(nan, nan, nan); // first row: stays a hole
  cloud.is_dense = false;
  const pcl::PointCloud<pcl::PointXYZ> out = HoleFillingFilter().filter(cloud, rays);
  EXPECT_FLOAT_EQ(out(1, 1).z, 1.5f);
  EXPECT_FLOAT_EQ(out(1, 1).x, 0.0f);
  EXPECT_FLOAT_EQ(out(1, 1).y, 0.0f);
  EXPECT_TRUE(std::isnan(out(2, 0).x) && std::isnan(out(2, 0).y) && std::isnan(out(2, 0).z));
  EXPECT_FALSE(out.is_dense);
  EXPECT_EQ(out(2, 2).z, 1.2003f);
  EXPECT_EQ(out(2, 2).x, cloud(2, 2).x);
  pcl::PointCloud<pcl::PointXYZ> wide(2, 1);
  wide(0, 0) = pcl::PointXYZ(0.0f, 0.0f, 70.0f); // 70000 mm: no 16-bit depth
  EXPECT_THROW(HoleFillingFilter().filter(wide, rays), std::invalid_argument);
}
