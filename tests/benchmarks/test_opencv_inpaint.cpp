// OpenCV's inpainting as the hole-filling comparison calls it (benchmarks/opencv_inpaint.h): a
// hole in a plane is filled near the plane on its pixels' rays, measured points keep their bits,
// and bad input is refused with a message that names it.
#include "opencv_inpaint.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <functional>
#include <string>
#include <limits>
#include <stdexcept>

using range_nlm::tools::librealsense::PinholeRays;
using range_nlm::tools::opencv::InpaintMethod;
using range_nlm::tools::opencv::inpaintDepth;
using Cloud = pcl::PointCloud<pcl::PointXYZ>;

namespace
{
constexpr int kWidth = 40, kHeight = 30;

PinholeRays
rays()
{
  PinholeRays r;
  r.fx = r.fy = 40.0;
  r.cx = 19.5, r.cy = 14.5;
  return r;
}

/// A plane whose depth grows by 2 mm per column from 1.5 m, with the 6 x 6 hole at (17, 12) NaN.
Cloud
planeWithHole()
{
  Cloud c(kWidth, kHeight);
  const PinholeRays r = rays();
  for (int v = 0; v < kHeight; ++v)
    for (int u = 0; u < kWidth; ++u) {
      pcl::PointXYZ& p = c.at(u, v);
      const float z = 1.5f + 0.002f * u;
      p.x = static_cast<float>((u - r.cx) / r.fx * z);
      p.y = static_cast<float>((v - r.cy) / r.fy * z);
      p.z = z;
      if (u >= 17 && u < 23 && v >= 12 && v < 18)
        p.x = p.y = p.z = std::numeric_limits<float>::quiet_NaN();
    }
  c.is_dense = false;
  return c;
}
} // namespace

TEST(OpencvInpaint, AHoleInAPlaneIsFilledNearThePlaneOnItsRaysAndMeasuredPointsKeepTheirBits)
{
  const Cloud in = planeWithHole();
  for (const InpaintMethod method : {InpaintMethod::telea, InpaintMethod::navier_stokes}) {
    const Cloud out = inpaintDepth(in, rays(), method, 3.0);
    ASSERT_EQ(out.width, in.width);
    ASSERT_EQ(out.height, in.height);
    EXPECT_TRUE(out.is_dense) << toString(method);
    for (int v = 0; v < kHeight; ++v)
      for (int u = 0; u < kWidth; ++u) {
        const pcl::PointXYZ &p = out.at(u, v), &q = in.at(u, v);
        if (std::isfinite(q.z)) {
          EXPECT_EQ(std::memcmp(&p, &q, sizeof(float) * 3), 0) << u << ", " << v;
          continue;
        }
        // Within a few millimetres (the image holds whole millimetres) of the plane.
        EXPECT_NEAR(p.z, 1.5f + 0.002f * u, 0.006f) << toString(method) << " " << u << ", " << v;
        EXPECT_NEAR(p.x / p.z, (u - 19.5) / 40.0, 1e-6);
        EXPECT_NEAR(p.y / p.z, (v - 14.5) / 40.0, 1e-6);
      }
  }
}

TEST(OpencvInpaint, BadInputIsRefusedWithWhatIsWrong)
{
  const Cloud in = planeWithHole();
  const auto message = [](const std::function<void()>& f) {
    try {
      f();
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(message([&] { inpaintDepth(in, rays(), InpaintMethod::telea, 0.5); }).find("radius"), std::string::npos);
  Cloud unorganized = in;
  unorganized.width = static_cast<std::uint32_t>(in.size());
  unorganized.height = 1;
  unorganized.points.pop_back();
  EXPECT_NE(message([&] { inpaintDepth(unorganized, rays(), InpaintMethod::telea, 3.0); }).find("not organized"),
            std::string::npos);
  Cloud far = in;
  far.at(3, 4).z = 70.0f;
  const std::string e = message([&] { inpaintDepth(far, rays(), InpaintMethod::navier_stokes, 3.0); });
  EXPECT_NE(e.find("pixel (3, 4)"), std::string::npos) << e;
  EXPECT_NE(e.find("65.535"), std::string::npos) << e;
}
