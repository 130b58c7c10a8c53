// The frame change analysis (analyseFrameChange), the motion test (framesMoved) and the
// frame-to-frame noise ratio (estimateTemporalNoiseRatio) of the guarded cross-frame bandwidths,
// and the levelling of frames that differ by a drift along the rays.
#include "frame_fixtures.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

using namespace range_nlm;
using namespace range_nlm::test;

TEST(FramesMoved, NoiseIsNotMotionAShiftIs)
{
  SceneOptions o = planeScene("stereo", 320, 240, 2);
  o.scene = SceneType::boxes;
  const auto seq = renderSequence(o);
  const Grid a = gridOf(seq[0].noisy), b = gridOf(seq[1].noisy);
  const NormalField n = estimateNormals(a, 7, kOrigin, 0);
  // A static scene with fresh correlated noise in each frame: not moved.
  EXPECT_FALSE(framesMoved(a, n, b));
  // The camera 40 mm closer (about twice this sensor's noise at these ranges): every point 40 mm
  // nearer along its ray.
  Grid closer = b;
  for (std::size_t i = 0; i < closer.size(); ++i) {
    const float len = std::sqrt(closer.x[i] * closer.x[i] + closer.y[i] * closer.y[i] + closer.z[i] * closer.z[i]);
    const float f = (len - 0.040f) / len;
    closer.x[i] *= f, closer.y[i] *= f, closer.z[i] *= f;
  }
  EXPECT_TRUE(framesMoved(a, n, closer));
  // Too few blocks to tell: not moved.
  Grid tiny(16, 12);
  EXPECT_FALSE(framesMoved(tiny, estimateNormals(tiny, 3, kOrigin, 0), tiny));
}

// A depth camera that stands still may see its whole depth map drift from frame to frame by
// more than its noise, slowly varying over the image (active stereo); a camera that moves shifts
// the image's structure too. Only the latter is motion.
TEST(FrameChange, NoiseIsNoneADriftAlongTheRaysIsAnOffsetAShiftIsMotion)
{
  SceneOptions o = planeScene("stereo", 320, 240, 2);
  o.scene = SceneType::boxes;
  const auto seq = renderSequence(o);
  const Grid a = gridOf(seq[0].noisy), b = gridOf(seq[1].noisy);
  const float w = static_cast<float>(a.width);
  // Fresh correlated noise in each frame of a static scene: no change.
  const FrameOffset noise = analyseFrameChange(a, b, kOrigin);
  EXPECT_EQ(noise.change, FrameChange::none);
  EXPECT_TRUE(noise.range_offset.empty());
  // The depth 40 to 60 mm farther, growing across the image: an offset, and the field follows it.
  const auto drift = [w](int u) { return 0.040f + 0.020f * u / w; };
  const Grid drifted = alongRays(b, drift);
  const FrameOffset offset = analyseFrameChange(a, drifted, kOrigin);
  ASSERT_EQ(offset.change, FrameChange::offset);
  ASSERT_EQ(offset.range_offset.size(), a.size());
  std::vector<float> errors;
  for (int v = 0; v < a.height; ++v)
    for (int u = 0; u < a.width; ++u)
      errors.push_back(std::fabs(offset.range_offset[static_cast<std::size_t>(v) * a.width + u] - drift(u)));
  std::nth_element(errors.begin(), errors.begin() + errors.size() / 2, errors.end());
  EXPECT_LT(errors[errors.size() / 2], 0.003f);
  const std::size_t row = static_cast<std::size_t>(a.height / 2) * a.width;
  EXPECT_GT(offset.range_offset[row + a.width - 1] - offset.range_offset[row], 0.012f);
  // The same drift with the image shifted by 3 pixels along the rows (the camera turned): motion.
  Grid turned(a.width, a.height);
  for (int v = 0; v < a.height; ++v)
    for (int u = 3; u < a.width; ++u) {
      const std::size_t to = static_cast<std::size_t>(v) * a.width + u, from = to - 3;
      turned.x[to] = drifted.x[from], turned.y[to] = drifted.y[from], turned.z[to] = drifted.z[from];
      turned.valid[to] = drifted.valid[from];
    }
  EXPECT_EQ(analyseFrameChange(a, turned, kOrigin).change, FrameChange::motion);
  // Blocks of 64 pixels alternately 150 mm farther and not: no smooth drift explains them (an
  // object moved against the rest), so motion, although nothing moved across the image.
  const Grid far = alongRays(b, [](int) { return 0.150f; });
  Grid patches = b;
  for (int v = 0; v < a.height; ++v)
    for (int u = 0; u < a.width; ++u) {
      const std::size_t i = static_cast<std::size_t>(v) * a.width + u;
      if ((u / 64 + v / 64) % 2 == 0)
        patches.x[i] = far.x[i], patches.y[i] = far.y[i], patches.z[i] = far.z[i];
    }
  EXPECT_EQ(analyseFrameChange(a, patches, kOrigin).change, FrameChange::motion);
  // Too few blocks (20 at 40 x 32) to tell a drift from blocks that moved: motion.
  SceneOptions tiny = planeScene("kinect", 40, 32, 2);
  const auto small = renderSequence(tiny);
  EXPECT_EQ(analyseFrameChange(gridOf(small[0].noisy), alongRays(gridOf(small[1].noisy), drift), kOrigin).change,
            FrameChange::motion);
  EXPECT_EQ(analyseFrameChange(a, a, kOrigin).change, FrameChange::none);
  for (int threads : {2, 3}) {
    const FrameOffset t = detail::analyseFrameChange(a, drifted, kOrigin, threads);
    EXPECT_EQ(t.change, offset.change) << threads;
    EXPECT_EQ(t.range_offset, offset.range_offset) << threads;
    EXPECT_EQ(detail::analyseFrameChange(a, turned, kOrigin, threads).change, FrameChange::motion) << threads;
  }
}

// Three frames of a static camera whose depth drifts by +45...+55, +15 and -60...-70 mm (mean 0):
// the default brings them to their mean level and filters the current frame there, close to the
// truth, where the paper's cross-frame bandwidths keep its +15 mm.
TEST(FrameChange, TemporalRunAveragesTheDriftOfAStaticCamera)
{
  SceneOptions o = planeScene("stereo", 320, 240, 3);
  o.scene = SceneType::boxes;
  const auto seq = renderSequence(o);
  const float w = static_cast<float>(o.width);
  const Grid f0 = alongRays(gridOf(seq[0].noisy), [w](int u) { return 0.045f + 0.010f * u / w; });
  const Grid f1 = alongRays(gridOf(seq[1].noisy), [](int) { return 0.015f; });
  const Grid f2 = alongRays(gridOf(seq[2].noisy), [w](int u) { return -0.060f - 0.010f * u / w; });
  ASSERT_EQ(analyseFrameChange(f1, f0, kOrigin).change, FrameChange::offset);
  ASSERT_EQ(analyseFrameChange(f1, f2, kOrigin).change, FrameChange::offset);
  const auto& truth = seq[1].truth;
  // Median of the signed range error of the filtered current frame against the truth.
  const auto medianError = [&](const FilterParameters& p) {
    const FilterRun run = runFilter({&f0, &f1, &f2}, 1, p, kOrigin, {});
    std::vector<float> errors;
    for (std::size_t i = 0; i < run.output.size(); ++i) {
      const pcl::PointNormal& t = truth.points[i];
      if (run.output.valid[i] && std::isfinite(t.z))
        errors.push_back(rangeOf(run.output, i) - std::sqrt(t.x * t.x + t.y * t.y + t.z * t.z));
    }
    std::nth_element(errors.begin(), errors.begin() + errors.size() / 2, errors.end());
    return errors[errors.size() / 2];
  };
  FilterParameters p = FilterParameters::recommended();
  EXPECT_LT(std::fabs(medianError(p)), 0.003f);
  p.cross_frame_bandwidth = CrossFrameBandwidth::spatial;
  EXPECT_GT(medianError(p), 0.010f);
}

// The temporal filter's motion test and frame-to-frame noise ratio run on several threads: the
// same answers as one thread; and the temporal default (radius 1, guarded cross-frame bandwidths,
// automatic dilation) gives the same bits with 1, 2 and 3 threads, with holes and borders.
TEST(FramesMoved, MotionTestNoiseRatioAndTemporalRunDoNotDependOnTheThreadCount)
{
  SceneOptions o = planeScene("stereo", 320, 240, 3);
  o.scene = SceneType::boxes;
  o.dropout = 0.05;
  const auto seq = renderSequence(o);
  const Grid a = gridOf(seq[1].noisy), b = gridOf(seq[0].noisy), c = gridOf(seq[2].noisy);
  const NormalField n = estimateNormals(a, 7, kOrigin, 1);
  const NoiseProfile profile = estimateNoiseProfile(b, 9, 1000, 7, kOrigin);
  Grid closer = b;
  for (std::size_t i = 0; i < closer.size(); ++i)
    closer.z[i] -= 0.04f;
  const float ratio = estimateTemporalNoiseRatio(a, n, b, profile, kOrigin);
  EXPECT_GT(ratio, 0.0f);
  for (int threads : {2, 3}) {
    EXPECT_EQ(detail::framesMoved(a, n, b, threads), framesMoved(a, n, b)) << threads;
    EXPECT_EQ(detail::framesMoved(a, n, closer, threads), framesMoved(a, n, closer)) << threads;
    EXPECT_EQ(detail::estimateTemporalNoiseRatio(a, n, b, profile, kOrigin, threads), ratio) << threads;
  }
  FilterParameters p = FilterParameters::recommended();
  p.threads = 1;
  const FilterRun one = runFilter({&b, &a, &c}, 1, p, kOrigin, {});
  EXPECT_FALSE(sameBits(one.output, a));
  for (int threads : {2, 3}) {
    p.threads = threads;
    EXPECT_TRUE(sameBits(runFilter({&b, &a, &c}, 1, p, kOrigin, {}).output, one.output)) << threads << " threads";
  }
}
