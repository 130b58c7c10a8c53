#include <range_nlm/impl/temporal_nonlocal_means_filter.hpp>
#include <range_nlm/impl/temporal_stream.hpp>

#include <pcl/point_types.h>

template class range_nlm::TemporalNonLocalMeansFilter<pcl::PointXYZ>;
template class range_nlm::TemporalNonLocalMeansFilter<pcl::PointXYZI>;
template class range_nlm::TemporalNonLocalMeansFilter<pcl::PointXYZRGB>;
template class range_nlm::TemporalNonLocalMeansFilter<pcl::PointXYZRGBA>;
template class range_nlm::TemporalNonLocalMeansFilter<pcl::PointNormal>;
template class range_nlm::TemporalNonLocalMeansFilter<pcl::PointXYZRGBNormal>;

template class range_nlm::TemporalStream<pcl::PointXYZ>;
template class range_nlm::TemporalStream<pcl::PointXYZI>;
template class range_nlm::TemporalStream<pcl::PointXYZRGB>;
template class range_nlm::TemporalStream<pcl::PointXYZRGBA>;
template class range_nlm::TemporalStream<pcl::PointNormal>;
template class range_nlm::TemporalStream<pcl::PointXYZRGBNormal>;

#define RANGE_NLM_INSTANTIATE_FILTER_SEQUENCE(T)                                                  \
  template std::vector<pcl::PointCloud<T>::Ptr> filterSequence<T>(                  \
      const std::vector<pcl::PointCloud<T>::ConstPtr>&, int, bool, const FilterParameters&);            \
  template std::vector<pcl::PointCloud<T>::Ptr> filterSequence<T>(                                  \
      const std::vector<pcl::PointCloud<T>::ConstPtr>&, int, TemporalWindow, const FilterParameters&);
namespace range_nlm
{
RANGE_NLM_INSTANTIATE_FILTER_SEQUENCE(pcl::PointXYZ)
RANGE_NLM_INSTANTIATE_FILTER_SEQUENCE(pcl::PointXYZI)
RANGE_NLM_INSTANTIATE_FILTER_SEQUENCE(pcl::PointXYZRGB)
RANGE_NLM_INSTANTIATE_FILTER_SEQUENCE(pcl::PointXYZRGBA)
RANGE_NLM_INSTANTIATE_FILTER_SEQUENCE(pcl::PointNormal)
RANGE_NLM_INSTANTIATE_FILTER_SEQUENCE(pcl::PointXYZRGBNormal)
} // namespace range_nlm
