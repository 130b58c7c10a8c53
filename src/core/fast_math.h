// Internal helpers shared by the kernels (not installed). They have internal linkage, so the
// baseline and the AVX2 row kernels (kernel_rows*.cpp) each compile their own copy.
#pragma once

#include <cstdint>
#include <cstring>

namespace range_nlm
{
namespace detail
{

/// exp(x) for x <= 0 (Cephes-style range reduction and a degree-6 polynomial); branch-free so
/// that loops calling it vectorize. Results below exp(-87) are flushed to 0.
static inline float
expNonPositiveInline(float x)
{
  x = x < -87.0f ? -87.0f : x;
  // Round x / ln 2 to the nearest integer n with the 1.5 * 2^23 trick (no float -> int
  // conversion, which keeps the loop vectorizable); t's low mantissa bits hold n.
  const float t = x * 1.44269504088896341f + 12582912.0f;
  const float n = t - 12582912.0f;
  float r = x - n * 0.693359375f;
  r = r + n * 2.12194440e-4f;
  // exp(r) = 1 + r + r^2 p(r) on |r| <= ln(2) / 2: Cephes' expf polynomial with its r^7 term
  // economized into the r^5 and r^3 coefficients (Chebyshev), one multiply-add fewer; the
  // relative error stays below 1.4e-7 for every float x in [-87, 0] (8.5e-8 with the r^7 term).
  float p = 1.3981999507e-3f;
  p = p * r + 8.3752302453e-3f;
  p = p * r + 4.1665795894e-2f;
  p = p * r + 1.6666540504e-1f;
  p = p * r + 5.0000001201e-1f;
  p = p * r * r + r + 1.0f;
  // Unsigned arithmetic: for a NaN argument the exponent overflows the shift, which is undefined
  // for int; the bits for every x <= 0 are the same.
  const unsigned e = (__builtin_bit_cast(unsigned, t) - 0x4B400000u + 127u) << 23;
  const float scale = __builtin_bit_cast(float, e);
  const float result = p * scale;
  return x <= -87.0f ? 0.0f : result;
}

/// Weight of an arbitrary bandwidth: 1 / b^2, with b = 0 giving a huge finite factor so that only
/// exact matches (argument 0) keep weight 1 and nothing divides by zero.
static inline float
inverseSquareInline(float bandwidth)
{
  if (!(bandwidth > 0.0f))
    return 1e30f;
  const double v = 1.0 / (static_cast<double>(bandwidth) * bandwidth);
  return v > 1e30 ? 1e30f : static_cast<float>(v);
}

} // namespace detail
} // namespace range_nlm
