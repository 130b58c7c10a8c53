/// \file parameter_reconfigure.h
/// \brief dynamic_reconfigure for the filter node, made from the parameter registry at run time
/// instead of from a generated .cfg: the node serves the protocol of dynamic_reconfigure's
/// C++ server (service `~set_parameters`, latched topics `~parameter_descriptions` and
/// `~parameter_updates`), so that `dynparam`, rqt_reconfigure and dynamic_reconfigure::Client
/// work with it, and adding a parameter to the registry adds it here too.
///
/// Reconfigurable: temporal_radius, causal, recursive and every registry entry (by its ROS
/// name; an entry with only a boolean switch, such as `displacement`, by its field name, as its
/// enumerator's name). Enumerators are strings. A value of 0 for an automatic bandwidth asks
/// for the automatic value. New values are not written to the parameter server.
#pragma once

#include <range_nlm/ros/message_stream.h>

#include <dynamic_reconfigure/Config.h>
#include <dynamic_reconfigure/ConfigDescription.h>
#include <dynamic_reconfigure/Reconfigure.h>
#include <ros/ros.h>

#include <functional>
#include <mutex>

namespace range_nlm_ros
{

/// The description (one group, "Default", every reconfigurable parameter with its type, range
/// and help) with `defaults` as dflt.
dynamic_reconfigure::ConfigDescription
reconfigureDescription(const StreamSettings& defaults);

/// `settings` as a dynamic_reconfigure Config.
dynamic_reconfigure::Config
reconfigureConfig(const StreamSettings& settings);

/// `current` with the values of `request` (any subset of the parameters). Throws
/// std::invalid_argument naming the parameter for an unknown name, a value of the wrong type or
/// out of its range, and for an invalid combination.
StreamSettings
applyReconfigure(const StreamSettings& current, const dynamic_reconfigure::Config& request);

/// Serves the protocol on a private node handle. `apply` is called (from the service callback)
/// with each accepted setting before the update is published; a refused request is logged with
/// the reason and answered with the setting unchanged.
class ParameterReconfigure
{
public:
  using Apply = std::function<void(const StreamSettings&)>;
  ParameterReconfigure(ros::NodeHandle private_node, const StreamSettings& initial, Apply apply);

private:
  bool onSetParameters(dynamic_reconfigure::Reconfigure::Request& request,
                       dynamic_reconfigure::Reconfigure::Response& response);

  ros::NodeHandle node_;
  Apply apply_;
  std::mutex mutex_;
  StreamSettings current_;
  ros::Publisher descriptions_, updates_;
  ros::ServiceServer service_;
};

} // namespace range_nlm_ros
