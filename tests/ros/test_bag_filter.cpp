// range_nlm_denoise --input-bag: a bag made here is filtered; other topics come out byte for
// byte, the filtered topic equals the directory mode's output on the same frames.
#include "ros_test_support.h"
#include "test_support.h"

#include <range_nlm/io/pcd_file.h>

#include <gtest/gtest.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/PointCloud2.h>
#include <std_msgs/String.h>

#include <cstdio>
#include <filesystem>
#include <limits>

using namespace range_nlm;
using namespace range_nlm::test;
using Cloud = pcl::PointCloud<pcl::PointXYZ>;
namespace fs = std::filesystem;

namespace
{

const char* const kTopic = "/camera/depth/points";

class BagFilter : public ::testing::Test
{
protected:
  void SetUp() override
  {
    char dir[] = "/tmp/range_nlm_bag_XXXXXX";
    ASSERT_TRUE(::mkdtemp(dir));
    dir_ = dir;
  }
  void TearDown() override
  {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }
  std::string path(const std::string& name) const { return dir_ + "/" + name; }

  static Cloud::Ptr frame(int k)
  {
    Cloud::Ptr cloud(new Cloud(makeCloud(48, 36, step(24, 1.5, 2.0), 0.004, 300 + k)));
    punchHoles(*cloud, 0.03, 400 + k);
    return cloud;
  }

  /// A bag with `frames` clouds on kTopic and a string and a camera info per frame on other topics.
  std::vector<sensor_msgs::PointCloud2> writeBag(const std::string& bag_path, int frames)
  {
    rosbag::Bag bag(bag_path, rosbag::bagmode::Write);
    std::vector<sensor_msgs::PointCloud2> clouds;
    for (int k = 0; k < frames; ++k) {
      const ros::Time t(1000 + k, 5000);
      std_msgs::String text;
      text.data = "frame " + std::to_string(k);
      bag.write("/log", t - ros::Duration(0.01), text);
      clouds.push_back(toPointCloud2(*frame(k), 1000 + k, 1000));
      clouds.back().header.seq = k;
      bag.write(kTopic, t, clouds.back());
      sensor_msgs::CameraInfo info;
      info.header.stamp = t;
      info.width = 48;
      info.K[0] = 300.0 + k;
      bag.write("/camera/depth/camera_info", t + ros::Duration(0.001), info);
    }
    bag.close();
    return clouds;
  }

  /// The same clouds as PCD files (every field), for the directory mode.
  void writeFrames(const std::string& directory, const std::vector<sensor_msgs::PointCloud2>& clouds)
  {
    fs::create_directories(directory);
    for (std::size_t k = 0; k < clouds.size(); ++k) {
      const sensor_msgs::PointCloud2& m = clouds[k];
      pcl::PCLPointCloud2 blob;
      blob.width = m.width;
      blob.height = m.height;
      blob.point_step = m.point_step;
      blob.row_step = m.row_step;
      blob.is_dense = m.is_dense;
      blob.is_bigendian = m.is_bigendian;
      for (const auto& f : m.fields) {
        pcl::PCLPointField field;
        field.name = f.name;
        field.offset = f.offset;
        field.datatype = f.datatype;
        field.count = f.count;
        blob.fields.push_back(field);
      }
      blob.data = m.data;
      char name[32];
      std::snprintf(name, sizeof name, "/frame_%03zu.pcd", k);
      io::saveCloudAtomic(directory + name, blob);
    }
  }

  std::string dir_;
};

/// Serialized bytes of every message of a bag, in time order: (topic, time, bytes).
struct Record
{
  std::string topic;
  ros::Time time;
  std::vector<std::uint8_t> bytes;
};
std::vector<Record>
records(const std::string& bag_path)
{
  rosbag::Bag bag(bag_path, rosbag::bagmode::Read);
  std::vector<Record> out;
  for (const rosbag::MessageInstance& m : rosbag::View(bag)) {
    Record r{m.getTopic(), m.getTime(), std::vector<std::uint8_t>(m.size())};
    ros::serialization::OStream stream(r.bytes.data(), static_cast<std::uint32_t>(r.bytes.size()));
    m.write(stream);
    out.push_back(std::move(r));
  }
  return out;
}

std::vector<sensor_msgs::PointCloud2::ConstPtr>
cloudsOf(const std::string& bag_path)
{
  rosbag::Bag bag(bag_path, rosbag::bagmode::Read);
  std::vector<sensor_msgs::PointCloud2::ConstPtr> out;
  for (const rosbag::MessageInstance& m : rosbag::View(bag, rosbag::TopicQuery(kTopic)))
    out.push_back(m.instantiate<sensor_msgs::PointCloud2>());
  return out;
}

class BagFilterModes : public BagFilter, public ::testing::WithParamInterface<const char*>
{
};

TEST_P(BagFilterModes, OtherTopicsByteIdenticalFilteredTopicEqualsTheDirectoryMode)
{
  const std::string options = std::string(GetParam()) + " --search-window 7 --patch 3 -q";
  const auto clouds = writeBag(path("in.bag"), 5);
  const CommandResult bag_run = runDenoise("--input-bag " + path("in.bag") + " --topic " + kTopic + " --output-bag " +
                                           path("out.bag") + " " + options);
  ASSERT_EQ(bag_run.status, 0) << bag_run.output;
  writeFrames(path("frames"), clouds);
  const CommandResult dir_run =
      runDenoise("--input-dir " + path("frames") + " --output-dir " + path("filtered") + " " + options);
  ASSERT_EQ(dir_run.status, 0) << dir_run.output;

  const auto in = records(path("in.bag")), out = records(path("out.bag"));
  ASSERT_EQ(in.size(), out.size());
  for (std::size_t i = 0; i < in.size(); ++i) {
    EXPECT_EQ(out[i].topic, in[i].topic) << i;
    EXPECT_EQ(out[i].time, in[i].time) << i;
    if (in[i].topic != kTopic)
      EXPECT_TRUE(out[i].bytes == in[i].bytes) << "message " << i << " on " << in[i].topic << " changed";
    else
      EXPECT_EQ(out[i].bytes.size(), in[i].bytes.size());
  }
  const auto filtered = cloudsOf(path("out.bag"));
  ASSERT_EQ(filtered.size(), clouds.size());
  for (std::size_t k = 0; k < clouds.size(); ++k) {
    char name[32];
    std::snprintf(name, sizeof name, "/frame_%03zu.pcd", k);
    const io::LoadedCloud expected = io::loadCloud(path("filtered") + name);
    EXPECT_EQ(compareXyz(xyzOf(*filtered[k]), io::xyzFromBlob(expected, name)), "") << "frame " << k;
    EXPECT_NE(compareXyz(xyzOf(*filtered[k]), xyzOf(clouds[k])), "") << "frame " << k << " was not filtered";
    EXPECT_EQ(filtered[k]->header.stamp, clouds[k].header.stamp);
    EXPECT_EQ(filtered[k]->header.seq, clouds[k].header.seq);
    bool others_kept = filtered[k]->data.size() == clouds[k].data.size();
    for (std::size_t i = 0; others_kept && i < clouds[k].data.size(); ++i)
      others_kept = i % clouds[k].point_step < 12 || filtered[k]->data[i] == clouds[k].data[i];
    EXPECT_TRUE(others_kept) << "frame " << k;
  }
}

INSTANTIATE_TEST_SUITE_P(Windows, BagFilterModes,
                         ::testing::Values("", "--temporal-radius 1", "--temporal-radius 2 --causal",
                                           "--temporal-radius 1 --recursive"));

TEST_F(BagFilter, ErrorsNameTheBagAndTopicAndLeaveNoOutput)
{
  writeBag(path("in.bag"), 2);
  CommandResult r = runDenoise("--input-bag " + path("in.bag") + " --topic /nothing --output-bag " + path("out.bag"));
  EXPECT_EQ(r.status, 1) << r.output;
  EXPECT_NE(r.output.find("no message on topic '/nothing'"), std::string::npos) << r.output;
  // The topics the bag has, with their types.
  EXPECT_NE(r.output.find("its topics: '/camera/depth/camera_info' (sensor_msgs/CameraInfo, 2 messages), "
                          "'/camera/depth/points' (sensor_msgs/PointCloud2, 2 messages), "
                          "'/log' (std_msgs/String, 2 messages)"),
            std::string::npos)
      << r.output;
  r = runDenoise("--input-bag " + path("in.bag") + " --topic /log --output-bag " + path("out.bag"));
  EXPECT_EQ(r.status, 1) << r.output;
  EXPECT_NE(r.output.find("holds std_msgs/String messages, not sensor_msgs/PointCloud2"), std::string::npos)
      << r.output;
  r = runDenoise("--input-bag " + path("missing.bag") + " --topic /log --output-bag " + path("out.bag"));
  EXPECT_EQ(r.status, 1) << r.output;
  EXPECT_NE(r.output.find("missing.bag"), std::string::npos) << r.output;
  r = runDenoise("--input-bag " + path("in.bag") + " --topic /log --output-bag " + path("out.bag") +
                 " --pass search=7,patch=3,radius=0");
  EXPECT_EQ(r.status, 2) << r.output;
  r = runDenoise("--input-bag " + path("in.bag") + " --output-bag " + path("out.bag"));
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_NE(r.output.find("--topic"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(path("out.bag")));
}

TEST_F(BagFilter, AnEmptyBagSaysItHasNoTopics)
{
  {
    rosbag::Bag bag(path("empty.bag"), rosbag::bagmode::Write);
  }
  const CommandResult r =
      runDenoise("--input-bag " + path("empty.bag") + " --topic " + kTopic + " --output-bag " + path("out.bag"));
  EXPECT_EQ(r.status, 1) << r.output;
  EXPECT_NE(r.output.find("has no message on topic '" + std::string(kTopic) + "'; its topics: none"),
            std::string::npos)
      << r.output;
  EXPECT_FALSE(fs::exists(path("out.bag")));
}

TEST_F(BagFilter, AnUnorganizedMessageStopsTheRunOrWithKeepGoingIsCopied)
{
  {
    rosbag::Bag bag(path("in.bag"), rosbag::bagmode::Write);
    for (int k = 0; k < 3; ++k) {
      sensor_msgs::PointCloud2 m = toPointCloud2(*frame(k), 50 + k, 0);
      if (k == 1) { // a 1-row cloud
        m.width *= m.height;
        m.height = 1;
        m.row_step = m.width * m.point_step;
      }
      bag.write(kTopic, ros::Time(50 + k), m);
    }
  }
  const std::string args =
      "--input-bag " + path("in.bag") + " --topic " + kTopic + " --output-bag " + path("out.bag") + " -q";
  CommandResult r = runDenoise(args);
  EXPECT_EQ(r.status, 1) << r.output;
  EXPECT_NE(r.output.find(stampText(51, 0)), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("unorganized"), std::string::npos) << r.output;
  for (const auto& entry : fs::directory_iterator(dir_)) // no output, no temporary left
    EXPECT_EQ(entry.path().filename().string(), "in.bag");

  r = runDenoise(args + " --keep-going --temporal-radius 1");
  EXPECT_EQ(r.status, 3) << r.output;
  EXPECT_NE(r.output.find(stampText(51, 0)), std::string::npos) << r.output;
  const auto in = records(path("in.bag")), out = records(path("out.bag"));
  ASSERT_EQ(out.size(), 3u);
  EXPECT_TRUE(out[1].bytes == in[1].bytes); // copied unchanged
  EXPECT_FALSE(out[0].bytes == in[0].bytes);
  EXPECT_FALSE(out[2].bytes == in[2].bytes);
}

} // namespace
