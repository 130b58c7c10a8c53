// ParameterSetters: a setter and a getter for every field of the registry, each writing its own
// field of the one FilterParameters and nothing else.
#include "parameter_values.h"

#include <range_nlm/parameter_setters.h>

#include <gtest/gtest.h>

#include <functional>
#include <map>
#include <string>

using namespace range_nlm;

namespace
{
struct Accessors
{
  std::function<void(ParameterSetters&, const FilterParameters&)> set;
  std::function<void(const ParameterSetters&, FilterParameters&)> get;
};

/// The entry of `field` in the table below: its setter and getter, by the PCL-style Name.
#define RANGE_NLM_ACCESSORS(field, Name)                                                             \
  {                                                                                                  \
    #field, Accessors                                                                                \
    {                                                                                                \
      [](ParameterSetters& s, const FilterParameters& v) { s.set##Name(v.field); },                  \
          [](const ParameterSetters& s, FilterParameters& out) { out.field = s.get##Name(); }        \
    }                                                                                                \
  }

const std::map<std::string, Accessors>&
accessors()
{
  static const std::map<std::string, Accessors> all = {
      RANGE_NLM_ACCESSORS(search_window, SearchWindowSize),
      RANGE_NLM_ACCESSORS(temporal_search_window, TemporalSearchWindowSize),
      RANGE_NLM_ACCESSORS(patch_size, PatchSize),
      RANGE_NLM_ACCESSORS(dilation, Dilation),
      RANGE_NLM_ACCESSORS(scales, Scales),
      RANGE_NLM_ACCESSORS(iterations, Iterations),
      RANGE_NLM_ACCESSORS(threads, NumberOfThreads),
      RANGE_NLM_ACCESSORS(distance_bandwidth, DistanceBandwidth),
      RANGE_NLM_ACCESSORS(similarity_bandwidth, SimilarityBandwidth),
      RANGE_NLM_ACCESSORS(distance_scale, DistanceScale),
      RANGE_NLM_ACCESSORS(similarity_scale, SimilarityScale),
      RANGE_NLM_ACCESSORS(similarity_spread, SimilaritySpread),
      RANGE_NLM_ACCESSORS(seed, Seed),
      RANGE_NLM_ACCESSORS(bandwidth_samples, BandwidthSamples),
      RANGE_NLM_ACCESSORS(normal_window, NormalWindowSize),
      RANGE_NLM_ACCESSORS(normal_presmooth_window, NormalPresmoothWindowSize),
      RANGE_NLM_ACCESSORS(normal_presmooth_range, NormalPresmoothRange),
      RANGE_NLM_ACCESSORS(normal_edge_gate, NormalEdgeGate),
      RANGE_NLM_ACCESSORS(patch_edge_gate, PatchEdgeGate),
      RANGE_NLM_ACCESSORS(line_of_sight_min_cos, LineOfSightMinCos),
      RANGE_NLM_ACCESSORS(bandwidth_model, BandwidthModel),
      RANGE_NLM_ACCESSORS(max_displacement, MaxDisplacement),
      RANGE_NLM_ACCESSORS(outlier_sigmas, OutlierSigmas),
      RANGE_NLM_ACCESSORS(displacement, Displacement),
      RANGE_NLM_ACCESSORS(cross_frame_bandwidth, CrossFrameBandwidth),
      RANGE_NLM_ACCESSORS(patch_guide, PatchGuide),
      RANGE_NLM_ACCESSORS(uncertainty, EstimateUncertainty),
      RANGE_NLM_ACCESSORS(evaluation, Evaluation),
      RANGE_NLM_ACCESSORS(fill_holes, FillHoles),
      RANGE_NLM_ACCESSORS(reuse_estimates, ReuseEstimates),
  };
  return all;
}
} // namespace

TEST(ParameterSetters, EveryFieldHasASetterAndAGetter)
{
  EXPECT_EQ(accessors().size(), parameterRegistry().size());
  for (const ParameterEntry& entry : parameterRegistry())
    EXPECT_EQ(accessors().count(entry.name), 1u) << entry.name;
}

TEST(ParameterSetters, SettersAndGettersRoundTripEveryField)
{
  for (const ParameterEntry& entry : parameterRegistry()) {
    const auto found = accessors().find(entry.name);
    ASSERT_NE(found, accessors().end()) << entry.name;
    const FilterParameters other = test::withOtherValue(entry, FilterParameters::recommended());
    ParameterSetters setters;
    found->second.set(setters, other);
    EXPECT_TRUE(test::sameField(entry, setters.getParameters(), other)) << entry.name;
    EXPECT_TRUE(test::sameOtherFields(entry, setters.getParameters(), FilterParameters::recommended())) << entry.name;
    FilterParameters read = FilterParameters::recommended();
    found->second.get(setters, read);
    EXPECT_TRUE(test::sameField(entry, read, other)) << entry.name;
  }
}

TEST(ParameterSetters, SetParametersReplacesEveryField)
{
  ParameterSetters setters;
  setters.setParameters(FilterParameters::paper());
  for (const ParameterEntry& entry : parameterRegistry())
    EXPECT_TRUE(test::sameField(entry, setters.getParameters(), FilterParameters::paper())) << entry.name;
  EXPECT_EQ(setters.getSearchWindowSize(), 7);
  EXPECT_EQ(setters.getBandwidthModel(), BandwidthModel::global);
  EXPECT_FALSE(setters.getPatchGuide());
}
