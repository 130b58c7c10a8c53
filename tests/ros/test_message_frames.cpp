// ROS messages -> organized frames: a PointCloud2 whose layout is ambiguous (an x field twice, an x
// of no elements) is refused as the PCD reader refuses such a header, and a cloud too small for
// the windows is refused before it is decoded.
#include "ros_test_support.h"
#include "test_support.h"

#include <range_nlm/ros/message_frames.h>

#include <gtest/gtest.h>

#include <sys/resource.h>

#include <string>

using namespace range_nlm;
using range_nlm_ros::cloudFromPointCloud2;
using range_nlm_ros::InvalidMessage;

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
