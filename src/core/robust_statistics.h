// Robust statistics of the frame estimates (medians, a trimmed mean), shared by their translation
// units and by the tests (not installed).
#pragma once

#include <cstddef>
#include <vector>

namespace range_nlm
{
namespace detail
{
/// The median of `v` (not empty): the value at rank v.size() / 2 from 0, as std::nth_element
/// finds it.
float
medianOf(std::vector<float> v);
/// medianOf(v) without the copy: `v` (not empty) is reordered.
float
medianInPlace(std::vector<float>& v);
/// The median (the value at rank count / 2 from 0, as std::nth_element finds it) of the count
/// values[i] >= 0 with mask[i] set (every i if mask is null) among n, by `threads` threads; NaN
/// if there is none. `count` (if given) receives that count.
float
medianOfNonNegative(const float* values, const unsigned char* mask, std::size_t n, int threads,
                    std::size_t* count = nullptr);
/// The mean of the smallest 80 % of `values` (non-negative; reordered): robust to depth edges, and
/// unlike a median not stuck on the steps of a quantized depth unit. 0 for fewer than two values.
/// (The noise correlation's statistic, estimateNoiseCorrelation.)
float
robustMean(std::vector<float>& values);

} // namespace detail
} // namespace range_nlm
