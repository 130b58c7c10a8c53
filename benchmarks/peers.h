// PCL's filters that range_nlm is compared with, configured in one place for the timing and the
// accuracy comparisons.
#pragma once

#include <pcl/filters/fast_bilateral_omp.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl/surface/mls.h>

#include <memory>

namespace range_nlm
{
namespace tools
{
namespace bench
{

/// pcl::FastBilateralFilterOMP with spatial sigma `sigma_s` (pixels) and range sigma `sigma_r`
/// (cloud units); `threads` 0 = all cores.
std::shared_ptr<pcl::FastBilateralFilterOMP<pcl::PointXYZ>>
makeFastBilateral(float sigma_s, float sigma_r, unsigned threads);

/// pcl::MovingLeastSquares of polynomial order 2 within `radius` (cloud units), points projected
/// onto the fit, no normals; `threads` 0 = all cores. Give it its input with setMlsInput().
std::shared_ptr<pcl::MovingLeastSquares<pcl::PointXYZ, pcl::PointXYZ>>
makeMovingLeastSquares(double radius, unsigned threads);

/// Sets `cloud` as the MLS input with a k-d tree over its finite points only: MLS asserts on NaN
/// points with an organized search.
void
setMlsInput(pcl::MovingLeastSquares<pcl::PointXYZ, pcl::PointXYZ>& mls,
            const pcl::PointCloud<pcl::PointXYZ>::ConstPtr& cloud);

} // namespace bench
} // namespace tools
} // namespace range_nlm
