/// \file temporal_filter_nodelet.h
/// \brief The nodelet range_nlm/TemporalFilterNodelet: filters an organized point cloud topic or
/// a depth image topic, frame by frame, static or temporal.
///
/// Topics are private (in the nodelet's own namespace, as pcl_ros's filters have them), so that
/// two instances in one namespace do not collide:
///   ~input = "points" (default): subscribes `~input` (sensor_msgs/PointCloud2), publishes
///     `~output`.
///   ~input = "depth": subscribes `~depth/image` (16UC1 mm or 32FC1 m) with its
///     `~depth/camera_info` through image_transport's CameraSubscriber (the two paired by stamp),
///     publishes `~depth_filtered/image` and `~depth_filtered/camera_info`.
/// With the hole filling on (~fill_holes > 0), `~filled/mask` (sensor_msgs/Image, mono8, stamped
/// as the output: 255 where a point was filled, 0 where it was measured) is published for every
/// output while it has subscribers; with ~uncertainty on, `~uncertainty/image` (32FC1) likewise.
/// Each of the two is advertised only while its feature is on (dynamic_reconfigure turning it on
/// or off advertises or withdraws it).
/// The input is subscribed only while someone subscribes to the output.
/// Parameters (private): node_settings.h; a missing, misspelt or invalid one makes onInit throw,
/// so that `nodelet load` fails. Live changes: parameter_reconfigure.h. Diagnostics on
/// /diagnostics: rates, latency, drops, bandwidths (frame_statistics.h). See docs/ros.md.
/// Output messages keep the input's header, layout and encoding; only x, y, z (or the depth)
/// change. A message that cannot be filtered is logged (ROS_WARN, with its stamp) and dropped.
#pragma once

#include <range_nlm/ros/frame_statistics.h>
#include <range_nlm/ros/message_frames.h>
#include <range_nlm/ros/message_stream.h>
#include <range_nlm/ros/node_settings.h>
#include <range_nlm/ros/parameter_reconfigure.h>

#include <diagnostic_updater/diagnostic_updater.h>
#include <image_transport/camera_common.h>
#include <image_transport/image_transport.h>
#include <nodelet/nodelet.h>
#include <ros/ros.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/PointCloud2.h>

#include <memory>
#include <mutex>
#include <string>
#include <utility>
#include <vector>

namespace range_nlm_ros
{

class TemporalFilterNodelet : public nodelet::Nodelet
{
private:
  using CloudStream = TaggedStream<sensor_msgs::PointCloud2::ConstPtr>;
  using DepthTag = std::pair<sensor_msgs::Image::ConstPtr, sensor_msgs::CameraInfo::ConstPtr>;
  using DepthStream = TaggedStream<DepthTag>;

  void onInit() override;
  /// Throws std::invalid_argument if ~image_transport names no installed plugin.
  void checkTransport() const;
  void advertise();
  /// Advertises ~uncertainty/image and ~filled/mask while their features are on, withdraws them
  /// while off. Called with stream_mutex_ held.
  void advertiseOptionalTopics();
  /// Subscribes the input when the output gains its first subscriber and unsubscribes it (and
  /// restarts the window) when the last one leaves.
  void onConnectionChange();
  void onPointCloud(const sensor_msgs::PointCloud2::ConstPtr& message);
  void onDepthImage(const sensor_msgs::Image::ConstPtr& image, const sensor_msgs::CameraInfo::ConstPtr& info);
  /// A new setting from dynamic_reconfigure: the frames still waiting come out with the old
  /// one, then the window restarts with the new one.
  void reconfigure(const StreamSettings& settings);
  void restartStreams();
  void publishClouds(const std::vector<CloudStream::Output>& ready);
  void publishDepth(const std::vector<DepthStream::Output>& ready);
  /// The mask of the filled points of one output, if the hole filling is on and someone listens.
  void publishFilledMask(const std_msgs::Header& header, const Cloud& cloud, const std::vector<unsigned char>& filled);
  void dropped(const char* what, const std_msgs::Header& header, const std::string& why);
  /// ~uncertainty/image: the frame's per-point uncertainty, when it has one and someone listens.
  void publishUncertainty(const std_msgs::Header& header, const Cloud& cloud, const std::vector<float>& sigma);
  /// Logs a frame-size change that restarted the temporal window.
  template <typename Stream>
  void noteRestart(const Stream& stream, std::uint32_t old_width, std::uint32_t old_height);
  void reportDiagnostics(diagnostic_updater::DiagnosticStatusWrapper& status);

  NodeSettings settings_;
  std::string input_topic_;
  std::unique_ptr<CloudStream> cloud_stream_;
  std::unique_ptr<DepthStream> depth_stream_;
  std::mutex stream_mutex_; // one frame at a time through the stream; guards the statistics too
  FrameStatistics statistics_;
  range_nlm::Bandwidths last_bandwidths_;
  std::mutex connection_mutex_;
  bool subscribed_ = false;
  std::unique_ptr<image_transport::ImageTransport> transport_;
  ros::Subscriber input_;
  image_transport::CameraSubscriber camera_input_;
  ros::Publisher output_;
  image_transport::CameraPublisher camera_output_;
  ros::Publisher uncertainty_output_;
  ros::Publisher filled_mask_;
  std::unique_ptr<ParameterReconfigure> reconfigure_;
  std::unique_ptr<diagnostic_updater::Updater> diagnostics_;
  ros::WallTimer diagnostics_timer_;
};

} // namespace range_nlm_ros
