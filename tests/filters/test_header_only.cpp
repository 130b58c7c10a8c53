// Header-only use (built with RANGE_NLM_HEADER_ONLY): the filters and the stream on a point type
// the library is not compiled for give the xyz of pcl::PointXYZ through the compiled library.
#include "header_only_reference.h"

#include <range_nlm/nonlocal_means_filter.h>
#include <range_nlm/temporal_stream.h>

#include <pcl/point_types.h>

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

#ifndef RANGE_NLM_HEADER_ONLY
#error "this test is built with RANGE_NLM_HEADER_ONLY"
#endif

namespace header_only_test
{
/// A point type of its own: x, y, z and a confidence, laid out as PCL lays out its types.
struct EIGEN_ALIGN16 RangePoint
{
  PCL_ADD_POINT4D;
  float confidence;
  PCL_MAKE_ALIGNED_OPERATOR_NEW
};
} // namespace header_only_test

POINT_CLOUD_REGISTER_POINT_STRUCT(header_only_test::RangePoint,
                                  (float, x, x)(float, y, y)(float, z, z)(float, confidence, confidence))

using header_only_test::RangePoint;
using namespace range_nlm;

namespace
{
using Cloud = pcl::PointCloud<pcl::PointXYZ>;

/// A tilted plane seen from the origin with Gaussian noise along the rays, a box in front of it
/// and 3 % of the pixels NaN.
Cloud
generatedFrame(std::uint32_t seed)
{
  Cloud cloud(40, 32);
  std::mt19937 random(seed);
  std::normal_distribution<float> noise(0.0f, 0.004f);
  std::uniform_real_distribution<float> uniform(0.0f, 1.0f);
  for (int v = 0; v < 32; ++v)
    for (int u = 0; u < 40; ++u) {
      const float a = (u - 19.5f) / 60.0f, b = (v - 15.5f) / 60.0f;
      const bool box = u >= 12 && u < 24 && v >= 8 && v < 20;
      const float z = (box ? 0.9f : 1.0f + 0.2f * a) + noise(random);
      pcl::PointXYZ& p = cloud.at(u, v);
      p.x = a * z, p.y = b * z, p.z = z;
      if (uniform(random) < 0.03f)
        p.x = p.y = p.z = std::numeric_limits<float>::quiet_NaN();
    }
  cloud.is_dense = false;
  return cloud;
}

pcl::PointCloud<RangePoint>
withConfidence(const Cloud& xyz)
{
  pcl::PointCloud<RangePoint> out(xyz.width, xyz.height);
  for (std::size_t i = 0; i < xyz.size(); ++i) {
    out[i].x = xyz[i].x, out[i].y = xyz[i].y, out[i].z = xyz[i].z;
    out[i].confidence = 0.5f + 0.001f * float(i);
  }
  out.is_dense = xyz.is_dense;
  return out;
}

/// x, y, z equal to the bit, confidence untouched.
void
expectSameXyz(const pcl::PointCloud<RangePoint>& got, const Cloud& expected)
{
  ASSERT_EQ(got.size(), expected.size());
  for (std::size_t i = 0; i < got.size(); ++i) {
    EXPECT_EQ(std::memcmp(&got[i].x, &expected[i].x, 3 * sizeof(float)), 0) << "point " << i;
    EXPECT_EQ(got[i].confidence, 0.5f + 0.001f * float(i)) << "point " << i;
  }
  EXPECT_EQ(got.is_dense, expected.is_dense);
}
} // namespace

TEST(HeaderOnly, CustomPointTypeFiltersAsPointXyzThroughTheLibrary)
{
  const Cloud xyz = generatedFrame(5);
  const FilterParameters p = FilterParameters::recommended();
  NonLocalMeansFilter<RangePoint> filter;
  filter.setParameters(p);
  filter.setInputCloud(pcl::PointCloud<RangePoint>::ConstPtr(new pcl::PointCloud<RangePoint>(withConfidence(xyz))));
  pcl::PointCloud<RangePoint> out;
  filter.filter(out);
  const Cloud expected = test::filteredByLibrary(xyz, p);
  expectSameXyz(out, expected);
  EXPECT_NE(std::memcmp(&expected[0].x, &xyz[0].x, 3 * sizeof(float)), 0) << "the filter moved nothing";
}

TEST(HeaderOnly, CustomPointTypeStreamsAsPointXyzThroughTheLibrary)
{
  std::vector<Cloud::ConstPtr> xyz;
  std::vector<pcl::PointCloud<RangePoint>::ConstPtr> frames;
  for (std::uint32_t k = 0; k < 3; ++k) {
    xyz.emplace_back(new Cloud(generatedFrame(10 + k)));
    frames.emplace_back(new pcl::PointCloud<RangePoint>(withConfidence(*xyz.back())));
  }
  const FilterParameters p = FilterParameters::recommended();
  const auto out = filterSequence<RangePoint>(frames, 1, TemporalWindow::centred, p);
  const auto expected = test::sequenceFilteredByLibrary(xyz, p);
  ASSERT_EQ(out.size(), 3u);
  ASSERT_EQ(expected.size(), 3u);
  for (std::size_t k = 0; k < 3; ++k)
    expectSameXyz(*out[k], *expected[k]);
}
