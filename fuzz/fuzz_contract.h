// What the PCD-and-filter fuzzer (fuzz_pcd_filter.cpp) and the test that replays its findings
// (tests/test_bad_input.cpp) both accept as a legitimate refusal.
#pragma once

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <cmath>
#include <cstddef>

namespace range_nlm
{
namespace fuzz
{

/// Under 5% of the valid points have 3 valid neighbours in their 3 x 3 window: the noise estimate
/// (from 1000 random valid points, see estimateNoiseProfile) may find no window to fit a plane to.
/// With 5% or more, it misses them all with probability 0.95^1000 < 1e-22.
inline bool
tooSparseForNoiseEstimate(const pcl::PointCloud<pcl::PointXYZ>& cloud)
{
  auto valid = [&](int u, int v) {
    if (u < 0 || v < 0 || u >= int(cloud.width) || v >= int(cloud.height))
      return false;
    const pcl::PointXYZ& p = cloud[std::size_t(v) * cloud.width + u];
    return std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z);
  };
  int points = 0, fitting = 0;
  for (int v = 0; v < int(cloud.height); ++v)
    for (int u = 0; u < int(cloud.width); ++u) {
      if (!valid(u, v))
        continue;
      int around = 0;
      for (int dv = -1; dv <= 1; ++dv)
        for (int du = -1; du <= 1; ++du)
          around += valid(u + du, v + dv);
      ++points;
      fitting += around >= 4;
    }
  return fitting * 20 < points;
}

} // namespace fuzz
} // namespace range_nlm
