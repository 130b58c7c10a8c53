#include "test_support.h"

#include <range_nlm/grid_adaptor.h>
#include <range_nlm/point_types.h>

#include <pcl/point_types.h>

#include <boost/preprocessor/seq/enum.hpp>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <functional>
#include <limits>
#include <stdexcept>
#include <string>

using namespace range_nlm;
using Cloud = pcl::PointCloud<pcl::PointXYZ>;

namespace
{
/// A 5 x 4 cloud of PointT whose every byte outside x, y, z holds a pattern of the point's index,
/// with a NaN in one coordinate of points 3 (x), 6 (y) and 13 (z).
template <typename PointT>
pcl::PointCloud<PointT>
patternedCloud()
{
  pcl::PointCloud<PointT> cloud(5, 4);
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    PointT& p = cloud[i];
    unsigned char* bytes = reinterpret_cast<unsigned char*>(&p);
    for (std::size_t b = 0; b < sizeof(PointT); ++b)
      bytes[b] = static_cast<unsigned char>(0x11 * (i % 7) + b);
    p.x = 0.01f * float(i % 5), p.y = 0.02f * float(i / 5), p.z = 1.0f + 0.001f * float(i);
  }
  const float nan = std::numeric_limits<float>::quiet_NaN();
  cloud[3].x = nan;
  cloud[6].y = nan;
  cloud[13].z = nan;
  cloud.is_dense = true; // wrong on purpose: fromGrid recomputes it
  return cloud;
}
} // namespace

// Every instantiated point type: a NaN in any one coordinate makes the point invalid, NaN in all
// of x, y and z on the way back; every field but x, y, z keeps its bytes, and is_dense is
// recomputed.
template <typename PointT>
class GridAdaptorPointTypes : public ::testing::Test
{};
using InstantiatedTypes = ::testing::Types<BOOST_PP_SEQ_ENUM(RANGE_NLM_POINT_TYPES)>;
TYPED_TEST_SUITE(GridAdaptorPointTypes, InstantiatedTypes);

TYPED_TEST(GridAdaptorPointTypes, NanInAnyCoordinateGivesNanInAllAndOtherFieldsStay)
{
  const pcl::PointCloud<TypeParam> in = patternedCloud<TypeParam>();
  const Grid g = toGrid(in);
  ASSERT_EQ(g.width, 5);
  ASSERT_EQ(g.height, 4);
  EXPECT_EQ(g.countValid(), in.size() - 3);
  pcl::PointCloud<TypeParam> out;
  fromGrid(in, g, out);
  ASSERT_EQ(out.size(), in.size());
  EXPECT_EQ(out.width, in.width);
  EXPECT_EQ(out.height, in.height);
  EXPECT_FALSE(out.is_dense);
  for (std::size_t i = 0; i < in.size(); ++i) {
    const bool invalid = i == 3 || i == 6 || i == 13;
    EXPECT_EQ(g.valid[i], invalid ? 0 : 1) << i;
    if (invalid)
      EXPECT_TRUE(std::isnan(out[i].x) && std::isnan(out[i].y) && std::isnan(out[i].z)) << i;
    TypeParam expected = in[i];
    expected.x = out[i].x, expected.y = out[i].y, expected.z = out[i].z;
    EXPECT_EQ(std::memcmp(&expected, &out[i], sizeof(TypeParam)), 0) << "fields of point " << i;
    if (!invalid)
      EXPECT_TRUE(out[i].x == in[i].x && out[i].y == in[i].y && out[i].z == in[i].z) << i;
  }
  // In place, and into an output of the input's size (its storage is reused).
  pcl::PointCloud<TypeParam> same = in;
  fromGrid(same, g, same);
  EXPECT_EQ(std::memcmp(same.data(), out.data(), sizeof(TypeParam) * out.size()), 0);
  fromGrid(in, g, out);
  EXPECT_EQ(std::memcmp(same.data(), out.data(), sizeof(TypeParam) * out.size()), 0);

  // A cloud without an invalid point comes back dense.
  pcl::PointCloud<TypeParam> dense = in;
  dense[3].x = dense[6].y = dense[13].z = 0.5f;
  dense.is_dense = false;
  fromGrid(dense, toGrid(dense), out);
  EXPECT_TRUE(out.is_dense);
}

// A cloud the filters cannot read as a grid is refused with a message naming it.
TEST(GridAdaptor, UnorganizedCloudsAreRefusedByName)
{
  Cloud row(20, 1);
  EXPECT_NE(test::errorOf([&] { toGrid(row, "test frame"); }).find("the test frame is not organized (width 20, height 1)"),
            std::string::npos);
  Cloud mismatched(4, 3);
  mismatched.height = 4;
  EXPECT_NE(test::errorOf([&] { toGrid(mismatched); }).find("holds 12 points but declares width x height = 4 x 4"),
            std::string::npos);
}

// The conversion to the grid decides validity from the bits of the coordinates: a point with any
// NaN coordinate is invalid with NaN in all three, the extreme finite values (largest float,
// denormal, negative zero) stay valid and unchanged, and the first infinity of either sign in
// any coordinate is reported at its pixel, with a clean conversion before it.
TEST(GridAdaptor, ValidityAndInfinitiesFromTheCoordinateBits)
{
  Cloud cloud(4, 3);
  for (std::size_t i = 0; i < cloud.size(); ++i)
    cloud[i].x = 0.1f * i, cloud[i].y = -0.2f, cloud[i].z = 1.0f + 0.01f * i;
  cloud[1].y = std::nanf("");                       // one NaN coordinate
  cloud[2].x = -std::numeric_limits<float>::max(); // extreme finite values
  cloud[2].z = std::numeric_limits<float>::denorm_min();
  cloud[3].y = -0.0f;
  const Grid g = toGrid(cloud);
  ASSERT_EQ(g.size(), cloud.size());
  EXPECT_EQ(g.valid[1], 0);
  EXPECT_TRUE(std::isnan(g.x[1]) && std::isnan(g.y[1]) && std::isnan(g.z[1]));
  for (std::size_t i : {0u, 2u, 3u, 11u}) {
    EXPECT_EQ(g.valid[i], 1) << i;
    EXPECT_EQ(g.x[i], cloud[i].x) << i;
    EXPECT_EQ(g.y[i], cloud[i].y) << i;
    EXPECT_EQ(g.z[i], cloud[i].z) << i;
  }
  EXPECT_TRUE(std::signbit(g.y[3]));
  EXPECT_EQ(g.countValid(), cloud.size() - 1);

  Cloud back;
  fromGrid(cloud, g, back);
  EXPECT_FALSE(back.is_dense);
  EXPECT_TRUE(std::isnan(back[1].x) && std::isnan(back[1].z));
  EXPECT_EQ(back[2].x, cloud[2].x);

  Cloud infinite = cloud;
  infinite[9].y = -INFINITY; // pixel (1, 2)
  infinite[10].z = INFINITY;
  EXPECT_NE(test::errorOf([&] { toGrid(infinite); }).find("infinite coordinate at pixel (1, 2)"),
            std::string::npos);
}

