// Robust statistics of the frame estimates: medians by selection and by a histogram of the
// values' bits, and the trimmed mean of the noise correlation.
#include "internal.h"
#include "robust_statistics.h"
#include "tuned.h"

#include <algorithm>
#include <cstdint>
#include <limits>

namespace range_nlm
{

float
detail::medianOf(std::vector<float> v)
{
  return medianInPlace(v);
}

float
detail::medianInPlace(std::vector<float>& v)
{
  const std::size_t mid = v.size() / 2;
  std::nth_element(v.begin(), v.begin() + mid, v.end());
  return v[mid];
}

float
detail::medianOfNonNegative(const float* values, const unsigned char* mask, std::size_t n, int threads,
                            std::size_t* count)
{
  // Non-negative floats order as their bits do: a histogram of the upper 16 bits finds the bin
  // holding the median's rank, and only that bin's values are copied and selected from (a tenth
  // of the time of std::nth_element over all of them at VGA size).
  constexpr std::size_t kBins = 1u << 16;
  const auto bin = [](float f) { return __builtin_bit_cast(std::uint32_t, f) >> 16; };
  const auto counted = [&](std::ptrdiff_t i) { return (!mask || mask[i]) && values[i] >= 0.0f; };
  const std::ptrdiff_t size = static_cast<std::ptrdiff_t>(n);
  std::vector<std::uint32_t> histogram(kBins, 0u);
#pragma omp parallel num_threads(detail::resolveThreads(threads))
  {
    std::vector<std::uint32_t> mine(kBins, 0u);
#pragma omp for schedule(static) nowait
    for (std::ptrdiff_t i = 0; i < size; ++i)
      if (counted(i))
        ++mine[bin(values[i])];
#pragma omp critical(range_nlm_median_histogram)
    for (std::size_t b = 0; b < kBins; ++b)
      histogram[b] += mine[b];
  }
  std::size_t total = 0;
  for (std::uint32_t h : histogram)
    total += h;
  if (count)
    *count = total;
  if (total == 0)
    return std::numeric_limits<float>::quiet_NaN();
  const std::size_t rank = total / 2;
  std::size_t below = 0, chosen = 0;
  for (; below + histogram[chosen] <= rank; ++chosen)
    below += histogram[chosen];
  // The bin's values, gathered by the threads side by side; the value of rank k among them does
  // not depend on the order they are gathered in.
  std::vector<float> in_bin;
  in_bin.reserve(histogram[chosen]);
#pragma omp parallel num_threads(detail::resolveThreads(threads))
  {
    std::vector<float> mine;
#pragma omp for schedule(static) nowait
    for (std::ptrdiff_t i = 0; i < size; ++i)
      if (counted(i) && bin(values[i]) == chosen)
        mine.push_back(values[i]);
#pragma omp critical(range_nlm_median_bin)
    in_bin.insert(in_bin.end(), mine.begin(), mine.end());
  }
  const std::ptrdiff_t k = static_cast<std::ptrdiff_t>(rank - below);
  std::nth_element(in_bin.begin(), in_bin.begin() + k, in_bin.end());
  return in_bin[k];
}

float
detail::robustMean(std::vector<float>& values)
{
  const std::size_t keep = values.size() * tuned::kRobustMeanKeptFifths / 5;
  if (keep == 0)
    return 0.0f;
  // Non-negative floats order as their bits do: a histogram of bits 30..20 (the exponent and
  // three mantissa bits) finds the bin holding the keep-th smallest value; the values of the
  // bins below it are all kept, and only that bin's values are selected from (std::nth_element
  // over every value took most of the automatic dilation's estimate).
  constexpr int kShift = 20;
  constexpr std::size_t kBins = std::size_t(1) << (31 - kShift);
  const auto bin = [](float f) { return __builtin_bit_cast(std::uint32_t, f) >> kShift; };
  std::vector<std::uint32_t> histogram(kBins, 0u);
  for (float v : values)
    ++histogram[bin(v)];
  std::size_t below = 0, chosen = 0;
  for (; below + histogram[chosen] < keep; ++chosen)
    below += histogram[chosen];
  double sum = 0.0;
  std::size_t in_bin = 0;
  for (float v : values) {
    const std::uint32_t b = bin(v);
    sum += b < chosen ? double(v) : 0.0;
    if (b == chosen)
      values[in_bin++] = v; // in place: every value is read before its slot can be written
  }
  const std::size_t take = keep - below; // 1 ... in_bin
  std::nth_element(values.begin(), values.begin() + (take - 1), values.begin() + in_bin);
  for (std::size_t i = 0; i < take; ++i)
    sum += values[i];
  return static_cast<float>(sum / keep);
}

} // namespace range_nlm
