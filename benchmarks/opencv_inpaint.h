// OpenCV's image inpainting (cv::inpaint, the photo module) on depth frames, as a baseline for the
// hole-filling comparison of range_nlm_bench: what a program that has OpenCV at hand reaches for
// to close the holes of a depth image.
//
// cv::inpaint takes a single-channel image and an 8-bit mask of the pixels to fill, and fills them
// by one of two methods: Telea's fast marching (A. Telea, "An image inpainting technique
// based on the fast marching method", J. Graphics Tools 9(1), 2004), each pixel a weighted
// first-order extrapolation of the known pixels within the radius, filled from the border inward;
// or the Navier-Stokes method (Bertalmio, Bertozzi and Sapiro, CVPR 2001), which carries the
// image's isophotes into the hole. Here the image is the frame's depth in millimetres, 16 bits (as
// depth cameras deliver it), 0 where there is no measurement, and the mask is every such pixel: as
// a user would call it on a depth frame. Not in metres as float: before OpenCV 4.10 (Debian 12 has
// 4.6) Telea's float path adds the 0.5 meant to round integers to every filled value
// (opencv/opencv#25404), half a metre.
#pragma once

#include "librealsense_holes.h"

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

namespace range_nlm
{
namespace tools
{
namespace opencv
{

/// cv::inpaint's flags.
enum class InpaintMethod
{
  telea,        // cv::INPAINT_TELEA
  navier_stokes // cv::INPAINT_NS
};

/// "Telea" or "Navier-Stokes".
const char*
toString(InpaintMethod method);

/// cv::inpaint on the depth of an organized cloud (metres, NaN = no measurement; x right, y down,
/// z forward, camera at the origin), as a 16-bit image of round(z / 1 mm): every pixel without a
/// finite z is in the mask, `radius` is cv::inpaint's inpaintRadius in pixels. A measured point is
/// kept bit for bit; a filled pixel is its inpainted depth on the ray `rays` give it; a pixel
/// inpainted to a depth of 0 stays a hole. Throws std::invalid_argument naming the problem for an
/// unorganized cloud, a radius below 1 pixel, or a measured depth outside 0 ... 65.535 m.
pcl::PointCloud<pcl::PointXYZ>
inpaintDepth(const pcl::PointCloud<pcl::PointXYZ>& frame, const librealsense::PinholeRays& rays, InpaintMethod method,
             double radius);

} // namespace opencv
} // namespace tools
} // namespace range_nlm
