// The tuned numbers of the default: one table in the code (src/core/tuned.h), mirrored row by row
// in docs/method.md's "Tuned numbers" section, so the docs cannot drift from the code.
#include "core/tuned.h"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <vector>

namespace
{

using range_nlm::tuned::kTunedNumberCount;
using range_nlm::tuned::kTunedNumbers;

/// A row of the docs table: | `kName` | value | fitted on | why |
struct DocRow
{
  std::string value, fitted_on;
};

std::string
trim(const std::string& s)
{
  const auto a = s.find_first_not_of(" \t`");
  const auto b = s.find_last_not_of(" \t`");
  return a == std::string::npos ? std::string() : s.substr(a, b - a + 1);
}

/// The rows of the table under "## Tuned numbers" in docs/method.md, by name.
std::map<std::string, DocRow>
docsTable()
{
  std::ifstream in(std::string(RANGE_NLM_SOURCE_DIR) + "/docs/method.md");
  EXPECT_TRUE(in.good()) << "docs/method.md not found under " << RANGE_NLM_SOURCE_DIR;
  std::map<std::string, DocRow> rows;
  std::string line;
  bool in_section = false;
  while (std::getline(in, line)) {
    if (line.rfind("## ", 0) == 0)
      in_section = line == "## Tuned numbers";
    if (!in_section || line.rfind("| `k", 0) != 0)
      continue;
    std::vector<std::string> cells;
    std::stringstream row(line.substr(1));
    std::string cell;
    while (std::getline(row, cell, '|'))
      cells.push_back(trim(cell));
    if (cells.size() >= 3)
      rows[cells[0]] = DocRow{cells[1], cells[2]};
  }
  return rows;
}

TEST(TunedNumbers, EveryRowHasANameAValueWhereItWasFittedAndWhy)
{
  ASSERT_GT(kTunedNumberCount, 0u);
  std::set<std::string> names;
  for (std::size_t i = 0; i < kTunedNumberCount; ++i) {
    const auto& row = kTunedNumbers[i];
    SCOPED_TRACE(row.name);
    EXPECT_TRUE(names.insert(row.name).second) << "listed twice";
    EXPECT_EQ(row.name[0], 'k');
    EXPECT_TRUE(std::isfinite(row.value));
    const std::string fitted = row.fitted_on;
    EXPECT_TRUE(fitted == "generated" || fitted == "real" || fitted == "derived" || fitted == "generated and real")
        << "fitted_on '" << fitted << "'";
    EXPECT_GT(std::string(row.why).size(), 10u) << "give one line of why";
  }
}

TEST(TunedNumbers, DocsMirrorTheTable)
{
  const auto docs = docsTable();
  for (std::size_t i = 0; i < kTunedNumberCount; ++i) {
    const auto& row = kTunedNumbers[i];
    SCOPED_TRACE(row.name);
    const auto it = docs.find(row.name);
    ASSERT_NE(it, docs.end()) << "docs/method.md, 'Tuned numbers', has no row for " << row.name;
    // The table holds float, int and double numbers; float precision compares them all.
    EXPECT_FLOAT_EQ(static_cast<float>(std::stod(it->second.value)), static_cast<float>(row.value))
        << "docs say " << it->second.value;
    EXPECT_EQ(it->second.fitted_on, row.fitted_on);
  }
  for (const auto& [name, doc] : docs) {
    bool found = false;
    for (std::size_t i = 0; i < kTunedNumberCount && !found; ++i)
      found = name == kTunedNumbers[i].name;
    EXPECT_TRUE(found) << "docs/method.md lists " << name << ", which src/core/tuned.h does not";
  }
}

} // namespace
