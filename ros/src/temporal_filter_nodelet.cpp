#include <range_nlm/ros/temporal_filter_nodelet.h>

#include <range_nlm/parameter_registry.h>

#include <pluginlib/class_list_macros.hpp>

#include <cmath>
#include <exception>
#include <limits>
#include <string>
#include <type_traits>
#include <utility>
#include <variant>

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

[[noreturn]] void
wrongType(const std::string& name, const char* type, XmlRpc::XmlRpcValue& raw)
{
  throw std::invalid_argument("parameter ~" + name + " must be " + type + ", got '" + raw.toXml() + "'");
}

/// An integer parameter: an int, or a double with an integral value.
long long
integerOf(const std::string& name, XmlRpc::XmlRpcValue& raw)
{
  if (raw.getType() == XmlRpc::XmlRpcValue::TypeInt)
    return static_cast<int>(raw);
  if (raw.getType() == XmlRpc::XmlRpcValue::TypeDouble) {
    const double d = static_cast<double>(raw);
    if (std::isfinite(d) && d == std::floor(d) && std::fabs(d) < 1e15)
      return static_cast<long long>(d);
  }
  wrongType(name, "an integer", raw);
}

/// Sets a parameter's field from its ROS value, read by the field's type: integers as integers,
/// fractional parameters as doubles (an int is taken too), enumerators by name.
void
setFromValue(const range_nlm::ParameterEntry& entry, const std::string& name, XmlRpc::XmlRpcValue& raw,
             range_nlm::FilterParameters& p)
{
  std::visit(
      [&](auto member) {
        using T = std::decay_t<decltype(p.*member)>;
        if constexpr (std::is_enum_v<T>) {
          if (raw.getType() != XmlRpc::XmlRpcValue::TypeString)
            wrongType(name, "a string", raw);
          const std::string text = static_cast<std::string&>(raw);
          const int value = range_nlm::choiceValue(entry, text);
          if (value < 0)
            throw std::invalid_argument("parameter ~" + name + " = '" + text + "' is invalid: expected " +
                                        range_nlm::choiceList(entry));
          p.*member = static_cast<T>(value);
        } else if constexpr (std::is_same_v<T, bool>) {
          if (raw.getType() != XmlRpc::XmlRpcValue::TypeBoolean)
            wrongType(name, "a boolean", raw);
          p.*member = static_cast<bool>(raw);
        } else if constexpr (std::is_floating_point_v<T>) {
          if (raw.getType() == XmlRpc::XmlRpcValue::TypeInt)
            p.*member = static_cast<T>(static_cast<int>(raw));
          else if (raw.getType() == XmlRpc::XmlRpcValue::TypeDouble)
            p.*member = static_cast<T>(static_cast<double>(raw));
          else
            wrongType(name, "a number", raw);
        } else if constexpr (std::is_unsigned_v<T>) {
          const long long value = integerOf(name, raw);
          if (value < 0)
            throw std::invalid_argument("parameter ~" + name + " must be >= 0, got " + std::to_string(value));
          p.*member = static_cast<T>(value);
        } else {
          const long long value = integerOf(name, raw);
          if (value < std::numeric_limits<T>::min() || value > std::numeric_limits<T>::max())
            wrongType(name, "an integer", raw);
          p.*member = static_cast<T>(value);
        }
      },
      entry.field);
}

/// Reads the parameter of a registry entry (its value, or its switch) if the node has it, and
/// checks the value at once, so that the message names the ROS parameter.
void
readEntry(const ros::NodeHandle& node, const range_nlm::ParameterEntry& entry, range_nlm::FilterParameters& p)
{
  XmlRpc::XmlRpcValue raw;
  if (entry.ros_name && node.hasParam(entry.ros_name) && node.getParam(entry.ros_name, raw)) {
    const std::string name = entry.ros_name;
    setFromValue(entry, name, raw, p);
    if (entry.explicit_positive && !range_nlm::isPositive(entry, p))
      throw std::invalid_argument("parameter ~" + name + " must be a positive number (omit it for automatic), got " +
                                  range_nlm::parameterText(entry, p));
    try {
      range_nlm::checkParameter(entry, p);
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument("parameter ~" + name + ": " + e.what());
    }
  }
  bool flag = false;
  if (entry.ros_switch.name && readParameter(node, entry.ros_switch.name, flag, "a boolean")) {
    const int value = flag ? entry.ros_switch.on : entry.ros_switch.off;
    if (value >= 0)
      range_nlm::setChoice(entry, p, value);
  }
}

} // namespace

range_nlm::FilterParameters
filterParametersFromParameters(const ros::NodeHandle& node)
{
  std::string preset = "default";
  readParameter(node, "preset", preset, "a string");
  range_nlm::FilterParameters p;
  try {
    p = range_nlm::FilterParameters::preset(preset);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument("parameter ~preset: " + std::string(e.what()));
  }
  for (const range_nlm::ParameterEntry& entry : range_nlm::parameterRegistry())
    readEntry(node, entry, p);
  return p;
}

StreamSettings
streamSettingsFromParameters(const ros::NodeHandle& node)
{
  StreamSettings settings;
  settings.parameters = filterParametersFromParameters(node);
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
