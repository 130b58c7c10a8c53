// The dynamic_reconfigure protocol made from the parameter registry: every parameter described
// with its type, requests applied by type and range, refusals naming the parameter.
#include <range_nlm/parameter_registry.h>
#include <range_nlm/ros/parameter_reconfigure.h>

#include <gtest/gtest.h>

#include <set>
#include <stdexcept>
#include <string>

using namespace range_nlm;
using range_nlm_ros::StreamSettings;

namespace
{

/// What applyReconfigure refuses for `request` ("" if nothing).
std::string
refusal(const dynamic_reconfigure::Config& request)
{
  try {
    range_nlm_ros::applyReconfigure(StreamSettings(), request);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

template <typename Parameter, typename Value>
dynamic_reconfigure::Config
request(std::vector<Parameter> dynamic_reconfigure::Config::*list, const std::string& name, const Value& value)
{
  dynamic_reconfigure::Config config;
  Parameter p;
  p.name = name;
  p.value = value;
  (config.*list).push_back(p);
  return config;
}

} // namespace

TEST(ParameterReconfigure, TheDescriptionHasEveryRegistryParameterWithItsType)
{
  const auto description = range_nlm_ros::reconfigureDescription(StreamSettings());
  ASSERT_EQ(description.groups.size(), 1u);
  std::set<std::string> described;
  for (const auto& p : description.groups[0].parameters)
    described.insert(p.name + ":" + p.type);
  for (const ParameterEntry& entry : parameterRegistry()) {
    const std::string name = entry.ros_name ? entry.ros_name : entry.name;
    const bool listed = described.count(name + ":int") || described.count(name + ":double") ||
                        described.count(name + ":bool") || described.count(name + ":str");
    EXPECT_TRUE(listed) << name;
  }
  EXPECT_TRUE(described.count("outlier_sigmas:double"));
  EXPECT_TRUE(described.count("search_window:int"));
  EXPECT_TRUE(described.count("cross_frame:str"));
  EXPECT_TRUE(described.count("displacement:str"));
  EXPECT_TRUE(described.count("temporal_radius:int"));
  EXPECT_TRUE(described.count("recursive:bool"));
  // min, max and dflt hold every parameter too.
  const auto count = [](const dynamic_reconfigure::Config& c) {
    return c.ints.size() + c.doubles.size() + c.bools.size() + c.strs.size();
  };
  EXPECT_EQ(count(description.dflt), description.groups[0].parameters.size());
  EXPECT_EQ(count(description.min), description.groups[0].parameters.size());
  EXPECT_EQ(count(description.max), description.groups[0].parameters.size());
}

TEST(ParameterReconfigure, ValuesAreAppliedByTheirType)
{
  using C = dynamic_reconfigure::Config;
  StreamSettings s = range_nlm_ros::applyReconfigure(StreamSettings(), request(&C::doubles, "outlier_sigmas", 2.5));
  EXPECT_EQ(s.parameters.outlier_sigmas, 2.5f); // not rounded
  s = range_nlm_ros::applyReconfigure(s, request(&C::ints, "search_window", 11));
  EXPECT_EQ(s.parameters.search_window, 11);
  EXPECT_EQ(s.parameters.outlier_sigmas, 2.5f); // the earlier change stays
  s = range_nlm_ros::applyReconfigure(s, request(&C::ints, "patch_gate", 4)); // an int for a double
  EXPECT_EQ(s.parameters.patch_edge_gate, 4.0f);
  s = range_nlm_ros::applyReconfigure(s, request(&C::strs, "cross_frame", std::string("spatial")));
  EXPECT_EQ(s.parameters.cross_frame_bandwidth, CrossFrameBandwidth::spatial);
  s = range_nlm_ros::applyReconfigure(s, request(&C::strs, "displacement", std::string("normal")));
  EXPECT_EQ(s.parameters.displacement, Displacement::normal);
  s = range_nlm_ros::applyReconfigure(s, request(&C::ints, "temporal_radius", 2));
  s = range_nlm_ros::applyReconfigure(s, request(&C::bools, "causal", false));
  EXPECT_EQ(s.temporal_radius, 2);
  EXPECT_EQ(s.window, TemporalWindow::centred);
  s = range_nlm_ros::applyReconfigure(s, request(&C::bools, "recursive", true));
  EXPECT_EQ(s.window, TemporalWindow::recursive);
  // The setting comes back as it was applied.
  const auto config = range_nlm_ros::reconfigureConfig(s);
  EXPECT_EQ(range_nlm_ros::applyReconfigure(StreamSettings(), config).parameters.search_window, 11);
  EXPECT_EQ(range_nlm_ros::applyReconfigure(StreamSettings(), config).window, TemporalWindow::recursive);
}

TEST(ParameterReconfigure, BadRequestsAreRefusedNamingTheParameter)
{
  using C = dynamic_reconfigure::Config;
  EXPECT_EQ(refusal(request(&C::ints, "search_window", 8)),
            "reconfigure: parameter search_window: range_nlm: parameter search_window = 8 is invalid: must be a "
            "positive odd number of pixels, at most 101");
  EXPECT_EQ(refusal(request(&C::doubles, "search_window", 9.0)),
            "reconfigure: parameter search_window must be an integer");
  EXPECT_EQ(refusal(request(&C::strs, "outlier_sigmas", std::string("2.5"))),
            "reconfigure: parameter outlier_sigmas must be a number");
  EXPECT_EQ(refusal(request(&C::strs, "cross_frame", std::string("always"))),
            "reconfigure: parameter cross_frame = 'always' is invalid: expected 'guarded', 'temporal' or 'spatial'");
  EXPECT_EQ(refusal(request(&C::ints, "serch_window", 9)), "reconfigure: parameter serch_window is unknown");
  EXPECT_EQ(refusal(request(&C::ints, "temporal_radius", -1)),
            "reconfigure: temporal_radius must be >= 0, got -1");
}
