// The nodelet against a real ROS master: range_nlm_node and a nodelet manager with the plugin
// loaded, fed PointCloud2 and depth image messages; outputs equal the library's TemporalStream on
// the same frames (the depth topic also range_nlm_denoise's PNG output), bad messages are
// dropped with a log line naming their stamp. Also: private topics, lazy subscription,
// reconfiguration between frames, diagnostics, depth and CameraInfo paired by stamp, parameters
// read by type, misspelt parameters and a failed nodelet load.
#include "parameter_values.h"
#include "ros_node_test.h"
#include "ros_test_support.h"
#include "test_support.h"

#include <range_nlm/io/depth_image.h>
#include <range_nlm/io/ray_reprojection.h>
#include <range_nlm/parameter_registry.h>
#include <range_nlm/ros/node_settings.h>
#include <range_nlm/temporal_stream.h>

#include <diagnostic_msgs/DiagnosticArray.h>
#include <dynamic_reconfigure/Reconfigure.h>
#include <gtest/gtest.h>
#include <ros/ros.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/PointCloud2.h>

#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstring>
#include <deque>
#include <filesystem>
#include <fstream>
#include <limits>
#include <memory>
#include <mutex>
#include <thread>
#include <type_traits>
#include <variant>

using namespace range_nlm;
using namespace range_nlm::test;
using Cloud = pcl::PointCloud<pcl::PointXYZ>;

namespace
{

/// Frame k of a noisy scene with a depth step and holes, w x h.
Cloud::Ptr
frame(int k, int w = 64, int h = 48)
{
  Cloud::Ptr cloud(new Cloud(makeCloud(w, h, step(w / 2, 1.5, 2.0), 0.004, 1000 + k)));
  punchHoles(*cloud, 0.03, 2000 + k);
  return cloud;
}

/// The node's default preset (live) with windows small enough for the test frames.
FilterParameters
testParameters()
{
  FilterParameters p = FilterParameters::live();
  p.search_window = 7;
  p.patch_size = 3;
  return p;
}

std::string
nodeExecutable()
{
  return std::string(RANGE_NLM_ROS_DEVEL_PREFIX) + "/lib/range_nlm/range_nlm_node";
}

TEST(RosNode, PointCloud2CausalEqualsTheLibraryAndDropsBadMessages)
{
  ros::param::set("/rnlm_points/temporal_radius", 1);
  ros::param::set("/rnlm_points/recursive", false); // the live preset's default window is recursive
  ros::param::set("/rnlm_points/search_window", 7);
  ros::param::set("/rnlm_points/patch", 3);
  ros::param::set("/rnlm_points/queue_size", 10); // every message of a burst reaches the node
  ChildProcess node({nodeExecutable(), "__name:=rnlm_points", "~input:=/rnlm/in", "~output:=/rnlm/out"},
                    g_master->directory() + "/rnlm_points.log");
  ros::NodeHandle nh;
  ros::Publisher input = nh.advertise<sensor_msgs::PointCloud2>("/rnlm/in", 10);
  Inbox<sensor_msgs::PointCloud2> output("/rnlm/out");
  ASSERT_TRUE(waitFor([&] { return input.getNumSubscribers() > 0 && output.publishers() > 0; }))
      << readLog(node.log());

  TemporalStream<pcl::PointXYZ> expected_stream(1, TemporalWindow::causal, testParameters());
  std::uint32_t sec = 100;
  auto expectFiltered = [&](const Cloud::Ptr& cloud, TemporalStream<pcl::PointXYZ>& stream) {
    const sensor_msgs::PointCloud2 in = toPointCloud2(*cloud, ++sec, 250);
    input.publish(in);
    const auto out = output.next();
    ASSERT_TRUE(out) << "no output for " << stampText(sec, 250) << "\n" << readLog(node.log());
    EXPECT_EQ(out->header.stamp, in.header.stamp);
    EXPECT_EQ(out->header.frame_id, in.header.frame_id);
    EXPECT_EQ(out->fields.size(), in.fields.size());
    EXPECT_EQ(out->point_step, in.point_step);
    EXPECT_EQ(out->row_step, in.row_step);
    ASSERT_EQ(out->data.size(), in.data.size());
    const auto ready = stream.push(cloud);
    ASSERT_EQ(ready.size(), 1u);
    EXPECT_EQ(compareXyz(xyzOf(*out), *ready[0]), "");
    bool others_kept = true; // every byte but x, y, z (intensity, ring, padding)
    for (std::size_t i = 0; i < in.data.size(); ++i)
      others_kept = others_kept && (i % in.point_step < 12 || out->data[i] == in.data[i]);
    EXPECT_TRUE(others_kept);
  };
  for (int k = 0; k < 3; ++k)
    expectFiltered(frame(k), expected_stream);

  // Bad messages: each is dropped (no output, the stream unchanged), the next good frame is
  // filtered with the good frames before it as its window.
  const Cloud::Ptr good = frame(3);
  sensor_msgs::PointCloud2 wrong_row_step = toPointCloud2(*good, 500, 1);
  wrong_row_step.row_step += 4;
  sensor_msgs::PointCloud2 unorganized = toPointCloud2(*good, 501, 2);
  unorganized.width *= unorganized.height;
  unorganized.height = 1;
  unorganized.row_step = unorganized.width * unorganized.point_step;
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const sensor_msgs::PointCloud2 nan_only =
      toPointCloud2(Cloud(good->width, good->height, pcl::PointXYZ(nan, nan, nan)), 502, 3);
  for (const sensor_msgs::PointCloud2* bad :
       std::vector<const sensor_msgs::PointCloud2*>{&wrong_row_step, &unorganized, &nan_only}) {
    input.publish(*bad);
    expectFiltered(frame(int(sec)), expected_stream); // the output that comes is the good frame's
  }
  const std::string log = readLog(node.log());
  EXPECT_NE(log.find("dropped PointCloud2 on /rnlm/in (" + stampText(500, 1)), std::string::npos) << log;
  EXPECT_NE(log.find("row_step"), std::string::npos) << log;
  EXPECT_NE(log.find("dropped PointCloud2 on /rnlm/in (" + stampText(501, 2)), std::string::npos) << log;
  EXPECT_NE(log.find("unorganized"), std::string::npos) << log;
  EXPECT_NE(log.find("dropped PointCloud2 on /rnlm/in (" + stampText(502, 3)), std::string::npos) << log;
  EXPECT_NE(log.find("no valid point"), std::string::npos) << log;

  // Another frame size starts a new window: the result is that of a fresh stream.
  TemporalStream<pcl::PointXYZ> smaller(1, TemporalWindow::causal, testParameters());
  expectFiltered(frame(20, 40, 30), smaller);
  expectFiltered(frame(21, 40, 30), smaller);
  EXPECT_NE(readLog(node.log()).find("temporal window restarted"), std::string::npos);
  EXPECT_TRUE(node.running()) << readLog(node.log());
  EXPECT_EQ(output.pending(), 0u);
  // The start-up log states the whole setting, the given parameters marked.
  EXPECT_NE(log.find("preset 'live', temporal radius 1 (set), causal window, points move along the line of "
                     "sight (automatic)"),
            std::string::npos)
      << log;
  EXPECT_NE(log.find(" search_window=7 (set) patch=3 (set) temporal_search_window=3 dilation=0 "), std::string::npos) << log;
}

TEST(RosNode, TheUncertaintyImageIsPublishedWhenEnabledWithTheInputHeader)
{
  ros::param::set("/rnlm_sigma/temporal_radius", 1);
  ros::param::set("/rnlm_sigma/recursive", false);
  ros::param::set("/rnlm_sigma/search_window", 7);
  ros::param::set("/rnlm_sigma/patch", 3);
  ros::param::set("/rnlm_sigma/uncertainty", true);
  ChildProcess node({nodeExecutable(), "__name:=rnlm_sigma", "~input:=/sigma/in", "~output:=/sigma/out"},
                    g_master->directory() + "/rnlm_sigma.log");
  ros::NodeHandle nh;
  ros::Publisher input = nh.advertise<sensor_msgs::PointCloud2>("/sigma/in", 10);
  Inbox<sensor_msgs::PointCloud2> output("/sigma/out");
  Inbox<sensor_msgs::Image> sigma("/rnlm_sigma/uncertainty/image");
  ASSERT_TRUE(waitFor([&] {
    return input.getNumSubscribers() > 0 && output.publishers() > 0 && sigma.publishers() > 0;
  })) << readLog(node.log());
  FilterParameters p = testParameters();
  p.uncertainty = true;
  TemporalStream<pcl::PointXYZ> expected(1, TemporalWindow::causal, p);
  for (int k = 0; k < 2; ++k) {
    const Cloud::Ptr cloud = frame(k);
    const sensor_msgs::PointCloud2 in = toPointCloud2(*cloud, 300 + k, 7);
    input.publish(in);
    ASSERT_TRUE(output.next()) << readLog(node.log());
    const auto image = sigma.next();
    ASSERT_TRUE(image) << "no uncertainty image\n" << readLog(node.log());
    EXPECT_EQ(image->header.stamp, in.header.stamp);
    EXPECT_EQ(image->header.frame_id, in.header.frame_id);
    EXPECT_EQ(image->encoding, "32FC1");
    ASSERT_EQ(image->width, cloud->width);
    ASSERT_EQ(image->height, cloud->height);
    ASSERT_EQ(image->data.size(), cloud->size() * sizeof(float));
    ASSERT_EQ(expected.push(cloud).size(), 1u);
    const std::vector<float>& want = expected.lastOutputs().front().uncertainty;
    ASSERT_EQ(want.size(), cloud->size());
    EXPECT_EQ(std::memcmp(image->data.data(), want.data(), image->data.size()), 0);
  }
}

TEST(RosNode, TheUncertaintyImageAndTheFilledMaskAreNotAdvertisedWhenOff)
{
  ros::param::set("/rnlm_nosigma/search_window", 7);
  ros::param::set("/rnlm_nosigma/patch", 3);
  ChildProcess node({nodeExecutable(), "__name:=rnlm_nosigma", "~input:=/nosigma/in", "~output:=/nosigma/out"},
                    g_master->directory() + "/rnlm_nosigma.log");
  ros::NodeHandle nh;
  ros::Publisher input = nh.advertise<sensor_msgs::PointCloud2>("/nosigma/in", 10);
  Inbox<sensor_msgs::PointCloud2> output("/nosigma/out");
  Inbox<sensor_msgs::Image> sigma("/rnlm_nosigma/uncertainty/image");
  Inbox<sensor_msgs::Image> mask("/rnlm_nosigma/filled/mask");
  ASSERT_TRUE(waitFor([&] { return input.getNumSubscribers() > 0 && output.publishers() > 0; }))
      << readLog(node.log());
  input.publish(toPointCloud2(*frame(0), 400, 1));
  ASSERT_TRUE(output.next()) << readLog(node.log());
  // The node advertised its output: had it advertised the optional topics, the master would list them.
  EXPECT_TRUE(advertised("/nosigma/out"));
  EXPECT_FALSE(advertised("/rnlm_nosigma/uncertainty/image"));
  EXPECT_FALSE(advertised("/rnlm_nosigma/filled/mask"));
  EXPECT_EQ(sigma.publishers(), 0u);
  EXPECT_EQ(mask.publishers(), 0u);
  EXPECT_FALSE(sigma.next(0.5));
}

TEST(RosNode, ReconfiguringUncertaintyAndHoleFillingAdvertisesAndWithdrawsTheirTopics)
{
  ros::param::set("/rnlm_optional/search_window", 7);
  ros::param::set("/rnlm_optional/patch", 3);
  ros::param::set("/rnlm_optional/temporal_radius", 0);
  ChildProcess node({nodeExecutable(), "__name:=rnlm_optional"}, g_master->directory() + "/rnlm_optional.log");
  ros::NodeHandle nh;
  ros::Publisher input = nh.advertise<sensor_msgs::PointCloud2>("/rnlm_optional/input", 10);
  Inbox<sensor_msgs::PointCloud2> output("/rnlm_optional/output");
  Inbox<sensor_msgs::Image> sigma("/rnlm_optional/uncertainty/image");
  ASSERT_TRUE(waitFor([&] { return input.getNumSubscribers() > 0 && output.publishers() > 0; }))
      << readLog(node.log());
  ASSERT_TRUE(ros::service::waitForService("/rnlm_optional/set_parameters", 20000));
  EXPECT_FALSE(advertised("/rnlm_optional/uncertainty/image"));
  EXPECT_FALSE(advertised("/rnlm_optional/filled/mask"));

  const auto set = [](bool uncertainty, int fill_holes) {
    dynamic_reconfigure::Reconfigure change;
    dynamic_reconfigure::BoolParameter b;
    b.name = "uncertainty";
    b.value = uncertainty;
    change.request.config.bools.push_back(b);
    dynamic_reconfigure::IntParameter i;
    i.name = "fill_holes";
    i.value = fill_holes;
    change.request.config.ints.push_back(i);
    return ros::service::call("/rnlm_optional/set_parameters", change);
  };
  ASSERT_TRUE(set(true, 6));
  EXPECT_TRUE(advertised("/rnlm_optional/uncertainty/image"));
  EXPECT_TRUE(advertised("/rnlm_optional/filled/mask"));
  ASSERT_TRUE(waitFor([&] { return sigma.publishers() > 0; })) << readLog(node.log());
  input.publish(toPointCloud2(*frame(0), 500, 1));
  ASSERT_TRUE(output.next()) << readLog(node.log());
  EXPECT_TRUE(sigma.next()) << "no uncertainty image once turned on\n" << readLog(node.log());

  ASSERT_TRUE(set(false, 0));
  EXPECT_FALSE(advertised("/rnlm_optional/uncertainty/image"));
  EXPECT_FALSE(advertised("/rnlm_optional/filled/mask"));
  input.publish(toPointCloud2(*frame(1), 501, 1));
  ASSERT_TRUE(output.next()) << readLog(node.log());
  EXPECT_FALSE(sigma.next(0.5));
}

TEST(RosNode, TheFilledMaskMarksExactlyThePointsTheHoleFillingGaveARange)
{
  ros::param::set("/rnlm_holes/search_window", 7);
  ros::param::set("/rnlm_holes/fill_holes", 6);
  ChildProcess node({nodeExecutable(), "__name:=rnlm_holes", "~input:=/rnlm_holes/in", "~output:=/rnlm_holes/out"},
                    g_master->directory() + "/rnlm_holes.log");
  ros::NodeHandle nh;
  ros::Publisher input = nh.advertise<sensor_msgs::PointCloud2>("/rnlm_holes/in", 10);
  Inbox<sensor_msgs::PointCloud2> output("/rnlm_holes/out");
  Inbox<sensor_msgs::Image> mask("/rnlm_holes/filled/mask");
  ASSERT_TRUE(waitFor([&] {
    return input.getNumSubscribers() > 0 && output.publishers() > 0 && mask.publishers() > 0;
  })) << readLog(node.log());
  Cloud cloud = makeCloud(64, 48, plane(Eigen::Vector3d(0.1, -0.1, 1.0).normalized(), 1.5), 0.002, 7);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (int v = 20; v < 23; ++v)
    for (int u = 30; u < 33; ++u)
      cloud(u, v) = pcl::PointXYZ(nan, nan, nan);
  input.publish(toPointCloud2(cloud, 300, 1));
  const auto out = output.next();
  const auto marks = mask.next();
  ASSERT_TRUE(out && marks) << readLog(node.log());
  EXPECT_EQ(marks->header.stamp, out->header.stamp);
  EXPECT_EQ(marks->encoding, "mono8");
  ASSERT_EQ(marks->width, 64u);
  ASSERT_EQ(marks->height, 48u);
  const Cloud filtered = xyzOf(*out);
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const bool filled = !std::isfinite(cloud[i].z) && std::isfinite(filtered[i].z);
    EXPECT_EQ(marks->data[i], filled ? 255 : 0) << i;
  }
  EXPECT_TRUE(std::isfinite(filtered(31, 21).z));
}

TEST(RosNode, CentredWindowDelaysOutputByTheRadius)
{
  ros::param::set("/rnlm_centred/temporal_radius", 1);
  ros::param::set("/rnlm_centred/causal", false);
  ros::param::set("/rnlm_centred/recursive", false);
  ros::param::set("/rnlm_centred/search_window", 7);
  ros::param::set("/rnlm_centred/patch", 3);
  // The options added to the tool are parameters too: a dilation of 2 changes every output.
  ros::param::set("/rnlm_centred/dilation", 2);
  ros::param::set("/rnlm_centred/cross_frame", std::string("spatial"));
  // Outliers left where they are: each frame below has one, which the default would move.
  ros::param::set("/rnlm_centred/outlier_sigmas", 0.0);
  // A tighter patch gate than the default's 18 sigmas changes the points around those outliers.
  ros::param::set("/rnlm_centred/patch_gate", 4.0);
  ChildProcess node({nodeExecutable(), "__name:=rnlm_centred", "~input:=/centred/in", "~output:=/centred/out"},
                    g_master->directory() + "/rnlm_centred.log");
  ros::NodeHandle nh;
  ros::Publisher input = nh.advertise<sensor_msgs::PointCloud2>("/centred/in", 10);
  Inbox<sensor_msgs::PointCloud2> output("/centred/out");
  ASSERT_TRUE(waitFor([&] { return input.getNumSubscribers() > 0 && output.publishers() > 0; }))
      << readLog(node.log());
  FilterParameters centred = testParameters();
  centred.dilation = 2;
  centred.cross_frame_bandwidth = CrossFrameBandwidth::spatial;
  centred.outlier_sigmas = 0.0f;
  centred.patch_edge_gate = 4.0f;
  TemporalStream<pcl::PointXYZ> expected(1, TemporalWindow::centred, centred);
  std::vector<Cloud::Ptr> frames;
  for (int k = 0; k < 4; ++k) {
    frames.push_back(frame(k));
    Cloud& c = *frames.back();
    std::size_t i = std::size_t(20) * c.width + 10;
    while (!std::isfinite(c[i].z)) // a point, not a hole
      ++i;
    const float f = 1.0f - 0.3f / std::sqrt(c[i].x * c[i].x + c[i].y * c[i].y + c[i].z * c[i].z);
    c[i].x *= f, c[i].y *= f, c[i].z *= f; // 30 cm toward the sensor along its ray
    input.publish(toPointCloud2(*frames.back(), 10 + k, 0));
    const auto ready = expected.push(frames.back());
    if (k == 0) {
      EXPECT_TRUE(ready.empty());
      EXPECT_FALSE(output.next(1.0)) << "frame 0 came out before its successor arrived";
      continue;
    }
    ASSERT_EQ(ready.size(), 1u);
    const auto out = output.next();
    ASSERT_TRUE(out) << readLog(node.log());
    EXPECT_EQ(out->header.stamp.sec, std::uint32_t(10 + k - 1)); // frame k - 1, a frame late
    EXPECT_EQ(compareXyz(xyzOf(*out), *ready[0]), "");
  }
}

/// Sets the ROS parameter `key` to the entry's field of `p`, as the field's type: an int, a
/// double, a bool, or an enumerator's name.
void
setRosParameter(const std::string& key, const ParameterEntry& entry, const FilterParameters& p)
{
  std::visit(
      [&](auto member) {
        using T = std::decay_t<decltype(p.*member)>;
        if constexpr (std::is_enum_v<T>)
          ros::param::set(key, parameterText(entry, p));
        else if constexpr (std::is_same_v<T, bool>)
          ros::param::set(key, bool(p.*member));
        else if constexpr (std::is_floating_point_v<T>)
          ros::param::set(key, double(p.*member));
        else
          ros::param::set(key, int(p.*member));
      },
      entry.field);
}

/// What filterParametersFromParameters refuses in namespace `ns` ("" if nothing).
std::string
rosRefusal(const std::string& ns)
{
  try {
    range_nlm_ros::filterParametersFromParameters(ros::NodeHandle(ns));
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

TEST(RosParameters, EveryRegistryParameterReachesTheFilterParameters)
{
  const FilterParameters base = FilterParameters::live(); // the node's default preset
  for (const ParameterEntry& entry : parameterRegistry()) {
    const std::string ns = std::string("/rnlm_registry_") + entry.name;
    if (entry.ros_name) {
      const FilterParameters other = test::withOtherValue(entry, base);
      setRosParameter(ns + "/" + entry.ros_name, entry, other);
      const FilterParameters p = range_nlm_ros::filterParametersFromParameters(ros::NodeHandle(ns));
      EXPECT_TRUE(test::sameField(entry, p, other)) << "~" << entry.ros_name;
      EXPECT_TRUE(test::sameOtherFields(entry, p, base)) << "~" << entry.ros_name;
      ros::param::del(ns + "/" + entry.ros_name);
    }
    if (entry.ros_switch.name) {
      const std::string key = ns + "/" + entry.ros_switch.name;
      for (const bool flag : {true, false}) {
        ros::param::set(key, flag);
        FilterParameters expected = base;
        const int value = flag ? entry.ros_switch.on : entry.ros_switch.off;
        if (value >= 0)
          setChoice(entry, expected, value);
        const FilterParameters p = range_nlm_ros::filterParametersFromParameters(ros::NodeHandle(ns));
        EXPECT_TRUE(test::sameField(entry, p, expected)) << "~" << entry.ros_switch.name << " " << flag;
        EXPECT_TRUE(test::sameOtherFields(entry, p, base)) << "~" << entry.ros_switch.name << " " << flag;
      }
      ros::param::del(key);
    }
  }
}

// Without ~preset a node runs the live preset, one frame of history in the recursive window, with
// queues of one frame (the newest); the accuracy setting for recorded data filters each frame
// alone with queues of two unless told otherwise.
TEST(RosParameters, ANodeDefaultsToTheLivePresetInTheRecursiveWindow)
{
  const range_nlm_ros::StreamSettings live =
      range_nlm_ros::streamSettingsFromParameters(ros::NodeHandle("/rnlm_defaults_live"));
  EXPECT_TRUE(test::sameOtherFields(*findParameter("threads"), live.parameters, FilterParameters::live()));
  EXPECT_EQ(live.temporal_radius, 1);
  EXPECT_EQ(live.window, TemporalWindow::recursive);
  const range_nlm_ros::NodeSettings live_node = range_nlm_ros::nodeSettingsFromParameters(ros::NodeHandle("/rnlm_defaults_live"));
  EXPECT_EQ(live_node.preset, "live");
  EXPECT_EQ(live_node.queue_size, 1);
  EXPECT_EQ(range_nlm_ros::publisherQueue(live_node), 2); // a reader of one output keeps the next

  ros::param::set("/rnlm_defaults_default/preset", std::string("default"));
  const range_nlm_ros::StreamSettings recorded =
      range_nlm_ros::streamSettingsFromParameters(ros::NodeHandle("/rnlm_defaults_default"));
  EXPECT_TRUE(test::sameOtherFields(*findParameter("threads"), recorded.parameters, FilterParameters::recommended()));
  EXPECT_EQ(recorded.temporal_radius, 0);
  EXPECT_EQ(range_nlm_ros::nodeSettingsFromParameters(ros::NodeHandle("/rnlm_defaults_default")).queue_size, 2);
  ros::param::set("/rnlm_defaults_live/queue_size", 3);
  const range_nlm_ros::NodeSettings deeper = range_nlm_ros::nodeSettingsFromParameters(ros::NodeHandle("/rnlm_defaults_live"));
  EXPECT_EQ(deeper.queue_size, 3);
  EXPECT_EQ(range_nlm_ros::publisherQueue(deeper), 3);
  ros::param::del("/rnlm_defaults_live/queue_size");
  ros::param::set("/rnlm_defaults_default/temporal_radius", 1);
  EXPECT_EQ(range_nlm_ros::streamSettingsFromParameters(ros::NodeHandle("/rnlm_defaults_default")).window,
            TemporalWindow::causal);
  ros::param::set("/rnlm_defaults_live/recursive", false);
  EXPECT_EQ(range_nlm_ros::streamSettingsFromParameters(ros::NodeHandle("/rnlm_defaults_live")).window,
            TemporalWindow::causal);
  ros::param::del("/rnlm_defaults_default");
  ros::param::del("/rnlm_defaults_live");
}

TEST(RosParameters, FractionalValuesAreReadAsDoublesAndIntegersAsIntegers)
{
  ros::param::set("/rnlm_fraction/outlier_sigmas", 2.5);
  ros::param::set("/rnlm_fraction/patch_gate", 4); // an int for a fractional parameter
  ros::param::set("/rnlm_fraction/preset", std::string("paper"));
  ros::param::set("/rnlm_fraction/search_window", 9.0); // an integral double
  ros::param::set("/rnlm_fraction/distance_bandwidth", 0.005);
  const FilterParameters p = range_nlm_ros::filterParametersFromParameters(ros::NodeHandle("/rnlm_fraction"));
  EXPECT_EQ(p.outlier_sigmas, 2.5f);
  EXPECT_EQ(p.distance_bandwidth, 0.005f);
  EXPECT_EQ(p.patch_edge_gate, 4.0f);
  EXPECT_EQ(p.search_window, 9);
  EXPECT_EQ(p.patch_size, FilterParameters::paper().patch_size);
  EXPECT_EQ(p.bandwidth_model, BandwidthModel::global);
}

TEST(RosParameters, BadValuesAreRefusedNamingTheParameter)
{
  ros::param::set("/rnlm_bad1/patch_gate", -1.0);
  EXPECT_EQ(rosRefusal("/rnlm_bad1"), "parameter ~patch_gate: range_nlm: parameter patch_edge_gate = -1 is invalid: "
                                      "must be finite and >= 0 (0 = off), at most 1000");
  ros::param::set("/rnlm_bad2/search_window", 7.5);
  EXPECT_NE(rosRefusal("/rnlm_bad2").find("parameter ~search_window must be an integer"), std::string::npos);
  ros::param::set("/rnlm_bad3/cross_frame", std::string("always"));
  EXPECT_EQ(rosRefusal("/rnlm_bad3"),
            "parameter ~cross_frame = 'always' is invalid: expected 'guarded', 'temporal' or 'spatial'");
  ros::param::set("/rnlm_bad4/distance_bandwidth", 0.0);
  EXPECT_NE(rosRefusal("/rnlm_bad4").find("parameter ~distance_bandwidth must be a positive number"),
            std::string::npos);
  ros::param::set("/rnlm_bad5/seed", -3);
  EXPECT_EQ(rosRefusal("/rnlm_bad5"), "parameter ~seed must be >= 0, got -3");
  ros::param::set("/rnlm_bad6/patch_guide", 1);
  EXPECT_NE(rosRefusal("/rnlm_bad6").find("parameter ~patch_guide must be a boolean"), std::string::npos);
  ros::param::set("/rnlm_bad7/normal_window", 4);
  EXPECT_NE(rosRefusal("/rnlm_bad7").find("parameter ~normal_window: range_nlm: parameter normal_window = 4"),
            std::string::npos);
  ros::param::set("/rnlm_bad8/outlier_sigmas", std::string("2.5")); // a string for a number
  EXPECT_EQ(rosRefusal("/rnlm_bad8"), "parameter ~outlier_sigmas must be a number, got '<value>2.5</value>'");
}

/// What nodeSettingsFromParameters refuses in namespace `ns` ("" if nothing).
std::string
nodeRefusal(const std::string& ns)
{
  try {
    range_nlm_ros::nodeSettingsFromParameters(ros::NodeHandle(ns));
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

TEST(RosParameters, AMisspeltParameterIsRefusedWithTheNearestName)
{
  ros::param::set("/rnlm_typo/search_window", 7);
  ros::param::set("/rnlm_typo/outlier_sigmas", 2.5);
  ros::param::set("/rnlm_typo/image_transport", std::string("raw")); // image_transport's own
  EXPECT_EQ(nodeRefusal("/rnlm_typo"), "");
  ros::param::set("/rnlm_typo/temporal_raduis", 1);
  EXPECT_EQ(nodeRefusal("/rnlm_typo"),
            "unknown parameter ~temporal_raduis (did you mean ~temporal_radius?); the parameters are listed in "
            "docs/ros.md");
  ros::param::del("/rnlm_typo/temporal_raduis");
  ros::param::set("/rnlm_typo/colour", std::string("red"));
  EXPECT_EQ(nodeRefusal("/rnlm_typo"), "unknown parameter ~colour; the parameters are listed in docs/ros.md");
}

/// The 16UC1 image of a cloud's z (millimetres, 0 = no depth).
sensor_msgs::Image
depth16(const Cloud& cloud, std::uint32_t sec)
{
  sensor_msgs::Image image;
  image.header.stamp.sec = sec;
  image.header.frame_id = "camera_depth_optical_frame";
  image.width = cloud.width;
  image.height = cloud.height;
  image.encoding = "16UC1";
  image.step = image.width * 2;
  image.data.resize(std::size_t(image.step) * image.height);
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const std::uint16_t v = std::isfinite(cloud[i].z) ? std::uint16_t(std::lround(cloud[i].z * 1000.0)) : 0;
    std::memcpy(&image.data[i * 2], &v, 2);
  }
  return image;
}

/// The 32FC1 image of a cloud's z (metres, NaN = no depth).
sensor_msgs::Image
depth32(const Cloud& cloud, std::uint32_t sec)
{
  sensor_msgs::Image image = depth16(cloud, sec);
  image.encoding = "32FC1";
  image.step = image.width * 4;
  image.data.resize(std::size_t(image.step) * image.height);
  for (std::size_t i = 0; i < cloud.size(); ++i)
    std::memcpy(&image.data[i * 4], &cloud[i].z, 4);
  return image;
}

/// Frame k of a noisy tilted scene with a depth step and holes, w x h: moves along the normals
/// of a frame filtered alone run across the rays.
Cloud::Ptr
tiltedFrame(int k, int w = 64, int h = 48)
{
  Cloud::Ptr cloud(new Cloud(
      makeCloud(w, h, [w](double a, double, int u, int) { return (u < w / 2 ? 1.5 : 2.0) / (1.0 + 0.6 * a); },
                0.004, 1000 + k)));
  punchHoles(*cloud, 0.03, 2000 + k);
  return cloud;
}

/// The depth values of a 16UC1 message.
DepthImage
depthValues(const sensor_msgs::Image& image)
{
  DepthImage depth;
  depth.width = int(image.width);
  depth.height = int(image.height);
  depth.values.resize(std::size_t(image.width) * image.height);
  std::memcpy(depth.values.data(), image.data.data(), depth.values.size() * 2);
  return depth;
}

sensor_msgs::CameraInfo
cameraInfo(int w, int h, std::uint32_t sec)
{
  sensor_msgs::CameraInfo info;
  info.header.stamp.sec = sec;
  info.header.frame_id = "camera_depth_optical_frame";
  info.width = w;
  info.height = h;
  info.K = {300.0, 0.0, (w - 1) / 2.0, 0.0, 300.0, (h - 1) / 2.0, 0.0, 0.0, 1.0};
  return info;
}

TEST(RosNodelet, DepthImagesThroughANodeletManagerEqualTheLibrary)
{
  ::setenv("AMENT_PREFIX_PATH", RANGE_NLM_ROS_DEVEL_PREFIX, 1); // where pluginlib finds the plugin
  ros::param::set("/rnlm_depth/input", std::string("depth"));
  ros::param::set("/rnlm_depth/temporal_radius", 1);
  ros::param::set("/rnlm_depth/recursive", false);
  ros::param::set("/rnlm_depth/search_window", 7);
  ros::param::set("/rnlm_depth/patch", 3);
  ros::param::set("/rnlm_depth/queue_size", 10); // every message of a burst reaches the node
  std::vector<std::string> manager_command = {RANGE_NLM_NODELET_EXECUTABLE, "manager", "__name:=rnlm_manager"};
#ifdef RANGE_NLM_ASAN_RUNTIME
  // An AddressSanitizer build of the plugin loads only into a process whose first library is the
  // ASan runtime; Debian's nodelet manager is not instrumented.
  manager_command.insert(manager_command.begin(), {"env", "LD_PRELOAD=" RANGE_NLM_ASAN_RUNTIME});
#endif
  ChildProcess manager(manager_command, g_master->directory() + "/rnlm_manager.log");
  // Remapping the image remaps its CameraInfo too (image_transport: the sibling camera_info).
  ChildProcess loader({RANGE_NLM_NODELET_EXECUTABLE, "load", "range_nlm/TemporalFilterNodelet", "rnlm_manager",
                       "__name:=rnlm_depth", "~depth/image:=/cam/depth/image",
                       "~depth_filtered/image:=/cam/filtered/image"},
                      g_master->directory() + "/rnlm_load.log");
  ros::NodeHandle nh;
  ros::Publisher images = nh.advertise<sensor_msgs::Image>("/cam/depth/image", 10);
  ros::Publisher infos = nh.advertise<sensor_msgs::CameraInfo>("/cam/depth/camera_info", 10);
  Inbox<sensor_msgs::Image> output("/cam/filtered/image");
  Inbox<sensor_msgs::CameraInfo> output_info("/cam/filtered/camera_info");
  ASSERT_TRUE(waitFor([&] {
    return images.getNumSubscribers() > 0 && infos.getNumSubscribers() > 0 && output.publishers() > 0 &&
           output_info.publishers() > 0;
  })) << readLog(manager.log())
      << readLog(loader.log());

  // 16UC1 millimetres: the library's back-projection, stream and encoding of a filtered frame
  // (each point re-projected onto its pixel's ray).
  const int w = 64, h = 48;
  const int w2 = 40, h2 = 30;
  DepthIntrinsics intrinsics;
  intrinsics.fx = intrinsics.fy = 300.0;
  intrinsics.cx = (w - 1) / 2.0;
  intrinsics.cy = (h - 1) / 2.0;
  intrinsics.depth_scale = 1000.0;
  TemporalStream<pcl::PointXYZ> stream16(1, TemporalWindow::causal, testParameters());
  std::vector<DepthImage> inputs, outputs;
  for (int k = 0; k < 3; ++k) {
    const sensor_msgs::Image in = depth16(*tiltedFrame(k), 200 + k);
    // Each image is paired with the CameraInfo of its stamp, whichever came last: here the
    // next image's (of another size) comes before this one's.
    if (k == 2)
      infos.publish(cameraInfo(w2, h2, 300));
    images.publish(in);
    infos.publish(cameraInfo(w, h, 200 + k));
    if (k == 1) { // a colour image on the depth topic is dropped; the next depth image goes on
      sensor_msgs::Image rgb = in;
      rgb.encoding = "rgb8";
      rgb.header.stamp.sec = 777;
      images.publish(rgb);
      infos.publish(cameraInfo(w, h, 777));
    }
    const auto out = output.next();
    ASSERT_TRUE(out) << readLog(manager.log());
    const auto info = output_info.next();
    ASSERT_TRUE(info);
    EXPECT_EQ(out->header.stamp, in.header.stamp);
    EXPECT_EQ(info->header.stamp, in.header.stamp);
    EXPECT_EQ(out->encoding, "16UC1");
    EXPECT_EQ(out->step, in.step);
    inputs.push_back(depthValues(in));
    const Cloud input = depthImageToCloud(inputs.back(), intrinsics);
    const auto ready = stream16.push(Cloud::Ptr(new Cloud(input)));
    ASSERT_EQ(ready.size(), 1u);
    const DepthImage expected = cloudToDepthImage(input, *ready[0], 1000.0);
    ASSERT_EQ(out->data.size(), expected.values.size() * 2);
    outputs.push_back(depthValues(*out));
    EXPECT_EQ(outputs.back().values, expected.values) << "frame " << k;
    EXPECT_NE(outputs.back().values, inputs.back().values) << "frame " << k; // it did filter
    if (k == 0) // the first frame, filtered alone, moved along its normals: z alone is another image
      EXPECT_NE(outputs.back().values, cloudToDepthImage(*ready[0], 1000.0).values);
  }
  // The same frames as depth PNGs through range_nlm_denoise: its PNG outputs are the topic's.
  const std::filesystem::path cli = std::filesystem::path(g_master->directory()) / "depth_cli";
  std::filesystem::create_directories(cli / "in");
  std::ofstream(cli / "intrinsics.txt") << "fx 300\nfy 300\ncx " << (w - 1) / 2.0 << "\ncy " << (h - 1) / 2.0
                                        << "\ndepth_scale 1000\n";
  for (int k = 0; k < 3; ++k)
    writeDepthPng((cli / "in" / (std::to_string(k) + ".png")).string(), inputs[std::size_t(k)]);
  const CommandResult run = runDenoise("--input-dir " + (cli / "in").string() + " --output-dir " + (cli / "out").string() +
                                       " --intrinsics " + (cli / "intrinsics.txt").string() +
                                       " --output-format png --temporal-radius 1 --causal --search-window 7 --patch 3 --preset live -q");
  ASSERT_EQ(run.status, 0) << run.output;
  for (int k = 0; k < 3; ++k)
    EXPECT_EQ(readDepthPng((cli / "out" / (std::to_string(k) + ".png")).string()).values, outputs[std::size_t(k)].values)
        << "frame " << k;
  EXPECT_TRUE(waitFor([&] { return readLog(manager.log()).find(stampText(777, 0)) != std::string::npos; }));
  EXPECT_NE(readLog(manager.log()).find("encoding 'rgb8' is not supported"), std::string::npos);

  // 32FC1 metres of another size: a new window; x = (u - cx) z / fx, y = (v - cy) z / fy.
  TemporalStream<pcl::PointXYZ> stream32(1, TemporalWindow::causal, testParameters());
  for (int k = 0; k < 2; ++k) {
    const Cloud::Ptr source = frame(10 + k, w2, h2);
    const sensor_msgs::Image in = depth32(*source, 300 + k);
    images.publish(in);
    if (k > 0)
      infos.publish(cameraInfo(w2, h2, 300 + k));
    const auto out = output.next();
    ASSERT_TRUE(out) << readLog(manager.log());
    EXPECT_EQ(out->encoding, "32FC1");
    Cloud::Ptr cloud(new Cloud(w2, h2));
    const float nan = std::numeric_limits<float>::quiet_NaN();
    for (int v = 0; v < h2; ++v)
      for (int u = 0; u < w2; ++u) {
        const float z = (*source)[v * w2 + u].z;
        pcl::PointXYZ& p = (*cloud)[v * w2 + u];
        if (!std::isfinite(z)) {
          p = pcl::PointXYZ(nan, nan, nan);
          continue;
        }
        p.x = float((u - (w2 - 1) / 2.0) * double(z) / 300.0);
        p.y = float((v - (h2 - 1) / 2.0) * double(z) / 300.0);
        p.z = z;
      }
    cloud->is_dense = false;
    const auto ready = stream32.push(cloud);
    ASSERT_EQ(ready.size(), 1u);
    ASSERT_EQ(out->data.size(), std::size_t(w2) * h2 * 4);
    const Cloud on_rays = reprojectOntoRays(*cloud, *ready[0]);
    for (std::size_t i = 0; i < ready[0]->size(); ++i) {
      float z;
      std::memcpy(&z, &out->data[i * 4], 4);
      const float e = on_rays[i].z;
      ASSERT_TRUE(z == e || (std::isnan(z) && std::isnan(e))) << "pixel " << i << ": " << z << " vs " << e;
    }
  }
  EXPECT_TRUE(manager.running()) << readLog(manager.log());
}


/// Someone subscribes `topic` (as the master knows it).
bool
hasSubscriber(const ros::Publisher& publisher)
{
  return publisher.getNumSubscribers() > 0;
}

TEST(RosNode, TwoInstancesInOneNamespaceSubscribeOnlyWhileTheirOutputIsWanted)
{
  // Two nodes in /twins with their default private topics: /twins/twin_a/input -> output, ...
  for (const char* name : {"/twins/twin_a", "/twins/twin_b"}) {
    ros::param::set(std::string(name) + "/search_window", 7);
    ros::param::set(std::string(name) + "/patch", 3);
    ros::param::set(std::string(name) + "/temporal_radius", 0); // each frame alone
  }
  ros::param::set("/twins/twin_b/outlier_sigmas", 2.5);
  ChildProcess a({nodeExecutable(), "__ns:=/twins", "__name:=twin_a"}, g_master->directory() + "/twin_a.log");
  ChildProcess b({nodeExecutable(), "__ns:=/twins", "__name:=twin_b"}, g_master->directory() + "/twin_b.log");
  ros::NodeHandle nh;
  ros::Publisher input_a = nh.advertise<sensor_msgs::PointCloud2>("/twins/twin_a/input", 10);
  ros::Publisher input_b = nh.advertise<sensor_msgs::PointCloud2>("/twins/twin_b/input", 10);
  ASSERT_TRUE(waitFor([&] { return advertised("/twins/twin_a/output") && advertised("/twins/twin_b/output"); }))
      << readLog(a.log()) << readLog(b.log());
  // Nobody listens: neither subscribes its input.
  ros::WallDuration(0.5).sleep();
  EXPECT_FALSE(hasSubscriber(input_a));
  EXPECT_FALSE(hasSubscriber(input_b));
  {
    Inbox<sensor_msgs::PointCloud2> output_b("/twins/twin_b/output");
    ASSERT_TRUE(waitFor([&] { return hasSubscriber(input_b); })) << readLog(b.log());
    EXPECT_FALSE(hasSubscriber(input_a)); // only the instance whose output is wanted
    const Cloud::Ptr cloud = frame(5);
    input_b.publish(toPointCloud2(*cloud, 40, 0));
    const auto out = output_b.next();
    ASSERT_TRUE(out) << readLog(b.log());
    FilterParameters p = testParameters();
    p.outlier_sigmas = 2.5f;
    TemporalStream<pcl::PointXYZ> expected(0, TemporalWindow::causal, p);
    EXPECT_EQ(compareXyz(xyzOf(*out), *expected.push(cloud)[0]), "");
  }
  // The last subscriber left: the input is unsubscribed again.
  EXPECT_TRUE(waitFor([&] { return !hasSubscriber(input_b); })) << readLog(b.log());
  EXPECT_TRUE(a.running() && b.running());
}

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

TEST(RosNode, ReconfiguringABandwidthBetweenTwoFramesChangesTheOutputAndDiagnosticsArePublished)
{
  ros::param::set("/rnlm_live/search_window", 7);
  ros::param::set("/rnlm_live/patch", 3);
  ros::param::set("/rnlm_live/temporal_radius", 0);
  ChildProcess node({nodeExecutable(), "__name:=rnlm_live"}, g_master->directory() + "/rnlm_live.log");
  ros::NodeHandle nh;
  ros::Publisher input = nh.advertise<sensor_msgs::PointCloud2>("/rnlm_live/input", 10);
  Inbox<sensor_msgs::PointCloud2> output("/rnlm_live/output");
  Inbox<diagnostic_msgs::DiagnosticArray> diagnostics("/diagnostics");
  ASSERT_TRUE(waitFor([&] { return hasSubscriber(input) && output.publishers() > 0; })) << readLog(node.log());
  ASSERT_TRUE(ros::service::waitForService("/rnlm_live/set_parameters", 20000));

  const Cloud::Ptr cloud = frame(7);
  TemporalStream<pcl::PointXYZ> before(0, TemporalWindow::causal, testParameters());
  input.publish(toPointCloud2(*cloud, 60, 0));
  auto out = output.next();
  ASSERT_TRUE(out) << readLog(node.log());
  const Cloud automatic = *before.push(cloud)[0];
  EXPECT_EQ(compareXyz(xyzOf(*out), automatic), "");

  dynamic_reconfigure::Reconfigure change;
  dynamic_reconfigure::DoubleParameter d;
  d.name = "distance_bandwidth";
  d.value = 0.002;
  change.request.config.doubles.push_back(d);
  ASSERT_TRUE(ros::service::call("/rnlm_live/set_parameters", change));
  bool reported = false;
  for (const auto& value : change.response.config.doubles)
    reported = reported || (value.name == "distance_bandwidth" && std::fabs(value.value - 0.002) < 1e-9);
  EXPECT_TRUE(reported);

  // The same frame again: now filtered with d = 0.002.
  FilterParameters narrow = testParameters();
  narrow.distance_bandwidth = 0.002f;
  TemporalStream<pcl::PointXYZ> after(0, TemporalWindow::causal, narrow);
  input.publish(toPointCloud2(*cloud, 61, 0));
  out = output.next();
  ASSERT_TRUE(out) << readLog(node.log());
  const Cloud expected = *after.push(cloud)[0];
  EXPECT_EQ(compareXyz(xyzOf(*out), expected), "");
  EXPECT_NE(compareXyz(expected, automatic), ""); // the change is visible

  // A value out of range is refused, and the setting stays.
  dynamic_reconfigure::Reconfigure bad;
  dynamic_reconfigure::IntParameter window;
  window.name = "search_window";
  window.value = 8;
  bad.request.config.ints.push_back(window);
  ASSERT_TRUE(ros::service::call("/rnlm_live/set_parameters", bad));
  for (const auto& value : bad.response.config.ints)
    if (value.name == "search_window")
      EXPECT_EQ(value.value, 7);
  EXPECT_TRUE(waitFor([&] { return readLog(node.log()).find("search_window = 8 is invalid") != std::string::npos; }));

  // Diagnostics: the frames published, the bandwidth the filter used.
  bool seen = false;
  for (int i = 0; i < 30 && !seen; ++i) {
    const auto array = diagnostics.next(5.0);
    ASSERT_TRUE(array) << "no diagnostics\n" << readLog(node.log());
    seen = diagnosticValue(*array, "rnlm_live: filter", "frames published in all") == "2";
    if (seen) {
      EXPECT_EQ(diagnosticValue(*array, "rnlm_live: filter", "distance bandwidth d"), "0.002");
      EXPECT_EQ(diagnosticValue(*array, "rnlm_live: filter", "subscribed"), "True");
    }
  }
  EXPECT_TRUE(seen);
}

TEST(RosNodelet, ANodeletWithABadParameterFailsItsLoad)
{
  ::setenv("AMENT_PREFIX_PATH", RANGE_NLM_ROS_DEVEL_PREFIX, 1);
  ros::param::set("/rnlm_refused/patch_gate", std::string("high"));
  std::vector<std::string> manager_command = {RANGE_NLM_NODELET_EXECUTABLE, "manager", "__name:=rnlm_manager2"};
#ifdef RANGE_NLM_ASAN_RUNTIME
  manager_command.insert(manager_command.begin(), {"env", "LD_PRELOAD=" RANGE_NLM_ASAN_RUNTIME});
#endif
  ChildProcess manager(manager_command, g_master->directory() + "/rnlm_manager2.log");
  ChildProcess loader({RANGE_NLM_NODELET_EXECUTABLE, "load", "range_nlm/TemporalFilterNodelet", "rnlm_manager2",
                       "__name:=rnlm_refused"},
                      g_master->directory() + "/rnlm_refused.log");
  const int status = loader.waitExit(30.0);
  EXPECT_NE(status, -1) << "nodelet load still runs\n" << readLog(loader.log());
  EXPECT_NE(status, 0) << readLog(loader.log());
  EXPECT_NE(readLog(manager.log()).find("parameter ~patch_gate must be a number, got '<value>high</value>'"),
            std::string::npos)
      << readLog(manager.log());
  EXPECT_FALSE(advertised("/rnlm_refused/output"));

  // A depth transport whose image_transport plugin is not installed fails the load too.
  ros::param::set("/rnlm_no_plugin/input", std::string("depth"));
  ros::param::set("/rnlm_no_plugin/image_transport", std::string("noSuchTransport"));
  ChildProcess plugin_loader({RANGE_NLM_NODELET_EXECUTABLE, "load", "range_nlm/TemporalFilterNodelet",
                              "rnlm_manager2", "__name:=rnlm_no_plugin"},
                             g_master->directory() + "/rnlm_no_plugin.log");
  const int plugin_status = plugin_loader.waitExit(30.0);
  EXPECT_NE(plugin_status, -1);
  EXPECT_NE(plugin_status, 0);
  EXPECT_NE(readLog(manager.log()).find("parameter ~image_transport = 'noSuchTransport': no such image_transport "
                                        "plugin is installed (installed: raw"),
            std::string::npos)
      << readLog(manager.log());
  EXPECT_TRUE(manager.running());
}


TEST(RosLaunch, TheLaunchFileStartsTheNodeWithPrivateParametersAndTheCameraTopics)
{
  // Parameters left by an earlier run (here a misspelt one, which the node would refuse) are
  // cleared when the launch file starts the node.
  ros::param::set("/rnlm_launch/serch_window", 7);
  const std::string devel = RANGE_NLM_ROS_DEVEL_PREFIX;
  ::setenv("CMAKE_PREFIX_PATH", devel.c_str(), 1);
  ::setenv("ROS_PACKAGE_PATH", (devel + "/share:/usr/share").c_str(), 1);
  ChildProcess launch({"roslaunch", devel + "/share/range_nlm/launch/range_nlm.launch", "name:=rnlm_launch",
                       "points:=/launched/points", "search_window:=7", "patch:=3", "outlier_sigmas:=2.5"},
                      g_master->directory() + "/rnlm_launch.log");
  ros::NodeHandle nh;
  ros::Publisher input = nh.advertise<sensor_msgs::PointCloud2>("/launched/points", 10);
  Inbox<sensor_msgs::PointCloud2> output("/launched/points_filtered");
  ASSERT_TRUE(waitFor([&] { return hasSubscriber(input) && output.publishers() > 0; })) << readLog(launch.log());
  EXPECT_FALSE(ros::param::has("/rnlm_launch/serch_window"));
  double sigmas = 0.0;
  EXPECT_TRUE(ros::param::get("/rnlm_launch/outlier_sigmas", sigmas));
  EXPECT_EQ(sigmas, 2.5);
  EXPECT_FALSE(ros::param::has("/range_nlm/outlier_sigmas")); // nothing outside the node's namespace

  // The launch file's default for a live camera: the live preset, radius 1 in the recursive window,
  // along the line of sight, the newest frame only.
  EXPECT_TRUE(waitFor([&] { return readLog(launch.log()).find("queue 1") != std::string::npos; }))
      << readLog(launch.log());
  EXPECT_NE(readLog(launch.log()).find("recursive window"), std::string::npos) << readLog(launch.log());
  FilterParameters p = testParameters();
  p.outlier_sigmas = 2.5f;
  p.displacement = Displacement::line_of_sight;
  TemporalStream<pcl::PointXYZ> expected(1, TemporalWindow::recursive, p);
  for (int k = 0; k < 3; ++k) {
    const Cloud::Ptr cloud = frame(30 + k);
    input.publish(toPointCloud2(*cloud, 70 + k, 0));
    const auto out = output.next();
    ASSERT_TRUE(out) << readLog(launch.log());
    EXPECT_EQ(compareXyz(xyzOf(*out), *expected.push(cloud)[0]), "");
  }
}


TEST(RosLaunch, TheLaunchFileHasAnArgAndAPrivateParameterForEveryParameter)
{
  const std::string launch =
      readLog(std::string(RANGE_NLM_ROS_DEVEL_PREFIX) + "/share/range_nlm/launch/range_nlm.launch");
  ASSERT_FALSE(launch.empty());
  const std::size_t node = launch.find("<node ");
  ASSERT_NE(node, std::string::npos);
  for (const std::string& name : range_nlm_ros::knownParameterNames()) {
    EXPECT_NE(launch.find("<arg name=\"" + name + "\""), std::string::npos) << name;
    // Inside the node element: a private parameter.
    EXPECT_NE(launch.find("<param name=\"" + name + "\" value=\"$(arg " + name + ")\"", node), std::string::npos)
        << name;
  }
}

} // namespace

int
main(int argc, char** argv)
{
  ::testing::InitGoogleTest(&argc, argv);
  ::testing::AddGlobalTestEnvironment(new RosEnvironment(argc, argv));
  return RUN_ALL_TESTS();
}
