// range_nlm_ros_camera_rate: the camera-rate benchmark's player (ros/bench/camera_rate.sh runs
// it around a nodelet manager, on a bag made by range_nlm_make_bag).
//
//   range_nlm_ros_camera_rate play BAG INPUT OUTPUT SECONDS [RATE_HZ]
//       publishes the bag's clouds on INPUT at RATE_HZ (30), looping, each stamped with the time
//       it is sent, as a camera driver does; receives OUTPUT and prints one line of figures:
//       output rate, latency from stamp to receipt (median, 95th percentile), frames dropped and
//       the median age of the previous output's frame.
//   range_nlm_ros_camera_rate play-depth BAG INPUT OUTPUT SECONDS [RATE_HZ]
//       the same with the clouds' z as 16UC1 depth images (millimetres) on INPUT, each with a
//       CameraInfo on the sibling camera_info topic (the Kinect's intrinsics: f = 525 px, principal
//       point (320, 240)), as a depth camera's driver publishes them; OUTPUT is a depth image.
#include <ros/ros.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/PointCloud2.h>

#include <cmath>
#include <cstdint>
#include <cstring>

#include <algorithm>
#include <cstdio>
#include <exception>
#include <stdexcept>
#include <mutex>
#include <string>
#include <utility>
#include <vector>

namespace
{

/// What came back: per output, the stamp it carries and when it arrived.
struct Receipts
{
  std::mutex mutex;
  std::vector<double> stamps, arrivals;
};

double
quantile(std::vector<double> values, double q)
{
  if (values.empty())
    return 0.0;
  std::sort(values.begin(), values.end());
  const std::size_t rank = static_cast<std::size_t>(q * static_cast<double>(values.size()) + 0.999999);
  return values[std::min(values.size() - 1, rank == 0 ? 0 : rank - 1)];
}

std::vector<sensor_msgs::PointCloud2>
readBag(const std::string& path)
{
  rosbag::Bag bag(path, rosbag::bagmode::Read);
  std::vector<sensor_msgs::PointCloud2> clouds;
  for (const rosbag::MessageInstance& m : rosbag::View(bag))
    if (const auto cloud = m.instantiate<sensor_msgs::PointCloud2>())
      clouds.push_back(*cloud);
  if (clouds.empty())
    throw std::runtime_error(path + " holds no sensor_msgs/PointCloud2");
  return clouds;
}

/// Prints the figures of the frames sent after the first second (the warm-up).
void
report(Receipts& r, double warmup_end, std::size_t sent_after_warmup, double seconds)
{
  std::vector<double> latencies, gaps;
  double first = 0.0, last = 0.0;
  std::size_t received = 0;
  for (std::size_t i = 0; i < r.stamps.size(); ++i) {
    if (r.stamps[i] < warmup_end)
      continue;
    latencies.push_back((r.arrivals[i] - r.stamps[i]) * 1000.0);
    if (received > 0)
      gaps.push_back((r.stamps[i] - last) * 1000.0);
    if (received++ == 0)
      first = r.stamps[i];
    last = r.stamps[i];
  }
  const double span = last - first;
  const double rate = received > 1 && span > 0 ? static_cast<double>(received - 1) / span : 0.0;
  std::printf("sent %zu in %.1f s, received %zu, output %.1f Hz, latency median %.0f ms, p95 %.0f ms, dropped %zu "
              "(%.0f %%), previous output's frame %.0f ms older (median)\n",
              sent_after_warmup, seconds, received, rate, quantile(latencies, 0.5), quantile(latencies, 0.95),
              sent_after_warmup - std::min(sent_after_warmup, received),
              100.0 * static_cast<double>(sent_after_warmup - std::min(sent_after_warmup, received)) /
                  static_cast<double>(std::max<std::size_t>(1, sent_after_warmup)),
              quantile(gaps, 0.5));
}

/// The z of an organized PointCloud2 with FLOAT32 x, y, z as a 16UC1 depth image (millimetres, 0
/// where z is NaN or out of range), and the CameraInfo of the Kinect's intrinsics for it.
std::pair<sensor_msgs::Image, sensor_msgs::CameraInfo>
depthImageOf(const sensor_msgs::PointCloud2& cloud)
{
  int z_offset = -1;
  for (const sensor_msgs::PointField& f : cloud.fields)
    if (f.name == "z" && f.datatype == sensor_msgs::PointField::FLOAT32)
      z_offset = static_cast<int>(f.offset);
  if (z_offset < 0)
    throw std::runtime_error("the bag's clouds have no FLOAT32 z field");
  sensor_msgs::Image image;
  image.width = cloud.width;
  image.height = cloud.height;
  image.encoding = "16UC1";
  image.is_bigendian = 0;
  image.step = cloud.width * 2;
  image.data.resize(static_cast<std::size_t>(image.step) * image.height);
  for (std::size_t i = 0; i < static_cast<std::size_t>(cloud.width) * cloud.height; ++i) {
    float z;
    std::memcpy(&z, &cloud.data[i * cloud.point_step + static_cast<std::size_t>(z_offset)], sizeof z);
    const std::uint16_t millimetres =
        std::isfinite(z) && z > 0.0f && z < 65.0f ? static_cast<std::uint16_t>(std::lround(z * 1000.0f)) : 0;
    std::memcpy(&image.data[i * 2], &millimetres, sizeof millimetres);
  }
  sensor_msgs::CameraInfo info;
  info.width = cloud.width;
  info.height = cloud.height;
  info.distortion_model = "plumb_bob";
  info.D.assign(5, 0.0);
  info.K = {525.0, 0.0, 320.0, 0.0, 525.0, 240.0, 0.0, 0.0, 1.0};
  info.R = {1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0};
  info.P = {525.0, 0.0, 320.0, 0.0, 0.0, 525.0, 240.0, 0.0, 0.0, 0.0, 1.0, 0.0};
  return {image, info};
}

/// The topic beside an image topic that holds its CameraInfo (image_transport's convention).
std::string
cameraInfoTopic(const std::string& image_topic)
{
  const std::size_t slash = image_topic.rfind('/');
  return (slash == std::string::npos ? std::string() : image_topic.substr(0, slash + 1)) + "camera_info";
}

/// Publishes the bag's frames on `input` (clouds, or with `depth` 16UC1 images and their
/// CameraInfo), receives `output` (of the same kind) and prints the figures.
int
play(const std::string& path, const std::string& input, const std::string& output, double seconds, double rate,
     bool depth)
{
  const std::vector<sensor_msgs::PointCloud2> clouds = readBag(path);
  std::vector<std::pair<sensor_msgs::Image, sensor_msgs::CameraInfo>> images;
  if (depth)
    for (const sensor_msgs::PointCloud2& cloud : clouds)
      images.push_back(depthImageOf(cloud));
  ros::NodeHandle node;
  Receipts receipts;
  ros::Publisher publisher = depth ? node.advertise<sensor_msgs::Image>(input, 1)
                                   : node.advertise<sensor_msgs::PointCloud2>(input, 1);
  ros::Publisher info_publisher;
  if (depth)
    info_publisher = node.advertise<sensor_msgs::CameraInfo>(cameraInfoTopic(input), 1);
  const auto received = [&](const std_msgs::Header& header) {
    const double now = ros::WallTime::now().toSec();
    std::lock_guard<std::mutex> lock(receipts.mutex);
    receipts.stamps.push_back(header.stamp.toSec());
    receipts.arrivals.push_back(now);
  };
  ros::Subscriber subscriber =
      depth ? node.subscribe<sensor_msgs::Image>(output, 100,
                                                 [&](const sensor_msgs::Image::ConstPtr& m) { received(m->header); })
            : node.subscribe<sensor_msgs::PointCloud2>(output, 100, [&](const sensor_msgs::PointCloud2::ConstPtr& m) {
                received(m->header);
              });
  ros::AsyncSpinner spinner(1);
  spinner.start();
  const ros::WallTime deadline = ros::WallTime::now() + ros::WallDuration(30.0);
  // The nodelet subscribes its input once it sees this subscriber of its output (lazy).
  while (publisher.getNumSubscribers() == 0 && ros::WallTime::now() < deadline)
    ros::WallDuration(0.05).sleep();
  if (publisher.getNumSubscribers() == 0)
    throw std::runtime_error("nobody subscribes " + input + " (is the nodelet loaded?)");
  const double start = ros::WallTime::now().toSec(), warmup_end = start + 1.0;
  std::size_t sent = 0, sent_after_warmup = 0;
  ros::WallRate pace(rate);
  while (ros::ok() && ros::WallTime::now().toSec() < start + seconds) {
    std_msgs::Header header = clouds[sent % clouds.size()].header;
    header.seq = static_cast<std::uint32_t>(sent);
    header.stamp.fromSec(ros::WallTime::now().toSec()); // stamped at capture, as a driver does
    if (header.stamp.toSec() >= warmup_end)
      ++sent_after_warmup;
    if (depth) {
      auto [image, info] = images[sent % images.size()];
      image.header = info.header = header;
      info_publisher.publish(info);
      publisher.publish(image);
    } else {
      sensor_msgs::PointCloud2 m = clouds[sent % clouds.size()];
      m.header = header;
      publisher.publish(m);
    }
    ++sent;
    pace.sleep();
  }
  ros::WallDuration(1.5).sleep(); // the last frames' outputs
  std::lock_guard<std::mutex> lock(receipts.mutex);
  report(receipts, warmup_end, sent_after_warmup, seconds - 1.0);
  return 0;
}

} // namespace

int
main(int argc, char** argv)
{
  ros::init(argc, argv, "range_nlm_camera_rate", ros::init_options::AnonymousName);
  const std::vector<std::string> args(argv + 1, argv + argc);
  try {
    if ((args.size() == 5 || args.size() == 6) && (args[0] == "play" || args[0] == "play-depth"))
      return play(args[1], args[2], args[3], std::stod(args[4]), args.size() == 6 ? std::stod(args[5]) : 30.0,
                  args[0] == "play-depth");
  } catch (const std::exception& e) {
    std::fprintf(stderr, "range_nlm_ros_camera_rate: %s\n", e.what());
    return 1;
  }
  std::fprintf(stderr, "usage: range_nlm_ros_camera_rate play|play-depth BAG INPUT OUTPUT SECONDS [RATE_HZ]\n");
  return 2;
}
