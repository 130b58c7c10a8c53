#include <range_nlm/impl/grid_adaptor.hpp>
#include <range_nlm/point_types.h>

#include <pcl/impl/instantiate.hpp>

PCL_INSTANTIATE(GridAdaptor, RANGE_NLM_POINT_TYPES)
