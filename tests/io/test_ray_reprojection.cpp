// reprojectOntoRays and the depth-image encoding of a filtered frame (cloudToDepthImage(input,
// filtered, ...)): points on their pixels' rays where the rays meet the filtered surface, a
// grazing surface bounded, moves along the rays kept, the invalid-pixel rules and the errors.
#include "test_support.h"

#include <range_nlm/io/depth_image.h>
#include <range_nlm/io/ray_reprojection.h>
#include <range_nlm/nonlocal_means_filter.h>

#include "io/ray_reprojection_builds.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <random>

using namespace range_nlm;
using Cloud = pcl::PointCloud<pcl::PointXYZ>;

namespace
{

constexpr int kWidth = 96, kHeight = 72;
constexpr double kFocal = 80.0;

/// The intrinsics test::makeCloud renders with.
DepthIntrinsics
intrinsicsOf(double depth_scale)
{
  DepthIntrinsics k;
  k.fx = k.fy = kFocal;
  k.cx = (kWidth - 1) / 2.0;
  k.cy = (kHeight - 1) / 2.0;
  k.depth_scale = depth_scale;
  return k;
}

Eigen::Vector3d
vec(const pcl::PointXYZ& p)
{
  return Eigen::Vector3d(p.x, p.y, p.z);
}

/// The plane 0.3 x - 0.2 y + z = 1.2 (tilted against every ray), unit normal and offset.
const Eigen::Vector3d kTiltedNormal = Eigen::Vector3d(0.3, -0.2, 1.0).normalized();
const double kTiltedOffset = 1.2 / Eigen::Vector3d(0.3, -0.2, 1.0).norm();

/// `noisy` moved onto the plane (n, c) the way several filter moves might put it there: along
/// the normal by the point's height, then along its ray by `ray_move` times a random amount,
/// then across within the plane (lateral offsets of a few pixels): only the plane is common.
Cloud
movedOntoPlane(const Cloud& noisy, const Eigen::Vector3d& n, double c, double ray_move, std::uint64_t seed)
{
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  const Eigen::Vector3d along = n.unitOrthogonal(), other = n.cross(along);
  Cloud out = noisy;
  for (pcl::PointXYZ& p : out) {
    if (!std::isfinite(p.z))
      continue;
    Eigen::Vector3d x = vec(p);
    x *= 1.0 + ray_move * unit(rng); // along the ray first ...
    x -= (n.dot(x) - c) * n;         // ... then along the normal onto the plane ...
    x += 0.01 * (unit(rng) * along + unit(rng) * other); // ... and within it
    p = pcl::PointXYZ(float(x.x()), float(x.y()), float(x.z()));
  }
  return out;
}

/// Largest distance of the valid points of `cloud` from the plane n . x = c.
double
largestPlaneDistance(const Cloud& cloud, const Eigen::Vector3d& n, double c)
{
  double largest = 0.0;
  for (const pcl::PointXYZ& p : cloud)
    if (std::isfinite(p.z))
      largest = std::max(largest, std::fabs(n.dot(vec(p)) - c));
  return largest;
}

} // namespace

TEST(RayReprojection, PngOfPointsMovedOntoATiltedPlaneLiesOnThatPlaneWithinTheQuantization)
{
  const double scale = 5000.0;
  const Cloud noisy = test::makeCloud(kWidth, kHeight, test::plane(Eigen::Vector3d(0.3, -0.2, 1.0), 1.2), 0.01, 7,
                                      kFocal);
  for (double ray_move : {0.0, 0.01}) {
    const Cloud filtered = movedOntoPlane(noisy, kTiltedNormal, kTiltedOffset, ray_move, 11);
    ASSERT_LT(largestPlaneDistance(filtered, kTiltedNormal, kTiltedOffset), 1e-6);
    const Cloud png = depthImageToCloud(cloudToDepthImage(noisy, filtered, scale), intrinsicsOf(scale));
    // Rounding z to 1 / scale moves a point along its ray by at most 0.5 / scale * |p| / z,
    // which changes its distance from the plane by that times |n . r| < 1; plus float rounding.
    double bound = 0.0;
    for (const pcl::PointXYZ& p : png)
      bound = std::max(bound, 0.5 / scale * vec(p).norm() / p.z);
    EXPECT_LE(largestPlaneDistance(png, kTiltedNormal, kTiltedOffset), bound + 1e-6) << "ray move " << ray_move;
    // z alone (the encoding of a cloud already on its rays) leaves the points off the plane by
    // the lateral offsets' height change, far beyond the quantization.
    const Cloud z_only = depthImageToCloud(cloudToDepthImage(filtered, scale), intrinsicsOf(scale));
    EXPECT_GT(largestPlaneDistance(z_only, kTiltedNormal, kTiltedOffset), 10 * bound) << "ray move " << ray_move;
  }
}

TEST(RayReprojection, FilteredTiltedPlaneAsPngIsAsCloseToThePlaneAsTheFilteredCloud)
{
  const Cloud noisy = test::makeCloud(kWidth, kHeight, test::plane(Eigen::Vector3d(0.3, -0.2, 1.0), 1.2), 0.004, 3,
                                      kFocal);
  NonLocalMeansFilter<pcl::PointXYZ> filter; // the default: two passes along the normals
  FilterParameters parameters = FilterParameters::recommended();
  parameters.threads = 1;
  filter.setParameters(parameters);
  filter.setInputCloud(Cloud::ConstPtr(new Cloud(noisy)));
  Cloud filtered;
  filter.filter(filtered);
  const double scale = 5000.0;
  const Cloud png = depthImageToCloud(cloudToDepthImage(noisy, filtered, scale), intrinsicsOf(scale));
  const Cloud z_only = depthImageToCloud(cloudToDepthImage(filtered, scale), intrinsicsOf(scale));
  const double pcd_rmse = test::planeRmse(filtered, kTiltedNormal, kTiltedOffset);
  const double png_rmse = test::planeRmse(png, kTiltedNormal, kTiltedOffset);
  ASSERT_LT(pcd_rmse, 0.6 * test::planeRmse(noisy, kTiltedNormal, kTiltedOffset));
  // Within 2 % and the quantization's own RMS (0.2 mm / sqrt(12) along the ray).
  EXPECT_NEAR(png_rmse, pcd_rmse, 0.02 * pcd_rmse + 0.2e-3 / std::sqrt(12.0));
  EXPECT_GT(test::planeRmse(z_only, kTiltedNormal, kTiltedOffset), 1.1 * pcd_rmse);
}

TEST(RayReprojection, RidgeAsPngIsNoRougherThanTheInputWhereTheWindowsPlanesDisagree)
{
  // A ridge 1 m away (faces z = 1 - 0.8 |x|, 39 degrees from the image plane) with 3 mm noise
  // along the rays. The filtered points lie on the surface but three pixels across their rays,
  // as a filter moving points along tilted normals puts them: next to the ridge the plane fitted
  // around a point is the other face's, and carried along the ray in full it leaves the band
  // rougher than the input (3.16 mm RMS against 2.33 without the weight).
  constexpr double focal = 300.0, slope = 0.8;
  constexpr int shift = 3, band = 3;
  const test::DepthFunction ridge = test::crease(kWidth / 2, 1.0, slope);
  const Cloud input = test::makeCloud(kWidth, kHeight, ridge, 0.003, 3, focal);
  const Cloud surface = test::makeCloud(kWidth, kHeight, ridge, 0.0, 3, focal);
  Cloud filtered(kWidth, kHeight);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (int v = 0; v < kHeight; ++v)
    for (int u = 0; u < kWidth; ++u)
      filtered.at(u, v) = u + shift < kWidth ? surface.at(u + shift, v) : pcl::PointXYZ(nan, nan, nan);
  const Cloud out = reprojectOntoRays(input, filtered);
  // RMS distance over the band around the ridge from the face each pixel sees.
  auto rms = [&](const Cloud& cloud) {
    double sum = 0.0;
    int count = 0;
    for (int v = 0; v < kHeight; ++v)
      for (int u = kWidth / 2 - band; u <= kWidth / 2 + band; ++u) {
        const double side = surface.at(u, v).x < 0.0f ? -1.0 : 1.0;
        const Eigen::Vector3d face(side * slope, 0.0, 1.0);
        const double d = (face.dot(vec(cloud.at(u, v))) - 1.0) / face.norm();
        sum += d * d;
        ++count;
      }
    return std::sqrt(sum / count);
  };
  EXPECT_LE(rms(out), rms(input));
}

TEST(RayReprojection, GrazingSurfaceStaysOnItsRaysWithABoundedMove)
{
  // A plane seen almost edge-on by a narrow camera: the rays meet it at 73 to 85 degrees from
  // its normal, at depths 1.3 to 5 m.
  const double focal = 400.0;
  const Eigen::Vector3d n = Eigen::Vector3d(1.0, 0.0, 0.2).normalized();
  const double c = n.dot(Eigen::Vector3d(0.0, 0.0, 2.0));
  Cloud input(kWidth, kHeight), filtered(kWidth, kHeight);
  std::mt19937_64 rng(5);
  std::normal_distribution<double> noise(0.0, 0.003);
  double largest_move = 0.0;
  for (int v = 0; v < kHeight; ++v)
    for (int u = 0; u < kWidth; ++u) {
      const Eigen::Vector3d ray((u - (kWidth - 1) / 2.0) / focal, (v - (kHeight - 1) / 2.0) / focal, 1.0);
      const Eigen::Vector3d p = c / n.dot(ray) * ray;
      const Eigen::Vector3d moved = p + noise(rng) * n; // a filter's move along the normal
      input.at(u, v) = pcl::PointXYZ(float(p.x()), float(p.y()), float(p.z()));
      filtered.at(u, v) = pcl::PointXYZ(float(moved.x()), float(moved.y()), float(moved.z()));
      largest_move = std::max(largest_move, (moved - p).norm());
    }
  RayReprojectionParameters parameters;
  RayReprojectionCounts counts;
  const Cloud out = reprojectOntoRays(input, filtered, parameters, &counts);
  EXPECT_GT(counts.grazing, out.size() / 2);
  // The part of a move m along the ray is kept (|m| cos), the part across it is carried at most
  // |m| sin / min_cos: together at most |m| sqrt(1 + 1 / min_cos^2).
  const double bound = largest_move * std::sqrt(1.0 + 1.0 / (parameters.min_cos * parameters.min_cos));
  for (std::size_t i = 0; i < out.size(); ++i) {
    const Eigen::Vector3d p = vec(input[i]), o = vec(out[i]);
    ASSERT_TRUE(o.allFinite()) << i;
    EXPECT_LT(o.normalized().cross(p.normalized()).norm(), 1e-6) << "off its ray at " << i;
    EXPECT_LE(std::fabs(o.norm() - p.norm()), bound + 1e-6) << i;
  }
}

TEST(RayReprojection, MoveAlongTheRayIsKeptAndUnmovedPointsStay)
{
  Cloud input = test::makeCloud(kWidth, kHeight, test::plane(Eigen::Vector3d(0.3, -0.2, 1.0), 1.2), 0.004, 9, kFocal);
  Cloud filtered = input;
  std::mt19937_64 rng(2);
  std::uniform_real_distribution<double> move(-0.01, 0.01);
  for (std::size_t i = 0; i < filtered.size(); i += 2) { // every other point moves along its ray
    const double k = 1.0 + move(rng);
    filtered[i] = pcl::PointXYZ(float(k * input[i].x), float(k * input[i].y), float(k * input[i].z));
  }
  RayReprojectionCounts counts;
  const Cloud out = reprojectOntoRays(input, filtered, RayReprojectionParameters(), &counts);
  EXPECT_EQ(counts.unmoved, input.size() / 2);
  for (std::size_t i = 0; i < out.size(); ++i) {
    if (i % 2 == 1) {
      EXPECT_EQ(out[i].z, input[i].z) << i;
      continue;
    }
    EXPECT_NEAR(out[i].x, filtered[i].x, 1e-6) << i;
    EXPECT_NEAR(out[i].y, filtered[i].y, 1e-6) << i;
    EXPECT_NEAR(out[i].z, filtered[i].z, 1e-6) << i;
  }
}

TEST(RayReprojection, InvalidPixelsFollowTheRules)
{
  const float nan = std::numeric_limits<float>::quiet_NaN();
  Cloud input = test::makeCloud(kWidth, kHeight, test::plane(Eigen::Vector3d(0, 0, 1), 1.0), 0.002, 4, kFocal);
  Cloud filtered = input;
  for (pcl::PointXYZ& p : filtered)
    p.z += 0.001f;
  input[10] = pcl::PointXYZ(nan, nan, nan);    // a hole the filter filled: kept as it is
  filtered[20] = pcl::PointXYZ(nan, nan, nan); // an invalid output: NaN, 0 in the image
  input[30] = filtered[30] = pcl::PointXYZ(nan, nan, nan);
  RayReprojectionCounts counts;
  const Cloud out = reprojectOntoRays(input, filtered, RayReprojectionParameters(), &counts);
  EXPECT_FALSE(out.is_dense);
  EXPECT_EQ(counts.without_ray, 1u);
  EXPECT_EQ(out[10].z, filtered[10].z);
  for (std::size_t i : {std::size_t(20), std::size_t(30)})
    EXPECT_TRUE(std::isnan(out[i].x) && std::isnan(out[i].y) && std::isnan(out[i].z)) << i;
  const DepthImage image = cloudToDepthImage(input, filtered, 1000.0);
  EXPECT_EQ(image.values[20], 0);
  EXPECT_EQ(image.values[30], 0);
  EXPECT_EQ(image.values[10], std::lround(filtered[10].z * 1000.0));
}

TEST(RayReprojection, BadInputIsRefusedWithItsName)
{
  const Cloud a = test::makeCloud(8, 6, test::plane(Eigen::Vector3d(0, 0, 1), 1.0), 0.0, 1, 10.0);
  const Cloud b = test::makeCloud(6, 8, test::plane(Eigen::Vector3d(0, 0, 1), 1.0), 0.0, 1, 10.0);
  EXPECT_NE(test::errorOf([&] { reprojectOntoRays(a, b); }).find("6 x 8"), std::string::npos);
  EXPECT_NE(test::errorOf([&] { reprojectOntoRays(Cloud(), a); }).find("input cloud"), std::string::npos);
  RayReprojectionParameters p;
  p.min_cos = 0.0;
  EXPECT_NE(test::errorOf([&] { reprojectOntoRays(a, a, p); }).find("min_cos"), std::string::npos);
  p = RayReprojectionParameters();
  p.window = 4;
  EXPECT_NE(test::errorOf([&] { reprojectOntoRays(a, a, p); }).find("window"), std::string::npos);
  p = RayReprojectionParameters();
  p.range_gate = std::numeric_limits<double>::quiet_NaN();
  EXPECT_NE(test::errorOf([&] { reprojectOntoRays(a, a, p); }).find("range_gate"), std::string::npos);
  EXPECT_NE(test::errorOf([&] { cloudToDepthImage(a, a, 0.0); }).find("depth_scale"), std::string::npos);
}

// The windows' planes summed a row's pixels at a time, in every instruction-set build this CPU
// runs, give the bits of the pixel-by-pixel reference (and its counts): on frames whose widths
// are no multiple of the lanes, with holes, a depth step and a crease, points filtered by the
// default and moved by hand in every direction, for the narrowest, the default and a wide window.
TEST(RayReprojection, EveryBuildGivesTheReferenceBits)
{
  ASSERT_GE(detail::rayReprojectionBuilds(), 2u);
  struct Scene
  {
    int width, height;
    test::DepthFunction depth;
  };
  const Scene scenes[] = {{61, 37, test::step(30, 0.9, 1.6)}, {kWidth, kHeight, test::crease(40, 1.1, 0.7)},
                          {9, 13, test::plane(kTiltedNormal, kTiltedOffset)}};
  NonLocalMeansFilter<pcl::PointXYZ> filter;
  std::mt19937_64 rng(17);
  std::uniform_real_distribution<float> unit(-1.0f, 1.0f);
  for (const Scene& scene : scenes) {
    Cloud input = test::makeCloud(scene.width, scene.height, scene.depth, 0.004, 5);
    test::punchHoles(input, 0.08, 6);
    filter.setInputCloud(Cloud::ConstPtr(new Cloud(input)));
    Cloud filtered;
    filter.filter(filtered);
    // Some points moved by hand as well, and one left where it was.
    for (std::size_t i = 0; i < filtered.size(); i += 7)
      if (std::isfinite(filtered[i].z)) {
        filtered[i].x += 0.002f * unit(rng), filtered[i].y += 0.002f * unit(rng), filtered[i].z += 0.002f * unit(rng);
      }
    filtered[filtered.size() / 2] = input[filtered.size() / 2];
    for (int window : {3, 5, 9}) {
      RayReprojectionParameters parameters;
      parameters.window = window;
      RayReprojectionCounts reference_counts;
      const Cloud reference = detail::reprojectOntoRaysWithBuild(0, input, filtered, parameters, &reference_counts);
      EXPECT_GT(reference_counts.on_plane, filtered.size() / 2);
      const std::vector<Eigen::Vector3d> planes = detail::surfacePlaneNormalsWithBuild(0, filtered, parameters);
      for (std::size_t build = 1; build < detail::rayReprojectionBuilds(); ++build) {
        const std::vector<Eigen::Vector3d> normals = detail::surfacePlaneNormalsWithBuild(build, filtered, parameters);
        ASSERT_EQ(normals.size(), planes.size());
        for (std::size_t i = 0; i < planes.size(); ++i)
          ASSERT_EQ(std::memcmp(normals[i].data(), planes[i].data(), sizeof(double) * 3), 0)
              << scene.width << " x " << scene.height << ", window " << window << ", build " << build << ", pixel "
              << i << ": " << normals[i].transpose() << " against " << planes[i].transpose();
        RayReprojectionCounts counts;
        const Cloud out = detail::reprojectOntoRaysWithBuild(build, input, filtered, parameters, &counts);
        ASSERT_EQ(out.size(), reference.size());
        EXPECT_EQ(std::memcmp(out.points.data(), reference.points.data(), out.size() * sizeof(pcl::PointXYZ)), 0)
            << scene.width << " x " << scene.height << ", window " << window << ", build " << build;
        EXPECT_EQ(counts.on_plane, reference_counts.on_plane);
        EXPECT_EQ(counts.grazing, reference_counts.grazing);
        EXPECT_EQ(counts.unmoved, reference_counts.unmoved);
      }
    }
  }
}
