// range_nlm_bench --generalisation: the settings it scores are read through the parameter
// registry, and its quick table has a row for every cell, "(wins)" marks that agree with the
// summary, and summary ratios that are those of the rows.
#include "generalisation_comparison.h"
#include "test_support.h"

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

using namespace range_nlm;
namespace generalisation = range_nlm::tools::generalisation;

namespace
{

/// The cells of a Markdown table row, trimmed ("| a | b |" gives {"a", "b"}).
std::vector<std::string>
cellsOf(const std::string& line)
{
  std::vector<std::string> cells;
  std::istringstream in(line.substr(1));
  std::string cell;
  while (std::getline(in, cell, '|')) {
    const std::size_t a = cell.find_first_not_of(' '), b = cell.find_last_not_of(' ');
    cells.push_back(a == std::string::npos ? "" : cell.substr(a, b - a + 1));
  }
  return cells;
}

/// "flat / feature[ ...]" as two millimetre figures.
std::pair<double, double>
rmseOf(const std::string& cell)
{
  std::istringstream in(cell);
  double flat = 0.0, feature = 0.0;
  std::string slash;
  in >> flat >> slash >> feature;
  EXPECT_TRUE(in && slash == "/") << cell;
  return {flat, feature};
}

struct Tally
{
  int won = 0, cells = 0;
  double log_flat = 0.0, log_feature = 0.0;
};

std::string
errorOf(const std::string& spec)
{
  try {
    generalisation::settingFromText(spec);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

} // namespace

TEST(GeneralisationComparison, SettingsAreFieldsOfTheRegistryOnTopOfTheDefault)
{
  const generalisation::Setting s = generalisation::settingFromText("iterations=3,patch_edge_gate=0");
  EXPECT_EQ(s.name, "iterations=3,patch_edge_gate=0");
  EXPECT_EQ(s.parameters.iterations, 3);
  EXPECT_EQ(s.parameters.patch_edge_gate, 0.0f);
  const FilterParameters recommended = FilterParameters::recommended();
  EXPECT_EQ(s.parameters.search_window, recommended.search_window);
  EXPECT_EQ(s.parameters.dilation, recommended.dilation);
  EXPECT_NE(errorOf("no_such_field=1").find("'no_such_field=1'"), std::string::npos) << errorOf("no_such_field=1");
  EXPECT_NE(errorOf("iterations=3,iterations").find("'iterations'"), std::string::npos);
  EXPECT_NE(errorOf("iterations=three").find("iterations"), std::string::npos);
  EXPECT_NE(errorOf("iterations=0").find("iterations = 0"), std::string::npos) << errorOf("iterations=0");
  EXPECT_NE(errorOf("").find("NAME=VALUE"), std::string::npos);
}

TEST(GeneralisationComparison, ToolRefusesABadSettingByName)
{
  const test::CommandResult r =
      test::runTool("range_nlm_bench", "--generalisation --generalisation-setting iterations=3,bogus=2 -q");
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_NE(r.output.find("--generalisation-setting 'bogus=2'"), std::string::npos) << r.output;
}

// The quick table at a small size: one row per scene and correlation length at noise scale 1,
// each with the noisy frame, both range_nlm settings, FastBilateral's best-balanced setting and
// no MLS; the filter lowers the flat RMSE of the noisy frame; the summary counts the rows'
// "(wins)" and gives the geometric means of the rows' ratios to FastBilateral.
TEST(GeneralisationComparison, QuickTableHasEveryCellAndASummaryOfItsRows)
{
  const test::CommandResult r =
      test::runTool("range_nlm_bench", "--generalisation --generalisation-quick --quality-size 128x96 "
                                       "--generalisation-setting iterations=3 --threads 2 -q");
  ASSERT_EQ(r.status, 0) << r.output;
  const std::vector<std::string> settings{"default", "iterations=3"};
  std::map<std::string, int> rows; // "scene L" -> rows seen
  std::map<std::string, Tally> tally, summary;
  std::istringstream lines(r.output);
  for (std::string line; std::getline(lines, line);) {
    if (line.rfind("| boxes |", 0) == 0 || line.rfind("| steps |", 0) == 0 || line.rfind("| ridges |", 0) == 0) {
      const std::vector<std::string> c = cellsOf(line);
      ASSERT_EQ(c.size(), 8u) << line; // scene, scale, length, noisy, 2 settings, FastBilateral, MLS
      EXPECT_EQ(c[1], "1.0") << line;
      ++rows[c[0] + " " + c[2]];
      const auto noisy = rmseOf(c[3]);
      const auto fb = rmseOf(c[6]);
      EXPECT_NE(c[6].find("(sigma_s "), std::string::npos) << line;
      EXPECT_EQ(c[7], "-") << line;
      for (std::size_t k = 0; k < settings.size(); ++k) {
        const auto ours = rmseOf(c[4 + k]);
        EXPECT_LT(ours.first, noisy.first) << line;
        const bool marked = c[4 + k].find("(wins)") != std::string::npos;
        EXPECT_EQ(marked, ours.first <= fb.first && ours.second <= fb.second) << line;
        Tally& t = tally[settings[k]];
        t.won += marked ? 1 : 0;
        t.cells += 1;
        t.log_flat += std::log(ours.first / fb.first);
        t.log_feature += std::log(ours.second / fb.second);
      }
    } else if (line.rfind("| default |", 0) == 0 || line.rfind("| iterations=3 |", 0) == 0) {
      const std::vector<std::string> c = cellsOf(line);
      ASSERT_EQ(c.size(), 4u) << line;
      Tally& t = summary[c[0]];
      ASSERT_EQ(std::sscanf(c[1].c_str(), "%d of %d", &t.won, &t.cells), 2) << line;
      t.log_flat = std::log(std::stod(c[2]));
      t.log_feature = std::log(std::stod(c[3]));
    }
  }
  for (const std::string scene : {"boxes", "steps", "ridges"})
    for (const std::string length : {"0", "2", "4", "8"})
      EXPECT_EQ(rows[scene + " " + length], 1) << scene << " L " << length << "\n" << r.output;
  EXPECT_EQ(rows.size(), 12u) << r.output;
  for (const std::string& setting : settings) {
    SCOPED_TRACE(setting);
    ASSERT_EQ(summary.count(setting), 1u) << r.output;
    EXPECT_EQ(summary[setting].cells, 12);
    EXPECT_EQ(summary[setting].won, tally[setting].won);
    // The table's RMSEs are rounded to 0.01 mm: the ratios agree to about 1 %.
    EXPECT_NEAR(summary[setting].log_flat, tally[setting].log_flat / 12, 0.02);
    EXPECT_NEAR(summary[setting].log_feature, tally[setting].log_feature / 12, 0.02);
  }
  EXPECT_NE(r.output.find("12 cells in "), std::string::npos) << r.output;
}

// --generalisation-scenes runs some of the scenes; each keeps its seed, so its rows are the full
// run's to the digit. An unknown scene is refused by name.
TEST(GeneralisationComparison, ASceneRunAloneScoresTheSameCells)
{
  const std::string common = "--generalisation --generalisation-quick --quality-size 96x72 --threads 2 -q";
  const test::CommandResult all = test::runTool("range_nlm_bench", common);
  const test::CommandResult one = test::runTool("range_nlm_bench", common + " --generalisation-scenes ridges");
  ASSERT_EQ(all.status, 0) << all.output;
  ASSERT_EQ(one.status, 0) << one.output;
  auto rowsOf = [](const std::string& output, const std::string& prefix) {
    std::vector<std::string> rows;
    std::istringstream lines(output);
    for (std::string line; std::getline(lines, line);)
      if (line.rfind(prefix, 0) == 0)
        rows.push_back(line);
    return rows;
  };
  EXPECT_EQ(rowsOf(one.output, "| ridges |").size(), 4u) << one.output;
  EXPECT_EQ(rowsOf(one.output, "| ridges |"), rowsOf(all.output, "| ridges |"));
  EXPECT_TRUE(rowsOf(one.output, "| boxes |").empty()) << one.output;
  const test::CommandResult bad = test::runTool("range_nlm_bench", common + " --generalisation-scenes boxes,stairs");
  EXPECT_EQ(bad.status, 2) << bad.output;
  EXPECT_NE(bad.output.find("unknown scene 'stairs'"), std::string::npos) << bad.output;
}
