#include "opencv_inpaint.h"

#include <opencv2/core.hpp>
#include <opencv2/photo.hpp>

#include <cmath>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <string>

namespace range_nlm
{
namespace tools
{
namespace opencv
{
namespace
{
constexpr double kMillimetre = 0.001;
}

const char*
toString(InpaintMethod method)
{
  return method == InpaintMethod::telea ? "Telea" : "Navier-Stokes";
}

pcl::PointCloud<pcl::PointXYZ>
inpaintDepth(const pcl::PointCloud<pcl::PointXYZ>& in, const librealsense::PinholeRays& rays, InpaintMethod method,
             double radius)
{
  if (in.height < 1 || in.width < 1 || std::size_t(in.width) * in.height != in.size())
    throw std::invalid_argument("OpenCV inpainting: the cloud is not organized (" + std::to_string(in.width) + " x " +
                                std::to_string(in.height) + ", " + std::to_string(in.size()) + " points)");
  if (!(radius >= 1.0))
    throw std::invalid_argument("OpenCV inpainting: the radius " + std::to_string(radius) +
                                " is below one pixel");
  const int w = static_cast<int>(in.width), h = static_cast<int>(in.height);
  cv::Mat depth(h, w, CV_16UC1, cv::Scalar(0)), mask(h, w, CV_8UC1, cv::Scalar(0));
  for (int v = 0; v < h; ++v)
    for (int u = 0; u < w; ++u) {
      const float z = in[std::size_t(v) * w + u].z;
      if (!std::isfinite(z)) {
        mask.at<unsigned char>(v, u) = 255;
        continue;
      }
      const double mm = std::round(double(z) / kMillimetre);
      if (mm < 0.0 || mm > 65535.0)
        throw std::invalid_argument("OpenCV inpainting: pixel (" + std::to_string(u) + ", " + std::to_string(v) +
                                    ") has z " + std::to_string(z) +
                                    " m, outside a 16-bit depth image of millimetres (0 ... 65.535 m)");
      depth.at<std::uint16_t>(v, u) = static_cast<std::uint16_t>(mm);
    }
  cv::Mat filled;
  cv::inpaint(depth, mask, filled, radius, method == InpaintMethod::telea ? cv::INPAINT_TELEA : cv::INPAINT_NS);

  pcl::PointCloud<pcl::PointXYZ> out = in;
  bool dense = true;
  for (int v = 0; v < h; ++v)
    for (int u = 0; u < w; ++u) {
      pcl::PointXYZ& q = out[std::size_t(v) * w + u];
      if (!mask.at<unsigned char>(v, u))
        continue; // measured: kept as it was
      dense &= rays.place(q, u, v, filled.at<std::uint16_t>(v, u) * kMillimetre);
    }
  out.is_dense = dense;
  return out;
}

} // namespace opencv
} // namespace tools
} // namespace range_nlm
