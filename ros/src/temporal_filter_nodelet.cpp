#include <range_nlm/ros/temporal_filter_nodelet.h>

#include <pluginlib/class_list_macros.hpp>

#include <cmath>
#include <exception>
#include <string>
#include <utility>

namespace range_nlm_ros
{
namespace
{

/// A private parameter of the expected type, or std::invalid_argument naming it.
template <typename T>
bool
readParameter(const ros::NodeHandle& node, const std::string& name, T& value, const char* type)
{
  if (!node.hasParam(name))
    return false;
  if (!node.getParam(name, value)) {
    XmlRpc::XmlRpcValue raw;
    node.getParam(name, raw);
    throw std::invalid_argument("parameter ~" + name + " must be " + type + ", got '" + raw.toXml() + "'");
  }
  return true;
}

/// A float parameter given as an integer or a double.
bool
readNumber(const ros::NodeHandle& node, const std::string& name, float& value)
{
  double d = 0.0;
  if (node.hasParam(name)) {
    int i = 0;
    if (node.getParam(name, i)) {
      value = float(i);
      return true;
    }
  }
  if (!readParameter(node, name, d, "a number"))
    return false;
  value = float(d);
  return true;
}

} // namespace

StreamSettings
streamSettingsFromParameters(const ros::NodeHandle& node)
{
  StreamSettings settings;
  std::string preset = "default";
  readParameter(node, "preset", preset, "a string");
  try {
    settings.parameters = range_nlm::FilterParameters::preset(preset);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument("parameter ~preset: " + std::string(e.what()));
  }
  range_nlm::FilterParameters& p = settings.parameters;
  readParameter(node, "search_window", p.search_window, "an integer");
  readParameter(node, "patch", p.patch_size, "an integer");
  readParameter(node, "iterations", p.iterations, "an integer");
  readParameter(node, "threads", p.threads, "an integer");
  readParameter(node, "normal_window", p.normal_window, "an integer");
  readParameter(node, "dilation", p.dilation, "an integer");
  std::string cross_frame;
  if (readParameter(node, "cross_frame", cross_frame, "a string")) {
    if (cross_frame == "guarded")
      p.cross_frame_bandwidth = range_nlm::CrossFrameBandwidth::guarded;
    else if (cross_frame == "temporal")
      p.cross_frame_bandwidth = range_nlm::CrossFrameBandwidth::temporal;
    else if (cross_frame == "spatial")
      p.cross_frame_bandwidth = range_nlm::CrossFrameBandwidth::spatial;
    else
      throw std::invalid_argument("parameter ~cross_frame = '" + cross_frame +
                                  "' is invalid: expected 'guarded', 'temporal' or 'spatial'");
  }
  int seed = 42;
  if (readParameter(node, "seed", seed, "an integer") && seed < 0)
    throw std::invalid_argument("parameter ~seed must be >= 0, got " + std::to_string(seed));
  p.seed = static_cast<std::uint64_t>(seed);
  for (const char* name : {"distance_bandwidth", "similarity_bandwidth"}) {
    float value = 0.0f;
    if (readNumber(node, name, value)) {
      if (!(value > 0.0f))
        throw std::invalid_argument(std::string("parameter ~") + name +
                                    " must be a positive number (omit it for automatic), got " + std::to_string(value));
      (std::string(name) == "distance_bandwidth" ? p.distance_bandwidth : p.similarity_bandwidth) = value;
    }
  }
  // Thresholds in noise sigmas, 0 = off.
  for (const auto& [name, target] : {std::pair<const char*, float*>{"outlier_sigmas", &p.outlier_sigmas},
                                     std::pair<const char*, float*>{"patch_gate", &p.patch_edge_gate}}) {
    float value = 0.0f;
    if (readNumber(node, name, value)) {
      if (!(value >= 0.0f) || !std::isfinite(value))
        throw std::invalid_argument(std::string("parameter ~") + name + " must be a number >= 0 (0 = off), got " +
                                    std::to_string(value));
      *target = value;
    }
  }
  bool flag = false;
  if (readParameter(node, "direct", flag, "a boolean") && flag)
    p.evaluation = range_nlm::Evaluation::direct;
  flag = false;
  // Unset: automatic (along the line of sight whenever other frames take part).
  if (readParameter(node, "line_of_sight", flag, "a boolean"))
    p.displacement = flag ? range_nlm::Displacement::line_of_sight : range_nlm::Displacement::normal;
  readParameter(node, "temporal_radius", settings.temporal_radius, "an integer");
  bool causal = true, recursive = false;
  readParameter(node, "causal", causal, "a boolean");
  readParameter(node, "recursive", recursive, "a boolean");
  settings.window = recursive ? range_nlm::TemporalWindow::recursive
                    : causal  ? range_nlm::TemporalWindow::causal
                              : range_nlm::TemporalWindow::centred;
  try {
    settings.validate();
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument("parameters of " + node.getNamespace() + ": " + e.what());
  }
  return settings;
}

void
TemporalFilterNodelet::onInit()
{
  ros::NodeHandle& node = getNodeHandle();
  ros::NodeHandle& private_node = getPrivateNodeHandle();
  StreamSettings settings;
  std::string input = "points";
  int queue_size = 2;
  try {
    settings = streamSettingsFromParameters(private_node);
    readParameter(private_node, "input", input, "a string");
    readParameter(private_node, "queue_size", queue_size, "an integer");
    if (input != "points" && input != "depth")
      throw std::invalid_argument("parameter ~input must be 'points' or 'depth', got '" + input + "'");
    if (queue_size < 1)
      throw std::invalid_argument("parameter ~queue_size must be >= 1, got " + std::to_string(queue_size));
  } catch (const std::exception& e) {
    NODELET_ERROR("%s; not filtering anything", e.what());
    return;
  }
  const char* window = settings.window == range_nlm::TemporalWindow::recursive ? "recursive"
                       : settings.window == range_nlm::TemporalWindow::causal  ? "causal"
                                                                               : "centred";
  if (input == "points") {
    cloud_stream_ = std::make_unique<TaggedStream<sensor_msgs::PointCloud2::ConstPtr>>(settings);
    output_ = node.advertise<sensor_msgs::PointCloud2>("output", queue_size);
    input_ = node.subscribe("input", queue_size, &TemporalFilterNodelet::onPointCloud, this);
    NODELET_INFO("filtering %s -> %s (temporal radius %d, %s window, search %d, patch %d)",
                 input_.getTopic().c_str(), output_.getTopic().c_str(), settings.temporal_radius, window,
                 settings.parameters.search_window, settings.parameters.patch_size);
  } else {
    depth_stream_ = std::make_unique<TaggedStream<DepthTag>>(settings);
    image_output_ = node.advertise<sensor_msgs::Image>("depth_filtered/image", queue_size);
    info_output_ = node.advertise<sensor_msgs::CameraInfo>("depth_filtered/camera_info", queue_size);
    info_input_ = node.subscribe("depth/camera_info", queue_size, &TemporalFilterNodelet::onCameraInfo, this);
    image_input_ = node.subscribe("depth/image", queue_size, &TemporalFilterNodelet::onDepthImage, this);
    NODELET_INFO("filtering %s (+ %s) -> %s (temporal radius %d, %s window, search %d, patch %d)",
                 image_input_.getTopic().c_str(), info_input_.getTopic().c_str(), image_output_.getTopic().c_str(),
                 settings.temporal_radius, window, settings.parameters.search_window,
                 settings.parameters.patch_size);
  }
  configured_ = true;
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
TemporalFilterNodelet::onPointCloud(const sensor_msgs::PointCloud2::ConstPtr& message)
{
  std::vector<TaggedStream<sensor_msgs::PointCloud2::ConstPtr>::Output> ready;
  try {
    const Cloud::Ptr cloud = cloudFromPointCloud2(*message);
    if (!hasValidPoint(*cloud))
      throw InvalidMessage("no valid point (every x, y, z is NaN)");
    std::lock_guard<std::mutex> lock(stream_mutex_);
    const std::uint32_t w = cloud_stream_->width(), h = cloud_stream_->height();
    ready = cloud_stream_->push(cloud, message);
    noteRestart(*cloud_stream_, w, h);
  } catch (const std::exception& e) {
    NODELET_WARN("dropped PointCloud2 on %s (%s): %s", input_.getTopic().c_str(), describe(message->header).c_str(),
                 e.what());
    return;
  }
  for (const auto& out : ready) {
    if (!out.problem.empty()) {
      NODELET_WARN("dropped PointCloud2 on %s (%s): not filtered: %s", input_.getTopic().c_str(),
                   describe(out.tag->header).c_str(), out.problem.c_str());
      continue;
    }
    try {
      output_.publish(sensor_msgs::PointCloud2::ConstPtr(pointCloud2WithXyz(*out.tag, *out.cloud)));
    } catch (const std::exception& e) {
      NODELET_WARN("dropped PointCloud2 on %s (%s): %s", input_.getTopic().c_str(), describe(out.tag->header).c_str(),
                   e.what());
    }
  }
}

void
TemporalFilterNodelet::onCameraInfo(const sensor_msgs::CameraInfo::ConstPtr& info)
{
  std::lock_guard<std::mutex> lock(info_mutex_);
  camera_info_ = info;
}

void
TemporalFilterNodelet::onDepthImage(const sensor_msgs::Image::ConstPtr& image)
{
  sensor_msgs::CameraInfo::ConstPtr info;
  {
    std::lock_guard<std::mutex> lock(info_mutex_);
    info = camera_info_;
  }
  std::vector<TaggedStream<DepthTag>::Output> ready;
  try {
    if (!info)
      throw InvalidMessage("no CameraInfo received yet on " + info_input_.getTopic());
    const Cloud::Ptr cloud = cloudFromDepthImage(*image, *info);
    if (!hasValidPoint(*cloud))
      throw InvalidMessage("no valid pixel (every depth is 0 or NaN)");
    std::lock_guard<std::mutex> lock(stream_mutex_);
    const std::uint32_t w = depth_stream_->width(), h = depth_stream_->height();
    ready = depth_stream_->push(cloud, DepthTag(image, info));
    noteRestart(*depth_stream_, w, h);
  } catch (const std::exception& e) {
    NODELET_WARN("dropped depth image on %s (%s): %s", image_input_.getTopic().c_str(),
                 describe(image->header).c_str(), e.what());
    return;
  }
  for (const auto& out : ready) {
    const sensor_msgs::Image& in = *out.tag.first;
    if (!out.problem.empty()) {
      NODELET_WARN("dropped depth image on %s (%s): not filtered: %s", image_input_.getTopic().c_str(),
                   describe(in.header).c_str(), out.problem.c_str());
      continue;
    }
    try {
      sensor_msgs::Image::ConstPtr filtered = depthImageWithZ(in, *out.cloud);
      // The image's own CameraInfo, stamped like it, so that consumers pairing them by stamp
      // (depth_image_proc, rviz's DepthCloud) match the two.
      sensor_msgs::CameraInfo::Ptr info_out(new sensor_msgs::CameraInfo(*out.tag.second));
      info_out->header = in.header;
      image_output_.publish(filtered);
      info_output_.publish(sensor_msgs::CameraInfo::ConstPtr(info_out));
    } catch (const std::exception& e) {
      NODELET_WARN("dropped depth image on %s (%s): %s", image_input_.getTopic().c_str(), describe(in.header).c_str(),
                   e.what());
    }
  }
}

} // namespace range_nlm_ros

PLUGINLIB_EXPORT_CLASS(range_nlm_ros::TemporalFilterNodelet, nodelet::Nodelet)
