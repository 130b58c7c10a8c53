/// \file point_types.h
/// \brief The point types the compiled library instantiates its templates for.
#pragma once

#include <pcl/point_types.h>

/// The PCL point types range_nlm's filters, stream and grid adaptor are compiled for, as a
/// Boost.Preprocessor sequence (for PCL_INSTANTIATE, or BOOST_PP_SEQ_ENUM for a type list). Any
/// other point type whose first three floats are x, y, z works when RANGE_NLM_HEADER_ONLY is
/// defined before the range_nlm headers are included.
#define RANGE_NLM_POINT_TYPES                                                                                   \
  (pcl::PointXYZ)(pcl::PointXYZI)(pcl::PointXYZRGB)(pcl::PointXYZRGBA)(pcl::PointNormal)(pcl::PointXYZRGBNormal)
