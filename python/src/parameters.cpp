// Parameters: FilterParameters with one attribute and one keyword argument per entry of the
// parameter registry, checked by the registry's own validation.
#include "bindings.h"

#include <range_nlm/parameter_registry.h>

#include <pybind11/stl.h>

#include <limits>
#include <type_traits>

namespace range_nlm
{
namespace python
{
namespace
{

/// The registry entry a keyword names: its field name, or its command-line option with '_' for
/// '-' (search_window, patch, patch_gate, cross_frame, ...). Null if neither.
const ParameterEntry*
entryNamed(const std::string& keyword)
{
  if (const ParameterEntry* entry = findParameter(keyword))
    return entry;
  for (const ParameterEntry& entry : parameterRegistry()) {
    if (!entry.cli_option)
      continue;
    std::string option = entry.cli_option;
    for (char& c : option)
      c = c == '-' ? '_' : c;
    if (option == keyword)
      return &entry;
  }
  return nullptr;
}

std::string
knownNames()
{
  std::string names;
  for (const ParameterEntry& entry : parameterRegistry())
    names += (names.empty() ? "" : ", ") + std::string(entry.name);
  return names;
}

[[noreturn]] void
invalid(const ParameterEntry& entry, const py::handle& value, const std::string& requirement)
{
  throw py::value_error("range_nlm: parameter " + std::string(entry.name) + " = " +
                        py::repr(value).cast<std::string>() + " is invalid: " + requirement);
}

[[noreturn]] void
wrongType(const ParameterEntry& entry, const py::handle& value, const char* expected)
{
  throw py::type_error("range_nlm: parameter " + std::string(entry.name) + " needs " + expected + ", got " +
                       py::repr(value).cast<std::string>() + " (" +
                       py::str(value.get_type().attr("__name__")).cast<std::string>() + ")");
}

bool
isInteger(const py::handle& value)
{
  return !py::isinstance<py::bool_>(value) && PyIndex_Check(value.ptr());
}

bool
isNumber(const py::handle& value)
{
  return !py::isinstance<py::bool_>(value) && !py::isinstance<py::str>(value) &&
         (isInteger(value) || py::hasattr(value, "__float__"));
}

/// An integer value as the field's type; out of that type's range is an invalid value.
template <typename T>
T
integerValue(const ParameterEntry& entry, const py::handle& value)
{
  if (!isInteger(value))
    wrongType(entry, value, "an integer");
  const py::int_ number = py::reinterpret_steal<py::int_>(PyNumber_Index(value.ptr()));
  const py::int_ low(std::numeric_limits<T>::min()), high(std::numeric_limits<T>::max());
  if (number < low || number > high)
    invalid(entry, value, entry.range.requirement ? entry.range.requirement : "must be an integer >= 0");
  return number.cast<T>();
}

/// Sets the entry's field of `p` from a Python value of the field's type, then checks it with
/// the registry's validation (a std::invalid_argument, i.e. ValueError, naming it).
void
setField(const ParameterEntry& entry, FilterParameters& p, const py::handle& value)
{
  if (entry.explicit_positive && value.is_none()) { // the automatic value
    setParameterFromText(entry, p, "0");
    return;
  }
  std::visit(
      [&](auto member) {
        using T = std::decay_t<decltype(p.*member)>;
        if constexpr (std::is_enum_v<T>) {
          if (!py::isinstance<py::str>(value))
            wrongType(entry, value, ("one of " + choiceList(entry)).c_str());
          const int choice = choiceValue(entry, value.cast<std::string>());
          if (choice < 0)
            invalid(entry, value, "must be " + choiceList(entry));
          p.*member = static_cast<T>(choice);
        } else if constexpr (std::is_same_v<T, bool>) {
          if (!py::isinstance<py::bool_>(value))
            wrongType(entry, value, "True or False");
          p.*member = value.cast<bool>();
        } else if constexpr (std::is_floating_point_v<T>) {
          if (!isNumber(value))
            wrongType(entry, value, "a number");
          p.*member = static_cast<T>(py::float_(py::reinterpret_borrow<py::object>(value)).cast<double>());
        } else {
          p.*member = integerValue<T>(entry, value);
        }
      },
      entry.field);
  if (entry.explicit_positive && !isPositive(entry, p))
    invalid(entry, value, "a bandwidth given explicitly must be a positive number (None or leaving it out: automatic)");
  checkParameter(entry, p);
}

/// The field's value as a Python object: numbers, True / False, enumerators by name.
py::object
fieldValue(const ParameterEntry& entry, const FilterParameters& p)
{
  return std::visit(
      [&](auto member) -> py::object {
        using T = std::decay_t<decltype(p.*member)>;
        if constexpr (std::is_enum_v<T>)
          return py::str(parameterText(entry, p));
        else
          return py::cast(p.*member);
      },
      entry.field);
}

const char*
typeName(const ParameterEntry& entry)
{
  return std::visit(
      [](auto member) -> const char* {
        using T = std::decay_t<decltype(std::declval<FilterParameters>().*member)>;
        if constexpr (std::is_enum_v<T>)
          return "str";
        else if constexpr (std::is_same_v<T, bool>)
          return "bool";
        else if constexpr (std::is_floating_point_v<T>)
          return "float";
        else
          return "int";
      },
      entry.field);
}

/// The attribute's docstring: help, unit, default, valid values, as the docs' table gives them.
std::string
fieldDoc(const ParameterEntry& entry)
{
  const FilterParameters recommended = FilterParameters::recommended(), paper = FilterParameters::paper();
  std::string doc = std::string(entry.help) + " (" + typeName(entry);
  if (*entry.unit)
    doc += ", " + std::string(entry.unit);
  doc += "; default " + parameterText(entry, recommended) + ", paper " + parameterText(entry, paper);
  if (!entry.choices.empty())
    doc += "; " + choiceList(entry);
  else if (entry.range.requirement)
    doc += "; " + std::string(entry.range.requirement);
  if (entry.zero_means)
    doc += "; 0 = " + std::string(entry.zero_means);
  if (entry.cli_option)
    doc += "; range_nlm_denoise --" + std::string(entry.cli_option);
  return doc + ")";
}

/// Applies keyword arguments to `p`; an unknown keyword is a TypeError naming it.
void
applyKeywords(FilterParameters& p, const py::dict& keywords)
{
  for (const auto& item : keywords) {
    const std::string key = py::str(item.first);
    const ParameterEntry* entry = entryNamed(key);
    if (!entry)
      throw py::type_error("range_nlm: unexpected keyword argument '" + key + "'; the parameters are " +
                           knownNames());
    setField(*entry, p, item.second);
  }
}

py::dict
registryEntry(const ParameterEntry& entry)
{
  py::list choices;
  for (const auto& c : entry.choices)
    choices.append(c.first);
  py::dict d;
  d["name"] = entry.name;
  d["type"] = typeName(entry);
  d["unit"] = entry.unit;
  d["default"] = fieldValue(entry, FilterParameters::recommended());
  d["paper"] = fieldValue(entry, FilterParameters::paper());
  d["choices"] = choices;
  d["requirement"] = entry.range.requirement ? py::object(py::str(entry.range.requirement)) : py::none();
  d["zero_means"] = entry.zero_means ? py::object(py::str(entry.zero_means)) : py::none();
  d["help"] = entry.help;
  d["cli_option"] = entry.cli_option ? py::object(py::str(std::string("--") + entry.cli_option)) : py::none();
  d["doc"] = fieldDoc(entry);
  return d;
}

py::dict
asDict(const FilterParameters& p)
{
  py::dict d;
  for (const ParameterEntry& entry : parameterRegistry())
    d[entry.name] = fieldValue(entry, p);
  return d;
}

bool
sameParameters(const FilterParameters& a, const FilterParameters& b)
{
  for (const ParameterEntry& entry : parameterRegistry())
    if (parameterText(entry, a) != parameterText(entry, b))
      return false;
  return true;
}

} // namespace

FilterParameters
parametersOf(const py::handle& parameters)
{
  if (parameters.is_none())
    return FilterParameters::recommended();
  if (py::isinstance<py::str>(parameters))
    return FilterParameters::preset(parameters.cast<std::string>());
  if (!py::isinstance<FilterParameters>(parameters))
    throw py::type_error("range_nlm: parameters must be a range_nlm.Parameters, a preset name ('default', 'live' or "
                         "'paper') or None, got " +
                         py::str(parameters.get_type().attr("__name__")).cast<std::string>());
  return parameters.cast<FilterParameters>();
}

void
bindParameters(py::module_& m)
{
  py::class_<FilterParameters> cls(m, "Parameters",
                                   "The filter's parameters, one attribute per entry of the parameter registry "
                                   "(the options of range_nlm_denoise). Parameters(**kw) is the recommended "
                                   "setting with the keywords applied; a bad value raises ValueError naming it.");
  cls.def(py::init([](const py::kwargs& kw) {
            FilterParameters p = FilterParameters::recommended();
            applyKeywords(p, kw);
            return p;
          }))
      .def_static("recommended", &FilterParameters::recommended, "The project's recommended setting (the default).")
      .def_static("paper", &FilterParameters::paper, "The literal method of the paper.")
      .def_static("live", &FilterParameters::live, "The setting for a live camera's frame rate.")
      .def_static("preset", &FilterParameters::preset, py::arg("name"), "'default', 'live' or 'paper'.")
      .def(
          "replace",
          [](const FilterParameters& p, const py::kwargs& kw) {
            FilterParameters copy = p;
            applyKeywords(copy, kw);
            return copy;
          },
          "A copy with the keywords applied.")
      .def("validate", [](const FilterParameters& p) { p.validate(); })
      .def("as_dict", &asDict, "{name: value} for every parameter.")
      .def("__eq__", [](const FilterParameters& a, const FilterParameters& b) { return sameParameters(a, b); })
      .def("__copy__", [](const FilterParameters& p) { return p; })
      .def("__deepcopy__", [](const FilterParameters& p, const py::dict&) { return p; })
      .def("__repr__",
           [](const FilterParameters& p) {
             std::string text = "range_nlm.Parameters(";
             bool first = true;
             for (const ParameterEntry& entry : parameterRegistry()) {
               text += (first ? "" : ", ") + std::string(entry.name) + "=" +
                       py::repr(fieldValue(entry, p)).cast<std::string>();
               first = false;
             }
             return text + ")";
           })
      .def_static(
          "registry",
          [] {
            py::list entries;
            for (const ParameterEntry& entry : parameterRegistry())
              entries.append(registryEntry(entry));
            return entries;
          },
          "Every parameter as a dict: name, type, unit, default, paper, choices, requirement, zero_means, help, "
          "cli_option, doc.");
  cls.attr("__hash__") = py::none();
  for (const ParameterEntry& entry : parameterRegistry())
    cls.def_property(
        entry.name, [&entry](const FilterParameters& p) { return fieldValue(entry, p); },
        [&entry](FilterParameters& p, const py::object& value) {
          FilterParameters changed = p; // a refused value leaves the object as it was
          setField(entry, changed, value);
          p = changed;
        },
        fieldDoc(entry).c_str());
  m.def(
      "parameters_from",
      [](const py::object& parameters, const py::kwargs& kw) {
        FilterParameters p = parametersOf(parameters);
        applyKeywords(p, kw);
        return p;
      },
      py::arg("parameters") = py::none(),
      "Parameters from a Parameters object, a preset name or None (recommended), with the keywords applied.");
}

} // namespace python
} // namespace range_nlm
