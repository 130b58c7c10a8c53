// Values of the parameter registry's fields for tests that send every parameter through one of
// its ways in (options, --pass, ROS parameters, setters).
#pragma once

#include <range_nlm/parameter_registry.h>

#include <type_traits>
#include <variant>

namespace range_nlm
{
namespace test
{

/// `p` with the entry's field set to a valid value other than its own: integers + 2 (odd stays
/// odd; the 0 of a field that is odd or 0 becomes 3), numbers + 0.5 (fractional where the value is whole), seeds + 2, booleans negated,
/// enumerators the first other name.
inline FilterParameters
withOtherValue(const ParameterEntry& entry, FilterParameters p)
{
  std::visit(
      [&](auto member) {
        using T = std::decay_t<decltype(p.*member)>;
        if constexpr (std::is_enum_v<T>) {
          for (const auto& c : entry.choices)
            if (c.second != static_cast<int>(p.*member)) {
              p.*member = static_cast<T>(c.second);
              break;
            }
        } else if constexpr (std::is_same_v<T, bool>) {
          p.*member = !(p.*member);
        } else if constexpr (std::is_floating_point_v<T>) {
          p.*member = p.*member + 0.5f <= entry.range.max ? p.*member + 0.5f : p.*member - 0.25f;
        } else if (entry.range.odd && p.*member == 0) {
          p.*member = 3;
        } else {
          p.*member = p.*member + 2;
        }
      },
      entry.field);
  return p;
}

/// Whether the entry's field is the same in a and b (exactly; NaN never is).
inline bool
sameField(const ParameterEntry& entry, const FilterParameters& a, const FilterParameters& b)
{
  return std::visit([&](auto member) { return a.*member == b.*member; }, entry.field);
}

/// Whether every field but the entry's is the same in a and b.
inline bool
sameOtherFields(const ParameterEntry& entry, const FilterParameters& a, const FilterParameters& b)
{
  for (const ParameterEntry& other : parameterRegistry())
    if (&other != &entry && !sameField(other, a, b))
      return false;
  return true;
}

} // namespace test
} // namespace range_nlm
