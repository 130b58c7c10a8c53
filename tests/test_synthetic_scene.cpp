// Tests of the synthetic range-frame generator: exact geometry, noise statistics, determinism,
// dropouts and motion.
#include <range_nlm/synthetic_scene.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <map>
#include <numeric>

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

TEST(SyntheticScene, TruthPointsLieOnTheirAnalyticSurfacesWithTheirNormals)
{
  SceneOptions o;
  o.noise = NoiseModel::none;
  const SyntheticFrame f = renderFrame(o);
  const Scene scene = Scene::build(o, 0);
  std::size_t checked = 0, normal_mismatch = 0;
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
  EXPECT_GT(checked, 200000u);
  // Only pixels exactly on an edge or crease may disagree about the nearest face.
  EXPECT_LT(double(normal_mismatch), 1e-3 * double(checked));
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
