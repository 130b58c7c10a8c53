#include <range_nlm/impl/grid_adaptor.hpp>

#include <pcl/point_types.h>

#define RANGE_NLM_INSTANTIATE_ADAPTORS(T)                                                                   \
  template range_nlm::Grid range_nlm::toGrid<T>(const pcl::PointCloud<T>&, const char*);                    \
  template void range_nlm::toGrid<T>(const pcl::PointCloud<T>&, range_nlm::Grid&, const char*);             \
  template void range_nlm::fromGrid<T>(const pcl::PointCloud<T>&, const range_nlm::Grid&, pcl::PointCloud<T>&);
RANGE_NLM_INSTANTIATE_ADAPTORS(pcl::PointXYZ)
RANGE_NLM_INSTANTIATE_ADAPTORS(pcl::PointXYZI)
RANGE_NLM_INSTANTIATE_ADAPTORS(pcl::PointXYZRGB)
RANGE_NLM_INSTANTIATE_ADAPTORS(pcl::PointXYZRGBA)
RANGE_NLM_INSTANTIATE_ADAPTORS(pcl::PointNormal)
RANGE_NLM_INSTANTIATE_ADAPTORS(pcl::PointXYZRGBNormal)
