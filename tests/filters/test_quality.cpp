// Quality regression: accuracy of the default setting against ground truth on small generated
// scenes (the full comparison with PCL's filters is `range_nlm_bench --quality`).
#include <range_nlm/eval/metrics.h>
#include <range_nlm/nonlocal_means_filter.h>
#include <range_nlm/eval/synthetic_scene.h>
#include <range_nlm/temporal_nonlocal_means_filter.h>

#include <gtest/gtest.h>

#include <cstdio>
#include <deque>

using namespace range_nlm;
using Cloud = pcl::PointCloud<pcl::PointXYZ>;

namespace
{
/// The boxes scene at 200 x 150 with the field of view of the 640 x 480 camera.
SceneOptions
smallScene(const char* noise, int frames, std::uint64_t seed)
{
  SceneOptions o;
  o.width = 200;
  o.height = 150;
  o.fx = o.fy = 525.0 * 200 / 640;
  o.noise = noiseModelFromString(noise);
  o.frames = frames;
  o.seed = seed;
  return o;
}

FrameMetrics
score(const std::vector<SyntheticFrame>& seq, const FilterParameters& p, std::size_t frames)
{
  std::deque<Cloud::ConstPtr> window;
  for (std::size_t k = 0; k < frames; ++k)
    window.emplace_back(new Cloud(seq[k].noisy));
  const std::size_t c = frames / 2;
  TemporalNonLocalMeansFilter<pcl::PointXYZ> f;
  f.setParameters(p);
  f.setFrames(window, c);
  Cloud out;
  f.filter(out);
  return evaluateFrame(seq[c].truth, out, window[c].get());
}

void
print(const char* what, const FrameMetrics& m)
{
  std::printf("%-28s flat %.3f mm, feature %.3f mm, lost %zu\n", what, 1000 * m.flat_rmse, 1000 * m.feature_rmse,
              m.points_lost);
}
} // namespace

TEST(Quality, DepthCameraNoiseDefaultsBeatThePaperPreset)
{
  const auto seq = renderSequence(smallScene("kinect", 1, 3));
  const FrameMetrics input = evaluateFrame(seq[0].truth, seq[0].noisy);
  const FrameMetrics def = score(seq, FilterParameters::recommended(), 1);
  const FrameMetrics paper = score(seq, FilterParameters::paper(), 1);
  print("input", input);
  print("default", def);
  print("paper", paper);
  EXPECT_LT(def.flat_rmse, 0.8 * paper.flat_rmse);
  EXPECT_LT(def.feature_rmse, 0.9 * paper.feature_rmse);
  // Measured 1.71 / 3.75 mm (input 10.1 / 9.0 mm, paper preset 5.5 / 7.8 mm).
  EXPECT_LT(def.flat_rmse, 2.0e-3);
  EXPECT_LT(def.feature_rmse, 4.3e-3);
  EXPECT_EQ(def.points_lost, 0u);
}

TEST(Quality, LaserGradeNoiseThresholds)
{
  const auto seq = renderSequence(smallScene("laser", 1, 4));
  const FrameMetrics input = evaluateFrame(seq[0].truth, seq[0].noisy);
  const FrameMetrics def = score(seq, FilterParameters::recommended(), 1);
  print("input", input);
  print("default", def);
  // Measured 1.21 / 1.90 mm (input 2.53 / 2.29 mm); pixels are 3.2x coarser than at 640 x 480.
  EXPECT_LT(def.flat_rmse, 1.4e-3);
  EXPECT_LT(def.feature_rmse, 2.2e-3);
  EXPECT_EQ(def.points_lost, 0u);
}

TEST(Quality, TemporalWindowImprovesOnOneFrame)
{
  const auto seq = renderSequence(smallScene("kinect", 3, 5));
  const FrameMetrics one = [&] {
    std::vector<SyntheticFrame> centre{seq[1]};
    return score(centre, FilterParameters::recommended(), 1);
  }();
  const FrameMetrics three = score(seq, FilterParameters::recommended(), 3);
  print("one frame", one);
  print("three frames", three);
  // Measured 1.53 vs 1.73 mm.
  EXPECT_LT(three.flat_rmse, 0.95 * one.flat_rmse);
  EXPECT_LT(three.feature_rmse, one.feature_rmse);
}
