#include <range_nlm/impl/temporal_nonlocal_means_filter.hpp>
#include <range_nlm/impl/temporal_stream.hpp>
#include <range_nlm/point_types.h>

#include <pcl/impl/instantiate.hpp>

PCL_INSTANTIATE(TemporalNonLocalMeansFilter, RANGE_NLM_POINT_TYPES)
PCL_INSTANTIATE(TemporalStream, RANGE_NLM_POINT_TYPES)
PCL_INSTANTIATE(filterSequence, RANGE_NLM_POINT_TYPES)
