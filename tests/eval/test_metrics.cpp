// Tests of the evaluation metrics: region classification, exact RMSEs of hand-made offsets,
// lost points, temporal statistics and moving edges.
#include <range_nlm/eval/metrics.h>
#include <range_nlm/eval/synthetic_scene.h>

#include "test_support.h"

#include <pcl/io/pcd_io.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <functional>
#include <limits>
#include <map>
#include <random>

using namespace range_nlm;

namespace
{

using Truth = pcl::PointCloud<pcl::PointNormal>;
using Cloud = pcl::PointCloud<pcl::PointXYZ>;

constexpr double kPi = 3.14159265358979323846;
const float kNaN = std::numeric_limits<float>::quiet_NaN();

bool
valid(const pcl::PointNormal& p)
{
  return std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z);
}

/// A hand-made truth grid seen by a camera with f = 500 px: depth z(u, v) and a normal tilted by
/// `tilt(u, v)` degrees about the y axis from the optical axis (toward the camera).
Truth
gridTruth(int width, int height, const std::function<double(int, int)>& depth,
          const std::function<double(int, int)>& tilt = [](int, int) { return 0.0; })
{
  Truth t(width, height);
  for (int v = 0; v < height; ++v)
    for (int u = 0; u < width; ++u) {
      pcl::PointNormal& p = t.at(u, v);
      const double z = depth(u, v);
      if (!std::isfinite(z)) {
        p.x = p.y = p.z = p.normal_x = p.normal_y = p.normal_z = kNaN;
        continue;
      }
      p.z = float(z);
      p.x = float((u - 0.5 * (width - 1)) / 500.0 * z);
      p.y = float((v - 0.5 * (height - 1)) / 500.0 * z);
      const double a = tilt(u, v) * kPi / 180.0;
      p.normal_x = float(std::sin(a));
      p.normal_y = 0.0f;
      p.normal_z = float(-std::cos(a));
    }
  return t;
}

Cloud
xyzOf(const Truth& truth)
{
  Cloud c(truth.width, truth.height);
  for (std::size_t i = 0; i < truth.size(); ++i) {
    c[i].x = truth[i].x;
    c[i].y = truth[i].y;
    c[i].z = truth[i].z;
  }
  return c;
}

/// Truth points moved along their normals by offset(i) metres.
Cloud
offsetAlongNormals(const Truth& truth, const std::function<double(std::size_t)>& offset)
{
  Cloud c = xyzOf(truth);
  for (std::size_t i = 0; i < truth.size(); ++i) {
    const double h = offset(i);
    c[i].x = float(truth[i].x + h * truth[i].normal_x);
    c[i].y = float(truth[i].y + h * truth[i].normal_y);
    c[i].z = float(truth[i].z + h * truth[i].normal_z);
  }
  return c;
}

SceneOptions
noiseFree(SceneType scene = SceneType::boxes)
{
  SceneOptions o;
  o.scene = scene;
  o.noise = NoiseModel::none;
  return o;
}

/// Half-resolution boxes scene (same field of view), to keep sequence tests quick.
SceneOptions
smallBoxes()
{
  SceneOptions o = noiseFree();
  o.width = 320;
  o.height = 240;
  o.fx = o.fy = 262.5;
  return o;
}

} // namespace

TEST(Evaluation, FeatureMaskMarksADepthStepWithinThreePixels)
{
  // Left half at 1 m, right half at 2 m: seeds in columns 9 and 10, dilated by 3.
  const Truth t = gridTruth(20, 12, [](int u, int) { return u < 10 ? 1.0 : 2.0; });
  const std::vector<unsigned char> mask = featureMask(t);
  for (int v = 0; v < 12; ++v)
    for (int u = 0; u < 20; ++u)
      EXPECT_EQ(mask[v * 20 + u], (u >= 6 && u <= 13) ? 1 : 0) << u << ", " << v;
}

TEST(Evaluation, DepthJumpThresholdIsFivePercentOfTheRange)
{
  auto featureCount = [](double ratio) {
    const Truth t = gridTruth(20, 12, [ratio](int u, int) { return u < 10 ? 1.0 : ratio; });
    const std::vector<unsigned char> mask = featureMask(t);
    return std::count(mask.begin(), mask.end(), 1);
  };
  EXPECT_EQ(featureCount(1.04), 0);
  EXPECT_EQ(featureCount(1.06), 8 * 12);
}

TEST(Evaluation, FeatureMaskMarksCreasesAboveTwentyDegrees)
{
  auto roof = [](double half_angle) {
    return gridTruth(
        20, 12, [](int, int) { return 1.0; }, [half_angle](int u, int) { return u < 10 ? half_angle : -half_angle; });
  };
  const std::vector<unsigned char> sharp = featureMask(roof(30.0)); // 60 degrees between the halves
  for (int v = 0; v < 12; ++v)
    for (int u = 0; u < 20; ++u)
      EXPECT_EQ(sharp[v * 20 + u], (u >= 6 && u <= 13) ? 1 : 0) << u << ", " << v;
  const std::vector<unsigned char> gentle = featureMask(roof(7.5)); // 15 degrees
  EXPECT_EQ(std::count(gentle.begin(), gentle.end(), 1), 0);
}

TEST(Evaluation, FeatureMaskSurroundsHolesButNotTheImageBorder)
{
  const Truth t = gridTruth(21, 21, [](int u, int v) {
    return (u == 10 && v == 10) ? std::numeric_limits<double>::quiet_NaN() : 1.5;
  });
  const std::vector<unsigned char> mask = featureMask(t);
  for (int v = 0; v < 21; ++v)
    for (int u = 0; u < 21; ++u) {
      const int d = std::max(std::abs(u - 10), std::abs(v - 10));
      EXPECT_EQ(mask[v * 21 + u], (d >= 1 && d <= 4) ? 1 : 0) << u << ", " << v;
    }
}

TEST(Evaluation, FeatureMaskCoversEveryObjectBoundaryOfTheBoxesScene)
{
  const SyntheticFrame f = renderFrame(noiseFree());
  const int w = int(f.truth.width), h = int(f.truth.height);
  const std::vector<unsigned char> mask = featureMask(f.truth);
  // Pixels next to a different object (or nothing) are depth edges or creases in this scene.
  std::vector<unsigned char> boundary(f.truth.size(), 0);
  for (int v = 0; v < h; ++v)
    for (int u = 0; u < w; ++u)
      for (int dv = -1; dv <= 1; ++dv)
        for (int du = -1; du <= 1; ++du) {
          const int nu = u + du, nv = v + dv;
          if (nu >= 0 && nv >= 0 && nu < w && nv < h && f.shape_index[nv * w + nu] != f.shape_index[v * w + u])
            boundary[v * w + u] = 1;
        }
  const Scene scene = Scene::build(noiseFree(), 0);
  std::size_t near = 0, far_planar = 0;
  for (int v = 0; v < h; ++v)
    for (int u = 0; u < w; ++u) {
      const int i = v * w + u;
      if (!valid(f.truth[i]))
        continue;
      int distance = 1000;
      for (int dv = -4; dv <= 4; ++dv)
        for (int du = -4; du <= 4; ++du) {
          const int nu = u + du, nv = v + dv;
          if (nu >= 0 && nv >= 0 && nu < w && nv < h && boundary[nv * w + nu])
            distance = std::min(distance, std::max(std::abs(du), std::abs(dv)));
        }
      if (distance <= 3) {
        ASSERT_EQ(mask[i], 1) << "pixel (" << u << ", " << v << ") is " << distance << " px from an object edge";
        ++near;
      } else if (scene.shapes()[f.shape_index[i]]->name() == "rectangle") {
        // Floor and wall are single planes: away from their edges they are flat.
        ASSERT_EQ(mask[i], 0) << "pixel (" << u << ", " << v << ") on the floor or wall";
        ++far_planar;
      }
    }
  EXPECT_GT(near, 20000u);
  EXPECT_GT(far_planar, 100000u);
}

TEST(Evaluation, TruthAgainstItselfHasZeroError)
{
  const SyntheticFrame f = renderFrame(noiseFree());
  const Cloud result = xyzOf(f.truth);
  const FrameMetrics m = evaluateFrame(f.truth, result, &f.noisy);
  EXPECT_EQ(m.flat_rmse, 0.0);
  EXPECT_EQ(m.feature_rmse, 0.0);
  EXPECT_EQ(m.points_lost, 0u);
  EXPECT_EQ(m.points_invented, 0u);
  EXPECT_EQ(m.missing_pixels, 0u);
  EXPECT_EQ(m.flat_pixels + m.feature_pixels, m.truth_pixels);
  EXPECT_GT(m.feature_pixels, 10000u);
  EXPECT_GT(m.flat_pixels, 100000u);
  EXPECT_LT(m.flat_normal_error, 0.5);
  // Near edges the 5x5 fit straddles two surfaces.
  EXPECT_GT(m.feature_normal_error, m.flat_normal_error);

  const SyntheticFrame plane = renderFrame(noiseFree(SceneType::plane));
  const FrameMetrics p = evaluateFrame(plane.truth, xyzOf(plane.truth));
  EXPECT_EQ(p.feature_pixels, 0u);
  EXPECT_EQ(p.flat_pixels, plane.truth.size());
  EXPECT_LT(p.flat_normal_error, 0.01);
  EXPECT_TRUE(std::isnan(p.feature_rmse));
  EXPECT_FALSE(p.has_input);
}

TEST(Evaluation, OffsetAlongNormalsGivesThatRmse)
{
  const SyntheticFrame f = renderFrame(noiseFree());
  const FrameMetrics uniform = evaluateFrame(f.truth, offsetAlongNormals(f.truth, [](std::size_t) { return 0.002; }));
  EXPECT_NEAR(uniform.flat_rmse, 0.002, 1e-6);
  EXPECT_NEAR(uniform.feature_rmse, 0.002, 1e-6);

  // Different offsets in the two regions are reported apart; the sign does not matter.
  const std::vector<unsigned char> feature = featureMask(f.truth);
  const FrameMetrics split =
      evaluateFrame(f.truth, offsetAlongNormals(f.truth, [&](std::size_t i) { return feature[i] ? -0.003 : 0.001; }));
  EXPECT_NEAR(split.flat_rmse, 0.001, 1e-6);
  EXPECT_NEAR(split.feature_rmse, 0.003, 1e-6);

  // A shift within the tangent plane costs nothing: the metric is point-to-plane.
  const SyntheticFrame plane = renderFrame(noiseFree(SceneType::plane));
  Cloud slid = xyzOf(plane.truth);
  for (auto& p : slid)
    p.x += 0.01f;
  EXPECT_NEAR(evaluateFrame(plane.truth, slid).flat_rmse, 0.0, 1e-9);
}

TEST(Evaluation, CountsLostInventedAndMissingPoints)
{
  const Truth t = gridTruth(40, 30, [](int, int) { return 1.2; });
  Cloud input = xyzOf(t), result = xyzOf(t);
  std::size_t kept = 0;
  for (std::size_t i = 0; i < 350; i += 7) { // 50 holes in the input
    input[i].x = input[i].y = input[i].z = kNaN;
    if (kept++ >= 10) // the result fills 10 of them
      result[i].x = result[i].y = result[i].z = kNaN;
  }
  for (std::size_t i = 1000; i < 1100; ++i) // 100 points the filter dropped
    result[i].x = result[i].y = result[i].z = kNaN;
  const FrameMetrics m = evaluateFrame(t, result, &input);
  EXPECT_TRUE(m.has_input);
  EXPECT_EQ(m.points_lost, 100u);
  EXPECT_EQ(m.points_invented, 10u);
  EXPECT_EQ(m.missing_pixels, 140u);
  EXPECT_EQ(m.truth_pixels, 1200u);
  EXPECT_EQ(m.flat_pixels + m.feature_pixels, 1200u - 140u);
}

TEST(Evaluation, TemporalStdIsZeroForIdenticalFramesAndExactForAlternatingOffsets)
{
  SceneOptions o = noiseFree(SceneType::plane);
  o.width = 80;
  o.height = 60;
  o.noise = NoiseModel::kinect;
  const SyntheticFrame f = renderFrame(o);
  const std::vector<Truth> truth(4, f.truth);

  const SequenceMetrics same = evaluateSequence(truth, std::vector<Cloud>(4, f.noisy));
  EXPECT_EQ(same.temporal_pixels, 80u * 60u);
  EXPECT_EQ(same.temporal_std, 0.0);
  EXPECT_GT(same.total.flat_rmse, 0.001) << "the frames are noisy, only not over time";

  // Residuals +d, -d, +d, -d: sample standard deviation d * sqrt(4 / 3) at every pixel.
  const double d = 0.001;
  std::vector<Cloud> alternating;
  for (int k = 0; k < 4; ++k)
    alternating.push_back(offsetAlongNormals(f.truth, [&](std::size_t) { return k % 2 ? -d : d; }));
  const SequenceMetrics alt = evaluateSequence(truth, alternating);
  EXPECT_EQ(alt.temporal_pixels, 80u * 60u);
  EXPECT_NEAR(alt.temporal_std, d * std::sqrt(4.0 / 3.0), 2e-7); // float coordinates
  EXPECT_NEAR(alt.total.flat_rmse, d, 2e-7);
  EXPECT_EQ(alt.moving_edge_pixels, 0u);
  EXPECT_TRUE(std::isnan(alt.moving_edge_rmse));

  // A pixel that is NaN in one result frame is not a static pixel.
  alternating[2][0].x = alternating[2][0].y = alternating[2][0].z = kNaN;
  EXPECT_EQ(evaluateSequence(truth, alternating).temporal_pixels, 80u * 60u - 1u);

  // One frame has no temporal statistics.
  const SequenceMetrics one = evaluateSequence({f.truth}, {f.noisy});
  EXPECT_TRUE(std::isnan(one.temporal_std));
  EXPECT_EQ(one.temporal_pixels, 0u);
}

TEST(Evaluation, PooledSequenceMetricsWeighEveryPixel)
{
  SceneOptions o = noiseFree(SceneType::plane);
  o.width = 80;
  o.height = 60;
  const Truth t = renderFrame(o).truth;
  // Frame errors of 1 mm and 3 mm over equal pixel counts pool to sqrt(5) mm.
  const SequenceMetrics s = evaluateSequence(
      {t, t}, {offsetAlongNormals(t, [](std::size_t) { return 0.001; }),
               offsetAlongNormals(t, [](std::size_t) { return 0.003; })});
  ASSERT_EQ(s.frames.size(), 2u);
  EXPECT_NEAR(s.frames[0].flat_rmse, 0.001, 2e-7); // float coordinates
  EXPECT_NEAR(s.frames[1].flat_rmse, 0.003, 2e-7);
  const double pooled = std::sqrt(0.5 * (s.frames[0].flat_rmse * s.frames[0].flat_rmse +
                                         s.frames[1].flat_rmse * s.frames[1].flat_rmse));
  EXPECT_NEAR(s.total.flat_rmse, pooled, 1e-12);
  EXPECT_NEAR(s.total.flat_rmse, std::sqrt(5.0) * 0.001, 2e-7);
  EXPECT_EQ(s.total.flat_pixels, 2u * 80u * 60u);
}

TEST(Evaluation, MovingEdgesAreFoundOnlyWhereTheTruthMoves)
{
  SceneOptions o = smallBoxes();
  o.frames = 3;
  o.motion = Motion::moving_box;
  const std::vector<SyntheticFrame> frames = renderSequence(o);
  const int moving = Scene::build(o, 0).movingShape();
  std::vector<Truth> truth;
  std::vector<Cloud> shifted, box_only;
  std::size_t valid_pixels = 0;
  for (const SyntheticFrame& f : frames) {
    truth.push_back(f.truth);
    shifted.push_back(offsetAlongNormals(f.truth, [](std::size_t) { return 0.002; }));
    box_only.push_back(offsetAlongNormals(f.truth, [&](std::size_t i) { return f.shape_index[i] == moving ? 0.005 : 0.0; }));
  }
  for (const auto& p : truth[0])
    valid_pixels += valid(p);

  const SequenceMetrics uniform = evaluateSequence(truth, shifted);
  EXPECT_GT(uniform.moving_edge_pixels, 500u);
  EXPECT_NEAR(uniform.moving_edge_rmse, 0.002, 1e-6);

  // Brute-force count: feature pixels of frame k within 3 px of a pixel whose truth differs
  // from frame k - 1 or k + 1.
  const int w = int(o.width), h = int(o.height);
  auto differs = [&](int a, int b, int i) {
    const auto &p = truth[a][i], &q = truth[b][i];
    if (valid(p) != valid(q))
      return true;
    return valid(p) && (Eigen::Vector3f(p.x, p.y, p.z) - Eigen::Vector3f(q.x, q.y, q.z)).norm() > 1e-5f;
  };
  std::size_t expected = 0;
  for (int k = 0; k < 3; ++k) {
    const std::vector<unsigned char> feature = featureMask(truth[k]);
    for (int v = 0; v < h; ++v)
      for (int u = 0; u < w; ++u) {
        if (!feature[v * w + u])
          continue;
        bool near = false;
        for (int dv = -3; dv <= 3 && !near; ++dv)
          for (int du = -3; du <= 3 && !near; ++du) {
            const int nu = u + du, nv = v + dv;
            if (nu < 0 || nv < 0 || nu >= w || nv >= h)
              continue;
            const int j = nv * w + nu;
            near = (k > 0 && differs(k, k - 1, j)) || (k < 2 && differs(k, k + 1, j));
          }
        expected += near;
      }
  }
  EXPECT_EQ(uniform.moving_edge_pixels, expected);

  // Only the box is wrong: its edges carry the error, the static pixels do not flicker.
  const SequenceMetrics box = evaluateSequence(truth, box_only);
  EXPECT_GT(box.moving_edge_rmse, 0.001);
  EXPECT_EQ(box.temporal_std, 0.0);
  EXPECT_LT(box.temporal_pixels, valid_pixels - 1000u) << "the moving box is not static";
  EXPECT_GT(box.temporal_pixels, valid_pixels / 2);

  // A static sequence has no moving edge and every valid pixel is static.
  o.motion = Motion::none;
  const std::vector<SyntheticFrame> still = renderSequence(o);
  std::vector<Truth> still_truth;
  std::vector<Cloud> still_result;
  for (const SyntheticFrame& f : still) {
    still_truth.push_back(f.truth);
    still_result.push_back(offsetAlongNormals(f.truth, [](std::size_t) { return 0.002; }));
  }
  const SequenceMetrics s = evaluateSequence(still_truth, still_result);
  EXPECT_EQ(s.moving_edge_pixels, 0u);
  EXPECT_TRUE(std::isnan(s.moving_edge_rmse));
  EXPECT_EQ(s.temporal_pixels, valid_pixels);
}

TEST(Evaluation, StreamingEvaluatorEqualsTheWholeSequenceEvaluation)
{
  SceneOptions o = smallBoxes();
  o.noise = NoiseModel::kinect;
  o.frames = 3;
  o.motion = Motion::moving_box;
  const std::vector<SyntheticFrame> frames = renderSequence(o);
  std::vector<Truth> truth;
  std::vector<Cloud> noisy;
  SequenceEvaluator evaluator;
  for (const SyntheticFrame& f : frames) {
    truth.push_back(f.truth);
    noisy.push_back(f.noisy);
    const FrameMetrics m = evaluator.add(f.truth, f.noisy);
    EXPECT_EQ(m.flat_rmse, evaluateFrame(f.truth, f.noisy).flat_rmse);
  }
  const SequenceMetrics a = evaluator.metrics(), b = evaluateSequence(truth, noisy);
  EXPECT_EQ(a.total.flat_rmse, b.total.flat_rmse);
  EXPECT_EQ(a.total.feature_rmse, b.total.feature_rmse);
  EXPECT_EQ(a.temporal_std, b.temporal_std);
  EXPECT_EQ(a.moving_edge_rmse, b.moving_edge_rmse);
  // Kinect noise at 0.8 - 3 m: several millimetres.
  EXPECT_GT(a.total.flat_rmse, 0.003);
  EXPECT_LT(a.total.flat_rmse, 0.02);
  EXPECT_GT(a.temporal_std, 0.003);
}

TEST(Evaluation, MismatchedInputsThrowNamingTheProblem)
{
  const Truth t = gridTruth(20, 12, [](int, int) { return 1.0; });
  const Cloud small(10, 10);
  try {
    evaluateFrame(t, small);
    FAIL() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("result is 10 x 10 but the ground truth is 20 x 12"), std::string::npos)
        << e.what();
  }
  const Cloud good = xyzOf(t);
  EXPECT_THROW(evaluateFrame(t, good, &small), std::invalid_argument);
  EXPECT_THROW(evaluateSequence({t, t}, {good}), std::invalid_argument);
  EXPECT_THROW(evaluateSequence({t}, {good}, {good, good}), std::invalid_argument);
  SequenceEvaluator evaluator;
  evaluator.add(t, good);
  const Truth other = gridTruth(30, 12, [](int, int) { return 1.0; });
  try {
    evaluator.add(other, xyzOf(other));
    FAIL() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("frame 1"), std::string::npos) << e.what();
  }
  EvaluationOptions bad;
  bad.feature_radius = -1;
  EXPECT_THROW(featureMask(t, bad), std::invalid_argument);
  bad = EvaluationOptions{};
  bad.normal_window = 4;
  try {
    evaluateFrame(t, good, nullptr, bad);
    FAIL() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("normal_window = 4"), std::string::npos) << e.what();
  }
}

TEST(Evaluation, TableAndJsonPrintMillimetresAndMarkMissingValues)
{
  const Truth t = gridTruth(20, 12, [](int, int) { return 1.0; });
  const FrameMetrics m = evaluateFrame(t, offsetAlongNormals(t, [](std::size_t) { return 0.0025; }));
  const std::string json = toJson(m);
  EXPECT_NE(json.find("\"flat_rmse_mm\": 2.5"), std::string::npos) << json;
  EXPECT_NE(json.find("\"feature_rmse_mm\": null"), std::string::npos) << json;
  EXPECT_NE(json.find("\"points_lost\": null"), std::string::npos) << json;
  const std::string row = metricsTableRow("frame_0000.pcd", m);
  EXPECT_EQ(row.rfind("frame_0000.pcd", 0), 0u);
  EXPECT_NE(row.find("2.500"), std::string::npos) << row;
  EXPECT_EQ(row.back(), '-') << "no input: lost points unknown";
  EXPECT_EQ(metricsTableHeader().size(), row.size());

  SequenceMetrics s = evaluateSequence({t}, {xyzOf(t)});
  const std::string sequence_json = toJson(s, {"a\"b.pcd"});
  EXPECT_NE(sequence_json.find("\"frame_count\": 1"), std::string::npos) << sequence_json;
  EXPECT_NE(sequence_json.find("\"name\": \"a\\\"b.pcd\""), std::string::npos) << sequence_json;
  EXPECT_NE(sequence_json.find("\"temporal_std_mm\": null"), std::string::npos) << sequence_json;
}

namespace
{

/// Organized cloud of pixels (u, v) seen with f = 100 px, principal point at the centre, at
/// depth z(u, v) along each pixel's ray.
Cloud
rayCloud(int width, int height, const std::function<double(int, int)>& depth)
{
  Cloud c(width, height);
  for (int v = 0; v < height; ++v)
    for (int u = 0; u < width; ++u) {
      const double z = depth(u, v);
      pcl::PointXYZ& p = c.at(u, v);
      p.x = float((u - 0.5 * (width - 1)) / 100.0 * z);
      p.y = float((v - 0.5 * (height - 1)) / 100.0 * z);
      p.z = float(z);
    }
  c.is_dense = true;
  return c;
}

} // namespace

TEST(Evaluation, PlanarResidualOfANoisyPlaneIsItsNoise)
{
  SceneOptions o;
  o.scene = SceneType::plane;
  o.plane_depth = 1.5;
  o.width = 160;
  o.height = 120;
  o.fx = o.fy = 131.25;
  const SyntheticFrame raw = renderFrame(o, 0), other = renderFrame(o, 1);
  const PlanarRegions regions = findPlanarRegions(raw.noisy);
  ASSERT_EQ(regions.planes.size(), 1u);
  EXPECT_EQ(regions.sizes[0], raw.noisy.size());
  EXPECT_NEAR(std::abs(regions.planes[0][2]), 1.0, 1e-3);
  EXPECT_NEAR(regions.planes[0][3] / -regions.planes[0][2], 1.5, 1e-3);
  const double sigma = kinectAxialSigma(1.5);
  // Another frame of the same plane: its own noise, about the known sigma.
  const PlanarResidual noisy = planarResidual(regions, other.noisy);
  EXPECT_EQ(noisy.regions, 1u);
  EXPECT_EQ(noisy.interior_pixels, raw.noisy.size());
  EXPECT_EQ(noisy.border_pixels, 0u) << "the image border is not a region border";
  EXPECT_NEAR(noisy.interior_rms, sigma, 0.03 * sigma);
  EXPECT_TRUE(std::isnan(noisy.border_rms));
  // The exact plane has (almost) no residual: only the fit's error on the noisy raw frame.
  Cloud exact(o.width, o.height);
  for (std::size_t i = 0; i < exact.size(); ++i)
    exact[i].x = raw.truth[i].x, exact[i].y = raw.truth[i].y, exact[i].z = raw.truth[i].z;
  EXPECT_LT(planarResidual(regions, exact).interior_rms, 0.05 * sigma);
}

TEST(Evaluation, PlanarResidualReportsTheBorderBandBleedingAndLostPoints)
{
  // Left half at 1 m, right half at 1.3 m: two regions meeting at column 40.
  const int width = 80, height = 60;
  auto step = [](int u, int) { return u < 40 ? 1.0 : 1.3; };
  const Cloud raw = rayCloud(width, height, step);
  PlanarRegionOptions options;
  options.min_region_pixels = 500;
  options.border_band = 3;
  const PlanarRegions regions = findPlanarRegions(raw, options);
  ASSERT_EQ(regions.planes.size(), 2u);
  EXPECT_EQ(regions.sizes[0] + regions.sizes[1], std::size_t(width * height));
  PlanarResidual r = planarResidual(regions, raw);
  // Three columns on each side of the step.
  EXPECT_EQ(r.border_pixels, std::size_t(2 * 3 * height));
  EXPECT_EQ(r.interior_pixels, std::size_t(width * height - 2 * 3 * height));
  EXPECT_LT(r.interior_rms, 1e-6);
  EXPECT_LT(r.border_rms, 1e-6);
  EXPECT_EQ(r.points_lost, 0u);

  // A filter that bleeds: the two columns on each side of the step move 10 cm toward the other
  // side; five points are lost.
  Cloud bled = rayCloud(width, height, [](int u, int v) {
    if (u >= 38 && u < 40)
      return 1.1;
    if (u >= 40 && u < 42)
      return 1.2;
    return u < 40 ? 1.0 : 1.3 + 0.0 * v;
  });
  for (int k = 0; k < 5; ++k)
    bled.at(10 + k, 10).x = bled.at(10 + k, 10).y = bled.at(10 + k, 10).z = kNaN;
  r = planarResidual(regions, bled);
  EXPECT_EQ(r.points_lost, 5u);
  EXPECT_EQ(r.border_pixels, std::size_t(2 * 3 * height));
  EXPECT_LT(r.interior_rms, 1e-6);
  // Orthogonal distance to a fronto-parallel plane is the depth offset: 4 of 6 band columns are 10 cm off.
  EXPECT_NEAR(r.border_rms, 0.1 * std::sqrt(4.0 / 6.0), 1e-5);
  EXPECT_EQ(r.regions, 2u);

  const std::string json = toJson(r);
  EXPECT_NE(json.find("\"border_rms_mm\": 81.6"), std::string::npos) << json;
  EXPECT_NE(json.find("\"points_lost\": 5"), std::string::npos) << json;
  EXPECT_THROW(planarResidual(regions, Cloud(width + 1, height)), std::invalid_argument);
}

TEST(Evaluation, PlanarRegionsAreFoundOnRealisticScenesAndSmallOnesDropped)
{
  // On the boxes scene the floor and the back wall are the largest planes.
  SceneOptions o;
  o.noise = NoiseModel::kinect;
  const SyntheticFrame f = renderFrame(o, 0);
  const PlanarRegions regions = findPlanarRegions(f.noisy);
  ASSERT_GE(regions.planes.size(), 2u);
  for (std::size_t size : regions.sizes)
    EXPECT_GE(size, 2000u);
  // Each region lies on one shape of the scene, but for the strips within the noise of a crease
  // or contact (wall, box and cylinder bottoms on the floor, a few rows at 2-3 m).
  std::vector<std::map<int, std::size_t>> shapes(regions.planes.size());
  for (std::size_t i = 0; i < f.noisy.size(); ++i)
    if (regions.label[i] >= 0)
      ++shapes[std::size_t(regions.label[i])][f.shape_index[i]];
  for (const auto& s : shapes) {
    std::size_t total = 0, largest = 0;
    for (const auto& [shape, count] : s) {
      total += count;
      largest = std::max(largest, count);
    }
    EXPECT_GT(double(largest), 0.95 * double(total));
  }
  PlanarRegionOptions big;
  big.min_region_pixels = 1 << 20;
  EXPECT_TRUE(findPlanarRegions(f.noisy, big).planes.empty());
  const PlanarResidual none = planarResidual(findPlanarRegions(f.noisy, big), f.noisy);
  EXPECT_TRUE(std::isnan(none.interior_rms));
  EXPECT_NE(toJson(none).find("\"interior_rms_mm\": null"), std::string::npos) << toJson(none);

  PlanarRegionOptions bad;
  bad.border_band = -1;
  try {
    findPlanarRegions(f.noisy, bad);
    FAIL() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("border_band = -1"), std::string::npos) << e.what();
  }
}

TEST(Evaluation, JitterOfAStaticSequenceIsItsPerFrameNoise)
{
  const int width = 40, height = 30, frames = 20;
  const double sigma = 0.002;
  const Cloud base = rayCloud(width, height, [](int u, int v) { return 2.0 + 0.001 * (u + v); });
  std::mt19937 rng(5);
  std::normal_distribution<double> normal(0.0, sigma);
  JitterEvaluator evaluator;
  std::vector<Cloud> all;
  for (int k = 0; k < frames; ++k) {
    Cloud f = base;
    for (auto& p : f) {
      // Range noise: move along the ray by a N(0, sigma) change of |p|.
      const double r = std::sqrt(double(p.x) * p.x + double(p.y) * p.y + double(p.z) * p.z);
      const double s = (r + normal(rng)) / r;
      p.x = float(p.x * s), p.y = float(p.y * s), p.z = float(p.z * s);
    }
    if (k == 7)
      f.at(3, 4).x = f.at(3, 4).y = f.at(3, 4).z = kNaN;
    evaluator.add(f);
    all.push_back(f);
  }
  const TemporalJitter j = evaluator.jitter();
  EXPECT_EQ(j.frames, std::size_t(frames));
  EXPECT_EQ(j.pixels, std::size_t(width * height - 1)) << "pixels valid in every frame";
  // E[s] = c4(20) sigma = 0.9869 sigma; median of s = sigma * sqrt(chi2_19 median / 19) ~ 0.9826 sigma.
  EXPECT_NEAR(j.mean, 0.9869 * sigma, 0.02 * sigma);
  EXPECT_NEAR(j.median, 0.9826 * sigma, 0.025 * sigma);
  const TemporalJitter whole = temporalJitter(all);
  EXPECT_EQ(whole.mean, j.mean);
  EXPECT_EQ(whole.median, j.median);
  // Identical frames do not jitter; one frame has no jitter to measure.
  EXPECT_EQ(temporalJitter({base, base, base}).mean, 0.0);
  EXPECT_TRUE(std::isnan(temporalJitter({base}).median));
  EXPECT_NE(toJson(temporalJitter({base})).find("\"mean_jitter_mm\": null"), std::string::npos);
  EXPECT_NE(toJson(j).find("\"frames\": 20"), std::string::npos) << toJson(j);
  JitterEvaluator mismatched;
  mismatched.add(base);
  EXPECT_THROW(mismatched.add(Cloud(width, height + 1)), std::invalid_argument);
}

TEST(Evaluation, ToolScoresRealFramesWithoutGroundTruth)
{
  namespace fs = std::filesystem;
  const fs::path dir = fs::temp_directory_path() / ("range_nlm_eval_real_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir / "sequence");
  const int width = 80, height = 60;
  const Cloud raw = rayCloud(width, height, [](int u, int) { return u < 40 ? 1.0 : 1.3; });
  Cloud bled = rayCloud(width, height, [](int u, int) { return u < 38 ? 1.0 : u < 40 ? 1.1 : u < 42 ? 1.2 : 1.3; });
  for (int k = 0; k < 5; ++k)
    bled.at(10 + k, 10).x = bled.at(10 + k, 10).y = bled.at(10 + k, 10).z = kNaN;
  ASSERT_EQ(pcl::io::savePCDFileBinary((dir / "raw.pcd").string(), raw), 0);
  ASSERT_EQ(pcl::io::savePCDFileBinary((dir / "bled.pcd").string(), bled), 0);
  for (int k = 0; k < 3; ++k)
    ASSERT_EQ(pcl::io::savePCDFileBinary((dir / "sequence" / ("f" + std::to_string(k) + ".pcd")).string(),
                                         k == 1 ? bled : raw),
              0);

  test::CommandResult r = test::runTool("range_nlm_eval", "--raw " + (dir / "raw.pcd").string() + " " +
                                                              (dir / "bled.pcd").string() + " --min-region 500 --json");
  ASSERT_EQ(r.status, 0) << r.output;
  // The raw frame first (no residual), then the bled one.
  EXPECT_NE(r.output.find("\"border_pixels\": 360, \"points_lost\": 0}"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("\"border_rms_mm\": 81.6"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("\"points_lost\": 5}"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("\"regions\": 2"), std::string::npos) << r.output;

  r = test::runTool("range_nlm_eval", "--jitter " + (dir / "sequence").string() + " --json");
  ASSERT_EQ(r.status, 0) << r.output;
  // Pixels valid in all three frames; only the four bled columns move (by 10 cm twice).
  EXPECT_NE(r.output.find("\"frames\": 3, \"pixels\": 4795"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("\"median_jitter_mm\": 0}"), std::string::npos) << r.output;

  r = test::runTool("range_nlm_eval", "--raw " + (dir / "raw.pcd").string() + " --border-band -1");
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_NE(r.output.find("border_band = -1"), std::string::npos) << r.output;
  r = test::runTool("range_nlm_eval", "--raw " + (dir / "raw.pcd").string() + " " + (dir / "none.pcd").string());
  EXPECT_EQ(r.status, 1) << r.output;
  EXPECT_NE(r.output.find("none.pcd"), std::string::npos) << r.output;
  fs::remove_all(dir);
}
