// Shading, mean curvature, colour scales, before/after images, coloured clouds, PNG output and
// the range_nlm_render tool.
#include "test_support.h"

#include <range_nlm/io/depth_image.h>
#include <range_nlm/eval/render.h>

#include <pcl/io/pcd_io.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <string>

#include <sys/wait.h>
#include <unistd.h>

namespace fs = std::filesystem;
using namespace range_nlm;

namespace
{

constexpr int kWidth = 120;
constexpr int kHeight = 100;
constexpr double kFocal = 150.0;

/// Depth along z of the sphere |p - (0, 0, centre_z)| = radius seen through ray (a, b, 1):
/// the near intersection (seen from outside) or, with `inside`, the far one.
test::DepthFunction
sphere(double centre_z, double radius, bool inside = false)
{
  return [=](double a, double b, int, int) {
    const double dd = a * a + b * b + 1.0;
    const double disc = centre_z * centre_z - dd * (centre_z * centre_z - radius * radius);
    if (disc < 0.0)
      return std::numeric_limits<double>::quiet_NaN();
    return (centre_z + (inside ? 1.0 : -1.0) * std::sqrt(disc)) / dd;
  };
}

/// Cylinder x^2 + (z - centre_z)^2 = radius^2 (axis along y), near side.
test::DepthFunction
cylinder(double centre_z, double radius)
{
  return [=](double a, double, int, int) {
    const double dd = a * a + 1.0;
    const double disc = centre_z * centre_z - dd * (centre_z * centre_z - radius * radius);
    if (disc < 0.0)
      return std::numeric_limits<double>::quiet_NaN();
    return (centre_z - std::sqrt(disc)) / dd;
  };
}

Grid
makeGrid(const test::DepthFunction& depth, double sigma = 0.0, std::uint64_t seed = 1)
{
  return gridFromCloud(test::makeCloud(kWidth, kHeight, depth, sigma, seed, kFocal));
}

/// Values at the points whose whole `margin` neighbourhood is valid (away from silhouettes).
std::vector<float>
interior(const Grid& grid, const std::vector<float>& values, int margin)
{
  std::vector<float> out;
  for (int v = margin; v < grid.height - margin; ++v)
    for (int u = margin; u < grid.width - margin; ++u) {
      bool all = true;
      for (int dv = -margin; dv <= margin && all; ++dv)
        for (int du = -margin; du <= margin && all; ++du)
          all = grid.valid[(v + dv) * grid.width + u + du] != 0;
      if (all)
        out.push_back(values[v * grid.width + u]);
    }
  return out;
}

float
median(std::vector<float> values)
{
  std::sort(values.begin(), values.end());
  return values[values.size() / 2];
}

std::string
readBytes(const std::string& path)
{
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

std::uint32_t
bigEndian32(const std::string& bytes, std::size_t at)
{
  return (std::uint32_t(std::uint8_t(bytes[at])) << 24) | (std::uint32_t(std::uint8_t(bytes[at + 1])) << 16) |
         (std::uint32_t(std::uint8_t(bytes[at + 2])) << 8) | std::uint32_t(std::uint8_t(bytes[at + 3]));
}

class RenderFiles : public ::testing::Test
{
protected:
  void SetUp() override
  {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::temp_directory_path() /
           ("range_nlm_render_" + std::string(info->name()) + "_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }

  fs::path dir_;
};

} // namespace

// ---- curvature ------------------------------------------------------------------------------

TEST(MeanCurvature, PlaneIsFlat)
{
  // Tilted plane 0.3 x + z = 1.2 seen at 1.0 ... 1.5 m.
  const Grid grid = makeGrid(test::plane(Eigen::Vector3d(0.3, 0.1, 1.0), 1.2));
  const RenderParameters parameters;
  const std::vector<float> h = meanCurvature(grid, parameters);
  ASSERT_EQ(h.size(), grid.size());
  std::size_t finite = 0;
  for (float value : h)
    if (std::isfinite(value)) {
      ++finite;
      EXPECT_LT(std::fabs(value), 0.02f);
    }
  EXPECT_EQ(finite, grid.size()); // borders included: the fit uses the available neighbours
}

TEST(MeanCurvature, SphereSeenFromOutsideIsPlusOneOverRadius)
{
  const double radius = 0.25;
  const Grid grid = makeGrid(sphere(1.0, radius));
  const std::vector<float> h = interior(grid, meanCurvature(grid, RenderParameters()), 4);
  ASSERT_GT(h.size(), 2000u);
  EXPECT_NEAR(median(h), 1.0 / radius, 0.01 / radius);
  std::size_t close = 0;
  for (float value : h)
    close += std::fabs(value - 1.0 / radius) < 0.05 / radius;
  EXPECT_GT(double(close) / h.size(), 0.95);
}

TEST(MeanCurvature, SphereSeenFromInsideIsNegative)
{
  // The camera sits inside a sphere of radius 2 m: the surface curves away from the viewer.
  const double radius = 2.0;
  const Grid grid = makeGrid(sphere(0.5, radius, true));
  const std::vector<float> h = interior(grid, meanCurvature(grid, RenderParameters()), 4);
  ASSERT_GT(h.size(), 5000u);
  EXPECT_NEAR(median(h), -1.0 / radius, 0.02 / radius);
}

TEST(MeanCurvature, CylinderIsHalfTheInverseRadius)
{
  // Mean, not Gaussian (0) or maximal (1/R) curvature.
  const double radius = 0.3;
  const Grid grid = makeGrid(cylinder(1.2, radius));
  const std::vector<float> h = interior(grid, meanCurvature(grid, RenderParameters()), 4);
  ASSERT_GT(h.size(), 2000u);
  EXPECT_NEAR(median(h), 0.5 / radius, 0.02 / radius);
}

TEST(MeanCurvature, DepthStepsDoNotEnterTheFit)
{
  // Two fronto-parallel planes 0.3 m apart: a flat scene with a jump edge.
  const Grid grid = makeGrid(test::step(kWidth / 2, 1.0, 1.3));
  const std::vector<float> h = meanCurvature(grid, RenderParameters());
  for (int v = 0; v < grid.height; ++v)
    for (int u = 0; u < grid.width; ++u)
      EXPECT_LT(std::fabs(h[v * grid.width + u]), 0.02f) << "pixel " << u << ", " << v;
}

TEST(MeanCurvature, InvalidPointsStayNaN)
{
  auto cloud = test::makeCloud(kWidth, kHeight, sphere(1.0, 0.25), 0.0, 1, kFocal);
  test::punchHoles(cloud, 0.1, 7);
  const Grid grid = gridFromCloud(cloud);
  const std::vector<float> h = meanCurvature(grid, RenderParameters());
  for (std::size_t i = 0; i < grid.size(); ++i)
    if (!grid.valid[i])
      EXPECT_TRUE(std::isnan(h[i]));
}

TEST(MeanCurvature, NoiseRaisesTheCurvatureScale)
{
  const Grid clean = makeGrid(sphere(1.0, 0.25));
  const Grid noisy = makeGrid(sphere(1.0, 0.25), 0.002, 3);
  const RenderParameters parameters;
  const float clean_limit = curvatureLimit(meanCurvature(clean, parameters), 95.0f);
  const float noisy_limit = curvatureLimit(meanCurvature(noisy, parameters), 95.0f);
  EXPECT_NEAR(clean_limit, 4.0f, 0.3f);
  EXPECT_GT(noisy_limit, 1.5f * clean_limit);
}

// ---- shading --------------------------------------------------------------------------------

TEST(Shading, PlaneUnderAxisLightIsUniform)
{
  const Eigen::Vector3d n(0.3, -0.2, 1.0);
  const Grid grid = makeGrid(test::plane(n, 1.2));
  RenderParameters parameters;
  parameters.light = Light::optical_axis;
  const std::vector<float> intensity = shadingIntensity(grid, parameters);
  const float expected = float(1.0 / n.norm());
  for (float value : intensity)
    EXPECT_NEAR(value, expected, 1e-4f);
  const RgbImage image = renderShaded(grid, parameters);
  const Rgb first = image.at(0, 0);
  EXPECT_EQ(first, shade(expected, parameters.ambient));
  for (int v = 0; v < image.height; ++v)
    for (int u = 0; u < image.width; ++u) {
      const Rgb c = image.at(u, v);
      EXPECT_LE(std::abs(int(c[0]) - int(first[0])), 1);
      EXPECT_TRUE(c[0] == c[1] && c[1] == c[2]);
    }
}

TEST(Shading, HeadlightIsTheCosineOfTheViewRay)
{
  const Grid grid = makeGrid(test::plane(Eigen::Vector3d(0.0, 0.0, 1.0), 1.0));
  const std::vector<float> intensity = shadingIntensity(grid, RenderParameters());
  for (std::size_t i = 0; i < grid.size(); ++i) {
    const double r = std::sqrt(double(grid.x[i]) * grid.x[i] + double(grid.y[i]) * grid.y[i] +
                               double(grid.z[i]) * grid.z[i]);
    EXPECT_NEAR(intensity[i], grid.z[i] / r, 1e-4);
  }
  // Corner darker than centre.
  EXPECT_LT(intensity[0], intensity[(kHeight / 2) * kWidth + kWidth / 2] - 0.05f);
}

TEST(Shading, ShadeAndBackground)
{
  EXPECT_EQ(shade(1.0f, 0.1f), (Rgb{255, 255, 255}));
  EXPECT_EQ(shade(0.0f, 0.1f), (Rgb{26, 26, 26}));
  EXPECT_EQ(shade(0.5f, 0.0f), (Rgb{128, 128, 128}));
  auto cloud = test::makeCloud(kWidth, kHeight, test::plane(Eigen::Vector3d(0, 0, 1), 1.0), 0.0, 1, kFocal);
  // Orientation: the image is the grid, row 0 on top, no flip.
  for (int v = 0; v < 10; ++v)
    for (int u = 0; u < 20; ++u)
      cloud.at(u, v).x = cloud.at(u, v).y = cloud.at(u, v).z = std::numeric_limits<float>::quiet_NaN();
  RenderParameters parameters;
  parameters.background = {10, 20, 30};
  const RgbImage image = renderShaded(gridFromCloud(cloud), parameters);
  ASSERT_EQ(image.width, kWidth);
  ASSERT_EQ(image.height, kHeight);
  EXPECT_EQ(image.at(0, 0), (Rgb{10, 20, 30}));
  EXPECT_EQ(image.at(19, 9), (Rgb{10, 20, 30}));
  EXPECT_NE(image.at(20, 9), (Rgb{10, 20, 30}));
  EXPECT_NE(image.at(19, 10), (Rgb{10, 20, 30}));
  EXPECT_NE(image.at(kWidth - 1, kHeight - 1), (Rgb{10, 20, 30}));
}

// ---- colour scale ---------------------------------------------------------------------------

TEST(ColourScale, CoolWarmEndsAndMiddle)
{
  EXPECT_EQ(coolWarm(0.0f), (Rgb{59, 76, 192}));
  EXPECT_EQ(coolWarm(0.5f), (Rgb{221, 221, 221}));
  EXPECT_EQ(coolWarm(1.0f), (Rgb{180, 4, 38}));
  EXPECT_EQ(coolWarm(-3.0f), coolWarm(0.0f));
  EXPECT_EQ(coolWarm(7.0f), coolWarm(1.0f));
  EXPECT_EQ(curvatureColour(0.0f, 2.0f), (Rgb{221, 221, 221}));
  EXPECT_EQ(curvatureColour(2.0f, 2.0f), (Rgb{180, 4, 38}));
  EXPECT_EQ(curvatureColour(50.0f, 2.0f), (Rgb{180, 4, 38}));
  EXPECT_EQ(curvatureColour(-2.0f, 2.0f), (Rgb{59, 76, 192}));
  // Monotone toward the ends: red grows away from blue.
  EXPECT_GT(curvatureColour(1.0f, 2.0f)[0], curvatureColour(0.0f, 2.0f)[0] - 10);
  EXPECT_LT(curvatureColour(1.0f, 2.0f)[2], curvatureColour(0.0f, 2.0f)[2]);
  EXPECT_LT(curvatureColour(-1.0f, 2.0f)[0], curvatureColour(0.0f, 2.0f)[0]);
}

TEST(ColourScale, PercentileLimit)
{
  const float nan = std::numeric_limits<float>::quiet_NaN();
  EXPECT_FLOAT_EQ(curvatureLimit({1, -2, 3, nan, -4, 5}, 50.0f), 3.0f);
  EXPECT_FLOAT_EQ(curvatureLimit({1, -2, 3, nan, -4, 5}, 100.0f), 5.0f);
  std::vector<float> ramp;
  for (int i = 1; i <= 101; ++i)
    ramp.push_back(i % 2 ? float(i) : -float(i));
  EXPECT_FLOAT_EQ(curvatureLimit(ramp, 95.0f), 96.0f);
  EXPECT_FLOAT_EQ(curvatureLimit({1.0f, 2.0f}, 50.0f), 1.5f);
  EXPECT_EQ(curvatureLimit({nan, nan}, 95.0f), 1.0f);
  EXPECT_GT(curvatureLimit({0.0f, 0.0f}, 95.0f), 0.0f);
  EXPECT_THROW(curvatureLimit({1.0f}, 0.0f), std::invalid_argument);
  EXPECT_THROW(curvatureLimit({1.0f}, 101.0f), std::invalid_argument);
}

// ---- images ---------------------------------------------------------------------------------

TEST(SideBySide, LayoutAndGap)
{
  const RgbImage left(4, 3, {1, 2, 3});
  const RgbImage right(5, 3, {7, 8, 9});
  const RgbImage both = sideBySide(left, right, 2, {255, 0, 255});
  ASSERT_EQ(both.width, 11);
  ASSERT_EQ(both.height, 3);
  for (int v = 0; v < 3; ++v) {
    for (int u = 0; u < 4; ++u)
      EXPECT_EQ(both.at(u, v), (Rgb{1, 2, 3}));
    EXPECT_EQ(both.at(4, v), (Rgb{255, 0, 255}));
    EXPECT_EQ(both.at(5, v), (Rgb{255, 0, 255}));
    for (int u = 6; u < 11; ++u)
      EXPECT_EQ(both.at(u, v), (Rgb{7, 8, 9}));
  }
  EXPECT_THROW(sideBySide(left, RgbImage(4, 2, {0, 0, 0}), 0, {0, 0, 0}), std::invalid_argument);
}

TEST(BeforeAfter, CurvatureHalvesShareTheBeforeScale)
{
  const Grid before = makeGrid(sphere(1.0, 0.25), 0.002, 5);
  const Grid after = makeGrid(sphere(1.0, 0.25));
  RenderParameters parameters;
  parameters.gap = 6;
  const BeforeAfterImage result = renderBeforeAfter(before, after, RenderMode::curvature, parameters);
  ASSERT_EQ(result.image.width, 2 * kWidth + 6);
  ASSERT_EQ(result.image.height, kHeight);
  const float expected_limit = curvatureLimit(meanCurvature(before, parameters), parameters.percentile);
  EXPECT_FLOAT_EQ(result.curvature_limit, expected_limit);
  // Each half is exactly the single rendering on that scale.
  const RgbImage left = renderCurvature(before, expected_limit, parameters);
  const RgbImage right = renderCurvature(after, expected_limit, parameters);
  std::size_t mismatches = 0;
  for (int v = 0; v < kHeight; ++v) {
    for (int u = 0; u < kWidth; ++u) {
      mismatches += result.image.at(u, v) != left.at(u, v);
      mismatches += result.image.at(kWidth + 6 + u, v) != right.at(u, v);
    }
    for (int u = kWidth; u < kWidth + 6; ++u)
      EXPECT_EQ(result.image.at(u, v), parameters.gap_colour);
  }
  EXPECT_EQ(mismatches, 0u);
  // The clean half is pale (curvature 4 on a scale of several times that), the noisy one is not.
  auto saturated = [&](int offset) {
    std::size_t count = 0;
    for (int v = 0; v < kHeight; ++v)
      for (int u = 0; u < kWidth; ++u) {
        const Rgb c = result.image.at(offset + u, v);
        count += c == coolWarm(1.0f) || c == coolWarm(0.0f);
      }
    return count;
  };
  EXPECT_GT(saturated(0), 100u);
  EXPECT_EQ(saturated(kWidth + 6), 0u);
}

TEST(BeforeAfter, ScaleFromBothOrGiven)
{
  const Grid before = makeGrid(sphere(1.0, 0.25));
  const Grid after = makeGrid(sphere(1.0, 0.25), 0.003, 9);
  RenderParameters parameters;
  std::vector<float> both = meanCurvature(before, parameters);
  const std::vector<float> h_after = meanCurvature(after, parameters);
  both.insert(both.end(), h_after.begin(), h_after.end());
  EXPECT_FLOAT_EQ(renderBeforeAfter(before, after, RenderMode::curvature, parameters, ScaleSource::both).curvature_limit,
                  curvatureLimit(both, parameters.percentile));
  parameters.curvature_limit = 12.5f;
  EXPECT_FLOAT_EQ(renderBeforeAfter(before, after, RenderMode::curvature, parameters).curvature_limit, 12.5f);
}

TEST(BeforeAfter, ShadedAndSizeMismatch)
{
  const Grid before = makeGrid(sphere(1.0, 0.25), 0.002, 5);
  const Grid after = makeGrid(sphere(1.0, 0.25));
  RenderParameters parameters;
  const BeforeAfterImage result = renderBeforeAfter(before, after, RenderMode::shaded, parameters);
  EXPECT_EQ(result.image.width, 2 * kWidth + parameters.gap);
  const RgbImage right = renderShaded(after, parameters);
  for (int v = 0; v < kHeight; ++v)
    for (int u = 0; u < kWidth; ++u)
      ASSERT_EQ(result.image.at(kWidth + parameters.gap + u, v), right.at(u, v));
  const Grid small = gridFromCloud(test::makeCloud(50, 40, sphere(1.0, 0.25), 0.0, 1, kFocal));
  try {
    renderBeforeAfter(before, small, RenderMode::shaded, parameters);
    ADD_FAILURE() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("50 x 40"), std::string::npos) << e.what();
  }
}

TEST(RenderParameters, ValidateNamesTheParameter)
{
  auto message = [](const RenderParameters& p) {
    try {
      p.validate();
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  RenderParameters p;
  EXPECT_EQ(message(p), "");
  p.normal_window = 4;
  EXPECT_NE(message(p).find("normal_window"), std::string::npos);
  p = RenderParameters();
  p.curvature_window = 3;
  EXPECT_NE(message(p).find("curvature_window"), std::string::npos);
  p = RenderParameters();
  p.percentile = 0.0f;
  EXPECT_NE(message(p).find("percentile"), std::string::npos);
  p = RenderParameters();
  p.curvature_limit = -1.0f;
  EXPECT_NE(message(p).find("curvature_limit"), std::string::npos);
  p = RenderParameters();
  p.max_depth_step = 0.0f;
  EXPECT_NE(message(p).find("max_depth_step"), std::string::npos);
  EXPECT_THROW(renderCurvature(makeGrid(sphere(1.0, 0.25)), 0.0f, RenderParameters()), std::invalid_argument);
}

// ---- coloured cloud -------------------------------------------------------------------------

TEST(ColorizeByCurvature, CopiesPointsAndColoursByCurvature)
{
  auto cloud = test::makeCloud(kWidth, kHeight, sphere(1.0, 0.25), 0.001, 11, kFocal);
  test::punchHoles(cloud, 0.05, 3);
  cloud.sensor_origin_ = Eigen::Vector4f(0, 0, 0, 1);
  RenderParameters parameters;
  float limit = 0.0f;
  const pcl::PointCloud<pcl::PointXYZRGB> coloured = colorizeByCurvature(cloud, parameters, &limit);
  ASSERT_EQ(coloured.width, cloud.width);
  ASSERT_EQ(coloured.height, cloud.height);
  EXPECT_FALSE(coloured.is_dense);
  const Grid grid = gridFromCloud(cloud);
  const std::vector<float> h = meanCurvature(grid, parameters);
  EXPECT_FLOAT_EQ(limit, curvatureLimit(h, parameters.percentile));
  std::size_t coloured_points = 0;
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const auto& p = coloured[i];
    if (!grid.valid[i]) {
      EXPECT_TRUE(std::isnan(p.x) && std::isnan(p.y) && std::isnan(p.z));
      continue;
    }
    EXPECT_EQ(p.x, cloud[i].x);
    EXPECT_EQ(p.y, cloud[i].y);
    EXPECT_EQ(p.z, cloud[i].z);
    const Rgb expected = std::isfinite(h[i]) ? curvatureColour(h[i], limit) : parameters.no_estimate;
    EXPECT_EQ((Rgb{p.r, p.g, p.b}), expected);
    coloured_points += std::isfinite(h[i]);
  }
  EXPECT_GT(coloured_points, cloud.size() / 3);
  parameters.curvature_limit = 3.0f;
  colorizeByCurvature(cloud, parameters, &limit);
  EXPECT_EQ(limit, 3.0f);
}

// ---- PNG output -----------------------------------------------------------------------------

TEST_F(RenderFiles, RgbPngIsReadableWithTheExpectedSize)
{
  const Grid grid = makeGrid(sphere(1.0, 0.25), 0.001, 2);
  const RgbImage image = renderShaded(grid, RenderParameters());
  const std::string out = path("shaded.png");
  saveRgbPng(out, image);
  const std::string bytes = readBytes(out);
  ASSERT_GT(bytes.size(), 33u);
  EXPECT_EQ(bytes.substr(0, 8), std::string("\x89PNG\r\n\x1a\n", 8));
  EXPECT_EQ(bigEndian32(bytes, 16), std::uint32_t(kWidth));
  EXPECT_EQ(bigEndian32(bytes, 20), std::uint32_t(kHeight));
  EXPECT_EQ(std::uint8_t(bytes[24]), 8u); // bit depth
  EXPECT_EQ(std::uint8_t(bytes[25]), 2u); // colour type: RGB
  const detail::PngPixels pixels = detail::readPng(out);
  EXPECT_EQ(pixels.width, kWidth);
  EXPECT_EQ(pixels.height, kHeight);
  EXPECT_EQ(pixels.channels, 3);
  EXPECT_EQ(pixels.bit_depth, 8);
  EXPECT_EQ(pixels.bytes, image.rgb);
}

TEST_F(RenderFiles, WriteErrorNamesTheFile)
{
  const std::string out = path("missing/dir/image.png");
  try {
    saveRgbPng(out, RgbImage(3, 2, {1, 2, 3}));
    ADD_FAILURE() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find(out), std::string::npos) << e.what();
  }
  EXPECT_THROW(saveRgbPng(path("empty.png"), RgbImage()), std::invalid_argument);
}

// ---- the tool -------------------------------------------------------------------------------

namespace
{
struct ToolResult
{
  int status = -1;
  std::string output;
};

ToolResult
runRender(const std::string& args)
{
  const test::CommandResult c = test::runTool("range_nlm_render", args);
  return ToolResult{c.status, c.output};
}
} // namespace

TEST_F(RenderFiles, ToolHelpListsEveryOptionWithItsDefault)
{
  const ToolResult r = runRender("--help");
  ASSERT_EQ(r.status, 0) << r.output;
  for (const char* option : {"--before", "--after", "--mode", "--light", "--normal-window", "--curvature-window",
                             "--max-depth-step", "--curvature-limit", "--percentile", "--scale-from", "--gap",
                             "--threads", "--fx", "--fy", "--cx", "--cy", "--depth-scale", "--intrinsics"})
    EXPECT_NE(r.output.find(option), std::string::npos) << option;
  EXPECT_NE(r.output.find("(=shaded)"), std::string::npos);
  EXPECT_NE(r.output.find("(=5000)"), std::string::npos);
}

TEST_F(RenderFiles, ToolRendersPcdPngAndComparisons)
{
  auto cloud = test::makeCloud(kWidth, kHeight, sphere(1.0, 0.25), 0.002, 4, kFocal);
  const std::string before = path("before.pcd");
  ASSERT_EQ(pcl::io::savePCDFileBinary(before, cloud), 0);
  const std::string after = path("after.pcd");
  ASSERT_EQ(pcl::io::savePCDFileBinary(after, test::makeCloud(kWidth, kHeight, sphere(1.0, 0.25), 0.0, 4, kFocal)),
            0);

  ToolResult r = runRender(before + " " + path("single.png") + " --mode curvature");
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("curvature scale"), std::string::npos) << r.output;
  detail::PngPixels single = detail::readPng(path("single.png"));
  EXPECT_EQ(single.width, kWidth);
  EXPECT_EQ(single.height, kHeight);

  r = runRender("--before " + before + " --after " + after + " " + path("pair.png") + " --gap 4");
  ASSERT_EQ(r.status, 0) << r.output;
  const detail::PngPixels pair = detail::readPng(path("pair.png"));
  EXPECT_EQ(pair.width, 2 * kWidth + 4);
  EXPECT_EQ(pair.height, kHeight);

  r = runRender(before + " " + path("coloured.pcd") + " --mode curvature --curvature-limit 20");
  ASSERT_EQ(r.status, 0) << r.output;
  pcl::PointCloud<pcl::PointXYZRGB> coloured;
  ASSERT_EQ(pcl::io::loadPCDFile(path("coloured.pcd"), coloured), 0);
  EXPECT_EQ(coloured.width, std::uint32_t(kWidth));
  EXPECT_EQ(coloured.height, std::uint32_t(kHeight));

  // A depth PNG as input: a plane 1 m away, TUM encoding.
  const std::string depth = path("depth.png");
  saveDepthPng(depth, test::makeCloud(64, 48, test::plane(Eigen::Vector3d(0, 0, 1), 1.0), 0.0, 1, 60.0), 5000.0);
  r = runRender(depth + " " + path("depth_shaded.png") + " --fx 60 --fy 60 --cx 31.5 --cy 23.5 --light axis");
  ASSERT_EQ(r.status, 0) << r.output;
  const detail::PngPixels shaded = detail::readPng(path("depth_shaded.png"));
  ASSERT_EQ(shaded.width, 64);
  EXPECT_EQ(shaded.bytes[0], 255); // a fronto-parallel plane under the axis light: full intensity
  EXPECT_EQ(shaded.bytes[3 * (24 * 64 + 32)], 255);
}

TEST_F(RenderFiles, ToolErrors)
{
  auto cloud = test::makeCloud(kWidth, kHeight, sphere(1.0, 0.25), 0.0, 4, kFocal);
  const std::string input = path("in.pcd");
  ASSERT_EQ(pcl::io::savePCDFileBinary(input, cloud), 0);
  ToolResult r = runRender(input + " " + path("out.png") + " --mode glossy");
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.output.find("glossy"), std::string::npos) << r.output;
  r = runRender(input + " " + path("out.png") + " --normal-window 4");
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.output.find("--normal-window"), std::string::npos) << r.output;
  r = runRender(input + " " + path("out.pcd"));
  EXPECT_EQ(r.status, 2) << r.output;
  r = runRender(path("absent.pcd") + " " + path("out.png"));
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.output.find("absent.pcd"), std::string::npos) << r.output;
  r = runRender("--before " + input + " " + path("out.png"));
  EXPECT_EQ(r.status, 2) << r.output;
  const std::string small = path("small.pcd");
  ASSERT_EQ(pcl::io::savePCDFileBinary(small, test::makeCloud(30, 20, sphere(1.0, 0.25), 0.0, 1, kFocal)), 0);
  r = runRender("--before " + input + " --after " + small + " " + path("out.png"));
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.output.find("small.pcd"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(path("out.png")));
}

TEST_F(RenderFiles, DenoiseToolColorizesByCurvature)
{
  auto cloud = test::makeCloud(kWidth, kHeight, sphere(1.0, 0.25), 0.002, 6, kFocal);
  const std::string input = path("in.pcd");
  ASSERT_EQ(pcl::io::savePCDFileBinary(input, cloud), 0);
  auto denoise = [](const std::string& args) {
    const test::CommandResult c = test::runTool("range_nlm_denoise", args);
    return ToolResult{c.status, c.output};
  };
  ToolResult r = denoise(input + " " + path("plain.pcd") + " --quiet");
  ASSERT_EQ(r.status, 0) << r.output;
  r = denoise(input + " " + path("coloured.pcd") + " --quiet --colorize curvature --curvature-limit 10");
  ASSERT_EQ(r.status, 0) << r.output;
  pcl::PointCloud<pcl::PointXYZ> plain;
  pcl::PointCloud<pcl::PointXYZRGB> coloured;
  ASSERT_EQ(pcl::io::loadPCDFile(path("plain.pcd"), plain), 0);
  ASSERT_EQ(pcl::io::loadPCDFile(path("coloured.pcd"), coloured), 0);
  ASSERT_EQ(coloured.width, plain.width);
  ASSERT_EQ(coloured.height, plain.height);
  RenderParameters parameters;
  parameters.curvature_limit = 10.0f;
  const pcl::PointCloud<pcl::PointXYZRGB> expected = colorizeByCurvature(plain, parameters);
  std::size_t mismatches = 0, red_or_blue = 0;
  for (std::size_t i = 0; i < plain.size(); ++i) {
    if (!std::isfinite(plain[i].z)) {
      EXPECT_TRUE(std::isnan(coloured[i].x) && std::isnan(coloured[i].y) && std::isnan(coloured[i].z));
      continue;
    }
    mismatches += coloured[i].x != plain[i].x || coloured[i].y != plain[i].y || coloured[i].z != plain[i].z;
    mismatches += coloured[i].r != expected[i].r || coloured[i].g != expected[i].g || coloured[i].b != expected[i].b;
    red_or_blue += coloured[i].r != coloured[i].b;
  }
  EXPECT_EQ(mismatches, 0u);
  EXPECT_GT(red_or_blue, 1000u); // a sphere of curvature 4 on a scale of 10: visibly red
  r = denoise(input + " " + path("x.pcd") + " --colorize normals");
  EXPECT_EQ(r.status, 2) << r.output;
}
