/// \file parameter_registry.h
/// \brief The one table of the filter's parameters: every FilterParameters field with its unit,
/// valid range, enumerator names, help, and its names on the command line, in ROS and in a
/// `--pass` schedule. Validation, the tools' options, the ROS node's parameters, the pass
/// schedules and the parameter table of docs/method.md are all made from it, so that adding a
/// parameter is one entry plus its use.
#pragma once

#include <range_nlm/parameters.h>

#include <cstdint>
#include <limits>
#include <string>
#include <utility>
#include <variant>
#include <vector>

namespace range_nlm
{

/// The field an entry stands for, as a pointer to the member of its own type.
using ParameterField =
    std::variant<int FilterParameters::*, float FilterParameters::*, std::uint64_t FilterParameters::*,
                 bool FilterParameters::*, BandwidthModel FilterParameters::*, Evaluation FilterParameters::*,
                 CrossFrameBandwidth FilterParameters::*, Displacement FilterParameters::*>;

/// Valid values of a numeric field: v == 0 where `zero_allowed`; otherwise min <= v (min < v
/// with `min_exclusive`) and v <= max, and odd with `odd`; the bounds are compared as the field's
/// type holds them. Floating-point values must also be finite. Every numeric field has a finite
/// min and max (without them one option can take the machine's memory or time, or overflow the
/// float arithmetic), with `why` they are where they are.
struct ParameterRange
{
  double min = -std::numeric_limits<double>::infinity();
  double max = std::numeric_limits<double>::infinity();
  bool min_exclusive = false;
  bool odd = false;
  bool zero_allowed = false;
  /// What a valid value is, as validate()'s message ends: "must be ...".
  const char* requirement = nullptr;
  /// Why the bounds are where they are: what a value beyond them would cost or break.
  const char* why = nullptr;
};

/// A name without a value of its own that sets an enumerated field: a command-line flag, or a
/// boolean ROS parameter.
struct ParameterSwitch
{
  const char* name = nullptr;
  /// Enumerator set by the flag, or by the ROS parameter's true.
  int on = 0;
  /// Enumerator set by the ROS parameter's false; -1: false leaves the field as it is.
  int off = -1;
  /// Command-line help of the flag.
  const char* help = "";
};

/// One parameter: a FilterParameters field and every name it goes by.
struct ParameterEntry
{
  /// The field's name in FilterParameters (and in docs/method.md).
  const char* name;
  ParameterField field;
  /// Unit of the value ("pixels", "cloud units", "noise sigmas"), "" for none.
  const char* unit = "";
  ParameterRange range;
  /// Enumerated fields: (name, enumerator) pairs in the order they are listed to a user.
  std::vector<std::pair<const char*, int>> choices;
  /// What a value of 0 stands for ("automatic", "off"), nullptr if nothing special.
  const char* zero_means = nullptr;
  /// One line of help: the command-line option's and the table's meaning.
  const char* help = "";
  /// Section of docs/method.md that explains the parameter, as a Markdown link (nullptr: none).
  const char* docs_section = nullptr;
  /// Command-line option, without "--" (nullptr: none; see cli_switches).
  const char* cli_option = nullptr;
  /// The option always has a value: the recommended one, shown in the help as boost's default.
  bool cli_always = false;
  /// Command-line flags that set an enumerated field.
  std::vector<ParameterSwitch> cli_switches;
  /// Private ROS parameter of the node (nullptr: none; see ros_switch).
  const char* ros_name = nullptr;
  /// A boolean ROS parameter that sets an enumerated field (name nullptr: none).
  ParameterSwitch ros_switch;
  /// Key in a `--pass` item key=value (nullptr: none).
  const char* pass_key = nullptr;
  /// A value given explicitly (on the command line, in ROS) must be > 0: 0 stands for the
  /// automatic value, which is asked for by leaving the parameter out.
  bool explicit_positive = false;
};

/// Every parameter, in the order of the fields of FilterParameters (validate() checks in it).
const std::vector<ParameterEntry>&
parameterRegistry();

/// The entry of field `name`, or nullptr.
const ParameterEntry*
findParameter(const std::string& name);

/// Throws std::invalid_argument "range_nlm: parameter NAME = VALUE is invalid: must be ..." if
/// the entry's field of `p` is out of its range.
void
checkParameter(const ParameterEntry& entry, const FilterParameters& p);

/// Whether the entry's field of `p` is a number > 0 (what explicit_positive asks of a value given
/// explicitly).
bool
isPositive(const ParameterEntry& entry, const FilterParameters& p);

/// The entry's value in `p` as text: numbers as a stream prints them, enumerators by name,
/// booleans as true / false.
std::string
parameterText(const ParameterEntry& entry, const FilterParameters& p);

/// Sets the entry's field of `p` from text: an integer, a number, true / false, or an
/// enumerator's name, the whole text. Throws std::invalid_argument saying what was expected
/// ("an integer", "a number", ...); the range is not checked here (checkParameter does).
void
setParameterFromText(const ParameterEntry& entry, FilterParameters& p, const std::string& text);

/// "'a', 'b' or 'c'": the names of an enumerated field's values, for messages and help.
std::string
choiceList(const ParameterEntry& entry);

/// The enumerator named `text`, or -1.
int
choiceValue(const ParameterEntry& entry, const std::string& text);

/// Sets an enumerated field to enumerator `value`.
void
setChoice(const ParameterEntry& entry, FilterParameters& p, int value);

/// The Markdown table of every field (field, default, live, paper, unit, valid values, meaning), as
/// docs/method.md shows it.
std::string
parameterTable();

} // namespace range_nlm
