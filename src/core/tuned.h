/// \file tuned.h
/// \brief The tuned numbers of the default setting, in one table (docs/method.md, "Tuned numbers").
///
/// Every number of the default that was chosen by measuring rather than derived (a threshold, a
/// margin, a reach) is one line here: its name, type, value, the data it was fitted on
/// ("generated": the scenes of range_nlm_synth; "real": the shipped frames; "derived": follows from
/// the method, kept here because it is a choice) and one line of why. The constants below are
/// made from the table, and `kTunedNumbers` lists it for the docs check (tests/core/test_tuned.cpp:
/// docs/method.md mirrors every row). Measured figures belong in docs/, not here.
///
/// Adding a number: one X(...) line in the section of the stage that uses it, then use the
/// constant `tuned::kName`.
#pragma once

#include <cstddef>

// X(name, type, value, fitted_on, why)

/// Numbers of the pipeline's stages (src/core/pipeline*.cpp, stages/): dilation, passes, guide.
#define RANGE_NLM_TUNED_PIPELINE(X)                                                                                   \
  X(kDilationReferenceWidth, int, 640, "derived",                                                                     \
    "the width (VGA) the automatic dilation's per-width numbers are given for, rounded to nearest")                   \
  X(kDilationReferenceLag, int, 8, "generated",                                                                       \
    "reference lag R per reference width: beyond the correlation length of the stereo noise")                         \
  X(kDilationMinLag, int, 2, "derived",                                                                               \
    "smallest reference lag: R / 2 must be a lag of its own")                                                         \
  X(kDilationMaxLag, int, 8, "derived",                                                                               \
    "largest reference lag: estimateNoiseCorrelation measures lags 1 .. 8")                                           \
  X(kDilationPerWidth, int, 2, "generated",                                                                           \
    "dilation of correlated noise per reference width: a dilated patch stays small")                                  \
  X(kDilationMin, int, 2, "derived",                                                                                  \
    "smallest dilation of correlated noise: 1 would be no dilation")                                                  \
  X(kDilationMax, int, 4, "generated",                                                                                \
    "largest dilation of correlated noise: a dilated 3 x 3 patch spans 9 pixels")                                     \
  X(kDilationCorrelationStep, int, 4, "derived",                                                                      \
    "noise correlation from every 4th row and column: enough triples, a fraction of the cost")                        \
  X(kCorrelatedVarianceRatio, float, 0.5f, "generated",                                                               \
    "correlated noise: the variance at lag 1 below this share of that at lag R")                                      \
  X(kStrongNoiseFootprints, float, 3.25f, "real",                                                                     \
    "strong noise (doubles the dilation, again per doubling): between the noisiest real frame and the gaining scenes") \
  X(kCorrelationLengthRise, float, 2.0f, "derived",                                                                   \
    "correlation length: the lag where the variance reaches this multiple of lag 1's (or half of lag R's)")           \
  X(kStrengthLagPerLength, float, 2.0f, "derived",                                                                    \
    "strong noise is read at this many correlation lengths (at least R / 2): beyond the blobs, the noise's height")   \
  X(kVeryStrongDilationFactor, float, 1.5f, "generated",                                                              \
    "noise beyond 2 kStrongNoiseFootprints: dilation up to this times the length's (6 px blobs: 6; 8 costs features)") \
  X(kScaleSurfaceSigmas, float, 3.0f, "generated",                                                                    \
    "multiscale: points of a 2 x 2 block within this many noise sigmas lie on one surface")                           \
  X(kScaleSurfaceFootprints, float, 2.0f, "generated",                                                                \
    "multiscale: and within at least this many pixel footprints (a noise-free frame)")                               \
  X(kChangeSigmas, float, 3.0f, "real",                                                                               \
    "test of change: a difference beyond this many sigmas of two samples is a change")                                \
  X(kGuideMargin, int, 2, "generated",                                                                                \
    "patch guide: pixels this near a changed one stay out (the vote passes a moved border)")                          \
  X(kGuideTolerance, float, 2.0f, "generated",                                                                        \
    "patch guide: a point's own difference within this many test thresholds (a lone change)")                         \
  X(kGuideMinFrames, int, 3, "real",                                                                                  \
    "patch guide from this many neighbours on: with fewer each finds its own noise in it")                            \
  X(kLineOfSightMinCosFloor, float, 1e-3f, "derived",                                                                 \
    "the line-of-sight step divides by |cos| of at least this, whatever min_cos is (a finite step)")

/// Numbers of the frame estimates (noise profile, noise correlation, frame change, history) and
/// of the isolated-outlier step.
#define RANGE_NLM_TUNED_ESTIMATES(X)                                                                                  \
  X(kProfileSamplesPerBin, int, 64, "generated", "one noise-profile range bin per 64 sampled windows")                \
  X(kProfileMaxBins, int, 8, "generated", "at most 8 noise-profile range bins")                                       \
  X(kRobustMeanKeptFifths, int, 4, "generated", "noise correlation: mean of the smallest 4/5, robust to edges")       \
  X(kNoiseCorrelationLags, int, 8, "derived", "lags 1..8 px, one per NoiseCorrelation::scale")                        \
  X(kNoiseCorrelationMinTriples, int, 64, "derived", "a lag's scale needs 64 pixel triples")                          \
  X(kMotionBlocksAcross, int, 20, "generated", "blocks of width/20 px hold many noise blobs each")                    \
  X(kMotionMinBlockSize, int, 8, "derived", "blocks of at least 8 x 8 px in small frames")                            \
  X(kMotionMinBlocks, int, 4, "derived", "fewer blocks cannot tell motion from noise")                                \
  X(kNoiseRatioMinPixels, int, 64, "derived", "the noise ratio needs 64 pixels, else 0")                              \
  X(kDriftMinBlocks, int, 24, "generated", "fewer blocks cannot tell a quadratic drift from motion")                  \
  X(kDriftHuberSpreads, double, 2.0, "generated", "Huber weights of the drift fit from 2 spreads")                    \
  X(kStructuredDeviation, double, 1.5, "generated", "structured: a shift raises the mean deviation 1.5x")             \
  X(kShiftedDeviation, double, 0.8, "generated", "shows a shift: a shift lowers it to 0.8x")                          \
  X(kMinStructuredBlocks, int, 8, "generated", "the structure test needs 8 structured blocks")                        \
  X(kStructuredPerShifted, int, 4, "generated", "motion if 1 in 4 structured blocks shows a shift")                   \
  X(kSurroundReach, int, 2, "generated", "outliers: the range-step guard's surroundings, 5 x 5 pixels")               \
  X(kSurroundSteps, float, 4.0f, "generated", "outliers: farther than 4 median steps of the surroundings")            \
  X(kSideReach, int, 5, "generated", "outliers: the side vote's surroundings, 11 x 11 pixels")                        \
  X(kFootprints, float, 3.0f, "generated", "outliers: 'on a surface' within at least 3 pixel footprints")             \
  X(kHistoryChangeSigmas, float, 2.0f, "generated", "history starts over below the filter's 3 sigmas of change")  \
  X(kReuseCheckColumns, int, 80, "derived", "carried estimates: a check lattice of 80 columns, 8 px apart in VGA")   \
  X(kReuseCheckGroups, int, 16, "derived", "carried estimates: a scale's error from the spread of 16 sample groups") \
  X(kReuseTestSigmas, double, 4.0, "derived", "carried estimates: a change beyond 4 standard errors is a change")   \
  X(kReuseRangeTail, double, 0.05, "derived", "carried estimates: the ranges' 5 % and 95 % quantiles")             \
  X(kReuseMaxFrames, int, 30, "derived", "carried estimates: made afresh at least once a second at 30 Hz")     \
  X(kSpreadQuantile, float, 0.25f, "generated", "patch spread: a sample's lower quartile of Sim to its candidates")

#define RANGE_NLM_TUNED_NUMBERS(X)                                                                                    \
  RANGE_NLM_TUNED_PIPELINE(X)                                                                                         \
  RANGE_NLM_TUNED_ESTIMATES(X)

namespace range_nlm::tuned
{

#define RANGE_NLM_TUNED_CONSTANT(name, type, value, fitted_on, why) inline constexpr type name = value;
RANGE_NLM_TUNED_NUMBERS(RANGE_NLM_TUNED_CONSTANT)
#undef RANGE_NLM_TUNED_CONSTANT

/// One row of the table.
struct TunedNumber
{
  const char* name;
  double value;
  const char* fitted_on;
  const char* why;
};

#define RANGE_NLM_TUNED_ROW(name, type, value, fitted_on, why) TunedNumber{#name, double(value), fitted_on, why},
inline constexpr TunedNumber kTunedNumbers[] = {RANGE_NLM_TUNED_NUMBERS(RANGE_NLM_TUNED_ROW) TunedNumber{}};
#undef RANGE_NLM_TUNED_ROW
/// Rows of kTunedNumbers (its last element is an empty end marker).
inline constexpr std::size_t kTunedNumberCount = sizeof(kTunedNumbers) / sizeof(kTunedNumbers[0]) - 1;

} // namespace range_nlm::tuned
