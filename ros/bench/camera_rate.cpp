// range_nlm_ros_camera_rate: the camera-rate benchmark's player (ros/bench/camera_rate.sh runs
// it around a nodelet manager, on a bag made by range_nlm_make_bag).
//
//   range_nlm_ros_camera_rate play BAG INPUT OUTPUT SECONDS [RATE_HZ]
//       publishes the bag's clouds on INPUT at RATE_HZ (30), looping, each stamped with the time
//       it is sent, as a camera driver does; receives OUTPUT and prints one line of figures:
//       output rate, latency from stamp to receipt (median, 95th percentile), frames dropped and
//       the median age of the previous output's frame.
#include <ros/ros.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <sensor_msgs/PointCloud2.h>

#include <algorithm>
#include <cstdio>
#include <exception>
#include <stdexcept>
#include <mutex>
#include <string>
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

int
play(const std::string& path, const std::string& input, const std::string& output, double seconds, double rate)
{
  const std::vector<sensor_msgs::PointCloud2> clouds = readBag(path);
  ros::NodeHandle node;
  Receipts receipts;
  ros::Publisher publisher = node.advertise<sensor_msgs::PointCloud2>(input, 1);
  ros::Subscriber subscriber =
      node.subscribe<sensor_msgs::PointCloud2>(output, 100, [&](const sensor_msgs::PointCloud2::ConstPtr& m) {
        const double now = ros::WallTime::now().toSec();
        std::lock_guard<std::mutex> lock(receipts.mutex);
        receipts.stamps.push_back(m->header.stamp.toSec());
        receipts.arrivals.push_back(now);
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
    sensor_msgs::PointCloud2 m = clouds[sent % clouds.size()];
    m.header.seq = static_cast<std::uint32_t>(sent);
    m.header.stamp.fromSec(ros::WallTime::now().toSec()); // stamped at capture, as a driver does
    if (m.header.stamp.toSec() >= warmup_end)
      ++sent_after_warmup;
    publisher.publish(m);
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
    if ((args.size() == 5 || args.size() == 6) && args[0] == "play")
      return play(args[1], args[2], args[3], std::stod(args[4]), args.size() == 6 ? std::stod(args[5]) : 30.0);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "range_nlm_ros_camera_rate: %s\n", e.what());
    return 1;
  }
  std::fprintf(stderr, "usage: range_nlm_ros_camera_rate play BAG INPUT OUTPUT SECONDS [RATE_HZ]\n");
  return 2;
}
