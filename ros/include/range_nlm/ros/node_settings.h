/// \file node_settings.h
/// \brief What the nodelet and range_nlm_node read from their private parameters: the filter's
/// parameters (every entry of the parameter registry, by its type), the temporal window, the
/// input kind and the queue size; the check that no private parameter is misspelt; and the
/// start-up description of the whole setting.
#pragma once

#include <range_nlm/ros/message_stream.h>

#include <ros/node_handle.h>

#include <string>
#include <vector>

namespace range_nlm_ros
{

/// The preset of a node whose ~preset is not set: the live camera's setting.
extern const char* const kDefaultPreset;

/// FilterParameters from a node's private parameters: the preset, overridden by every parameter
/// of the registry the node has. Integers are read as integers (a double only with an integral
/// value), fractional parameters as doubles (an int is taken too), enumerators by name. Throws
/// std::invalid_argument naming the ROS parameter and the value on a wrong type or an invalid
/// value.
range_nlm::FilterParameters
filterParametersFromParameters(const ros::NodeHandle& private_node);

/// The temporal window the `causal` and `recursive` parameters name (recursive wins; neither:
/// centred).
range_nlm::TemporalWindow
windowOf(bool causal, bool recursive);

/// Reads StreamSettings from a node's private parameters (names as above). The live default is
/// a causal window. Throws std::invalid_argument naming the parameter and the value on a wrong
/// type or an invalid value.
StreamSettings
streamSettingsFromParameters(const ros::NodeHandle& private_node);

/// Everything a filter node is told by its private parameters.
struct NodeSettings
{
  StreamSettings stream;
  /// "points" (sensor_msgs/PointCloud2) or "depth" (image + CameraInfo).
  std::string input = "points";
  /// The subscriber queue (>= 1): 1 with the live preset (the newest frame only), else 2. The
  /// publishers' queues hold at least two (publisherQueue).
  int queue_size = 1;
  /// image_transport of the depth input ("raw", "compressedDepth", ...).
  std::string image_transport = "raw";
  /// The preset the parameters start from (~preset; kDefaultPreset, "live", when not set).
  std::string preset = kDefaultPreset;
  /// The private parameters that were set, by their names (without "~"), in the order read.
  std::vector<std::string> given;
};

/// The private parameter names a filter node knows: its own, the registry's and those of the
/// ROS libraries it uses (image_transport, diagnostic_period).
const std::vector<std::string>&
knownParameterNames();

/// Reads NodeSettings. Throws std::invalid_argument naming the parameter on a wrong type, an
/// invalid value or a private parameter the node does not know ("unknown parameter ~serch_window
/// (did you mean ~search_window?)"), so that a misspelt name is never ignored.
NodeSettings
nodeSettingsFromParameters(const ros::NodeHandle& private_node);

/// Lines for the start-up log: the input, the window, the preset, where points move (line of
/// sight or normal) and every parameter's value, the given ones marked "(set)".
std::vector<std::string>
describeSettings(const NodeSettings& settings);

/// The queue of the node's publishers: queue_size, at least 2. A subscriber still reading a
/// filtered frame (several megabytes over a socket) when the next is published then gets both;
/// with one, the next would replace it and be lost while the node was keeping up.
int
publisherQueue(const NodeSettings& settings);

/// The name of a temporal window: "causal", "centred" or "recursive".
const char*
windowName(range_nlm::TemporalWindow window);

} // namespace range_nlm_ros
