// The filter options of the tools (tools/cli/cli.cpp): every parameter of the registry reaches
// FilterParameters through its option or flags, the existing options keep their names, and a bad
// value is refused naming the parameter.
#include "cli/cli.h"
#include "parameter_values.h"

#include <range_nlm/parameter_registry.h>

#include <gtest/gtest.h>

#include <sstream>
#include <string>
#include <vector>

using namespace range_nlm;
using namespace range_nlm::tools;
namespace po = boost::program_options;

namespace
{
/// FilterParameters from a command line of filter options.
FilterParameters
parse(std::vector<std::string> args)
{
  po::options_description options;
  addFilterOptions(options);
  std::vector<const char*> argv{"range_nlm_test"};
  for (const std::string& a : args)
    argv.push_back(a.c_str());
  po::variables_map vm;
  po::store(po::command_line_parser(int(argv.size()), argv.data()).options(options).run(), vm);
  po::notify(vm);
  return filterParametersFrom(vm);
}

/// The UsageError of a command line ("" if none).
std::string
refusal(const std::vector<std::string>& args)
{
  try {
    parse(args);
  } catch (const UsageError& e) {
    return e.what();
  }
  return "";
}
} // namespace

TEST(CliFilterOptions, EveryParameterReachesTheFilterParameters)
{
  const FilterParameters base = FilterParameters::recommended();
  for (const ParameterEntry& entry : parameterRegistry()) {
    if (entry.cli_option) {
      const FilterParameters other = test::withOtherValue(entry, base);
      const std::string value = parameterText(entry, other);
      const FilterParameters p = parse({"--" + std::string(entry.cli_option), value});
      EXPECT_TRUE(test::sameField(entry, p, other)) << "--" << entry.cli_option << " " << value;
      EXPECT_TRUE(test::sameOtherFields(entry, p, base)) << "--" << entry.cli_option << " " << value;
    }
    for (const ParameterSwitch& flag : entry.cli_switches) {
      FilterParameters expected = base;
      setChoice(entry, expected, flag.on);
      const FilterParameters p = parse({"--" + std::string(flag.name)});
      EXPECT_TRUE(test::sameField(entry, p, expected)) << "--" << flag.name;
      EXPECT_TRUE(test::sameOtherFields(entry, p, base)) << "--" << flag.name;
    }
  }
}

TEST(CliFilterOptions, ExistingOptionsKeepTheirNamesAndMeaning)
{
  const FilterParameters p =
      parse({"--search-window", "11", "--patch", "5", "--iterations", "3", "--threads", "2", "--distance-bandwidth",
             "0.25", "--similarity-bandwidth", "0.5", "--seed", "7", "--normal-window", "5", "--dilation", "2",
             "--cross-frame", "temporal", "--outlier-sigmas", "2.5", "--patch-gate", "4", "--direct",
             "--line-of-sight"});
  EXPECT_EQ(p.search_window, 11);
  EXPECT_EQ(p.patch_size, 5);
  EXPECT_EQ(p.iterations, 3);
  EXPECT_EQ(p.threads, 2);
  EXPECT_EQ(p.distance_bandwidth, 0.25f);
  EXPECT_EQ(p.similarity_bandwidth, 0.5f);
  EXPECT_EQ(p.seed, 7u);
  EXPECT_EQ(p.normal_window, 5);
  EXPECT_EQ(p.dilation, 2);
  EXPECT_EQ(p.cross_frame_bandwidth, CrossFrameBandwidth::temporal);
  EXPECT_EQ(p.outlier_sigmas, 2.5f);
  EXPECT_EQ(p.patch_edge_gate, 4.0f);
  EXPECT_EQ(p.evaluation, Evaluation::direct);
  EXPECT_EQ(p.displacement, Displacement::line_of_sight);
  EXPECT_EQ(parse({"--along-normal"}).displacement, Displacement::normal);
  // The preset, then the options given over it; without options each preset exactly.
  const FilterParameters paper = parse({"--preset", "paper", "--patch", "3"});
  EXPECT_EQ(paper.patch_size, 3);
  EXPECT_EQ(paper.search_window, 7);
  EXPECT_EQ(paper.bandwidth_model, BandwidthModel::global);
  for (const ParameterEntry& entry : parameterRegistry()) {
    EXPECT_TRUE(test::sameField(entry, parse({}), FilterParameters::recommended())) << entry.name;
    EXPECT_TRUE(test::sameField(entry, parse({"--preset", "paper"}), FilterParameters::paper())) << entry.name;
  }
}

TEST(CliFilterOptions, BadValuesAreRefusedNamingTheParameter)
{
  EXPECT_NE(refusal({"--search-window", "6"}).find("search_window = 6"), std::string::npos);
  EXPECT_NE(refusal({"--patch-gate", "-2"}).find("patch_edge_gate = -2"), std::string::npos);
  EXPECT_NE(refusal({"--normal-presmooth-window", "4"}).find("normal_presmooth_window = 4"), std::string::npos);
  EXPECT_NE(refusal({"--line-of-sight-min-cos", "1.5"}).find("line_of_sight_min_cos = 1.5"), std::string::npos);
  EXPECT_EQ(refusal({"--cross-frame", "always"}),
            "--cross-frame 'always' is invalid: expected 'guarded', 'temporal' or 'spatial'");
  EXPECT_NE(refusal({"--bandwidth-model", "local"}).find("--bandwidth-model 'local' is invalid"), std::string::npos);
  EXPECT_EQ(refusal({"--line-of-sight", "--along-normal"}),
            "--line-of-sight and --along-normal contradict each other: give one");
  EXPECT_NE(refusal({"--distance-bandwidth", "0"}).find("--distance-bandwidth 0: a bandwidth given on the command line "
                                                        "must be a positive number"),
            std::string::npos);
  EXPECT_NE(refusal({"--preset", "fancy"}).find("unknown preset 'fancy'"), std::string::npos);
  EXPECT_THROW(parse({"--patch", "3.5"}), po::error);
}

TEST(CliFilterOptions, HelpShowsThePresetsValues)
{
  po::options_description options;
  addFilterOptions(options);
  std::ostringstream help;
  help << options;
  EXPECT_NE(help.str().find("[default: 9; live: 9; paper: 7]"), std::string::npos) << help.str();
  EXPECT_NE(help.str().find("'live'"), std::string::npos) << help.str();
  EXPECT_NE(help.str().find("(=42)"), std::string::npos) << help.str();
  EXPECT_NE(help.str().find("--patch-guide"), std::string::npos) << help.str();
}
