// "Trying it without a camera" as docs/ros.md gives it: the build's setup.bash sourced, the node
// started with rosrun under use_sim_time, and the sample bag the build made of data/kinect-sequence
// played with `rosbag play --clock`. The node filters the bag's clouds, its diagnostics report a
// latency measured on the bag's clock (not the wall clock the stamps of 1 s are decades behind),
// also after that clock stops, and the topics of the features that are off are not advertised.
#include "ros_node_test.h"

#include <diagnostic_msgs/DiagnosticArray.h>
#include <gtest/gtest.h>
#include <ros/ros.h>
#include <sensor_msgs/PointCloud2.h>

#include <chrono>
#include <cmath>
#include <condition_variable>
#include <deque>
#include <fstream>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

using namespace range_nlm::test;

namespace
{

/// The value of `key` in the diagnostics status whose name ends with `name`, or "".
std::string
diagnosticValue(const diagnostic_msgs::DiagnosticArray& array, const std::string& name, const std::string& key)
{
  for (const auto& status : array.status)
    if (status.name.size() >= name.size() &&
        status.name.compare(status.name.size() - name.size(), name.size(), name) == 0)
      for (const auto& value : status.values)
        if (value.key == key)
          return value.value;
  return "";
}

/// `command` run by bash after sourcing the build's setup.bash.
std::vector<std::string>
withSetup(const std::string& command)
{
  return {"/bin/bash", "-c", "source '" + std::string(RANGE_NLM_ROS_DEVEL_PREFIX) + "/setup.bash' && " + command};
}

TEST(RosSampleBag, PlayedWithItsClockTheNodeReportsALatencyOnThatClockAndNoOptionalTopics)
{
  ros::param::set("/use_sim_time", true); // before the node starts: it reads it at start
  ros::param::set("/rnlm_bag/threads", 2);
  ChildProcess node(withSetup("exec rosrun range_nlm range_nlm_node __name:=rnlm_bag ~input:=/camera/depth/points"),
                    g_master->directory() + "/rnlm_bag.log");
  Inbox<sensor_msgs::PointCloud2> output("/rnlm_bag/output");
  Inbox<diagnostic_msgs::DiagnosticArray> diagnostics("/diagnostics");
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(30);
  while (output.publishers() == 0 && std::chrono::steady_clock::now() < deadline)
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  ASSERT_GT(output.publishers(), 0u) << readLog(node.log());

  // The node subscribes its input now that its output has a subscriber; the player waits for it.
  ChildProcess player({"/usr/bin/rosbag", "play", "--clock", "--wait-for-subscribers", RANGE_NLM_ROS_SAMPLE_BAG},
                      g_master->directory() + "/rosbag_play.log");
  ASSERT_TRUE(output.next(60.0)) << readLog(node.log()) << readLog(player.log());
  EXPECT_EQ(player.waitExit(60.0), 0) << readLog(player.log());

  // The bag's stamps start at 1 s: against the wall clock the latency would be some 1.8e12 ms.
  std::string median, p95, off_clock, published;
  for (int i = 0; i < 20 && published.empty(); ++i) {
    const auto array = diagnostics.next(5.0);
    ASSERT_TRUE(array) << "no diagnostics\n" << readLog(node.log());
    const std::string frames = diagnosticValue(*array, "rnlm_bag: filter", "frames published in all");
    median = diagnosticValue(*array, "rnlm_bag: filter", "latency median (ms)");
    if (!frames.empty() && frames != "0" && median != "n/a" && !median.empty()) {
      published = frames;
      p95 = diagnosticValue(*array, "rnlm_bag: filter", "latency p95 (ms)");
      off_clock = diagnosticValue(*array, "rnlm_bag: filter", "frames stamped off the node's clock");
    }
  }
  ASSERT_FALSE(published.empty()) << "no diagnostics with a latency\n" << readLog(node.log());
  const double median_ms = std::stod(median), p95_ms = std::stod(p95);
  EXPECT_TRUE(std::isfinite(median_ms) && median_ms >= 0.0 && median_ms < 10000.0) << median;
  EXPECT_TRUE(std::isfinite(p95_ms) && p95_ms >= median_ms && p95_ms < 10000.0) << p95;
  EXPECT_EQ(off_clock, "0");
  // The bag has ended and its clock stands still: the status still comes once a (wall) second.
  while (diagnostics.next(0.0))
    ;
  EXPECT_TRUE(diagnostics.next(3.0)) << "no diagnostics after the bag's clock stopped\n" << readLog(node.log());

  EXPECT_TRUE(advertised("/rnlm_bag/output"));
  EXPECT_FALSE(advertised("/rnlm_bag/uncertainty/image"));
  EXPECT_FALSE(advertised("/rnlm_bag/filled/mask"));
}

} // namespace

int
main(int argc, char** argv)
{
  ::testing::InitGoogleTest(&argc, argv);
  ::testing::AddGlobalTestEnvironment(new RosEnvironment(argc, argv, "range_nlm_sample_bag_test"));
  return RUN_ALL_TESTS();
}
