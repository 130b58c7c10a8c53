// The compiled library's filters on pcl::PointXYZ, from a translation unit built without
// RANGE_NLM_HEADER_ONLY: the reference of test_header_only.cpp.
#pragma once

#include <range_nlm/parameters.h>

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <vector>

namespace range_nlm::test
{
/// NonLocalMeansFilter<pcl::PointXYZ> of the compiled library.
pcl::PointCloud<pcl::PointXYZ>
filteredByLibrary(const pcl::PointCloud<pcl::PointXYZ>& cloud, const FilterParameters& parameters);
/// filterSequence<pcl::PointXYZ> of the compiled library, centred window of radius 1.
std::vector<pcl::PointCloud<pcl::PointXYZ>::Ptr>
sequenceFilteredByLibrary(const std::vector<pcl::PointCloud<pcl::PointXYZ>::ConstPtr>& frames,
                          const FilterParameters& parameters);
} // namespace range_nlm::test
