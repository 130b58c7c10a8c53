#include <range_nlm/ros/parameter_reconfigure.h>

#include <range_nlm/parameter_registry.h>
#include <range_nlm/ros/node_settings.h>

#include <climits>
#include <cmath>
#include <limits>
#include <string>
#include <type_traits>
#include <variant>

namespace range_nlm_ros
{
namespace
{

using dynamic_reconfigure::Config;

/// The name a registry entry has in the reconfigure protocol.
std::string
reconfigureName(const range_nlm::ParameterEntry& entry)
{
  return entry.ros_name ? entry.ros_name : entry.name;
}

/// dynamic_reconfigure's type name of an entry: int, double, bool or str (enumerators).
std::string
typeName(const range_nlm::ParameterEntry& entry)
{
  return std::visit(
      [](auto member) -> std::string {
        using T = std::decay_t<decltype(range_nlm::FilterParameters().*member)>;
        if constexpr (std::is_enum_v<T>)
          return "str";
        else if constexpr (std::is_same_v<T, bool>)
          return "bool";
        else if constexpr (std::is_floating_point_v<T>)
          return "double";
        else
          return "int";
      },
      entry.field);
}

/// The enumerators as dynamic_reconfigure's edit_method, which rqt_reconfigure shows as a list.
std::string
editMethod(const range_nlm::ParameterEntry& entry)
{
  if (entry.choices.empty())
    return "";
  std::string text = "{'enum_description': 'values', 'enum': [";
  for (std::size_t i = 0; i < entry.choices.size(); ++i) {
    const std::string name = entry.choices[i].first;
    text += std::string(i ? ", " : "") + "{'name': '" + name + "', 'type': 'str', 'value': '" + name +
            "', 'description': '" + name + "', 'srcline': 0, 'srcfile': '', 'cconsttype': 'const char * const', "
            "'ctype': 'std::string'}";
  }
  return text + "]}";
}

void
add(Config& config, const std::string& name, int value)
{
  dynamic_reconfigure::IntParameter p;
  p.name = name;
  p.value = value;
  config.ints.push_back(p);
}

void
add(Config& config, const std::string& name, double value)
{
  dynamic_reconfigure::DoubleParameter p;
  p.name = name;
  p.value = value;
  config.doubles.push_back(p);
}

void
add(Config& config, const std::string& name, bool value)
{
  dynamic_reconfigure::BoolParameter p;
  p.name = name;
  p.value = value;
  config.bools.push_back(p);
}

void
add(Config& config, const std::string& name, const std::string& value)
{
  dynamic_reconfigure::StrParameter p;
  p.name = name;
  p.value = value;
  config.strs.push_back(p);
}

/// An entry's value in `p` added to `config` under its type.
void
addEntry(Config& config, const range_nlm::ParameterEntry& entry, const range_nlm::FilterParameters& p)
{
  const std::string name = reconfigureName(entry);
  std::visit(
      [&](auto member) {
        using T = std::decay_t<decltype(p.*member)>;
        if constexpr (std::is_enum_v<T>)
          add(config, name, range_nlm::parameterText(entry, p));
        else if constexpr (std::is_same_v<T, bool>)
          add(config, name, bool(p.*member));
        else if constexpr (std::is_floating_point_v<T>)
          add(config, name, double(p.*member));
        else
          add(config, name, int(std::min<long long>(static_cast<long long>(p.*member), INT_MAX)));
      },
      entry.field);
}

/// The bounds of an entry, as generated configs state them (infinite or INT_MAX where none).
void
addBounds(Config& min, Config& max, const range_nlm::ParameterEntry& entry)
{
  const std::string name = reconfigureName(entry);
  const std::string type = typeName(entry);
  const double low = entry.range.zero_allowed ? std::min(0.0, entry.range.min) : entry.range.min;
  if (type == "int") {
    const bool is_unsigned = std::holds_alternative<std::uint64_t range_nlm::FilterParameters::*>(entry.field);
    const double floor = is_unsigned ? 0.0 : -double(INT_MAX);
    add(min, name, int(std::isfinite(low) ? low : floor));
    add(max, name, int(std::isfinite(entry.range.max) ? std::min(entry.range.max, double(INT_MAX)) : INT_MAX));
  } else if (type == "double") {
    add(min, name, low);
    add(max, name, entry.range.max);
  } else if (type == "bool") {
    add(min, name, false);
    add(max, name, true);
  } else {
    add(min, name, std::string());
    add(max, name, std::string());
  }
}

dynamic_reconfigure::ParamDescription
describe(const std::string& name, const std::string& type, const std::string& help, const std::string& edit = "")
{
  dynamic_reconfigure::ParamDescription d;
  d.name = name;
  d.type = type;
  d.level = 1; // every change restarts the temporal window
  d.description = help;
  d.edit_method = edit;
  return d;
}

void
addGroupState(Config& config)
{
  dynamic_reconfigure::GroupState state;
  state.name = "Default";
  state.state = true;
  state.id = 0;
  state.parent = 0;
  config.groups.push_back(state);
}

[[noreturn]] void
refuse(const std::string& name, const std::string& what)
{
  throw std::invalid_argument("reconfigure: parameter " + name + " " + what);
}

/// Sets an entry's field from a request's value of the matching type; `value` is a bool, an
/// int, a double or a string.
template <typename Value>
void
setEntry(const range_nlm::ParameterEntry& entry, const std::string& name, const Value& value,
         range_nlm::FilterParameters& p)
{
  std::visit(
      [&](auto member) {
        using T = std::decay_t<decltype(p.*member)>;
        if constexpr (std::is_enum_v<T>) {
          if constexpr (!std::is_same_v<Value, std::string>)
            refuse(name, "must be a string: " + range_nlm::choiceList(entry));
          else {
            const int choice = range_nlm::choiceValue(entry, value);
            if (choice < 0)
              refuse(name, "= '" + value + "' is invalid: expected " + range_nlm::choiceList(entry));
            p.*member = static_cast<T>(choice);
          }
        } else if constexpr (std::is_same_v<T, bool>) {
          if constexpr (!std::is_same_v<Value, bool>)
            refuse(name, "must be a boolean");
          else
            p.*member = value;
        } else if constexpr (std::is_floating_point_v<T>) {
          if constexpr (std::is_same_v<Value, double> || std::is_same_v<Value, int>)
            p.*member = static_cast<T>(value);
          else
            refuse(name, "must be a number");
        } else {
          if constexpr (!std::is_same_v<Value, int>)
            refuse(name, "must be an integer");
          else if (std::is_unsigned_v<T> && value < 0)
            refuse(name, "must be >= 0, got " + std::to_string(value));
          else
            p.*member = static_cast<T>(value);
        }
      },
      entry.field);
  try {
    range_nlm::checkParameter(entry, p);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument("reconfigure: parameter " + name + ": " + e.what());
  }
}

/// Applies one value to `settings`: the window's own parameters or a registry entry.
template <typename Value>
void
applyValue(StreamSettings& settings, bool& causal, bool& recursive, const std::string& name, const Value& value)
{
  if (name == "temporal_radius") {
    if constexpr (!std::is_same_v<Value, int>)
      refuse(name, "must be an integer");
    else
      settings.temporal_radius = value;
    return;
  }
  if (name == "causal" || name == "recursive") {
    if constexpr (!std::is_same_v<Value, bool>)
      refuse(name, "must be a boolean");
    else
      (name == "causal" ? causal : recursive) = value;
    return;
  }
  for (const range_nlm::ParameterEntry& entry : range_nlm::parameterRegistry())
    if (reconfigureName(entry) == name) {
      setEntry(entry, name, value, settings.parameters);
      return;
    }
  refuse(name, "is unknown");
}

} // namespace

dynamic_reconfigure::Config
reconfigureConfig(const StreamSettings& settings)
{
  Config config;
  add(config, "temporal_radius", settings.temporal_radius);
  add(config, "causal", settings.window != range_nlm::TemporalWindow::centred);
  add(config, "recursive", settings.window == range_nlm::TemporalWindow::recursive);
  for (const range_nlm::ParameterEntry& entry : range_nlm::parameterRegistry())
    addEntry(config, entry, settings.parameters);
  addGroupState(config);
  return config;
}

dynamic_reconfigure::ConfigDescription
reconfigureDescription(const StreamSettings& defaults)
{
  dynamic_reconfigure::ConfigDescription description;
  dynamic_reconfigure::Group group;
  group.name = "Default";
  group.id = 0;
  group.parent = 0;
  group.parameters.push_back(describe("temporal_radius", "int", "r, the neighbouring frames used on each side"));
  group.parameters.push_back(describe("causal", "bool", "window t - r .. t (no delay); false: centred"));
  group.parameters.push_back(describe("recursive", "bool", "the neighbour is the running average of the frames"));
  add(description.min, "temporal_radius", 0);
  add(description.max, "temporal_radius", INT_MAX);
  add(description.min, "causal", false);
  add(description.max, "causal", true);
  add(description.min, "recursive", false);
  add(description.max, "recursive", true);
  for (const range_nlm::ParameterEntry& entry : range_nlm::parameterRegistry()) {
    group.parameters.push_back(describe(reconfigureName(entry), typeName(entry), entry.help, editMethod(entry)));
    addBounds(description.min, description.max, entry);
  }
  description.groups.push_back(group);
  description.dflt = reconfigureConfig(defaults);
  addGroupState(description.min);
  addGroupState(description.max);
  return description;
}

StreamSettings
applyReconfigure(const StreamSettings& current, const dynamic_reconfigure::Config& request)
{
  StreamSettings settings = current;
  bool causal = current.window != range_nlm::TemporalWindow::centred;
  bool recursive = current.window == range_nlm::TemporalWindow::recursive;
  for (const auto& p : request.bools)
    applyValue(settings, causal, recursive, p.name, bool(p.value));
  for (const auto& p : request.ints)
    applyValue(settings, causal, recursive, p.name, int(p.value));
  for (const auto& p : request.doubles)
    applyValue(settings, causal, recursive, p.name, double(p.value));
  for (const auto& p : request.strs)
    applyValue(settings, causal, recursive, p.name, std::string(p.value));
  settings.window = windowOf(causal, recursive);
  try {
    settings.validate();
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(std::string("reconfigure: ") + e.what());
  }
  return settings;
}

ParameterReconfigure::ParameterReconfigure(ros::NodeHandle private_node, const StreamSettings& initial, Apply apply)
  : node_(private_node), apply_(std::move(apply)), current_(initial)
{
  descriptions_ = node_.advertise<dynamic_reconfigure::ConfigDescription>("parameter_descriptions", 1, true);
  updates_ = node_.advertise<dynamic_reconfigure::Config>("parameter_updates", 1, true);
  descriptions_.publish(reconfigureDescription(initial));
  updates_.publish(reconfigureConfig(initial));
  service_ = node_.advertiseService("set_parameters", &ParameterReconfigure::onSetParameters, this);
}

bool
ParameterReconfigure::onSetParameters(dynamic_reconfigure::Reconfigure::Request& request,
                                      dynamic_reconfigure::Reconfigure::Response& response)
{
  std::lock_guard<std::mutex> lock(mutex_);
  try {
    const StreamSettings next = applyReconfigure(current_, request.config);
    apply_(next);
    current_ = next;
  } catch (const std::exception& e) {
    ROS_ERROR("%s: %s; the setting is unchanged", node_.getNamespace().c_str(), e.what());
  }
  response.config = reconfigureConfig(current_);
  updates_.publish(response.config);
  return true;
}

} // namespace range_nlm_ros
