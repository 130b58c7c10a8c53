// The parameter sets of range_nlm_bench --quality (rangeNlmVariants): the rows that stand for the
// default are the default.
#include "quality_comparison.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <string>
#include <utility>
#include <vector>

using namespace range_nlm;

namespace
{
/// Every field of FilterParameters, one by one.
void
expectSameParameters(const FilterParameters& a, const FilterParameters& b, const std::string& row)
{
  SCOPED_TRACE(row);
  EXPECT_EQ(a.search_window, b.search_window);
  EXPECT_EQ(a.patch_size, b.patch_size);
  EXPECT_EQ(a.dilation, b.dilation);
  EXPECT_EQ(a.iterations, b.iterations);
  EXPECT_EQ(a.threads, b.threads);
  EXPECT_EQ(a.distance_bandwidth, b.distance_bandwidth);
  EXPECT_EQ(a.similarity_bandwidth, b.similarity_bandwidth);
  EXPECT_EQ(a.distance_scale, b.distance_scale);
  EXPECT_EQ(a.similarity_scale, b.similarity_scale);
  EXPECT_EQ(a.seed, b.seed);
  EXPECT_EQ(a.bandwidth_samples, b.bandwidth_samples);
  EXPECT_EQ(a.normal_window, b.normal_window);
  EXPECT_EQ(a.normal_presmooth_window, b.normal_presmooth_window);
  EXPECT_EQ(a.normal_presmooth_range, b.normal_presmooth_range);
  EXPECT_EQ(a.normal_edge_gate, b.normal_edge_gate);
  EXPECT_EQ(a.patch_edge_gate, b.patch_edge_gate);
  EXPECT_EQ(a.line_of_sight_min_cos, b.line_of_sight_min_cos);
  EXPECT_EQ(a.bandwidth_model, b.bandwidth_model);
  EXPECT_EQ(a.max_displacement, b.max_displacement);
  EXPECT_EQ(a.outlier_sigmas, b.outlier_sigmas);
  EXPECT_EQ(a.displacement, b.displacement);
  EXPECT_EQ(a.cross_frame_bandwidth, b.cross_frame_bandwidth);
  EXPECT_EQ(a.patch_guide, b.patch_guide);
  EXPECT_EQ(a.evaluation, b.evaluation);
  EXPECT_EQ(a.uncertainty, b.uncertainty);
}

bool
endsWith(const std::string& s, const std::string& tail)
{
  return s.size() >= tail.size() && s.compare(s.size() - tail.size(), tail.size(), tail) == 0;
}
} // namespace

// The table's "default" row and the last row of the levers ("... (= default)") are
// FilterParameters::recommended(), field by field.
TEST(QualityComparison, TheDefaultRowsAreTheRecommendedSetting)
{
  const FilterParameters recommended = FilterParameters::recommended();
  const std::vector<std::pair<std::string, FilterParameters>> rows = tools::quality::rangeNlmVariants(true);
  int defaults = 0;
  for (const auto& [name, parameters] : rows)
    if (name == "default" || endsWith(name, "(= default)")) {
      expectSameParameters(parameters, recommended, name);
      ++defaults;
    }
  EXPECT_EQ(defaults, 2);
  // Without the levers the default row leads.
  const std::vector<std::pair<std::string, FilterParameters>> short_rows = tools::quality::rangeNlmVariants(false);
  ASSERT_FALSE(short_rows.empty());
  EXPECT_EQ(short_rows.front().first, "default");
  expectSameParameters(short_rows.front().second, recommended, "default");
}

// The paper row, where the levers start, is FilterParameters::paper().
TEST(QualityComparison, ThePaperRowIsThePaperPreset)
{
  const std::vector<std::pair<std::string, FilterParameters>> rows = tools::quality::rangeNlmVariants(true);
  const auto paper = std::find_if(rows.begin(), rows.end(),
                                  [](const auto& row) { return row.first.rfind("preset paper", 0) == 0; });
  ASSERT_NE(paper, rows.end());
  expectSameParameters(paper->second, FilterParameters::paper(), paper->first);
}
