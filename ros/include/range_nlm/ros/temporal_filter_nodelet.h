/// \file temporal_filter_nodelet.h
/// \brief The nodelet range_nlm/TemporalFilterNodelet: filters an organized point cloud topic or
/// a depth image topic, frame by frame, static or temporal.
///
/// Topics (relative to the nodelet's namespace, remap them):
///   ~input = "points" (default): subscribes `input` (sensor_msgs/PointCloud2), publishes `output`.
///   ~input = "depth": subscribes `depth/image` (16UC1 mm or 32FC1 m) and `depth/camera_info`,
///     publishes `depth_filtered/image` and `depth_filtered/camera_info` (the info of that image).
/// Parameters (private): preset, and every parameter of the registry by its ROS name
/// (parameter_registry.h; mostly range_nlm_denoise's options with '-' -> '_': search_window,
/// patch, iterations, threads, distance_bandwidth, similarity_bandwidth, seed, normal_window,
/// dilation, cross_frame, outlier_sigmas, patch_gate, ..., and the switches direct and
/// line_of_sight), each of its field's type; temporal_radius, causal (default true here: no
/// output delay), recursive; plus input and queue_size. See docs/ros.md.
/// Output messages keep the input's header, layout and encoding; only x, y, z (or the depth)
/// change. A message that cannot be filtered is logged (ROS_WARN, with its stamp) and dropped.
#pragma once

#include <range_nlm/ros/message_frames.h>
#include <range_nlm/ros/message_stream.h>

#include <nodelet/nodelet.h>
#include <ros/ros.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/PointCloud2.h>

#include <memory>
#include <mutex>
#include <utility>

namespace range_nlm_ros
{

/// FilterParameters from a node's private parameters: the preset, overridden by every parameter
/// of the registry the node has. Integers are read as integers (a double only with an integral
/// value), fractional parameters as doubles (an int is taken too), enumerators by name. Throws
/// std::invalid_argument naming the ROS parameter and the value on a wrong type or an invalid
/// value.
range_nlm::FilterParameters
filterParametersFromParameters(const ros::NodeHandle& private_node);

/// Reads StreamSettings from a node's private parameters (names as above). The live default is
/// a causal window. Throws std::invalid_argument naming the parameter and the value on a wrong
/// type or an invalid value.
StreamSettings
streamSettingsFromParameters(const ros::NodeHandle& private_node);

class TemporalFilterNodelet : public nodelet::Nodelet
{
public:
  /// False if the parameters were invalid (the error was logged; nothing is subscribed).
  bool configured() const { return configured_; }

private:
  void onInit() override;
  void onPointCloud(const sensor_msgs::PointCloud2::ConstPtr& message);
  void onDepthImage(const sensor_msgs::Image::ConstPtr& image);
  void onCameraInfo(const sensor_msgs::CameraInfo::ConstPtr& info);
  /// Logs a frame-size change that restarted the temporal window.
  template <typename Stream>
  void noteRestart(const Stream& stream, std::uint32_t old_width, std::uint32_t old_height);

  using DepthTag = std::pair<sensor_msgs::Image::ConstPtr, sensor_msgs::CameraInfo::ConstPtr>;

  bool configured_ = false;
  std::unique_ptr<TaggedStream<sensor_msgs::PointCloud2::ConstPtr>> cloud_stream_;
  std::unique_ptr<TaggedStream<DepthTag>> depth_stream_;
  std::mutex stream_mutex_; // one frame at a time through the stream
  std::mutex info_mutex_;
  sensor_msgs::CameraInfo::ConstPtr camera_info_;
  ros::Subscriber input_, image_input_, info_input_;
  ros::Publisher output_, image_output_, info_output_;
};

} // namespace range_nlm_ros
