// Tests of the synthetic range-frame generator: exact geometry, noise statistics, determinism,
// dropouts and motion.
#include <range_nlm/eval/metrics.h>
#include <range_nlm/eval/synthetic_scene.h>

#include "test_support.h"

#include <pcl/io/pcd_io.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <limits>
#include <map>
#include <numeric>
#include <set>

using namespace range_nlm;

namespace
{

constexpr double kPi = 3.14159265358979323846;

bool
valid(const pcl::PointXYZ& p)
{
  return std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z);
}

bool
valid(const pcl::PointNormal& p)
{
  return std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z);
}

/// Bitwise equality of two clouds (NaN equals NaN).
template <typename PointT>
bool
identical(const pcl::PointCloud<PointT>& a, const pcl::PointCloud<PointT>& b)
{
  return a.width == b.width && a.height == b.height &&
         std::memcmp(a.points.data(), b.points.data(), a.size() * sizeof(PointT)) == 0;
}

SceneOptions
planeOptions(double depth, NoiseModel noise)
{
  SceneOptions o;
  o.scene = SceneType::plane;
  o.plane_depth = depth;
  o.noise = noise;
  return o;
}

/// Standard deviation and mean of z - depth over the valid noisy pixels.
void
depthErrorStatistics(const SyntheticFrame& f, double depth, double& mean, double& stddev, std::size_t& count)
{
  double sum = 0.0, sum_sq = 0.0;
  count = 0;
  for (const auto& p : f.noisy)
    if (valid(p)) {
      const double e = double(p.z) - depth;
      sum += e;
      sum_sq += e * e;
      ++count;
    }
  mean = sum / double(count);
  stddev = std::sqrt(sum_sq / double(count) - mean * mean);
}

int
shapeIndexByName(const Scene& scene, const std::string& name)
{
  for (std::size_t i = 0; i < scene.shapes().size(); ++i)
    if (scene.shapes()[i]->name() == name)
      return int(i);
  return -1;
}

} // namespace

TEST(SyntheticScene, PlaneTruthIsExactAndNoiseFreeFrameEqualsTruth)
{
  SceneOptions o = planeOptions(1.5, NoiseModel::none);
  const SyntheticFrame f = renderFrame(o);
  ASSERT_EQ(f.truth.width, 640u);
  ASSERT_EQ(f.truth.height, 480u);
  ASSERT_EQ(f.noisy.size(), f.truth.size());
  const double cx = 319.5, cy = 239.5;
  for (int v = 0; v < 480; v += 7)
    for (int u = 0; u < 640; u += 5) {
      const pcl::PointNormal& t = f.truth.at(u, v);
      EXPECT_FLOAT_EQ(t.z, 1.5f);
      EXPECT_FLOAT_EQ(t.x, float((u - cx) / 525.0 * 1.5));
      EXPECT_FLOAT_EQ(t.y, float((v - cy) / 525.0 * 1.5));
      EXPECT_EQ(t.normal_x, 0.0f);
      EXPECT_EQ(t.normal_y, 0.0f);
      EXPECT_EQ(t.normal_z, -1.0f);
      const pcl::PointXYZ& n = f.noisy.at(u, v);
      EXPECT_FLOAT_EQ(n.x, t.x);
      EXPECT_FLOAT_EQ(n.y, t.y);
      EXPECT_FLOAT_EQ(n.z, t.z);
    }
  EXPECT_TRUE(f.noisy.is_dense);
}

TEST(SyntheticScene, IntrinsicsAreSettable)
{
  SceneOptions o = planeOptions(2.0, NoiseModel::none);
  o.width = 40;
  o.height = 30;
  o.fx = 50.0;
  o.fy = 60.0;
  o.cx = 10.0;
  o.cy = 5.0;
  const SyntheticFrame f = renderFrame(o);
  ASSERT_EQ(f.truth.width, 40u);
  ASSERT_EQ(f.truth.height, 30u);
  EXPECT_FLOAT_EQ(f.truth.at(10, 5).x, 0.0f);
  EXPECT_FLOAT_EQ(f.truth.at(10, 5).y, 0.0f);
  EXPECT_FLOAT_EQ(f.truth.at(35, 25).x, float(25.0 / 50.0 * 2.0));
  EXPECT_FLOAT_EQ(f.truth.at(35, 25).y, float(20.0 / 60.0 * 2.0));
}

TEST(SyntheticScene, BoxesSceneShowsEveryObjectOverTheDepthRange)
{
  SceneOptions o;
  o.noise = NoiseModel::none;
  const SyntheticFrame f = renderFrame(o);
  const Scene scene = Scene::build(o, 0);
  std::map<std::string, int> pixels;
  float z_min = 1e9f, z_max = 0.0f;
  std::size_t missing = 0;
  for (std::size_t i = 0; i < f.truth.size(); ++i) {
    const int s = f.shape_index[i];
    EXPECT_EQ(s >= 0, valid(f.truth[i]));
    EXPECT_EQ(s >= 0, valid(f.noisy[i]));
    if (s < 0) {
      ++missing;
      continue;
    }
    ++pixels[scene.shapes()[s]->name()];
    z_min = std::min(z_min, f.truth[i].z);
    z_max = std::max(z_max, f.truth[i].z);
  }
  // Floor and back wall (rectangles), two boxes, sphere, cylinder, ridged panel.
  EXPECT_GT(pixels["rectangle"], 100000);
  EXPECT_GT(pixels["box"], 20000);
  EXPECT_GT(pixels["sphere"], 5000);
  EXPECT_GT(pixels["cylinder"], 5000);
  EXPECT_GT(pixels["ridged panel"], 5000);
  EXPECT_EQ(scene.shapes().size(), 7u);
  EXPECT_GT(missing, 1000u) << "the finite room leaves invalid pixels";
  EXPECT_LT(z_min, 0.95f);
  EXPECT_GT(z_max, 2.9f);
  EXPECT_LE(z_max, 3.0f + 1e-5f);
}

namespace
{

/// Every truth point of the scene `o` lies on the surface of the shape its pixel records, with a
/// unit normal facing the camera that agrees with the shape's own normal (but at edges), and no
/// shape occludes it. Sets `checked` to the number of points checked.
void
expectTruthOnAnalyticSurfaces(const SceneOptions& o, std::size_t& checked)
{
  const SyntheticFrame f = renderFrame(o);
  const Scene scene = Scene::build(o, 0);
  checked = 0;
  std::size_t normal_mismatch = 0;
  for (std::size_t i = 0; i < f.truth.size(); ++i) {
    const int s = f.shape_index[i];
    if (s < 0)
      continue;
    const pcl::PointNormal& t = f.truth[i];
    const Eigen::Vector3d p(t.x, t.y, t.z), n(t.normal_x, t.normal_y, t.normal_z);
    const Shape& shape = *scene.shapes()[s];
    // Float storage limits the accuracy to ~3e-7 m at 3 m.
    ASSERT_LT(shape.surfaceDistance(p), 2e-6) << shape.name() << " at pixel " << i;
    ASSERT_NEAR(n.norm(), 1.0, 1e-6);
    EXPECT_LT(n.dot(p), 0.0) << "normal must face the camera at pixel " << i;
    if ((n - shape.normalAt(p)).norm() > 1e-4)
      ++normal_mismatch;
    // Nearest hit: no shape meets this pixel's ray in front of the recorded point.
    const Eigen::Vector3d d = p / p.z();
    for (const auto& other : scene.shapes()) {
      double t_other;
      Eigen::Vector3d n_other;
      if (other->intersect(Eigen::Vector3d::Zero(), d, 1e-9, t_other, n_other))
        ASSERT_GE(t_other, p.z() - 1e-5) << other->name() << " occludes pixel " << i;
    }
    ++checked;
  }
  // Only pixels exactly on an edge or crease may disagree about the nearest face.
  EXPECT_LT(double(normal_mismatch), 1e-3 * double(checked)) << toString(o.scene);
}

} // namespace

TEST(SyntheticScene, TruthPointsLieOnTheirAnalyticSurfacesWithTheirNormals)
{
  SceneOptions o;
  o.noise = NoiseModel::none;
  std::size_t checked = 0;
  expectTruthOnAnalyticSurfaces(o, checked);
  EXPECT_GT(checked, 200000u);
}

TEST(SyntheticScene, StepsTruthPointsLieOnTheirAnalyticSurfacesWithUnitNormals)
{
  SceneOptions o;
  o.scene = SceneType::steps;
  o.noise = NoiseModel::none;
  std::size_t checked = 0;
  expectTruthOnAnalyticSurfaces(o, checked);
  EXPECT_GT(checked, 200000u);
}

// The steps scene: floor, wall, three steps, the tilted panel and the two halves of the folded
// panel all in view over 0.8 m - 3 m; the treads of the three steps at their three heights.
TEST(SyntheticScene, StepsSceneShowsEveryShapeOverTheDepthRange)
{
  SceneOptions o;
  o.scene = SceneType::steps;
  o.noise = NoiseModel::none;
  EXPECT_EQ(sceneTypeFromString("steps"), SceneType::steps);
  EXPECT_EQ(toString(SceneType::steps), "steps");
  const SyntheticFrame f = renderFrame(o);
  const Scene scene = Scene::build(o, 0);
  ASSERT_EQ(scene.shapes().size(), 8u);
  std::vector<int> pixels(scene.shapes().size(), 0);
  std::set<int> tread_heights_mm;
  float z_min = 1e9f, z_max = 0.0f;
  for (std::size_t i = 0; i < f.truth.size(); ++i) {
    const int s = f.shape_index[i];
    EXPECT_EQ(s >= 0, valid(f.noisy[i]));
    if (s < 0)
      continue;
    ++pixels[s];
    const pcl::PointNormal& t = f.truth[i];
    z_min = std::min(z_min, t.z);
    z_max = std::max(z_max, t.z);
    if (scene.shapes()[s]->name() == "box" && t.normal_y < -0.999f)
      tread_heights_mm.insert(int(std::lround(1000.0 * (0.55 - t.y))));
  }
  for (std::size_t s = 0; s < pixels.size(); ++s)
    EXPECT_GT(pixels[s], 2000) << "shape " << s << " (" << scene.shapes()[s]->name() << ")";
  EXPECT_EQ(tread_heights_mm, (std::set<int>{100, 220, 300}));
  EXPECT_LT(z_min, 0.9f);
  EXPECT_GT(z_max, 2.9f);
  EXPECT_LE(z_max, 3.0f + 1e-5f);
}

TEST(SyntheticScene, RidgesTruthPointsLieOnTheirAnalyticSurfacesWithUnitNormals)
{
  SceneOptions o;
  o.scene = SceneType::ridges;
  o.noise = NoiseModel::none;
  std::size_t checked = 0;
  expectTruthOnAnalyticSurfaces(o, checked);
  EXPECT_GT(checked, 250000u);
}

// The ridges scene: one plate fills the view, and the parts of its face seen by the camera lie at
// every level the features give it: the face (0), the grooves' bottoms in the 5 mm layer (3, 2,
// 1 mm proud; the deepest reaches the face), the ridges and the layer (2 - 5 mm), and the
// terraces (2, 5, 9 and 14 mm).
TEST(SyntheticScene, RidgesSceneShowsEveryFeatureLevel)
{
  SceneOptions o;
  o.scene = SceneType::ridges;
  o.noise = NoiseModel::none;
  EXPECT_EQ(sceneTypeFromString("ridges"), SceneType::ridges);
  EXPECT_EQ(toString(SceneType::ridges), "ridges");
  const SyntheticFrame f = renderFrame(o);
  const Eigen::Matrix3d r = (Eigen::AngleAxisd(15.0 * M_PI / 180.0, Eigen::Vector3d::UnitY()) *
                             Eigen::AngleAxisd(8.0 * M_PI / 180.0, Eigen::Vector3d::UnitX()))
                                .toRotationMatrix();
  const Eigen::Vector3d toward = -(r * Eigen::Vector3d::UnitZ()), center(0.0, 0.0, 1.1);
  std::map<int, int> levels; // mm proud of the face -> pixels
  std::size_t hit = 0;
  for (std::size_t i = 0; i < f.truth.size(); ++i) {
    if (f.shape_index[i] < 0)
      continue;
    ++hit;
    const pcl::PointNormal& t = f.truth[i];
    const Eigen::Vector3d n(t.normal_x, t.normal_y, t.normal_z), p(t.x, t.y, t.z);
    if (n.dot(toward) > 0.9999)
      ++levels[int(std::lround(1000.0 * toward.dot(p - center)))];
  }
  EXPECT_EQ(hit, f.truth.size()) << "the plate fills the view";
  std::set<int> seen;
  for (const auto& [level, pixels] : levels)
    if (pixels >= 20)
      seen.insert(level);
  EXPECT_EQ(seen, (std::set<int>{0, 1, 2, 3, 4, 5, 9, 14}));
  EvaluationOptions eval;
  const std::vector<unsigned char> feature = featureMask(f.truth, eval);
  const auto features = std::count(feature.begin(), feature.end(), 1);
  EXPECT_GT(features, 10000) << "every riser is a crease";
  EXPECT_LT(features, 100000);
}

TEST(SyntheticScene, RidgedPanelHasTwoFacetOrientationsThreeMillimetresHigh)
{
  SceneOptions o;
  o.noise = NoiseModel::none;
  const SyntheticFrame f = renderFrame(o);
  const Scene scene = Scene::build(o, 0);
  const int panel = shapeIndexByName(scene, "ridged panel");
  ASSERT_GE(panel, 0);
  // Cluster the panel's normals: the two ridge facets are tilted +-atan(3 mm / 5 mm) from the panel.
  std::vector<Eigen::Vector3d> facets;
  std::vector<int> counts;
  int total = 0;
  for (std::size_t i = 0; i < f.truth.size(); ++i) {
    if (f.shape_index[i] != panel)
      continue;
    const Eigen::Vector3d n(f.truth[i].normal_x, f.truth[i].normal_y, f.truth[i].normal_z);
    ++total;
    std::size_t k = 0;
    while (k < facets.size() && (facets[k] - n).norm() > 1e-4)
      ++k;
    if (k == facets.size()) {
      facets.push_back(n);
      counts.push_back(0);
    }
    ++counts[k];
  }
  ASSERT_GE(facets.size(), 2u);
  std::vector<std::size_t> order(facets.size());
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return counts[a] > counts[b]; });
  const Eigen::Vector3d a = facets[order[0]], b = facets[order[1]];
  EXPECT_GT(counts[order[0]] + counts[order[1]], int(0.95 * total));
  EXPECT_GT(counts[order[1]], int(0.3 * total));
  const double expected = 2.0 * std::atan(0.003 / 0.005) * 180.0 / kPi; // 61.93 degrees
  EXPECT_NEAR(std::acos(std::clamp(a.dot(b), -1.0, 1.0)) * 180.0 / kPi, expected, 0.01);
}

TEST(SyntheticScene, KinectNoiseStandardDeviationMatchesTheModel)
{
  for (double depth : {1.0, 2.5}) {
    SceneOptions o = planeOptions(depth, NoiseModel::kinect);
    const SyntheticFrame f = renderFrame(o);
    double mean, stddev;
    std::size_t count;
    depthErrorStatistics(f, depth, mean, stddev, count);
    ASSERT_EQ(count, f.noisy.size());
    const double sigma = kinectAxialSigma(depth);
    EXPECT_NEAR(stddev, sigma, 0.02 * sigma) << "depth " << depth;
    EXPECT_LT(std::abs(mean), 4.0 * sigma / std::sqrt(double(count)));
  }
  EXPECT_NEAR(kinectAxialSigma(1.5), 0.0012 + 0.0019 * 1.21, 1e-12);
  EXPECT_NEAR(kinectAxialSigma(2.0, 0.25), 0.25 * (0.0012 + 0.0019 * 2.56), 1e-12);
}

TEST(SyntheticScene, NoiseStaysOnTheCameraRay)
{
  const SyntheticFrame f = renderFrame(planeOptions(1.5, NoiseModel::kinect));
  for (int v = 0; v < 480; v += 13)
    for (int u = 0; u < 640; u += 11) {
      const pcl::PointXYZ& p = f.noisy.at(u, v);
      EXPECT_NEAR(p.x / p.z, (u - 319.5) / 525.0, 1e-6);
      EXPECT_NEAR(p.y / p.z, (v - 239.5) / 525.0, 1e-6);
    }
}

TEST(SyntheticScene, LaserIsAQuarterOfKinectAndScaleIsSettable)
{
  const double depth = 2.0, sigma = kinectAxialSigma(depth);
  double mean, stddev;
  std::size_t count;
  depthErrorStatistics(renderFrame(planeOptions(depth, NoiseModel::laser)), depth, mean, stddev, count);
  EXPECT_NEAR(stddev, 0.25 * sigma, 0.02 * 0.25 * sigma);
  SceneOptions o = planeOptions(depth, NoiseModel::kinect);
  o.noise_scale = 2.0;
  depthErrorStatistics(renderFrame(o), depth, mean, stddev, count);
  EXPECT_NEAR(stddev, 2.0 * sigma, 0.02 * 2.0 * sigma);
}

TEST(SyntheticScene, StripesAreASinusoidAlongColumnsWithPerFramePhase)
{
  SceneOptions o = planeOptions(1.5, NoiseModel::stripes);
  o.noise_scale = 0.0;
  o.frames = 2;
  const auto frames = renderSequence(o);
  for (const SyntheticFrame& f : frames) {
    double peak = 0.0;
    for (int u = 0; u < 640; ++u) {
      const double e = f.noisy.at(u, 0).z - 1.5;
      peak = std::max(peak, std::abs(e));
      // Constant along each column, periodic along the rows.
      EXPECT_NEAR(f.noisy.at(u, 479).z - 1.5, e, 1e-6);
      if (u + 16 < 640)
        EXPECT_NEAR(f.noisy.at(u + 16, 0).z - 1.5, e, 1e-6);
    }
    EXPECT_NEAR(peak, 0.002, 0.0002);
  }
  double phase_difference = 0.0;
  for (int u = 0; u < 16; ++u)
    phase_difference = std::max(phase_difference, double(std::abs(frames[0].noisy.at(u, 0).z - frames[1].noisy.at(u, 0).z)));
  EXPECT_GT(phase_difference, 0.0005) << "the stripe phase must change between frames";

  // With the default small Gaussian part, column means still follow the sinusoid.
  SceneOptions noisy = planeOptions(1.5, NoiseModel::stripes);
  const SyntheticFrame f = renderFrame(noisy);
  const SyntheticFrame pure = renderFrame(o);
  for (int u = 0; u < 640; u += 7) {
    double sum = 0.0;
    for (int v = 0; v < 480; ++v)
      sum += f.noisy.at(u, v).z - 1.5;
    const double sigma_mean = 0.25 * kinectAxialSigma(1.5) / std::sqrt(480.0);
    EXPECT_NEAR(sum / 480.0, pure.noisy.at(u, 0).z - 1.5, 5.0 * sigma_mean);
  }
}

TEST(SyntheticScene, SeedReproducesFramesExactlyAndAnotherSeedDiffers)
{
  SceneOptions o;
  o.frames = 2;
  o.dropout = 0.05;
  o.seed = 7;
  const auto a = renderSequence(o);
  const auto b = renderSequence(o);
  ASSERT_EQ(a.size(), 2u);
  for (int k = 0; k < 2; ++k) {
    EXPECT_TRUE(identical(a[k].noisy, b[k].noisy));
    EXPECT_TRUE(identical(a[k].truth, b[k].truth));
  }
  EXPECT_TRUE(identical(renderFrame(o, 1).noisy, a[1].noisy)) << "renderFrame(o, k) is frame k of the sequence";
  // Static scene: same truth, independent noise per frame.
  EXPECT_TRUE(identical(a[0].truth, a[1].truth));
  EXPECT_FALSE(identical(a[0].noisy, a[1].noisy));

  o.seed = 8;
  const SyntheticFrame c = renderFrame(o, 0);
  EXPECT_TRUE(identical(c.truth, a[0].truth));
  std::size_t differ = 0, both = 0;
  for (std::size_t i = 0; i < c.noisy.size(); ++i)
    if (valid(c.noisy[i]) && valid(a[0].noisy[i])) {
      ++both;
      differ += c.noisy[i].z != a[0].noisy[i].z;
    }
  EXPECT_GT(differ, both * 99 / 100);
}

TEST(SyntheticScene, RandomDropoutsHitTheRequestedFraction)
{
  for (double rate : {0.0, 0.2, 1.0}) {
    SceneOptions o = planeOptions(1.5, NoiseModel::kinect);
    o.dropout = rate;
    const SyntheticFrame f = renderFrame(o);
    std::size_t dropped = 0;
    for (std::size_t i = 0; i < f.noisy.size(); ++i) {
      ASSERT_TRUE(valid(f.truth[i])) << "dropouts never reach the truth";
      if (!valid(f.noisy[i])) {
        ++dropped;
        EXPECT_TRUE(std::isnan(f.noisy[i].x) && std::isnan(f.noisy[i].y) && std::isnan(f.noisy[i].z));
      }
    }
    // Binomial standard deviation over 307200 pixels is < 0.001.
    EXPECT_NEAR(double(dropped) / double(f.noisy.size()), rate, 0.004) << "rate " << rate;
    EXPECT_EQ(f.noisy.is_dense, dropped == 0);
  }
}

TEST(SyntheticScene, GrazingDropoutsFollowTheAngleBetweenRayAndNormal)
{
  SceneOptions o = planeOptions(1.5, NoiseModel::kinect);
  o.grazing_dropout = 30.0;
  const SyntheticFrame f = renderFrame(o);
  std::size_t dropped = 0;
  for (int v = 0; v < 480; ++v)
    for (int u = 0; u < 640; ++u) {
      // The plane's normal is the optical axis: the angle is that of the ray to the axis.
      const double a = (u - 319.5) / 525.0, b = (v - 239.5) / 525.0;
      const double angle = std::atan(std::sqrt(a * a + b * b)) * 180.0 / kPi;
      if (std::abs(angle - 30.0) < 1e-9)
        continue;
      EXPECT_EQ(!valid(f.noisy.at(u, v)), angle > 30.0) << u << ", " << v;
      dropped += angle > 30.0;
    }
  EXPECT_GT(dropped, 10000u);

  // In the boxes scene the far floor is seen at more than 75 degrees.
  SceneOptions boxes;
  boxes.grazing_dropout = 75.0;
  const SyntheticFrame g = renderFrame(boxes);
  std::size_t truth_valid = 0, noisy_valid = 0;
  for (std::size_t i = 0; i < g.noisy.size(); ++i) {
    truth_valid += valid(g.truth[i]);
    noisy_valid += valid(g.noisy[i]);
  }
  EXPECT_LT(noisy_valid, truth_valid);
}

TEST(SyntheticScene, MovingBoxTranslatesByTheStepPerFrame)
{
  SceneOptions o;
  o.noise = NoiseModel::none;
  o.frames = 3;
  o.motion = Motion::moving_box;
  o.motion_step = 0.01;
  const auto frames = renderSequence(o);
  const Scene first = Scene::build(o, 0);
  const int moving = first.movingShape();
  ASSERT_GE(moving, 0);
  EXPECT_EQ(first.shapes()[moving]->name(), "box");
  for (int k = 1; k < 3; ++k) {
    std::size_t changed = 0, on_box = 0;
    for (std::size_t i = 0; i < frames[k].truth.size(); ++i) {
      const auto& now = frames[k].truth[i];
      const auto& before = frames[k - 1].truth[i];
      const bool differs = valid(now) != valid(before) || (valid(now) && (now.x != before.x || now.z != before.z));
      if (differs) {
        ++changed;
        EXPECT_TRUE(frames[k].shape_index[i] == moving || frames[k - 1].shape_index[i] == moving)
            << "only the moving box changes, pixel " << i;
      }
      if (frames[k].shape_index[i] != moving)
        continue;
      // Shifted back by k steps, the point lies on the box of frame 0, and not before shifting.
      const Eigen::Vector3d p(now.x, now.y, now.z);
      EXPECT_LT(first.shapes()[moving]->surfaceDistance(p - Eigen::Vector3d(0.01 * k, 0, 0)), 2e-6);
      on_box += first.shapes()[moving]->surfaceDistance(p) > 1e-3;
    }
    EXPECT_GT(changed, 5000u);
    EXPECT_GT(on_box, 5000u);
  }
}

TEST(SyntheticScene, InvalidOptionsThrowNamingTheOption)
{
  auto message = [](const SceneOptions& o) {
    try {
      renderFrame(o);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("no exception");
  };
  SceneOptions o;
  o.dropout = 1.5;
  EXPECT_NE(message(o).find("dropout = 1.5"), std::string::npos) << message(o);
  o = SceneOptions{};
  o.fx = 0.0;
  EXPECT_NE(message(o).find("fx = 0"), std::string::npos) << message(o);
  o = SceneOptions{};
  o.grazing_dropout = 0.0;
  EXPECT_NE(message(o).find("grazing_dropout"), std::string::npos) << message(o);
  o = SceneOptions{};
  o.noise_scale = -1.0;
  EXPECT_NE(message(o).find("noise_scale = -1"), std::string::npos) << message(o);
  o = planeOptions(1.5, NoiseModel::none);
  o.motion = Motion::moving_box;
  EXPECT_NE(message(o).find("motion"), std::string::npos) << message(o);
  EXPECT_THROW(renderFrame(SceneOptions{}, -1), std::invalid_argument);
  EXPECT_THROW(noiseModelFromString("kinnect"), std::invalid_argument);
  EXPECT_EQ(noiseModelFromString("stripes"), NoiseModel::stripes);
  EXPECT_EQ(motionFromString("moving"), Motion::moving_box);
  EXPECT_EQ(sceneTypeFromString("plane"), SceneType::plane);
  EXPECT_THROW(sceneTypeFromString("stairs"), std::invalid_argument);
}

namespace
{

/// FNV-1a over the bytes of the noisy frame (x, y, z of every point, NaN bits included).
std::uint64_t
noisyHash(const pcl::PointCloud<pcl::PointXYZ>& cloud)
{
  std::uint64_t h = 1469598103934665603ull;
  for (const auto& p : cloud) {
    const float xyz[3] = {p.x, p.y, p.z};
    unsigned char bytes[sizeof xyz];
    std::memcpy(bytes, xyz, sizeof xyz);
    for (unsigned char b : bytes)
      h = (h ^ b) * 1099511628211ull;
  }
  return h;
}

} // namespace

TEST(SyntheticScene, ExistingNoiseModelsKeepTheirExactOutput)
{
  // Frames of the models that existed before the sensor models were added, hashed when they were
  // added: their random draws and arithmetic must not change.
  const std::pair<NoiseModel, std::uint64_t> expected[] = {
      {NoiseModel::none, 17698375432554255019ull}, {NoiseModel::kinect, 9104118400696139820ull},
      {NoiseModel::laser, 5241634585731123694ull}, {NoiseModel::stripes, 6378388060979735317ull}};
  for (const auto& [model, hash] : expected) {
    SceneOptions o;
    o.width = 160;
    o.height = 120;
    o.fx = o.fy = 131.25;
    o.noise = model;
    o.dropout = 0.02;
    o.grazing_dropout = 80.0;
    o.seed = 11;
    EXPECT_EQ(noisyHash(renderFrame(o, 1).noisy), hash) << toString(model);
  }
}

namespace
{

/// Disparity f B / z of every valid noisy pixel, NaN elsewhere.
std::vector<double>
disparities(const SyntheticFrame& f, double fb)
{
  std::vector<double> d(f.noisy.size(), std::numeric_limits<double>::quiet_NaN());
  for (std::size_t i = 0; i < d.size(); ++i)
    if (valid(f.noisy[i]))
      d[i] = fb / double(f.noisy[i].z);
  return d;
}

/// Sample autocorrelation of a (NaN-free) field along rows and columns at a lag of `lag` pixels,
/// each value centred on the field's mean and divided by its variance.
double
autocorrelation(const std::vector<double>& e, int width, int height, int lag)
{
  double mean = 0.0;
  for (double x : e)
    mean += x;
  mean /= double(e.size());
  double var = 0.0;
  for (double x : e)
    var += (x - mean) * (x - mean);
  var /= double(e.size());
  double sum = 0.0;
  std::size_t n = 0;
  for (int v = 0; v < height; ++v)
    for (int u = 0; u < width; ++u) {
      const double a = e[std::size_t(v) * width + u] - mean;
      if (u + lag < width) {
        sum += a * (e[std::size_t(v) * width + u + lag] - mean);
        ++n;
      }
      if (v + lag < height) {
        sum += a * (e[std::size_t(v + lag) * width + u] - mean);
        ++n;
      }
    }
  return sum / double(n) / var;
}

/// Whether x is a whole multiple of step, to `tolerance` of a step.
bool
multipleOf(double x, double step, double tolerance = 1e-3)
{
  return std::abs(x / step - std::round(x / step)) < tolerance;
}

} // namespace

TEST(SyntheticScene, StereoErrorHasTheRequestedCorrelationLengthAndShare)
{
  SceneOptions o = planeOptions(1.5, NoiseModel::stereo);
  o.width = 320;
  o.height = 240;
  o.stereo_subpixel = 0.0;
  const double fb = o.fx * o.stereo_baseline;
  for (const auto& [share, length] : {std::pair<double, double>{1.0, 4.0}, {0.6, 4.0}, {0.6, 8.0}, {0.0, 4.0}}) {
    o.stereo_correlated_share = share;
    o.stereo_correlation_length = length;
    double rho_l = 0.0, rho_half = 0.0, variance = 0.0;
    const int frames = 4;
    for (int k = 0; k < frames; ++k) {
      const SyntheticFrame f = renderFrame(o, k);
      std::vector<double> e = disparities(f, fb);
      double sq = 0.0;
      for (double& x : e) {
        ASSERT_TRUE(std::isfinite(x));
        x -= fb / 1.5;
        sq += x * x;
      }
      variance += sq / double(e.size()) / frames;
      rho_l += autocorrelation(e, o.width, o.height, int(length)) / frames;
      rho_half += autocorrelation(e, o.width, o.height, int(length / 2)) / frames;
    }
    // White part uncorrelated at any lag > 0; correlated part exp(-(lag / L)^2).
    EXPECT_NEAR(rho_l, share * std::exp(-1.0), 0.05) << share << " " << length;
    EXPECT_NEAR(rho_half, share * std::exp(-0.25), 0.05) << share << " " << length;
    EXPECT_NEAR(std::sqrt(variance), o.stereo_disparity_sigma, 0.1 * o.stereo_disparity_sigma);
  }
}

TEST(SyntheticScene, StereoDisparityIsQuantizedAndDepthErrorGrowsWithZSquared)
{
  SceneOptions o = planeOptions(1.0, NoiseModel::stereo);
  o.width = 320;
  o.height = 240;
  const double fb = o.fx * o.stereo_baseline;
  double stddev[2];
  for (int p = 0; p < 2; ++p) {
    o.plane_depth = p == 0 ? 1.0 : 2.0;
    double sum_sq = 0.0;
    std::size_t count = 0, odd = 0;
    for (int k = 0; k < 3; ++k) {
      const SyntheticFrame f = renderFrame(o, k);
      for (double d : disparities(f, fb)) {
        ASSERT_TRUE(std::isfinite(d));
        ASSERT_TRUE(multipleOf(d, 1.0 / 32.0)) << d;
        odd += !multipleOf(d, 1.0 / 16.0);
      }
      double mean, sd;
      std::size_t n;
      depthErrorStatistics(f, o.plane_depth, mean, sd, n);
      sum_sq += sd * sd * double(n);
      count += n;
    }
    EXPECT_GT(odd, count / 4) << "the step is 1/32 px, not coarser";
    stddev[p] = std::sqrt(sum_sq / double(count));
    // dz = z^2 / (f B) * dd.
    EXPECT_NEAR(stddev[p], o.plane_depth * o.plane_depth / fb * 0.08, 0.1 * stddev[p]) << o.plane_depth;
  }
  EXPECT_NEAR(stddev[1] / stddev[0], 4.0, 0.4);

  o.stereo_subpixel = 0.1;
  for (double d : disparities(renderFrame(o), fb))
    ASSERT_TRUE(multipleOf(d, 0.1)) << d;
}

TEST(SyntheticScene, Kinect1DisparityAndDepthAreQuantized)
{
  SceneOptions o = planeOptions(2.6, NoiseModel::kinect1);
  o.width = 200;
  o.height = 150;
  const double fb = o.fx * o.kinect1_baseline;
  // Without the depth rounding the disparity is a multiple of 1/8 px.
  o.kinect1_depth_unit = 0.0;
  std::size_t n = 0, inner = 0;
  const std::vector<double> d = disparities(renderFrame(o), fb);
  for (int v = 0; v < o.height; ++v)
    for (int u = 0; u < o.width; ++u) {
      const double x = d[std::size_t(v) * o.width + u];
      if (std::isfinite(x)) {
        ++n;
        ASSERT_TRUE(multipleOf(x, 0.125)) << x;
      }
      // A block touching the image border has no measurement; beyond a few shift sigmas a
      // fronto-parallel plane is measured everywhere.
      if (u < 4 || v < 4 || u + 4 >= o.width || v + 4 >= o.height)
        ASSERT_FALSE(std::isfinite(x)) << u << " " << v;
      else if (u >= 8 && v >= 8 && u + 8 < o.width && v + 8 < o.height)
        inner += std::isfinite(x);
    }
  EXPECT_EQ(inner, std::size_t(o.width - 16) * (o.height - 16));
  // With it, depth is a multiple of 1 mm, on a few bands only (1/8 px at 2.6 m is ~2 cm; the
  // 1/6 px disparity noise spreads over about +-4 steps).
  o.kinect1_depth_unit = 0.001;
  std::map<long, std::size_t> bands;
  for (const auto& p : renderFrame(o).noisy)
    if (valid(p)) {
      ASSERT_TRUE(multipleOf(p.z, 0.001, 1e-2)) << p.z;
      ++bands[std::lround(p.z * 1000.0)];
    }
  EXPECT_LE(bands.size(), 16u);
  EXPECT_GE(bands.size(), 2u);
  for (const auto& [mm, count] : bands) {
    (void)count;
    EXPECT_TRUE(multipleOf(fb / (mm * 0.001), 0.125, 0.05)) << mm << " mm is not the depth of a 1/8 px disparity";
  }
}

TEST(SyntheticScene, Kinect1HasNoMeasurementWhereABlockStraddlesADepthEdge)
{
  SceneOptions o;
  o.noise = NoiseModel::kinect1;
  const SyntheticFrame f = renderFrame(o, 0);
  SceneOptions none = o;
  none.noise = NoiseModel::none;
  const SyntheticFrame exact = renderFrame(none, 0);
  EXPECT_TRUE(identical(f.truth, exact.truth)) << "the truth stays the exact scene";
  // Edge: a 3x3 neighbour without a surface or whose true disparity differs by more than 4 px
  // (simkinect's distance weighting lets some jumps of one to three pixels through).
  const double fb = o.fx * o.kinect1_baseline;
  auto disparity = [&](int u, int v) { return fb / double(f.truth.at(u, v).z); };
  std::size_t edge = 0, edge_valid = 0, hit = 0, hit_valid = 0;
  for (int v = 1; v + 1 < o.height; ++v)
    for (int u = 1; u + 1 < o.width; ++u) {
      if (!valid(f.truth.at(u, v)))
        continue;
      ++hit;
      hit_valid += valid(f.noisy.at(u, v));
      bool at_edge = false;
      for (int dv = -1; dv <= 1; ++dv)
        for (int du = -1; du <= 1; ++du)
          at_edge = at_edge || !valid(f.truth.at(u + du, v + dv)) ||
                    std::abs(disparity(u + du, v + dv) - disparity(u, v)) > 4.0;
      if (at_edge) {
        ++edge;
        edge_valid += valid(f.noisy.at(u, v));
        EXPECT_FALSE(valid(f.noisy.at(u, v))) << u << " " << v;
      }
    }
  EXPECT_GT(edge, 1500u);
  EXPECT_EQ(edge_valid, 0u);
  // Away from edges most of the scene is measured (floor, walls and faces are not too slanted).
  EXPECT_GT(hit_valid, hit * 3 / 4);
  // Reproducible per seed and frame, fresh per frame.
  EXPECT_TRUE(identical(renderFrame(o, 0).noisy, f.noisy));
  EXPECT_FALSE(identical(renderFrame(o, 1).noisy, f.noisy));
}

TEST(SyntheticScene, TofMixedPixelsLieBetweenTheTwoSurfacesOnTheirRay)
{
  SceneOptions o;
  o.noise = NoiseModel::tof;
  o.tof_sigma = 0.0;
  o.tof_sigma_slope = 0.0;
  o.tof_mixed_probability = 1.0;
  o.tof_edge_band = 1;
  const SyntheticFrame f = renderFrame(o, 0);
  const double cx = o.principalX(), cy = o.principalY();
  auto range = [](const auto& p) { return std::sqrt(double(p.x) * p.x + double(p.y) * p.y + double(p.z) * p.z); };
  std::size_t mixed = 0, between = 0, far_from_truth = 0;
  for (int v = 0; v < o.height; ++v)
    for (int u = 0; u < o.width; ++u) {
      const auto& q = f.noisy.at(u, v);
      const auto& t = f.truth.at(u, v);
      ASSERT_EQ(valid(q), valid(t));
      if (!valid(q))
        continue;
      // On the pixel's ray.
      EXPECT_NEAR(q.x / q.z, (u - cx) / o.fx, 1e-5);
      EXPECT_NEAR(q.y / q.z, (v - cy) / o.fy, 1e-5);
      const double r = range(q);
      if (std::abs(r - range(t)) < 1e-5)
        continue;
      ++mixed;
      double r_near = 1e9, r_far = 0.0;
      for (int dv = -1; dv <= 1; ++dv)
        for (int du = -1; du <= 1; ++du) {
          if (u + du < 0 || v + dv < 0 || u + du >= o.width || v + dv >= o.height || !valid(f.truth.at(u + du, v + dv)))
            continue;
          r_near = std::min(r_near, range(f.truth.at(u + du, v + dv)));
          r_far = std::max(r_far, range(f.truth.at(u + du, v + dv)));
        }
      between += r >= r_near - 1e-5 && r <= r_far + 1e-5;
      far_from_truth += std::abs(r - range(t)) > 0.05;
    }
  EXPECT_GT(mixed, 2000u);
  EXPECT_EQ(between, mixed) << "every moved pixel lies between the nearest and farthest surface of its 3x3 window";
  EXPECT_GT(far_from_truth, mixed / 4) << "mixed pixels float between the surfaces";

  o.tof_mixed_probability = 0.0;
  const SyntheticFrame clean = renderFrame(o, 0);
  for (std::size_t i = 0; i < clean.noisy.size(); ++i)
    if (valid(clean.noisy[i]))
      ASSERT_NEAR(clean.noisy[i].z, f.truth[i].z, 1e-6);
  o.tof_mixed_probability = 0.5;
  std::size_t half_mixed = 0;
  const SyntheticFrame some = renderFrame(o, 0);
  for (std::size_t i = 0; i < some.noisy.size(); ++i)
    half_mixed += valid(some.noisy[i]) && std::abs(some.noisy[i].z - f.truth[i].z) > 1e-5;
  EXPECT_NEAR(double(half_mixed) / double(mixed), 0.5, 0.05);
}

TEST(SyntheticScene, TofRangeNoiseGrowsWithRange)
{
  SceneOptions o = planeOptions(1.0, NoiseModel::tof);
  o.width = 64;
  o.height = 48;
  o.frames = 1;
  for (double depth : {1.0, 3.0}) {
    o.plane_depth = depth;
    double sum_sq = 0.0;
    std::size_t count = 0;
    for (int k = 0; k < 8; ++k) {
      double mean, sd;
      std::size_t n;
      depthErrorStatistics(renderFrame(o, k), depth, mean, sd, n);
      sum_sq += sd * sd * double(n);
      count += n;
    }
    // The narrow field of view makes range and depth equal to 0.3 %.
    EXPECT_NEAR(std::sqrt(sum_sq / double(count)), o.tof_sigma + o.tof_sigma_slope * depth,
                0.05 * (o.tof_sigma + o.tof_sigma_slope * depth))
        << depth;
  }
}

TEST(SyntheticScene, SensorModelOptionsAreValidatedByName)
{
  auto message = [](const SceneOptions& o) {
    try {
      o.validate();
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("no exception");
  };
  SceneOptions o;
  o.stereo_correlated_share = 1.5;
  EXPECT_NE(message(o).find("stereo_correlated_share = 1.5"), std::string::npos) << message(o);
  o = SceneOptions{};
  o.stereo_baseline = 0.0;
  EXPECT_NE(message(o).find("stereo_baseline = 0"), std::string::npos) << message(o);
  o = SceneOptions{};
  o.kinect1_block = 8;
  EXPECT_NE(message(o).find("kinect1_block = 8"), std::string::npos) << message(o);
  o = SceneOptions{};
  o.kinect1_subpixel = -0.125;
  EXPECT_NE(message(o).find("kinect1_subpixel = -0.125"), std::string::npos) << message(o);
  o = SceneOptions{};
  o.tof_mixed_probability = -0.1;
  EXPECT_NE(message(o).find("tof_mixed_probability = -0.1"), std::string::npos) << message(o);
  o = SceneOptions{};
  o.tof_edge_band = 17;
  EXPECT_NE(message(o).find("tof_edge_band = 17"), std::string::npos) << message(o);
  EXPECT_EQ(noiseModelFromString("stereo"), NoiseModel::stereo);
  EXPECT_EQ(noiseModelFromString("kinect1"), NoiseModel::kinect1);
  EXPECT_EQ(noiseModelFromString("tof"), NoiseModel::tof);
  EXPECT_EQ(toString(NoiseModel::kinect1), "kinect1");
}

TEST(SyntheticScene, ToolTakesTheSensorModelOptionsAndNamesABadValue)
{
  namespace fs = std::filesystem;
  const fs::path dir = fs::temp_directory_path() / ("range_nlm_synth_sensor_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  test::CommandResult r =
      test::runTool("range_nlm_synth", "--output-dir " + dir.string() +
                                           " --scene plane --width 64 --height 48 --noise stereo --stereo-subpixel 0.25 -q");
  ASSERT_EQ(r.status, 0) << r.output;
  pcl::PointCloud<pcl::PointXYZ> noisy;
  ASSERT_EQ(pcl::io::loadPCDFile((dir / "noisy" / "frame_0000.pcd").string(), noisy), 0);
  SceneOptions o = planeOptions(1.5, NoiseModel::stereo);
  o.width = 64;
  o.height = 48;
  o.stereo_subpixel = 0.25;
  EXPECT_TRUE(identical(noisy, renderFrame(o).noisy)) << "the tool writes the library's frame";
  r = test::runTool("range_nlm_synth", "--output-dir " + dir.string() + " --scene steps --width 64 --height 48 -q");
  ASSERT_EQ(r.status, 0) << r.output;
  ASSERT_EQ(pcl::io::loadPCDFile((dir / "noisy" / "frame_0000.pcd").string(), noisy), 0);
  o = SceneOptions{};
  o.scene = SceneType::steps;
  o.width = 64;
  o.height = 48;
  EXPECT_TRUE(identical(noisy, renderFrame(o).noisy)) << "--scene steps renders the steps scene";
  r = test::runTool("range_nlm_synth", "--output-dir " + dir.string() + " --scene stairs");
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_NE(r.output.find("'stairs'"), std::string::npos) << r.output;
  r = test::runTool("range_nlm_synth", "--output-dir " + dir.string() + " --noise kinect1 --kinect1-block 8");
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_NE(r.output.find("kinect1_block = 8"), std::string::npos) << r.output;
  r = test::runTool("range_nlm_synth", "--output-dir " + dir.string() + " --noise tof --tof-mixed-probability 2");
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_NE(r.output.find("tof_mixed_probability = 2"), std::string::npos) << r.output;
  fs::remove_all(dir);
}

TEST(SyntheticScene, SensorModelsAreReproducibleFromTheSeedAndFreshPerFrame)
{
  for (NoiseModel model : {NoiseModel::stereo, NoiseModel::kinect1, NoiseModel::tof}) {
    SceneOptions o;
    o.width = 160;
    o.height = 120;
    o.fx = o.fy = 131.25;
    o.noise = model;
    o.seed = 3;
    o.frames = 2;
    const auto sequence = renderSequence(o);
    EXPECT_TRUE(identical(renderFrame(o, 1).noisy, sequence[1].noisy)) << toString(model);
    EXPECT_FALSE(identical(sequence[0].noisy, sequence[1].noisy)) << toString(model);
    o.seed = 4;
    EXPECT_FALSE(identical(renderFrame(o, 1).noisy, sequence[1].noisy)) << toString(model);
    // Dropouts apply to the sensor models too.
    o.dropout = 0.5;
    std::size_t valid_before = 0, valid_after = 0;
    for (const auto& p : sequence[1].noisy)
      valid_before += valid(p);
    for (const auto& p : renderFrame(o, 1).noisy)
      valid_after += valid(p);
    EXPECT_NEAR(double(valid_after), 0.5 * double(valid_before), 0.05 * double(valid_before)) << toString(model);
  }
}
