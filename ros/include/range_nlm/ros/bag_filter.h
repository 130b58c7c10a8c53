/// \file bag_filter.h
/// \brief Filters the PointCloud2 messages of one topic of a rosbag into a new bag; every other
/// message is copied unchanged. No ROS master is needed.
#pragma once

#include <range_nlm/ros/message_stream.h>

#include <cstddef>
#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

namespace range_nlm_ros
{

/// A bag that cannot be read or written, or a topic that cannot be filtered; the message names
/// the bag (and topic, message).
struct BagError : std::runtime_error
{
  using std::runtime_error::runtime_error;
};

struct BagFilterOptions
{
  std::string input_bag;
  std::string output_bag;
  /// Topic whose sensor_msgs/PointCloud2 messages are filtered.
  std::string topic;
  StreamSettings settings;
  /// A message of the topic that is not an organized cloud is copied unchanged (and listed)
  /// instead of ending the run.
  bool keep_going = false;
};

/// What became of the messages of the filtered topic.
struct BagFilterReport
{
  struct Frame
  {
    /// "stamp ..., frame ..., seq ..." of the message.
    std::string message;
    double milliseconds = 0.0;
    /// Empty if filtered, else why it was copied unchanged.
    std::string unfiltered;
  };
  std::vector<Frame> frames;
  /// Messages of other topics copied.
  std::size_t copied = 0;
  /// Messages of the topic that were not organized clouds (keep_going): message and reason.
  std::vector<std::pair<std::string, std::string>> invalid;
  /// Times the frame size changed and the temporal window restarted.
  std::size_t restarts = 0;
};

/// Reads `input_bag` in time order and writes `output_bag`: the messages of `topic` filtered
/// (static or temporal as `settings` say, frames in the bag's order, a new temporal window when
/// the frame size changes), every other message byte for byte, all with their record times and
/// connection headers. The output follows the rules of every range_nlm writer: a regular file is
/// written under a temporary name beside it and renamed into place at the end (so no
/// half-written bag ever carries its name, and none is left on failure); a symbolic link is
/// followed (its target written, the link stays); a character device or a FIFO gets the bag's
/// bytes (written to a scratch file in the temporary directory first, then copied); a directory,
/// a socket, a block device, a path ending in '/' or the input bag itself is refused before any
/// message is filtered. A full disk gives a BagError naming the output bag and saying so.
/// Throws BagError if a bag cannot be
/// read or written, the topic has no message or holds another type than sensor_msgs/PointCloud2,
/// or (without keep_going) one of its messages is not an organized cloud. `progress`, if given,
/// is called after each message of the topic with the count done and the total.
BagFilterReport
filterBag(const BagFilterOptions& options,
          const std::function<void(std::size_t done, std::size_t total)>& progress = nullptr);

} // namespace range_nlm_ros
