// The builds of reprojectOntoRays (internal, for tests): the windows' planes taken pixel by pixel
// (the reference), or summed a row's kLanes pixels at a time by each instruction-set build.
#pragma once

#include <range_nlm/io/ray_reprojection.h>

#include <Eigen/Core>

#include <cstddef>
#include <vector>

namespace range_nlm
{
namespace detail
{

/// How many ways of taking the windows this CPU runs: 0 pixel by pixel, then the baseline's, the
/// AVX2 and the AVX-512 lane sums (those the CPU has).
std::size_t
rayReprojectionBuilds();

/// The unit normals of the filtered surface's planes reprojectOntoRays fits around every valid
/// point (zero where no plane fits or the point is invalid), with build `build`.
std::vector<Eigen::Vector3d>
surfacePlaneNormalsWithBuild(std::size_t build, const pcl::PointCloud<pcl::PointXYZ>& filtered,
                             const RayReprojectionParameters& parameters = RayReprojectionParameters());

/// reprojectOntoRays with build `build` (< rayReprojectionBuilds()).
pcl::PointCloud<pcl::PointXYZ>
reprojectOntoRaysWithBuild(std::size_t build, const pcl::PointCloud<pcl::PointXYZ>& input,
                           const pcl::PointCloud<pcl::PointXYZ>& filtered,
                           const RayReprojectionParameters& parameters = RayReprojectionParameters(),
                           RayReprojectionCounts* counts = nullptr);

} // namespace detail
} // namespace range_nlm
