#include <range_nlm/parameters.h>

#include <gtest/gtest.h>

#include <limits>
#include <stdexcept>
#include <string>

using range_nlm::FilterParameters;

namespace
{
std::string
messageOf(const FilterParameters& p, int w = 0, int h = 0)
{
  try {
    if (w > 0)
      p.validateFor(w, h);
    else
      p.validate();
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}
} // namespace

TEST(Parameters, DefaultsAreValidAndDocumentedValues)
{
  const FilterParameters p;
  EXPECT_EQ(p.search_window, 9);
  EXPECT_EQ(p.patch_size, 3);
  EXPECT_EQ(p.iterations, 2);
  EXPECT_EQ(p.normal_window, 7);
  EXPECT_EQ(p.bandwidth_model, range_nlm::BandwidthModel::range_adaptive);
  EXPECT_EQ(p.displacement, range_nlm::Displacement::automatic);
  EXPECT_EQ(p.distance_bandwidth, FilterParameters::automatic);
  EXPECT_EQ(p.similarity_bandwidth, FilterParameters::automatic);
  const FilterParameters paper = FilterParameters::paper();
  EXPECT_EQ(paper.search_window, 7);
  EXPECT_EQ(paper.patch_size, 5);
  EXPECT_EQ(paper.iterations, 1);
  EXPECT_EQ(paper.normal_window, 3);
  EXPECT_EQ(paper.distance_scale, 0.75f);
  EXPECT_EQ(paper.similarity_scale, 1.0f);
  EXPECT_EQ(paper.bandwidth_model, range_nlm::BandwidthModel::global);
  EXPECT_EQ(paper.outlier_sigmas, 0.0f);
  EXPECT_EQ(paper.patch_edge_gate, 0.0f);
  EXPECT_EQ(p.patch_edge_gate, 18.0f);
  EXPECT_NO_THROW(p.validate());
  EXPECT_NO_THROW(FilterParameters::recommended().validate());
  EXPECT_NO_THROW(FilterParameters::paper().validate());
}

TEST(Parameters, EvenOrNonPositiveWindowsAreRejectedByName)
{
  FilterParameters p;
  p.search_window = 6;
  EXPECT_NE(messageOf(p).find("search_window = 6"), std::string::npos);
  p = FilterParameters();
  p.patch_size = 0;
  EXPECT_NE(messageOf(p).find("patch_size = 0"), std::string::npos);
  p = FilterParameters();
  p.patch_size = -3;
  EXPECT_NE(messageOf(p).find("patch_size = -3"), std::string::npos);
  p = FilterParameters();
  p.normal_window = 4;
  EXPECT_NE(messageOf(p).find("normal_window = 4"), std::string::npos);
}

TEST(Parameters, OtherInvalidValuesAreRejectedByName)
{
  FilterParameters p;
  p.iterations = 0;
  EXPECT_NE(messageOf(p).find("iterations"), std::string::npos);
  p = FilterParameters();
  p.threads = -1;
  EXPECT_NE(messageOf(p).find("threads"), std::string::npos);
  p = FilterParameters();
  p.distance_bandwidth = -0.5f;
  EXPECT_NE(messageOf(p).find("distance_bandwidth"), std::string::npos);
  p = FilterParameters();
  p.similarity_bandwidth = std::numeric_limits<float>::quiet_NaN();
  EXPECT_NE(messageOf(p).find("similarity_bandwidth"), std::string::npos);
  p = FilterParameters();
  p.normal_edge_gate = -1.0f;
  EXPECT_NE(messageOf(p).find("normal_edge_gate"), std::string::npos);
  p = FilterParameters();
  p.patch_edge_gate = -1.0f;
  EXPECT_NE(messageOf(p).find("patch_edge_gate"), std::string::npos);
  p = FilterParameters();
  p.patch_edge_gate = std::numeric_limits<float>::infinity();
  EXPECT_NE(messageOf(p).find("patch_edge_gate"), std::string::npos);
  p = FilterParameters();
  p.line_of_sight_min_cos = 1.5f;
  EXPECT_NE(messageOf(p).find("line_of_sight_min_cos"), std::string::npos);
  p = FilterParameters();
  p.max_displacement = -2.0f;
  EXPECT_NE(messageOf(p).find("max_displacement"), std::string::npos);
  p = FilterParameters();
  p.outlier_sigmas = -1.0f;
  EXPECT_NE(messageOf(p).find("outlier_sigmas"), std::string::npos);
  p.outlier_sigmas = std::numeric_limits<float>::infinity();
  EXPECT_NE(messageOf(p).find("outlier_sigmas"), std::string::npos);
  p = FilterParameters();
  p.bandwidth_samples = 0;
  EXPECT_NE(messageOf(p).find("bandwidth_samples"), std::string::npos);
}

TEST(Parameters, WindowLargerThanCloudIsRejected)
{
  FilterParameters p;
  p.search_window = 9;
  EXPECT_NE(messageOf(p, 8, 20).find("larger than the cloud (8 x 20)"), std::string::npos);
  EXPECT_EQ(messageOf(p, 9, 9), "");
}

// The other frames' search window: 0 (the search window) or odd; live searches a stream's history
// over 3 x 3.
TEST(Parameters, TemporalSearchWindowIsOddOrZero)
{
  FilterParameters p;
  EXPECT_EQ(p.temporal_search_window, 0);
  EXPECT_EQ(FilterParameters::live().temporal_search_window, 3);
  for (int good : {0, 1, 3, 9, 11}) {
    p.temporal_search_window = good;
    EXPECT_EQ(messageOf(p), "") << good;
  }
  p.temporal_search_window = 4;
  EXPECT_NE(messageOf(p).find("temporal_search_window = 4"), std::string::npos) << messageOf(p);
  p.temporal_search_window = -1;
  EXPECT_NE(messageOf(p).find("temporal_search_window = -1"), std::string::npos) << messageOf(p);
}

TEST(Parameters, Presets)
{
  EXPECT_EQ(FilterParameters::preset("paper").normal_window, 3);
  EXPECT_EQ(FilterParameters::preset("paper").normal_presmooth_window, 0);
  EXPECT_THROW(FilterParameters::preset("fancy"), std::invalid_argument);
}

// More threads than any machine offers (OpenMP would try to create them all and crash) is refused
// by name and value; the largest accepted count and 0 (= all cores) are valid.
TEST(Parameters, ThreadCountAboveTheMaximumIsRejected)
{
  FilterParameters p;
  p.threads = 100000;
  EXPECT_NE(messageOf(p).find("threads = 100000"), std::string::npos) << messageOf(p);
  EXPECT_NE(messageOf(p).find("1024"), std::string::npos) << messageOf(p);
  p.threads = 1025;
  EXPECT_NE(messageOf(p).find("threads = 1025"), std::string::npos);
  p.threads = 1024;
  EXPECT_EQ(messageOf(p), "");
  p.threads = 0;
  EXPECT_EQ(messageOf(p), "");
}
