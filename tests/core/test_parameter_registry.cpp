// The parameter registry: one entry per FilterParameters field, validate() made from its ranges,
// values as text both ways, and the docs table made from it.
#include "parameter_values.h"

#include <range_nlm/parameter_registry.h>

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <fstream>
#include <iterator>
#include <limits>
#include <set>
#include <stdexcept>
#include <string>
#include <variant>
#include <vector>

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
  // FilterParameters has 29 fields; a field added without its entry fails here.
  EXPECT_EQ(registry.size(), 30u);
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
    // An unsigned field's bounds are its type's (EveryNumericParameterIsBounded... checks it).
    if (!entry.range.requirement || std::holds_alternative<std::uint64_t FilterParameters::*>(entry.field))
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
    if (std::isfinite(entry.range.max)) // twice the largest: 1e18 + 1 is 1e18 in a float
      EXPECT_NE(validationMessage(withNumber(entry, {}, 2 * entry.range.max + 1)), "") << name;
  }
}

namespace
{
/// The smallest and largest valid values of a numeric entry, and values just outside them that its
/// field's type can hold (none where the bound is the type's own).
struct Bounds
{
  double lowest = 0, highest = 0;
  std::vector<double> outside;
};

template <typename T>
Bounds
boundsOf(const ParameterRange& r)
{
  Bounds b;
  if constexpr (std::is_floating_point_v<T>) {
    const T min = static_cast<T>(r.min), max = static_cast<T>(r.max);
    const T below = std::nextafter(min, -std::numeric_limits<T>::infinity());
    b.lowest = r.min_exclusive ? std::nextafter(min, std::numeric_limits<T>::infinity()) : min;
    b.highest = max;
    if (!(r.zero_allowed && (r.min_exclusive ? min : below) == T(0)))
      b.outside.push_back(r.min_exclusive ? min : below);
    b.outside.push_back(std::nextafter(max, std::numeric_limits<T>::infinity()));
    b.outside.push_back(std::numeric_limits<T>::max());
    b.outside.push_back(std::numeric_limits<T>::lowest());
  } else {
    const double first = r.min_exclusive ? r.min + 1 : r.min;
    b.lowest = r.odd && std::fmod(first, 2.0) == 0.0 ? first + 1 : first;
    b.highest = r.odd && std::fmod(r.max, 2.0) == 0.0 ? r.max - 1 : r.max;
    if (first - 1 >= double(std::numeric_limits<T>::lowest()) && !(r.zero_allowed && first - 1 == 0))
      b.outside.push_back(first - 1);
    if (r.max < double(std::numeric_limits<T>::max()))
      b.outside.push_back(r.max + 1);
    if (double(std::numeric_limits<T>::max()) > r.max)
      b.outside.push_back(double(std::numeric_limits<T>::max()));
    if (double(std::numeric_limits<T>::lowest()) < r.min)
      b.outside.push_back(double(std::numeric_limits<T>::lowest()));
  }
  return b;
}
} // namespace

// Every numeric parameter has a finite smallest and largest value, with the reason for them, and
// validate() takes both and refuses the values just outside (and the type's extremes). A field
// added without bounds fails here: without them a single option can take all the memory or time
// of the machine, or overflow the float arithmetic.
TEST(ParameterRegistry, EveryNumericParameterIsBoundedAndValidateEnforcesTheBounds)
{
  for (const ParameterEntry& entry : parameterRegistry()) {
    std::visit(
        [&](auto member) {
          using T = std::decay_t<decltype(FilterParameters{}.*member)>;
          if constexpr (std::is_arithmetic_v<T> && !std::is_same_v<T, bool>) {
            const ParameterRange& r = entry.range;
            const std::string name = entry.name;
            ASSERT_NE(r.requirement, nullptr) << name << " has no valid range";
            EXPECT_TRUE(std::isfinite(r.min)) << name << " has no smallest value";
            EXPECT_TRUE(std::isfinite(r.max)) << name << " has no largest value";
            EXPECT_TRUE(r.why && *r.why) << name << " does not say why its range ends where it does";
            if (!std::isfinite(r.min) || !std::isfinite(r.max))
              return;
            EXPECT_LE(r.min, r.max) << name;
            // Bounds the field's type cannot hold would not bound it.
            EXPECT_GE(r.min, double(std::numeric_limits<T>::lowest())) << name;
            EXPECT_LE(r.max, double(std::numeric_limits<T>::max())) << name;
            const Bounds b = boundsOf<T>(r);
            EXPECT_EQ(validationMessage(withNumber(entry, {}, b.lowest)), "") << name << " = " << b.lowest;
            EXPECT_EQ(validationMessage(withNumber(entry, {}, b.highest)), "") << name << " = " << b.highest;
            for (const double value : b.outside) {
              const std::string message = validationMessage(withNumber(entry, {}, value));
              EXPECT_NE(message.find("parameter " + name + " = "), std::string::npos) << name << " = " << value;
            }
            if (r.zero_allowed)
              EXPECT_EQ(validationMessage(withNumber(entry, {}, 0)), "") << name;
          }
        },
        entry.field);
  }
}

// The samples of the bandwidth estimate serve a few per-range medians: their number is bounded,
// and 2^31 - 1 of them (tens of GB of samples) is refused by name.
TEST(ParameterRegistry, BandwidthSamplesAreBoundedByTheirPurpose)
{
  const ParameterEntry& samples = *findParameter("bandwidth_samples");
  EXPECT_EQ(validationMessage(withNumber(samples, {}, FilterParameters::max_bandwidth_samples)), "");
  EXPECT_EQ(validationMessage(withNumber(samples, {}, 2147483647.0)),
            "range_nlm: parameter bandwidth_samples = 2147483647 is invalid: must be at least 1, at most 100000");
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
            "range_nlm: parameter patch_edge_gate = -2 is invalid: must be finite and >= 0 (0 = off), at most 1000");
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
