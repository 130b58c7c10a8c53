#include "header_only_reference.h"

#include <range_nlm/nonlocal_means_filter.h>
#include <range_nlm/temporal_stream.h>

#ifdef RANGE_NLM_HEADER_ONLY
#error "the reference must come from the compiled library"
#endif

namespace range_nlm::test
{
pcl::PointCloud<pcl::PointXYZ>
filteredByLibrary(const pcl::PointCloud<pcl::PointXYZ>& cloud, const FilterParameters& parameters)
{
  NonLocalMeansFilter<pcl::PointXYZ> filter;
  filter.setParameters(parameters);
  filter.setInputCloud(pcl::PointCloud<pcl::PointXYZ>::ConstPtr(new pcl::PointCloud<pcl::PointXYZ>(cloud)));
  pcl::PointCloud<pcl::PointXYZ> out;
  filter.filter(out);
  return out;
}

std::vector<pcl::PointCloud<pcl::PointXYZ>::Ptr>
sequenceFilteredByLibrary(const std::vector<pcl::PointCloud<pcl::PointXYZ>::ConstPtr>& frames,
                          const FilterParameters& parameters)
{
  return filterSequence<pcl::PointXYZ>(frames, 1, TemporalWindow::centred, parameters);
}
} // namespace range_nlm::test
