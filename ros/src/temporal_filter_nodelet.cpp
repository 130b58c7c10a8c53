#include <range_nlm/ros/temporal_filter_nodelet.h>

#include <pluginlib/class_list_macros.hpp>

#include <exception>
#include <string>

namespace range_nlm_ros
{

void
TemporalFilterNodelet::onInit()
{
  ros::NodeHandle& private_node = getPrivateNodeHandle();
  try {
    settings_ = nodeSettingsFromParameters(private_node);
  } catch (const std::exception& e) {
    // Thrown on: the nodelet manager refuses the load (nodelet load exits with an error),
    // range_nlm_node exits with status 1.
    NODELET_ERROR("%s", e.what());
    throw;
  }
  restartStreams();
  statistics_ = FrameStatistics(ros::WallTime::now().toSec());
  transport_ = std::make_unique<image_transport::ImageTransport>(private_node);
  if (settings_.input == "depth")
    checkTransport();
  input_topic_ = private_node.resolveName(settings_.input == "points" ? "input" : "depth/image");
  for (const std::string& line : describeSettings(settings_))
    NODELET_INFO("%s", line.c_str());

  diagnostics_ = std::make_unique<diagnostic_updater::Updater>(getNodeHandle(), private_node, getName());
  diagnostics_->setHardwareID("none");
  diagnostics_->add("filter", this, &TemporalFilterNodelet::reportDiagnostics);
  // Published by the wall clock: under use_sim_time the Updater's own pacing (by ros::Time)
  // stops while a bag's clock is paused or at its end, and for good when a looped bag's clock
  // goes back.
  diagnostics_timer_ = private_node.createWallTimer(ros::WallDuration(diagnostics_->getPeriod()),
                                                    [this](const ros::WallTimerEvent&) { diagnostics_->force_update(); });
  reconfigure_ = std::make_unique<ParameterReconfigure>(private_node, settings_.stream,
                                                        [this](const StreamSettings& s) { reconfigure(s); });
  advertise();
}

void
TemporalFilterNodelet::checkTransport() const
{
  const std::string& wanted = settings_.image_transport;
  std::string loadable;
  for (const std::string& name : transport_->getLoadableTransports()) {
    // Plugin names are "image_transport/raw", "compressed_depth_image_transport/compressedDepth"...
    const std::string transport = name.substr(name.rfind('/') + 1);
    if (transport == wanted || transport == wanted + "_sub")
      return;
    loadable += (loadable.empty() ? "" : ", ") + transport;
  }
  const std::string message = "parameter ~image_transport = '" + wanted +
                              "': no such image_transport plugin is installed (installed: " + loadable + ")";
  NODELET_ERROR("%s", message.c_str());
  throw std::invalid_argument(message);
}

void
TemporalFilterNodelet::advertise()
{
  ros::NodeHandle& private_node = getPrivateNodeHandle();
  const int queue = publisherQueue(settings_);
  {
    std::lock_guard<std::mutex> lock(stream_mutex_);
    advertiseOptionalTopics();
  }
  if (settings_.input == "points") {
    output_ = private_node.advertise<sensor_msgs::PointCloud2>(
        "output", queue, [this](const ros::SingleSubscriberPublisher&) { onConnectionChange(); },
        [this](const ros::SingleSubscriberPublisher&) { onConnectionChange(); });
    NODELET_INFO("filtering %s -> %s while %s has subscribers", input_topic_.c_str(), output_.getTopic().c_str(),
                 output_.getTopic().c_str());
  } else {
    auto image_change = [this](const image_transport::SingleSubscriberPublisher&) { onConnectionChange(); };
    auto info_change = [this](const ros::SingleSubscriberPublisher&) { onConnectionChange(); };
    camera_output_ = transport_->advertiseCamera("depth_filtered/image", queue, image_change, image_change,
                                                 info_change, info_change);
    NODELET_INFO("filtering %s with %s -> %s and %s while they have subscribers", input_topic_.c_str(),
                 image_transport::getCameraInfoTopic(input_topic_).c_str(), camera_output_.getTopic().c_str(),
                 camera_output_.getInfoTopic().c_str());
  }
}

void
TemporalFilterNodelet::advertiseOptionalTopics()
{
  ros::NodeHandle& private_node = getPrivateNodeHandle();
  const int queue = publisherQueue(settings_);
  const range_nlm::FilterParameters& parameters = settings_.stream.parameters;
  // Each published beside the filtered output while its feature is on and it has subscribers.
  const bool uncertainty = parameters.uncertainty;
  if (uncertainty && !uncertainty_output_) {
    uncertainty_output_ = private_node.advertise<sensor_msgs::Image>("uncertainty/image", queue);
  } else if (!uncertainty && uncertainty_output_) {
    uncertainty_output_.shutdown();
    uncertainty_output_ = ros::Publisher();
  }
  const bool filling = parameters.fill_holes > 0;
  if (filling && !filled_mask_) {
    filled_mask_ = private_node.advertise<sensor_msgs::Image>("filled/mask", queue);
  } else if (!filling && filled_mask_) {
    filled_mask_.shutdown();
    filled_mask_ = ros::Publisher();
  }
}

void
TemporalFilterNodelet::onConnectionChange()
{
  std::lock_guard<std::mutex> lock(connection_mutex_);
  const std::uint32_t listeners =
      settings_.input == "points" ? output_.getNumSubscribers() : camera_output_.getNumSubscribers();
  if (listeners > 0 && !subscribed_) {
    const int queue = settings_.queue_size;
    ros::NodeHandle& private_node = getPrivateNodeHandle();
    if (settings_.input == "points") {
      input_ = private_node.subscribe("input", queue, &TemporalFilterNodelet::onPointCloud, this);
    } else {
      const image_transport::TransportHints hints(settings_.image_transport, ros::TransportHints(), private_node);
      camera_input_ =
          transport_->subscribeCamera("depth/image", queue, &TemporalFilterNodelet::onDepthImage, this, hints);
    }
    subscribed_ = true;
    NODELET_DEBUG("output subscribed: subscribing %s", input_topic_.c_str());
  } else if (listeners == 0 && subscribed_) {
    input_.shutdown();
    camera_input_.shutdown();
    subscribed_ = false;
    // Frames after the pause are not neighbours of those before it.
    std::lock_guard<std::mutex> stream_lock(stream_mutex_);
    restartStreams();
    NODELET_DEBUG("no subscriber left: unsubscribed %s", input_topic_.c_str());
  }
}

void
TemporalFilterNodelet::restartStreams()
{
  if (settings_.input == "points")
    cloud_stream_ = std::make_unique<CloudStream>(settings_.stream);
  else
    depth_stream_ = std::make_unique<DepthStream>(settings_.stream);
}

void
TemporalFilterNodelet::reconfigure(const StreamSettings& settings)
{
  std::lock_guard<std::mutex> lock(stream_mutex_);
  if (cloud_stream_)
    publishClouds(cloud_stream_->flush());
  if (depth_stream_)
    publishDepth(depth_stream_->flush());
  settings_.stream = settings;
  advertiseOptionalTopics();
  restartStreams();
  NODELET_INFO("reconfigured; temporal window restarted");
  for (const std::string& line : describeSettings(settings_))
    NODELET_INFO("%s", line.c_str());
}

template <typename Stream>
void
TemporalFilterNodelet::noteRestart(const Stream& stream, std::uint32_t old_width, std::uint32_t old_height)
{
  if (stream.restarted())
    NODELET_INFO("frame size changed from %u x %u to %u x %u: temporal window restarted", old_width, old_height,
                 stream.width(), stream.height());
}

void
TemporalFilterNodelet::dropped(const char* what, const std_msgs::Header& header, const std::string& why)
{
  statistics_.dropped();
  NODELET_WARN("dropped %s on %s (%s): %s", what, input_topic_.c_str(), describe(header).c_str(), why.c_str());
}

void
TemporalFilterNodelet::onPointCloud(const sensor_msgs::PointCloud2::ConstPtr& message)
{
  std::lock_guard<std::mutex> lock(stream_mutex_);
  statistics_.received();
  std::vector<CloudStream::Output> ready;
  try {
    // A cloud too small for the windows is refused before it is decoded.
    const Cloud::Ptr cloud = cloudFromPointCloud2(*message, &cloud_stream_->parameters());
    if (!hasValidPoint(*cloud))
      throw InvalidMessage("no valid point (every x, y, z is NaN)");
    const std::uint32_t w = cloud_stream_->width(), h = cloud_stream_->height();
    ready = cloud_stream_->push(cloud, message);
    noteRestart(*cloud_stream_, w, h);
  } catch (const std::exception& e) {
    dropped("PointCloud2", message->header, e.what());
    return;
  }
  publishClouds(ready);
}

void
TemporalFilterNodelet::publishClouds(const std::vector<CloudStream::Output>& ready)
{
  for (const auto& out : ready) {
    if (!out.problem.empty()) {
      dropped("PointCloud2", out.tag->header, "not filtered: " + out.problem);
      continue;
    }
    try {
      output_.publish(sensor_msgs::PointCloud2::ConstPtr(
          pointCloud2WithXyz(*out.tag, *out.cloud, cloud_stream_->parameters().threads)));
      publishUncertainty(out.tag->header, *out.cloud, out.uncertainty);
      publishFilledMask(out.tag->header, *out.cloud, out.filled);
      statistics_.published((ros::Time::now() - out.tag->header.stamp).toSec(), out.milliseconds);
      last_bandwidths_ = out.bandwidths;
    } catch (const std::exception& e) {
      dropped("PointCloud2", out.tag->header, e.what());
    }
  }
}

void
TemporalFilterNodelet::publishFilledMask(const std_msgs::Header& header, const Cloud& cloud,
                                         const std::vector<unsigned char>& filled)
{
  if (filled.empty() || !filled_mask_ || filled_mask_.getNumSubscribers() == 0)
    return;
  sensor_msgs::Image::Ptr mask(new sensor_msgs::Image);
  mask->header = header;
  mask->width = cloud.width;
  mask->height = cloud.height;
  mask->encoding = "mono8";
  mask->step = cloud.width;
  mask->data.resize(filled.size());
  for (std::size_t i = 0; i < filled.size(); ++i)
    mask->data[i] = filled[i] ? 255 : 0;
  filled_mask_.publish(sensor_msgs::Image::ConstPtr(mask));
}

void
TemporalFilterNodelet::onDepthImage(const sensor_msgs::Image::ConstPtr& image,
                                    const sensor_msgs::CameraInfo::ConstPtr& info)
{
  std::lock_guard<std::mutex> lock(stream_mutex_);
  statistics_.received();
  std::vector<DepthStream::Output> ready;
  try {
    const Cloud::Ptr cloud = cloudFromDepthImage(*image, *info);
    if (!hasValidPoint(*cloud))
      throw InvalidMessage("no valid pixel (every depth is 0 or NaN)");
    const std::uint32_t w = depth_stream_->width(), h = depth_stream_->height();
    ready = depth_stream_->push(cloud, DepthTag(image, info));
    noteRestart(*depth_stream_, w, h);
  } catch (const std::exception& e) {
    dropped("depth image", image->header, e.what());
    return;
  }
  publishDepth(ready);
}

void
TemporalFilterNodelet::publishDepth(const std::vector<DepthStream::Output>& ready)
{
  for (const auto& out : ready) {
    const sensor_msgs::Image& in = *out.tag.first;
    if (!out.problem.empty()) {
      dropped("depth image", in.header, "not filtered: " + out.problem);
      continue;
    }
    try {
      sensor_msgs::Image::ConstPtr filtered = filteredDepthImage(in, *out.tag.second, *out.cloud);
      // The image's own CameraInfo, stamped like it, so that consumers pairing them by stamp
      // (depth_image_proc, rviz's DepthCloud) match the two.
      sensor_msgs::CameraInfo::Ptr info_out(new sensor_msgs::CameraInfo(*out.tag.second));
      info_out->header = in.header;
      camera_output_.publish(filtered, sensor_msgs::CameraInfo::ConstPtr(info_out));
      publishUncertainty(in.header, *out.cloud, out.uncertainty);
      publishFilledMask(in.header, *out.cloud, out.filled);
      statistics_.published((ros::Time::now() - in.header.stamp).toSec(), out.milliseconds);
      last_bandwidths_ = out.bandwidths;
    } catch (const std::exception& e) {
      dropped("depth image", in.header, e.what());
    }
  }
}

void
TemporalFilterNodelet::publishUncertainty(const std_msgs::Header& header, const Cloud& cloud,
                                          const std::vector<float>& sigma)
{
  if (sigma.empty() || !uncertainty_output_ || uncertainty_output_.getNumSubscribers() == 0)
    return;
  uncertainty_output_.publish(
      sensor_msgs::Image::ConstPtr(uncertaintyImage(header, cloud.width, cloud.height, sigma)));
}

void
TemporalFilterNodelet::reportDiagnostics(diagnostic_updater::DiagnosticStatusWrapper& status)
{
  FrameStatistics::Summary s;
  range_nlm::Bandwidths bandwidths;
  StreamSettings stream;
  {
    std::lock_guard<std::mutex> lock(stream_mutex_);
    s = statistics_.summarize(ros::WallTime::now().toSec());
    bandwidths = last_bandwidths_;
    stream = settings_.stream;
  }
  bool subscribed;
  {
    std::lock_guard<std::mutex> lock(connection_mutex_);
    subscribed = subscribed_;
  }
  if (!subscribed)
    status.summary(diagnostic_msgs::DiagnosticStatus::OK, "idle: no subscriber to the output");
  else if (s.dropped > 0)
    status.summaryf(diagnostic_msgs::DiagnosticStatus::WARN, "%zu frames dropped", s.dropped);
  else if (s.stamps_off_clock > 0)
    status.summaryf(diagnostic_msgs::DiagnosticStatus::WARN,
                    "%zu frames stamped on another clock than the node's: no latency (a bag played without "
                    "--clock and use_sim_time?)",
                    s.stamps_off_clock);
  else if (s.input_hz > 0.0 && s.output_hz < 0.9 * s.input_hz)
    status.summary(diagnostic_msgs::DiagnosticStatus::WARN, "the filter is slower than the input");
  else
    status.summary(diagnostic_msgs::DiagnosticStatus::OK, "filtering");
  status.add("input topic", input_topic_);
  status.add("subscribed", subscribed);
  status.addf("input rate (Hz)", "%.2f", s.input_hz);
  status.addf("output rate (Hz)", "%.2f", s.output_hz);
  if (s.latency_frames > 0) {
    status.addf("latency median (ms)", "%.1f", s.latency_median_ms);
    status.addf("latency p95 (ms)", "%.1f", s.latency_p95_ms);
  } else {
    status.add("latency median (ms)", "n/a");
    status.add("latency p95 (ms)", "n/a");
  }
  status.add("frames stamped off the node's clock", s.stamps_off_clock);
  status.addf("filter time median (ms)", "%.1f", s.filter_median_ms);
  status.add("frames dropped", s.dropped);
  status.add("frames dropped in all", s.dropped_total);
  status.add("frames published in all", s.published_total);
  status.addf("distance bandwidth d", "%g", bandwidths.distance);
  status.addf("similarity bandwidth s", "%g", bandwidths.similarity);
  status.add("temporal radius", stream.temporal_radius);
  status.add("window", windowName(stream.window));
}

} // namespace range_nlm_ros

PLUGINLIB_EXPORT_CLASS(range_nlm_ros::TemporalFilterNodelet, nodelet::Nodelet)
