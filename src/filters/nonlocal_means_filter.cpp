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
