// The robust statistics of the frame estimates: the histogram median and the trimmed mean.
#include "core/robust_statistics.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

using namespace range_nlm;

// The histogram median (the ranges' median of every run, the frame-to-frame noise ratio) is the
// value std::nth_element puts at rank count / 2, skipping negative, NaN and masked values; with
// ties (a quantized depth unit), values sharing one histogram bin and the count, for any thread
// count.
TEST(Median, HistogramMedianIsTheNthElementOfTheCountedValues)
{
  std::mt19937 rng(5);
  std::normal_distribution<float> noise(1.5f, 0.4f);
  for (std::size_t n : {1u, 2u, 7u, 1000u, 307200u}) {
    for (int quantized = 0; quantized < 2; ++quantized) {
      std::vector<float> values(n);
      std::vector<unsigned char> mask(n);
      for (std::size_t i = 0; i < n; ++i) {
        float v = noise(rng);
        if (quantized)
          v = std::round(v * 1000.0f) / 1000.0f; // many equal values, neighbours in one bin
        if (i % 11 == 3)
          v = -v;
        if (i % 17 == 5)
          v = std::numeric_limits<float>::quiet_NaN();
        values[i] = v;
        mask[i] = i % 5 != 1;
      }
      for (const unsigned char* m : {static_cast<const unsigned char*>(nullptr),
                                     static_cast<const unsigned char*>(mask.data())}) {
        std::vector<float> counted;
        for (std::size_t i = 0; i < n; ++i)
          if ((!m || m[i]) && values[i] >= 0.0f)
            counted.push_back(values[i]);
        for (int threads : {1, 2, 3}) {
          std::size_t count = 12345;
          const float median = detail::medianOfNonNegative(values.data(), m, n, threads, &count);
          ASSERT_EQ(count, counted.size()) << n;
          if (counted.empty()) {
            EXPECT_TRUE(std::isnan(median)) << n;
            continue;
          }
          std::vector<float> sorted = counted;
          std::nth_element(sorted.begin(), sorted.begin() + sorted.size() / 2, sorted.end());
          EXPECT_EQ(median, sorted[sorted.size() / 2]) << n << " quantized " << quantized << " threads " << threads;
        }
      }
    }
  }
  const std::vector<float> none = {-1.0f, std::numeric_limits<float>::quiet_NaN(), -0.5f};
  std::size_t count = 7;
  EXPECT_TRUE(std::isnan(detail::medianOfNonNegative(none.data(), nullptr, none.size(), 2, &count)));
  EXPECT_EQ(count, 0u);
}

// The noise correlation's statistic: the mean of the smallest 80 % of the values, found by a
// histogram of their upper bits, is that of a full sort, with ties across the cut (a quantized
// depth unit), zeros, values spread over many octaves and sizes down to 0 and 1.
TEST(NoiseCorrelation, RobustMeanIsTheMeanOfTheSmallestFourFifths)
{
  std::mt19937 rng(23);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  for (std::size_t n : {0u, 1u, 2u, 5u, 64u, 1000u, 38411u})
    for (int kind = 0; kind < 3; ++kind) {
      std::vector<float> values(n);
      for (float& v : values) {
        const float u = unit(rng);
        v = kind == 0   ? std::exp2(40.0f * u - 30.0f)                  // octaves 2^-30 .. 2^10
            : kind == 1 ? 0.001f * std::floor(u * 8.0f)                   // 8 steps, ties at the cut
                        : (unit(rng) < 0.3f ? 0.0f : 0.004f + 0.001f * u); // zeros and a narrow band
      }
      std::vector<float> sorted = values;
      std::sort(sorted.begin(), sorted.end());
      const std::size_t keep = n * 4 / 5;
      double sum = 0.0;
      for (std::size_t i = 0; i < keep; ++i)
        sum += sorted[i];
      const float expected = keep == 0 ? 0.0f : static_cast<float>(sum / keep);
      std::vector<float> work = values;
      EXPECT_FLOAT_EQ(detail::robustMean(work), expected) << "n " << n << " kind " << kind;
    }
}
