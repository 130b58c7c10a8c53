// Internal helpers shared by the direct and the fast kernel (not installed).
#pragma once

#include <cstdint>
#include <cstring>

namespace range_nlm
{
namespace detail
{

/// exp(x) for x <= 0 (Cephes-style range reduction and a degree-6 polynomial); branch-free so
/// that loops calling it vectorize. Results below exp(-87) are flushed to 0.
inline float
expNonPositiveInline(float x)
{
  x = x < -87.0f ? -87.0f : x;
  const float fx = x * 1.44269504088896341f;
  // round to nearest without a library call
  const float n = static_cast<float>(static_cast<int>(fx - 0.5f));
  float r = x - n * 0.693359375f;
  r = r + n * 2.12194440e-4f;
  float p = 1.9875691500e-4f;
  p = p * r + 1.3981999507e-3f;
  p = p * r + 8.3334519073e-3f;
  p = p * r + 4.1665795894e-2f;
  p = p * r + 1.6666665459e-1f;
  p = p * r + 5.0000001201e-1f;
  p = p * r * r + r + 1.0f;
  const std::int32_t e = (static_cast<std::int32_t>(n) + 127) << 23;
  float scale;
  std::memcpy(&scale, &e, sizeof(scale));
  const float result = p * scale;
  return x <= -87.0f ? 0.0f : result;
}

/// Weight of an arbitrary bandwidth: 1 / b^2, with b = 0 giving a huge finite factor so that only
/// exact matches (argument 0) keep weight 1 and nothing divides by zero.
inline float
inverseSquareInline(float bandwidth)
{
  if (!(bandwidth > 0.0f))
    return 1e30f;
  const double v = 1.0 / (static_cast<double>(bandwidth) * bandwidth);
  return v > 1e30 ? 1e30f : static_cast<float>(v);
}

} // namespace detail
} // namespace range_nlm
