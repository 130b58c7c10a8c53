#include "cli/passes.h"

#include "cli/cli.h"

#include <range_nlm/parameter_registry.h>

#include <set>
#include <sstream>
#include <stdexcept>

namespace range_nlm
{
namespace tools
{
namespace
{
const ParameterEntry*
findPassKey(const std::string& key)
{
  for (const ParameterEntry& entry : parameterRegistry())
    if (entry.pass_key && key == entry.pass_key)
      return &entry;
  return nullptr;
}

int
parseRadius(const std::string& spec, const std::string& value)
{
  try {
    std::size_t used = 0;
    const int radius = std::stoi(value, &used);
    if (used == value.size())
      return radius;
  } catch (const std::exception&) {
  }
  throw UsageError("--pass '" + spec + "': 'radius' needs an integer, got '" + value + "'");
}
} // namespace

std::vector<PassReach>
reachOf(const std::vector<Pass>& passes)
{
  std::vector<PassReach> reach;
  for (const Pass& pass : passes)
    reach.push_back(pass.reach());
  return reach;
}

std::string
passKeys()
{
  std::string keys = "radius";
  for (const ParameterEntry& entry : parameterRegistry())
    if (entry.pass_key)
      keys += std::string(", ") + entry.pass_key;
  return keys;
}

Pass
parsePass(const std::string& spec, const Pass& base)
{
  Pass pass = base;
  std::stringstream ss(spec);
  std::string item;
  std::set<std::string> keys;
  while (std::getline(ss, item, ',')) {
    const auto eq = item.find('=');
    if (eq == std::string::npos)
      throw UsageError("--pass '" + spec + "': expected key=value items, got '" + item + "'");
    const std::string key = item.substr(0, eq), value = item.substr(eq + 1);
    if (!keys.insert(key).second) // which of the two was meant is a guess
      throw UsageError("--pass '" + spec + "': '" + key + "' is given twice; give it once");
    if (key == "radius") {
      pass.radius = parseRadius(spec, value);
      continue;
    }
    const ParameterEntry* entry = findPassKey(key);
    if (!entry)
      throw UsageError("--pass '" + spec + "': unknown key '" + key + "' (expected " + passKeys() + ")");
    try {
      setParameterFromText(*entry, pass.parameters, value);
    } catch (const std::invalid_argument& expected) {
      throw UsageError("--pass '" + spec + "': '" + key + "' needs " + expected.what() + ", got '" + value + "'");
    }
  }
  try {
    pass.parameters.validate();
  } catch (const std::invalid_argument& e) {
    throw UsageError("--pass '" + spec + "': " + e.what());
  }
  if (pass.radius < 0)
    throw UsageError("--pass '" + spec + "': radius must be >= 0");
  return pass;
}

} // namespace tools
} // namespace range_nlm
