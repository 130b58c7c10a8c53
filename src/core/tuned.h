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
#define RANGE_NLM_TUNED_PIPELINE(X)

/// Numbers of the frame estimates (noise profile, noise correlation, frame change, history) and
/// of the isolated-outlier step.
#define RANGE_NLM_TUNED_ESTIMATES(X)

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
