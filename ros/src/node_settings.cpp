#include <range_nlm/ros/node_settings.h>

#include <range_nlm/parameter_registry.h>

#include <ros/param.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <type_traits>
#include <variant>

namespace range_nlm_ros
{
namespace
{

/// The node's own parameters besides the registry's; image_transport and diagnostic_updater
/// read the last two from the same private namespace.
const char* const kOwnParameters[] = {"input",  "queue_size", "preset",           "temporal_radius",
                                      "causal", "recursive",  "image_transport", "diagnostic_period"};

[[noreturn]] void
wrongType(const std::string& name, const char* type, XmlRpc::XmlRpcValue& raw)
{
  throw std::invalid_argument("parameter ~" + name + " must be " + type + ", got '" + raw.toXml() + "'");
}

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
    wrongType(name, type, raw);
  }
  return true;
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

/// Levenshtein distance, for the nearest known name of a misspelt one.
std::size_t
editDistance(const std::string& a, const std::string& b)
{
  std::vector<std::size_t> row(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j)
    row[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    std::size_t diagonal = row[0];
    row[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t above = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diagonal + (a[i - 1] == b[j - 1] ? 0 : 1)});
      diagonal = above;
    }
  }
  return row[b.size()];
}

/// Throws for the first private parameter (a direct child of the node's namespace) that is not
/// a known name, suggesting the nearest known one.
void
refuseUnknownParameters(const ros::NodeHandle& node)
{
  std::vector<std::string> names;
  if (!ros::param::getParamNames(names))
    return; // no master to ask: the values were read from it a moment ago, so this is rare
  const std::string prefix = node.getNamespace() + "/";
  const std::vector<std::string>& known = knownParameterNames();
  for (const std::string& full : names) {
    if (full.compare(0, prefix.size(), prefix) != 0)
      continue;
    const std::string name = full.substr(prefix.size());
    if (name.find('/') != std::string::npos || std::find(known.begin(), known.end(), name) != known.end())
      continue;
    const auto nearest = std::min_element(known.begin(), known.end(), [&](const auto& a, const auto& b) {
      return editDistance(name, a) < editDistance(name, b);
    });
    std::string message = "unknown parameter ~" + name;
    if (editDistance(name, *nearest) <= std::max<std::size_t>(2, name.size() / 3))
      message += " (did you mean ~" + *nearest + "?)";
    throw std::invalid_argument(message + "; the parameters are listed in docs/ros.md");
  }
}

} // namespace

const char* const kDefaultPreset = "live";

const char*
windowName(range_nlm::TemporalWindow window)
{
  switch (window) {
  case range_nlm::TemporalWindow::recursive:
    return "recursive";
  case range_nlm::TemporalWindow::causal:
    return "causal";
  default:
    return "centred";
  }
}

range_nlm::FilterParameters
filterParametersFromParameters(const ros::NodeHandle& node)
{
  std::string preset = kDefaultPreset;
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

range_nlm::TemporalWindow
windowOf(bool causal, bool recursive)
{
  return recursive ? range_nlm::TemporalWindow::recursive
         : causal  ? range_nlm::TemporalWindow::causal
                   : range_nlm::TemporalWindow::centred;
}

StreamSettings
streamSettingsFromParameters(const ros::NodeHandle& node)
{
  StreamSettings settings;
  settings.parameters = filterParametersFromParameters(node);
  // A camera's stream on the live preset: one frame of history in the recursive window (a
  // running average of what stayed static), no output delay; other presets filter each frame
  // alone unless told otherwise.
  std::string preset = kDefaultPreset;
  readParameter(node, "preset", preset, "a string");
  const bool live = preset == "live";
  settings.temporal_radius = live ? 1 : 0;
  readParameter(node, "temporal_radius", settings.temporal_radius, "an integer");
  bool causal = true, recursive = live;
  readParameter(node, "causal", causal, "a boolean");
  readParameter(node, "recursive", recursive, "a boolean");
  settings.window = windowOf(causal, recursive);
  try {
    settings.validate();
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument("parameters of " + node.getNamespace() + ": " + e.what());
  }
  return settings;
}

const std::vector<std::string>&
knownParameterNames()
{
  static const std::vector<std::string> names = [] {
    std::vector<std::string> all(std::begin(kOwnParameters), std::end(kOwnParameters));
    for (const range_nlm::ParameterEntry& entry : range_nlm::parameterRegistry()) {
      if (entry.ros_name)
        all.push_back(entry.ros_name);
      if (entry.ros_switch.name)
        all.push_back(entry.ros_switch.name);
    }
    return all;
  }();
  return names;
}

NodeSettings
nodeSettingsFromParameters(const ros::NodeHandle& node)
{
  NodeSettings settings;
  refuseUnknownParameters(node);
  settings.stream = streamSettingsFromParameters(node);
  readParameter(node, "preset", settings.preset, "a string");
  readParameter(node, "input", settings.input, "a string");
  // A live camera wants the newest frame: with one frame queued it waits behind the one being
  // filtered only, not behind older ones too (docs/ros.md, "Camera rate").
  settings.queue_size = settings.preset == "live" ? 1 : 2;
  readParameter(node, "queue_size", settings.queue_size, "an integer");
  readParameter(node, "image_transport", settings.image_transport, "a string");
  if (settings.input != "points" && settings.input != "depth")
    throw std::invalid_argument("parameter ~input must be 'points' or 'depth', got '" + settings.input + "'");
  if (settings.queue_size < 1)
    throw std::invalid_argument("parameter ~queue_size must be >= 1, got " + std::to_string(settings.queue_size));
  for (const std::string& name : knownParameterNames())
    if (node.hasParam(name))
      settings.given.push_back(name);
  return settings;
}

int
publisherQueue(const NodeSettings& settings)
{
  return std::max(settings.queue_size, 2);
}

std::vector<std::string>
describeSettings(const NodeSettings& settings)
{
  const range_nlm::FilterParameters& p = settings.stream.parameters;
  const bool temporal = settings.stream.temporal_radius > 0;
  const bool along_ray = p.displacement == range_nlm::Displacement::line_of_sight ||
                         (p.displacement == range_nlm::Displacement::automatic && temporal);
  auto given = [&](const std::string& name) {
    return std::find(settings.given.begin(), settings.given.end(), name) != settings.given.end() ? " (set)" : "";
  };
  std::ostringstream head;
  head << "preset '" << settings.preset << "'" << given("preset") << ", temporal radius "
       << settings.stream.temporal_radius << given("temporal_radius") << ", "
       << windowName(settings.stream.window) << " window, points move along "
       << (along_ray ? "the line of sight" : "their normals")
       << (p.displacement == range_nlm::Displacement::automatic ? " (automatic)" : " (set)") << ", queue "
       << settings.queue_size << " (published: " << publisherQueue(settings) << ")";
  std::ostringstream all;
  all << "parameters:";
  for (const range_nlm::ParameterEntry& entry : range_nlm::parameterRegistry()) {
    const std::string name = entry.ros_name ? entry.ros_name : entry.name;
    all << ' ' << name << '=' << range_nlm::parameterText(entry, p)
        << given(name) << (entry.ros_switch.name ? given(entry.ros_switch.name) : "");
  }
  return {head.str(), all.str()};
}

} // namespace range_nlm_ros
