#include <range_nlm/ros/bag_filter.h>

#include <range_nlm/ros/message_frames.h>

#include <rosbag/bag.h>
#include <rosbag/exceptions.h>
#include <rosbag/view.h>
#include <ros/message_traits.h>
#include <sensor_msgs/PointCloud2.h>

#include <deque>
#include <filesystem>
#include <memory>

#include <unistd.h>

namespace range_nlm_ros
{
namespace
{

namespace fs = std::filesystem;

std::string
quoted(const std::string& s)
{
  return "'" + s + "'";
}

/// A message of the topic on its way through the stream: what is needed to write it.
struct Pending
{
  sensor_msgs::PointCloud2::ConstPtr message;
  ros::Time time;
  boost::shared_ptr<ros::M_string> connection_header;
  std::size_t report_index = 0;
};

class BagRun
{
public:
  BagRun(const BagFilterOptions& options, BagFilterReport& report) : options_(options), report_(report) {}

  void run(const std::function<void(std::size_t, std::size_t)>& progress)
  {
    rosbag::Bag in;
    try {
      in.open(options_.input_bag, rosbag::bagmode::Read);
    } catch (const rosbag::BagException& e) {
      throw BagError("cannot read bag " + quoted(options_.input_bag) + ": " + e.what());
    }
    rosbag::View topic_view(in, rosbag::TopicQuery(options_.topic));
    if (topic_view.size() == 0)
      throw BagError("bag " + quoted(options_.input_bag) + " has no message on topic " + quoted(options_.topic));
    for (const rosbag::ConnectionInfo* c : topic_view.getConnections())
      if (c->datatype != ros::message_traits::datatype<sensor_msgs::PointCloud2>() ||
          (c->md5sum != "*" && c->md5sum != ros::message_traits::md5sum<sensor_msgs::PointCloud2>()))
        throw BagError("topic " + quoted(options_.topic) + " of bag " + quoted(options_.input_bag) + " holds " +
                       c->datatype + " messages, not sensor_msgs/PointCloud2");
    const std::size_t total = topic_view.size();

    const fs::path target(options_.output_bag);
    const fs::path tmp =
        target.parent_path() / ("." + target.filename().string() + ".tmp" + std::to_string(::getpid()));
    try {
      out_.open(tmp.string(), rosbag::bagmode::Write);
    } catch (const rosbag::BagException& e) {
      throw BagError("cannot write bag " + quoted(options_.output_bag) + ": " + e.what());
    }
    try {
      stream_ = std::make_unique<TaggedStream<Pending>>(options_.settings);
      rosbag::View all(in);
      std::size_t done = 0;
      for (const rosbag::MessageInstance& m : all) {
        if (m.getTopic() != options_.topic) {
          out_.write(m.getTopic(), m.getTime(), m, m.getConnectionHeader());
          ++report_.copied;
          continue;
        }
        filterMessage(m);
        if (progress)
          progress(++done, total);
      }
      write(stream_->flush());
      out_.close();
    } catch (const rosbag::BagException& e) {
      discard(tmp);
      throw BagError("bag " + quoted(options_.input_bag) + " -> " + quoted(options_.output_bag) + ": " + e.what());
    } catch (...) {
      discard(tmp);
      throw;
    }
    std::error_code ec;
    fs::rename(tmp, target, ec);
    if (ec) {
      fs::remove(tmp, ec);
      throw BagError("cannot move bag " + quoted(options_.output_bag) + " into place: " + ec.message());
    }
  }

private:
  void discard(const fs::path& tmp)
  {
    try {
      out_.close();
    } catch (...) {
    }
    std::error_code ec;
    fs::remove(tmp, ec);
  }

  void filterMessage(const rosbag::MessageInstance& m)
  {
    const sensor_msgs::PointCloud2::ConstPtr message = m.instantiate<sensor_msgs::PointCloud2>();
    if (!message)
      throw BagError("topic " + quoted(options_.topic) + ": a message at time " + std::to_string(m.getTime().toSec()) +
                     " is not a sensor_msgs/PointCloud2");
    const std::string name = describe(message->header);
    report_.frames.push_back({name, 0.0, ""});
    std::vector<TaggedStream<Pending>::Output> ready;
    try {
      const Cloud::Ptr cloud = cloudFromPointCloud2(*message);
      ready = stream_->push(cloud, Pending{message, m.getTime(), m.getConnectionHeader(), report_.frames.size() - 1});
    } catch (const std::invalid_argument& e) { // InvalidMessage, or the filter refused the frame
      report_.frames.pop_back();
      invalid(m, message, name, e.what());
      return;
    }
    report_.restarts += stream_->restarted();
    write(ready);
  }

  void invalid(const rosbag::MessageInstance& m, const sensor_msgs::PointCloud2::ConstPtr& message,
               const std::string& name, const std::string& why)
  {
    if (!options_.keep_going)
      throw BagError("bag " + quoted(options_.input_bag) + ", topic " + quoted(options_.topic) + ", message (" + name +
                     "): " + why);
    report_.invalid.emplace_back(name, why);
    // Copied unchanged; frames still in the window come out after it, in their own time order
    // in the bag's index.
    out_.write(options_.topic, m.getTime(), *message, m.getConnectionHeader());
  }

  void write(const std::vector<TaggedStream<Pending>::Output>& ready)
  {
    for (const auto& out : ready) {
      const Pending& p = out.tag;
      BagFilterReport::Frame& frame = report_.frames[p.report_index];
      frame.milliseconds = out.milliseconds;
      frame.unfiltered = out.problem;
      if (!out.problem.empty()) {
        out_.write(options_.topic, p.time, *p.message, p.connection_header);
        continue;
      }
      out_.write(options_.topic, p.time, *pointCloud2WithXyz(*p.message, *out.cloud), p.connection_header);
    }
  }

  const BagFilterOptions& options_;
  BagFilterReport& report_;
  rosbag::Bag out_;
  std::unique_ptr<TaggedStream<Pending>> stream_;
};

} // namespace

BagFilterReport
filterBag(const BagFilterOptions& options, const std::function<void(std::size_t, std::size_t)>& progress)
{
  if (options.input_bag.empty() || options.output_bag.empty() || options.topic.empty())
    throw BagError("filterBag needs an input bag, an output bag and a topic");
  std::error_code ec;
  if (fs::equivalent(options.input_bag, options.output_bag, ec))
    throw BagError("output bag " + quoted(options.output_bag) + " is the input bag; write elsewhere");
  BagFilterReport report;
  BagRun(options, report).run(progress);
  return report;
}

} // namespace range_nlm_ros
