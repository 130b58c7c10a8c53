// range_nlm_make_bag: a rosbag of organized PCD frames as sensor_msgs/PointCloud2, to try the
// node without a camera (the build makes one of data/kinect-sequence) and to feed benchmarks.
#include "cli/cli.h"

#include <rosbag/bag.h>
#include <ros/time.h>
#include <sensor_msgs/PointCloud2.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>

namespace po = boost::program_options;
using namespace range_nlm;
using namespace range_nlm::tools;

namespace
{

const char* const kUsage =
    "Usage:\n"
    "  range_nlm_make_bag OUT.bag FRAME.pcd... [--topic TOPIC] [--rate HZ] [--start SECONDS] [--frame-id ID]\n"
    "Writes the organized PCD frames, in the order given, as sensor_msgs/PointCloud2 messages (every\n"
    "field of the PCD kept) on TOPIC, 1 / HZ seconds apart from --start on: the header stamp and the\n"
    "record time of each message are the same, so that `rosbag play --clock` publishes a /clock that\n"
    "the stamps follow. The bag is written under a temporary name and renamed into place.";

sensor_msgs::PointCloud2
messageOf(const pcl::PCLPointCloud2& blob, const std::string& frame_id)
{
  sensor_msgs::PointCloud2 m;
  m.header.frame_id = frame_id;
  m.width = blob.width;
  m.height = blob.height;
  for (const pcl::PCLPointField& f : blob.fields) {
    sensor_msgs::PointField field;
    field.name = f.name;
    field.offset = f.offset;
    field.datatype = f.datatype;
    field.count = f.count;
    m.fields.push_back(field);
  }
  m.is_bigendian = blob.is_bigendian;
  m.point_step = blob.point_step;
  m.row_step = blob.row_step;
  m.data = blob.data;
  m.is_dense = blob.is_dense;
  return m;
}

int
run(int argc, char** argv)
{
  po::options_description options("Options");
  options.add_options()("output", po::value<std::string>(), "the bag to write")(
      "frames", po::value<std::vector<std::string>>(), "organized PCD files")(
      "topic", po::value<std::string>()->default_value("/camera/depth/points"), "topic of the clouds")(
      "rate", po::value<double>()->default_value(30.0), "frames per second (stamps 1 / rate apart)")(
      "start", po::value<double>()->default_value(1.0), "stamp of the first frame, seconds")(
      "frame-id", po::value<std::string>()->default_value("camera_depth_optical_frame"), "header frame_id");
  po::positional_options_description positional;
  positional.add("output", 1).add("frames", -1);
  po::variables_map vm;
  if (!parseCommandLine(argc, argv, options, positional, vm, kUsage))
    return 0;
  if (!vm.count("output") || !vm.count("frames"))
    throw UsageError("give the output bag and at least one PCD frame");
  const std::string output = vm["output"].as<std::string>();
  const std::vector<std::string> frames = vm["frames"].as<std::vector<std::string>>();
  const std::string topic = vm["topic"].as<std::string>();
  const double rate = vm["rate"].as<double>(), start = vm["start"].as<double>();
  if (!(std::isfinite(rate) && rate > 0.0))
    throw UsageError("--rate must be a positive number of frames per second, got " + std::to_string(rate));
  if (!(std::isfinite(start) && start > 0.0 && start < 4.0e9))
    throw UsageError("--start must be a time after 0 and before 2096 (seconds), got " + std::to_string(start));
  if (topic.empty() || topic[0] != '/')
    throw UsageError("--topic must be a global topic name (starting with '/'), got '" + topic + "'");

  const std::string temporary = output + ".partial";
  try {
    rosbag::Bag bag(temporary, rosbag::bagmode::Write);
    for (std::size_t k = 0; k < frames.size(); ++k) {
      const LoadedCloud loaded = loadCloud(frames[k]); // organized, checked: names the file
      sensor_msgs::PointCloud2 m = messageOf(loaded.blob, vm["frame-id"].as<std::string>());
      m.header.seq = static_cast<std::uint32_t>(k);
      m.header.stamp.fromSec(start + static_cast<double>(k) / rate);
      bag.write(topic, m.header.stamp, m);
    }
    bag.close();
    std::filesystem::rename(temporary, output);
  } catch (...) {
    std::error_code ignored;
    std::filesystem::remove(temporary, ignored);
    throw;
  }
  std::cout << "wrote " << frames.size() << " frame" << (frames.size() == 1 ? "" : "s") << " on " << topic << " at "
            << rate << " Hz to " << printable(output) << std::endl;
  return 0;
}

} // namespace

int
main(int argc, char** argv)
{
  return runTool("range_nlm_make_bag", [&] { return run(argc, argv); });
}
