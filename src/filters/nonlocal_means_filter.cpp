#include <range_nlm/impl/nonlocal_means_filter.hpp>

#include <range_nlm/point_types.h>

#include <pcl/impl/instantiate.hpp>

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

PCL_INSTANTIATE(NonLocalMeansFilter, RANGE_NLM_POINT_TYPES)
