// The parameter registry: one entry per FilterParameters field, validate() made from its ranges,
// values as text both ways, and the docs table made from it.
#include "parameter_values.h"

#include <range_nlm/parameter_registry.h>

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <iterator>
#include <limits>
#include <set>
#include <stdexcept>
#include <string>
#include <variant>

using namespace range_nlm;

namespace
{
std::string
validationMessage(const FilterParameters& p)
{
  try {
    p.validate();
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

/// `p` with the entry's numeric field set to `value` (converted to the field's type).
FilterParameters
withNumber(const ParameterEntry& entry, FilterParameters p, double value)
{
  std::visit(
      [&](auto member) {
        using T = std::decay_t<decltype(p.*member)>;
        if constexpr (std::is_arithmetic_v<T> && !std::is_same_v<T, bool>)
          p.*member = static_cast<T>(value);
      },
      entry.field);
  return p;
}

bool
isFloat(const ParameterEntry& entry)
{
  return std::holds_alternative<float FilterParameters::*>(entry.field);
}
} // namespace

TEST(ParameterRegistry, OneEntryPerFieldWithDistinctNames)
{
  const auto& registry = parameterRegistry();
  // FilterParameters has 28 fields; a field added without its entry fails here.
  EXPECT_EQ(registry.size(), 28u);
  std::set<std::string> names, options, ros_names, pass_keys;
  for (const ParameterEntry& entry : registry) {
    EXPECT_TRUE(names.insert(entry.name).second) << entry.name;
    EXPECT_EQ(findParameter(entry.name), &entry);
    EXPECT_STRNE(entry.help, "") << entry.name;
    // Every field has a way in from the command line and from ROS.
    EXPECT_TRUE(entry.cli_option || !entry.cli_switches.empty()) << entry.name;
    EXPECT_TRUE(entry.ros_name || entry.ros_switch.name) << entry.name;
    if (entry.cli_option)
      EXPECT_TRUE(options.insert(entry.cli_option).second) << entry.cli_option;
    for (const ParameterSwitch& flag : entry.cli_switches)
      EXPECT_TRUE(options.insert(flag.name).second) << flag.name;
    if (entry.ros_name)
      EXPECT_TRUE(ros_names.insert(entry.ros_name).second) << entry.ros_name;
    if (entry.ros_switch.name)
      EXPECT_TRUE(ros_names.insert(entry.ros_switch.name).second) << entry.ros_switch.name;
    if (entry.pass_key)
      EXPECT_TRUE(pass_keys.insert(entry.pass_key).second) << entry.pass_key;
    // An entry's other value differs from the default and is valid (the other tests rely on it).
    const FilterParameters other = test::withOtherValue(entry, FilterParameters::recommended());
    EXPECT_FALSE(test::sameField(entry, other, FilterParameters::recommended())) << entry.name;
    EXPECT_EQ(validationMessage(other), "") << entry.name;
  }
  EXPECT_EQ(findParameter("patch"), nullptr); // fields by their own name only
  EXPECT_EQ(pass_keys.count("radius"), 0u);   // the pass's own key
}

TEST(ParameterRegistry, ExistingNamesKeepTheirFields)
{
  const auto option = [](const char* name) { return std::string(findParameter(name)->cli_option); };
  const auto ros = [](const char* name) { return std::string(findParameter(name)->ros_name); };
  EXPECT_EQ(option("search_window"), "search-window");
  EXPECT_EQ(option("patch_size"), "patch");
  EXPECT_EQ(option("patch_edge_gate"), "patch-gate");
  EXPECT_EQ(option("cross_frame_bandwidth"), "cross-frame");
  EXPECT_EQ(ros("patch_size"), "patch");
  EXPECT_EQ(ros("patch_edge_gate"), "patch_gate");
  EXPECT_EQ(ros("cross_frame_bandwidth"), "cross_frame");
  EXPECT_STREQ(findParameter("search_window")->pass_key, "search");
  EXPECT_STREQ(findParameter("patch_size")->pass_key, "patch");
  EXPECT_STREQ(findParameter("iterations")->pass_key, "iterations");
  EXPECT_STREQ(findParameter("normal_window")->pass_key, "normal");
  EXPECT_STREQ(findParameter("displacement")->ros_switch.name, "line_of_sight");
  EXPECT_STREQ(findParameter("evaluation")->ros_switch.name, "direct");
}

TEST(ParameterRegistry, ValidateRefusesEveryOutOfRangeValueByName)
{
  for (const ParameterEntry& entry : parameterRegistry()) {
    if (!entry.range.requirement)
      continue;
    const std::string name = entry.name;
    // Below the smallest valid value (NaN for a number: never valid).
    const FilterParameters low =
        isFloat(entry) ? withNumber(entry, {}, std::numeric_limits<double>::quiet_NaN())
                       : withNumber(entry, {}, entry.range.min - 2);
    const std::string message = validationMessage(low);
    EXPECT_EQ(message.rfind("range_nlm: parameter " + name + " = ", 0), 0u) << message;
    EXPECT_NE(message.find(std::string("is invalid: ") + entry.range.requirement), std::string::npos) << message;
    if (isFloat(entry))
      EXPECT_NE(validationMessage(withNumber(entry, {}, std::numeric_limits<double>::infinity())), "") << name;
    if (entry.range.odd)
      EXPECT_NE(validationMessage(withNumber(entry, {}, entry.range.min + 1)), "") << name;
    if (std::isfinite(entry.range.max))
      EXPECT_NE(validationMessage(withNumber(entry, {}, entry.range.max + 1)), "") << name;
  }
}

TEST(ParameterRegistry, RangesAreTheDocumentedOnes)
{
  const auto valid = [](const char* name, double value) {
    return validationMessage(withNumber(*findParameter(name), {}, value)).empty();
  };
  EXPECT_TRUE(valid("normal_presmooth_window", 0));
  EXPECT_TRUE(valid("normal_presmooth_window", 1));
  EXPECT_FALSE(valid("normal_presmooth_window", 2));
  EXPECT_FALSE(valid("normal_window", 1));
  EXPECT_TRUE(valid("threads", 1024));
  EXPECT_FALSE(valid("threads", 1025));
  EXPECT_TRUE(valid("line_of_sight_min_cos", 0));
  EXPECT_TRUE(valid("line_of_sight_min_cos", 1));
  EXPECT_FALSE(valid("distance_scale", 0));
  EXPECT_TRUE(valid("distance_bandwidth", 0));
  EXPECT_FALSE(valid("distance_bandwidth", -0.5));
  EXPECT_EQ(validationMessage(withNumber(*findParameter("patch_edge_gate"), {}, -2)),
            "range_nlm: parameter patch_edge_gate = -2 is invalid: must be finite and >= 0 (0 = off)");
}

TEST(ParameterRegistry, TextRoundTripsEveryField)
{
  for (const ParameterEntry& entry : parameterRegistry()) {
    const FilterParameters other = test::withOtherValue(entry, FilterParameters::recommended());
    FilterParameters p = FilterParameters::recommended();
    setParameterFromText(entry, p, parameterText(entry, other));
    EXPECT_TRUE(test::sameField(entry, p, other)) << entry.name << " = " << parameterText(entry, other);
    EXPECT_THROW(setParameterFromText(entry, p, "x7"), std::invalid_argument) << entry.name;
    EXPECT_THROW(setParameterFromText(entry, p, ""), std::invalid_argument) << entry.name;
  }
  FilterParameters p;
  EXPECT_THROW(setParameterFromText(*findParameter("seed"), p, "-1"), std::invalid_argument);
  EXPECT_THROW(setParameterFromText(*findParameter("search_window"), p, "7.5"), std::invalid_argument);
  setParameterFromText(*findParameter("outlier_sigmas"), p, "2.5");
  EXPECT_EQ(p.outlier_sigmas, 2.5f);
  setParameterFromText(*findParameter("cross_frame_bandwidth"), p, "temporal");
  EXPECT_EQ(p.cross_frame_bandwidth, CrossFrameBandwidth::temporal);
  EXPECT_EQ(parameterText(*findParameter("displacement"), p), "automatic");
  EXPECT_EQ(parameterText(*findParameter("patch_guide"), p), "true");
  EXPECT_EQ(parameterText(*findParameter("distance_scale"), p), "1.5");
}

TEST(ParameterRegistry, ChoicesAreListedInTheirOrder)
{
  const ParameterEntry& cross_frame = *findParameter("cross_frame_bandwidth");
  EXPECT_EQ(choiceList(cross_frame), "'guarded', 'temporal' or 'spatial'");
  EXPECT_EQ(choiceValue(cross_frame, "spatial"), int(CrossFrameBandwidth::spatial));
  EXPECT_EQ(choiceValue(cross_frame, "Spatial"), -1);
  FilterParameters p;
  setChoice(*findParameter("evaluation"), p, int(Evaluation::direct));
  EXPECT_EQ(p.evaluation, Evaluation::direct);
  EXPECT_THROW(setChoice(*findParameter("iterations"), p, 1), std::logic_error);
}

TEST(ParameterRegistry, DocsShowTheGeneratedTable)
{
  std::ifstream in(std::string(RANGE_NLM_SOURCE_DIR) + "/docs/method.md");
  ASSERT_TRUE(in) << "docs/method.md";
  const std::string docs((std::istreambuf_iterator<char>(in)), {});
  const std::string table = parameterTable();
  EXPECT_NE(docs.find(table), std::string::npos)
      << "docs/method.md lacks the parameter table of parameterTable(); replace it by:\n"
      << table;
  for (const ParameterEntry& entry : parameterRegistry())
    EXPECT_NE(table.find("| `" + std::string(entry.name) + "` | "), std::string::npos) << entry.name;
  EXPECT_NE(table.find("| `patch_guide` | true | true | false |"), std::string::npos) << table;
  EXPECT_NE(table.find("| `dilation` | 0 (automatic) | 0 (automatic) | 1 |"), std::string::npos) << table;
  EXPECT_NE(table.find("| `reuse_estimates` | false | true | false |"), std::string::npos) << table;
}
