#include <range_nlm/impl/nonlocal_means_filter.hpp>

#include <pcl/point_types.h>

#include <string>

namespace range_nlm
{
namespace detail
{
std::vector<unsigned char>
activeMask(const pcl::Indices* indices, std::size_t size, bool use_indices)
{
  std::vector<unsigned char> mask;
  if (!use_indices || indices == nullptr)
    return mask;
  mask.assign(size, 0);
  for (const auto index : *indices) {
    if (index < 0 || static_cast<std::size_t>(index) >= size)
      throw std::invalid_argument("range_nlm: index " + std::to_string(index) +
                                  " is outside the cloud of " + std::to_string(size) + " points");
    mask[static_cast<std::size_t>(index)] = 1;
  }
  return mask;
}
} // namespace detail
} // namespace range_nlm

template class range_nlm::NonLocalMeansFilter<pcl::PointXYZ>;
template class range_nlm::NonLocalMeansFilter<pcl::PointXYZI>;
template class range_nlm::NonLocalMeansFilter<pcl::PointXYZRGB>;
template class range_nlm::NonLocalMeansFilter<pcl::PointXYZRGBA>;
template class range_nlm::NonLocalMeansFilter<pcl::PointNormal>;
template class range_nlm::NonLocalMeansFilter<pcl::PointXYZRGBNormal>;

// The adaptor helpers, for tools that convert clouds without a filter object.
#define RANGE_NLM_INSTANTIATE_ADAPTORS(T)                                                                   \
  template range_nlm::Grid range_nlm::detail::toGrid<T>(const pcl::PointCloud<T>&, const char*);            \
  template void range_nlm::detail::toGrid<T>(const pcl::PointCloud<T>&, range_nlm::Grid&, const char*);     \
  template void range_nlm::detail::fromGrid<T>(const pcl::PointCloud<T>&, const range_nlm::Grid&,           \
                                               pcl::PointCloud<T>&);
RANGE_NLM_INSTANTIATE_ADAPTORS(pcl::PointXYZ)
RANGE_NLM_INSTANTIATE_ADAPTORS(pcl::PointXYZI)
RANGE_NLM_INSTANTIATE_ADAPTORS(pcl::PointXYZRGB)
RANGE_NLM_INSTANTIATE_ADAPTORS(pcl::PointXYZRGBA)
RANGE_NLM_INSTANTIATE_ADAPTORS(pcl::PointNormal)
RANGE_NLM_INSTANTIATE_ADAPTORS(pcl::PointXYZRGBNormal)
