#include <range_nlm/ros/bag_filter.h>

#include <range_nlm/ros/message_frames.h>

#include "io/output_file.h"

#include <range_nlm/io/pcd_file.h>

#include <rosbag/bag.h>
#include <rosbag/exceptions.h>
#include <rosbag/view.h>
#include <ros/message_traits.h>
#include <sensor_msgs/PointCloud2.h>

#include <cerrno>
#include <cstdlib>
#include <deque>
#include <filesystem>
#include <map>
#include <memory>
#include <set>
#include <vector>

#include <fcntl.h>
#include <sys/statvfs.h>
#include <unistd.h>

namespace range_nlm_ros
{
namespace
{

namespace fs = std::filesystem;
namespace io = range_nlm::io;

std::string
quoted(const std::string& s)
{
  return "'" + s + "'";
}

/// The topics of `bag` with their message types and counts, in name order: "'/a'
/// (sensor_msgs/PointCloud2, 3 messages), '/b' (std_msgs/String, 1 message)", or "none" for a bag
/// without messages.
std::string
describeTopics(const rosbag::Bag& bag)
{
  rosbag::View all(bag);
  std::map<std::string, std::set<std::string>> types;
  for (const rosbag::ConnectionInfo* c : all.getConnections())
    types[c->topic].insert(c->datatype);
  std::string list;
  for (const auto& topic : types) {
    std::string type;
    for (const std::string& t : topic.second)
      type += (type.empty() ? "" : " and ") + t;
    const std::size_t count = rosbag::View(bag, rosbag::TopicQuery(topic.first)).size();
    list += (list.empty() ? "" : ", ") + quoted(topic.first) + " (" + type + ", " + std::to_string(count) +
            (count == 1 ? " message)" : " messages)");
  }
  return list.empty() ? "none" : list;
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
      throw BagError("bag " + quoted(options_.input_bag) + " has no message on topic " + quoted(options_.topic) +
                     "; its topics: " + describeTopics(in));
    for (const rosbag::ConnectionInfo* c : topic_view.getConnections())
      if (c->datatype != ros::message_traits::datatype<sensor_msgs::PointCloud2>() ||
          (c->md5sum != "*" && c->md5sum != ros::message_traits::md5sum<sensor_msgs::PointCloud2>()))
        throw BagError("topic " + quoted(options_.topic) + " of bag " + quoted(options_.input_bag) + " holds " +
                       c->datatype + " messages, not sensor_msgs/PointCloud2");
    const std::size_t total = topic_view.size();

    // The output: refused now if it cannot be written (a directory, a socket, ...), before any
    // message is filtered.
    try {
      io::detail::OutputFile output(options_.output_bag);
      filterInto(in, output, total, progress);
    } catch (const io::InputError& e) {
      throw BagError(e.what());
    }
  }

private:
  /// A file in the temporary directory for a bag bound for a device or a FIFO; the destructor
  /// removes it.
  struct ScratchFile
  {
    std::string path;
    ScratchFile() = default;
    ScratchFile(const ScratchFile&) = delete;
    ScratchFile& operator=(const ScratchFile&) = delete;
    ~ScratchFile()
    {
      if (!path.empty())
        ::unlink(path.c_str());
    }
    void create(io::detail::OutputFile& output)
    {
      std::string name = (fs::temp_directory_path() / "range_nlm_bag_XXXXXX").string();
      const int fd = ::mkstemp(name.data());
      if (fd < 0)
        output.fail("cannot create a scratch file for the bag in '" + fs::temp_directory_path().string() + "'", errno);
      ::close(fd);
      path = name;
    }
    /// Copies the scratch file's bytes into `output` (a write error is reported by commit()).
    void copyTo(io::detail::OutputFile& output) const
    {
      const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
      if (fd < 0)
        output.fail("cannot read the bag's scratch file '" + path + "'", errno);
      std::vector<char> buffer(1 << 20);
      for (;;) {
        const ssize_t n = ::read(fd, buffer.data(), buffer.size());
        if (n < 0 && errno == EINTR)
          continue;
        if (n < 0) {
          const int error = errno;
          ::close(fd);
          output.fail("cannot read the bag's scratch file '" + path + "'", error);
        }
        if (n == 0 || output.tryWrite(buffer.data(), static_cast<std::size_t>(n)) != 0)
          break;
      }
      ::close(fd);
    }
  };

  /// Filters `in` into `output`. rosbag writes by file name and seeks back while writing, so it
  /// writes the output's temporary file, which commit() moves into place; for a device or a FIFO
  /// it writes a scratch file whose bytes are then copied into the device or FIFO.
  void filterInto(rosbag::Bag& in, io::detail::OutputFile& output, std::size_t total,
                  const std::function<void(std::size_t, std::size_t)>& progress)
  {
    ScratchFile scratch;
    if (output.direct())
      scratch.create(output);
    const std::string file = output.direct() ? scratch.path : output.temporaryPath();
    out_ = std::make_unique<rosbag::Bag>();
    try {
      out_->open(file, rosbag::bagmode::Write);
      stream_ = std::make_unique<TaggedStream<Pending>>(options_.settings);
      rosbag::View all(in);
      std::size_t done = 0;
      for (const rosbag::MessageInstance& m : all) {
        if (m.getTopic() != options_.topic) {
          out_->write(m.getTopic(), m.getTime(), m, m.getConnectionHeader());
          ++report_.copied;
          continue;
        }
        filterMessage(m);
        if (progress)
          progress(++done, total);
      }
      write(stream_->flush());
      out_->close();
      out_.reset();
    } catch (const rosbag::BagException& e) {
      const int reason = ioErrorOf(errno, file); // before abandon() frees the space
      abandon(file, std::string(e.what()).rfind("Error closing file", 0) == 0);
      const std::string what =
          output.direct() ? "cannot write the bag's scratch file '" + file + "'" : std::string("cannot write the bag");
      if (reason != 0)
        output.fail(what, reason);
      output.fail(what + " (" + e.what() + ")", EIO);
    } catch (...) {
      abandon(file, false);
      throw;
    }
    if (output.direct())
      scratch.copyTo(output);
    output.commit();
  }

  /// Ends the output bag after a failure. rosbag::Bag's destructor closes the bag, which writes
  /// its index and throws if that fails; thrown from a destructor, that would end the process. So
  /// the space the partial bag takes is freed (it is discarded anyway) and the bag closed here,
  /// where an exception can be caught. After a failed fclose (`closing`) the C library has
  /// released the stream already and closing again would release it twice: then, as when closing
  /// fails once more, the rosbag::Bag is left allocated and never destroyed.
  void abandon(const std::string& file, bool closing) noexcept
  {
    if (!out_)
      return;
    if (!closing) {
      const int ignored = ::truncate(file.c_str(), 0); // removed by the caller either way
      (void)ignored;
      try {
        out_->close();
        out_.reset();
        return;
      } catch (...) {
      }
    }
    (void)out_.release();
  }

  /// The system's reason for a failed write of the bag `file`: `error` (errno just after
  /// rosbag's failure) if it is an error of writing, else ENOSPC if the file system has no space
  /// left, else 0.
  static int ioErrorOf(int error, const std::string& file)
  {
    for (int e : {ENOSPC, EDQUOT, EIO, EFBIG, EROFS})
      if (error == e)
        return error;
    struct statvfs disk;
    const std::string directory = fs::path(file).parent_path().string();
    if (::statvfs(directory.empty() ? "." : directory.c_str(), &disk) == 0 && disk.f_bavail == 0)
      return ENOSPC;
    return 0;
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
      // Refused for the windows before it is decoded, as the nodelet does.
      const Cloud::Ptr cloud = cloudFromPointCloud2(*message, &options_.settings.parameters);
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
    out_->write(options_.topic, m.getTime(), *message, m.getConnectionHeader());
  }

  void write(const std::vector<TaggedStream<Pending>::Output>& ready)
  {
    for (const auto& out : ready) {
      const Pending& p = out.tag;
      BagFilterReport::Frame& frame = report_.frames[p.report_index];
      frame.milliseconds = out.milliseconds;
      frame.unfiltered = out.problem;
      if (!out.problem.empty()) {
        out_->write(options_.topic, p.time, *p.message, p.connection_header);
        continue;
      }
      out_->write(options_.topic, p.time,
                  *pointCloud2WithXyz(*p.message, *out.cloud, options_.settings.parameters.threads),
                  p.connection_header);
    }
  }

  const BagFilterOptions& options_;
  BagFilterReport& report_;
  std::unique_ptr<rosbag::Bag> out_;
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
