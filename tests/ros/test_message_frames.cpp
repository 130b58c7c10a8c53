// ROS messages -> organized frames: a PointCloud2 whose layout is ambiguous (an x field twice, an x
// of no elements) is refused as the PCD reader refuses such a header, and a cloud too small for
// the windows is refused before it is decoded. The conversions run on the filter's threads and
// give the same cloud, message and first error whatever their number.
#include "ros_test_support.h"
#include "test_support.h"

#include <range_nlm/ros/message_frames.h>

#include <gtest/gtest.h>

#include <sys/resource.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <string>

using namespace range_nlm;
using range_nlm_ros::cloudFromPointCloud2;
using range_nlm_ros::InvalidMessage;
using range_nlm_ros::pointCloud2WithXyz;
using Cloud = range_nlm_ros::Cloud;

namespace
{

std::string
refusal(const sensor_msgs::PointCloud2& message, const FilterParameters* parameters = nullptr)
{
  try {
    cloudFromPointCloud2(message, parameters);
  } catch (const InvalidMessage& e) {
    return e.what();
  }
  return "";
}

sensor_msgs::PointCloud2
goodMessage()
{
  return test::toPointCloud2(test::makeCloud(16, 12, test::plane({0.0, 0.0, 1.0}, 1.0), 0.001, 3), 1, 0);
}

/// The peak of this process's resident set, bytes.
long long
peakResidentBytes()
{
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return static_cast<long long>(usage.ru_maxrss) * 1024;
}

} // namespace

TEST(MessageFrames, AmbiguousCoordinateFieldsAreRefusedAsInPcdFiles)
{
  EXPECT_EQ(refusal(goodMessage()), "");

  sensor_msgs::PointCloud2 twice = goodMessage();
  sensor_msgs::PointField second_x = twice.fields[0];
  second_x.offset = 16; // the intensity's bytes
  twice.fields.push_back(second_x);
  EXPECT_EQ(refusal(twice), "PointCloud2 field 'x' appears twice");

  sensor_msgs::PointCloud2 empty_x = goodMessage();
  empty_x.fields[0].count = 0;
  EXPECT_EQ(refusal(empty_x), "PointCloud2 field 'x' has COUNT 0");

  sensor_msgs::PointCloud2 twice_other = goodMessage();
  twice_other.fields.push_back(twice_other.fields[3]); // intensity
  EXPECT_EQ(refusal(twice_other), "PointCloud2 field 'intensity' appears twice");
}

// 1 x 10,000,000 points: no parameters filter it (the smallest plane fit is 3 x 3), and it is
// refused from its width and height, before a point of it is converted (160 MB more). With
// parameters, a cloud smaller than their windows is refused the same way.
TEST(MessageFrames, CloudTooSmallForTheWindowsIsRefusedBeforeItIsDecoded)
{
  sensor_msgs::PointCloud2 column = goodMessage();
  column.width = 1;
  column.height = 10000000;
  column.row_step = column.point_step;
  column.data.assign(std::size_t(column.row_step) * column.height, 0);
  const long long before = peakResidentBytes();
  EXPECT_EQ(refusal(column), "PointCloud2 of 1 x 10000000 is smaller than the filter's smallest window (3 x 3 "
                             "points for a normal)");
  if (!test::kAddressSanitizer)
    EXPECT_LT(peakResidentBytes() - before, 50ll << 20) << "the cloud was decoded before it was refused";

  const sensor_msgs::PointCloud2 small = goodMessage(); // 16 x 12
  const FilterParameters defaults;                      // 9 x 9 search window
  EXPECT_EQ(refusal(small, &defaults), "");
  FilterParameters wide;
  wide.search_window = 13;
  EXPECT_EQ(refusal(small, &wide),
            "PointCloud2 of 16 x 12: range_nlm: parameter search_window = 13 is larger than the cloud (16 x 12)");
}

namespace
{

/// Writes `value` into coordinate `field` (0: x, 1: y, 2: z) of pixel (u, v) of a FLOAT32 message.
void
setCoordinate(sensor_msgs::PointCloud2& message, int u, int v, int field, float value)
{
  std::uint8_t* p = &message.data[(std::size_t(v) * message.width + u) * message.point_step];
  std::memcpy(p + message.fields[field].offset, &value, sizeof value);
}

} // namespace

// Decoded by 1, 2 or 3 threads: the same cloud (NaN points and is_dense included), and a cloud
// with infinite coordinates is refused naming the first of them in row order.
TEST(MessageFrames, DecodingGivesTheSameCloudAndFirstErrorWhateverTheThreads)
{
  sensor_msgs::PointCloud2 message =
      test::toPointCloud2(test::makeCloud(64, 48, test::plane({0.0, 0.0, 1.0}, 1.0), 0.001, 5), 1, 0);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  setCoordinate(message, 10, 40, 1, nan);
  FilterParameters one;
  one.threads = 1;
  const Cloud::Ptr reference = cloudFromPointCloud2(message, &one);
  EXPECT_FALSE(reference->is_dense);
  EXPECT_TRUE(std::isnan((*reference)(10, 40).x));
  sensor_msgs::PointCloud2 infinite = message;
  setCoordinate(infinite, 30, 44, 2, INFINITY);
  setCoordinate(infinite, 7, 5, 0, -INFINITY);
  setCoordinate(infinite, 50, 5, 1, INFINITY);
  for (int threads : {1, 2, 3}) {
    FilterParameters p;
    p.threads = threads;
    const Cloud::Ptr cloud = cloudFromPointCloud2(message, &p);
    EXPECT_EQ(test::compareXyz(*cloud, *reference), "") << threads << " threads";
    EXPECT_EQ(cloud->is_dense, reference->is_dense);
    EXPECT_EQ(refusal(infinite, &p), "PointCloud2 has an infinite (or out of float range) coordinate at pixel (7, 5); "
                                     "invalid points must be NaN")
        << threads << " threads";
  }
}

// The filtered coordinates written into a copy of the message by 1, 2 or 3 threads: every other
// byte as it was, x, y, z those of the cloud, is_dense recomputed.
TEST(MessageFrames, WritingTheCoordinatesKeepsEveryOtherByteWhateverTheThreads)
{
  const sensor_msgs::PointCloud2 message =
      test::toPointCloud2(test::makeCloud(64, 48, test::plane({0.0, 0.0, 1.0}, 1.0), 0.001, 6), 1, 0);
  Cloud filtered = *cloudFromPointCloud2(message);
  for (pcl::PointXYZ& q : filtered.points)
    q.z += 0.25f;
  filtered(3, 47).x = std::numeric_limits<float>::quiet_NaN();
  for (int threads : {1, 2, 3}) {
    const sensor_msgs::PointCloud2::Ptr out = pointCloud2WithXyz(message, filtered, threads);
    EXPECT_EQ(test::compareXyz(test::xyzOf(*out), filtered), "") << threads << " threads";
    EXPECT_FALSE(out->is_dense);
    EXPECT_EQ(out->header.stamp, message.header.stamp);
    EXPECT_EQ(out->header.frame_id, message.header.frame_id);
    ASSERT_EQ(out->data.size(), message.data.size());
    ASSERT_EQ(out->fields.size(), message.fields.size());
    std::vector<bool> coordinate(message.point_step, false);
    for (int f = 0; f < 3; ++f)
      for (std::uint32_t b = 0; b < 4; ++b)
        coordinate[message.fields[f].offset + b] = true;
    std::size_t other_bytes_changed = 0;
    for (std::size_t i = 0; i < message.data.size(); ++i)
      other_bytes_changed += !coordinate[i % message.point_step] && out->data[i] != message.data[i];
    EXPECT_EQ(other_bytes_changed, 0u) << threads << " threads";
  }
  Cloud dense = filtered;
  dense(3, 47).x = 0.0f;
  EXPECT_TRUE(pointCloud2WithXyz(message, dense, 2)->is_dense);
}
