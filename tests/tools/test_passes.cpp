// --pass schedules (tools/cli/passes.cpp): every parameter with a pass key reaches the pass's
// FilterParameters, the existing keys keep working, bad items are refused naming them.
#include "cli/cli.h"
#include "cli/passes.h"
#include "parameter_values.h"

#include <range_nlm/parameter_registry.h>

#include <gtest/gtest.h>

#include <string>

using namespace range_nlm;
using namespace range_nlm::tools;

namespace
{
std::string
refusal(const std::string& spec)
{
  try {
    parsePass(spec, Pass{});
  } catch (const UsageError& e) {
    return e.what();
  }
  return "";
}
} // namespace

TEST(Passes, EveryPassKeyReachesThePassParameters)
{
  Pass base;
  base.radius = 1;
  base.causal = true;
  int keys = 0;
  for (const ParameterEntry& entry : parameterRegistry()) {
    if (!entry.pass_key)
      continue;
    ++keys;
    const FilterParameters other = test::withOtherValue(entry, base.parameters);
    const std::string spec = std::string(entry.pass_key) + "=" + parameterText(entry, other);
    const Pass pass = parsePass(spec, base);
    EXPECT_TRUE(test::sameField(entry, pass.parameters, other)) << spec;
    EXPECT_TRUE(test::sameOtherFields(entry, pass.parameters, base.parameters)) << spec;
    EXPECT_EQ(pass.radius, 1) << spec;
    EXPECT_EQ(pass.window(), TemporalWindow::causal) << spec;
  }
  EXPECT_GE(keys, 4);
}

TEST(Passes, ExistingKeysKeepWorking)
{
  Pass base;
  base.parameters = FilterParameters::paper();
  const Pass pass = parsePass("search=5,patch=3,radius=2,iterations=3,normal=5", base);
  EXPECT_EQ(pass.parameters.search_window, 5);
  EXPECT_EQ(pass.parameters.patch_size, 3);
  EXPECT_EQ(pass.radius, 2);
  EXPECT_EQ(pass.parameters.iterations, 3);
  EXPECT_EQ(pass.parameters.normal_window, 5);
  EXPECT_EQ(pass.parameters.bandwidth_model, BandwidthModel::global); // the base's, untouched
  base.recursive = true;
  const std::vector<PassReach> reach = reachOf({parsePass("radius=0", Pass{}), parsePass("radius=3", base)});
  ASSERT_EQ(reach.size(), 2u);
  EXPECT_EQ(reach[0].radius, 0);
  EXPECT_EQ(reach[0].window, TemporalWindow::centred);
  EXPECT_EQ(reach[1].radius, 3);
  EXPECT_EQ(reach[1].window, TemporalWindow::recursive);
}

TEST(Passes, BadItemsAreRefusedNamingThem)
{
  EXPECT_NE(refusal("search=9,patch=4").find("--pass 'search=9,patch=4': range_nlm: parameter patch_size = 4"),
            std::string::npos);
  EXPECT_EQ(refusal("search=x"), "--pass 'search=x': 'search' needs an integer, got 'x'");
  EXPECT_EQ(refusal("radius=1.5"), "--pass 'radius=1.5': 'radius' needs an integer, got '1.5'");
  EXPECT_EQ(refusal("outlier_sigmas=lots"), "--pass 'outlier_sigmas=lots': 'outlier_sigmas' needs a number, got 'lots'");
  EXPECT_EQ(refusal("cross_frame_bandwidth=always"),
            "--pass 'cross_frame_bandwidth=always': 'cross_frame_bandwidth' needs 'guarded', 'temporal' or "
            "'spatial', got 'always'");
  EXPECT_NE(refusal("outlier_sigmas=-1").find("outlier_sigmas = -1"), std::string::npos);
  EXPECT_EQ(refusal("radius=-1"), "--pass 'radius=-1': radius must be >= 0");
  EXPECT_EQ(refusal("search"), "--pass 'search': expected key=value items, got 'search'");
  const std::string unknown = refusal("window=5");
  EXPECT_EQ(unknown.rfind("--pass 'window=5': unknown key 'window' (expected radius, search, patch, ", 0), 0u)
      << unknown;
}
