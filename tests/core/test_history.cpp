// The recursive window's history (updateRunningAverage): what it averages, where it starts over.
#include <range_nlm/core/pipeline.h>
#include <range_nlm/eval/synthetic_scene.h>

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

using namespace range_nlm;

namespace
{
const Viewpoint kOrigin{0.0f, 0.0f, 0.0f};
constexpr int kLength = 3; // a radius-1 history: the newest frame weighted 1 / 3

Grid
gridOf(const pcl::PointCloud<pcl::PointXYZ>& c)
{
  return Grid::fromInterleaved(reinterpret_cast<const float*>(c.points.data()), static_cast<int>(c.width),
                               static_cast<int>(c.height), sizeof(pcl::PointXYZ) / sizeof(float));
}

/// Frames of a plane 1.5 m in front of a 160 x 120 camera, Kinect-like noise (about 4 mm there),
/// fresh noise per frame; the noise-free frame in `truth`.
std::vector<Grid>
noisyPlanes(int frames, Grid* truth = nullptr)
{
  SceneOptions o;
  o.width = 160;
  o.height = 120;
  o.fx = o.fy = 525.0 * 160 / 640;
  o.scene = SceneType::plane;
  o.plane_depth = 1.5;
  o.noise = noiseModelFromString("kinect");
  o.frames = frames;
  o.seed = 11;
  std::vector<Grid> out;
  for (const SyntheticFrame& f : renderSequence(o))
    out.push_back(gridOf(f.noisy));
  if (truth) {
    o.noise_scale = 0.0;
    *truth = gridOf(renderFrame(o).noisy);
  }
  return out;
}

float
rangeOf(const Grid& g, std::size_t i)
{
  return std::sqrt(g.x[i] * g.x[i] + g.y[i] * g.y[i] + g.z[i] * g.z[i]);
}

/// Every valid point moved along its ray by `delta` metres of range where `where(u, v)`.
template <typename Where>
Grid
shifted(Grid g, float delta, Where where)
{
  for (int v = 0; v < g.height; ++v)
    for (int u = 0; u < g.width; ++u) {
      const std::size_t i = static_cast<std::size_t>(v) * g.width + u;
      if (!g.valid[i] || !where(u, v))
        continue;
      const float f = (rangeOf(g, i) + delta) / rangeOf(g, i);
      g.x[i] *= f, g.y[i] *= f, g.z[i] *= f;
    }
  return g;
}

/// RMS range difference of a's valid points from b's.
double
rmsRangeDifference(const Grid& a, const Grid& b)
{
  double sum = 0.0;
  std::size_t n = 0;
  for (std::size_t i = 0; i < a.size(); ++i)
    if (a.valid[i] && b.valid[i]) {
      const double d = rangeOf(a, i) - rangeOf(b, i);
      sum += d * d;
      ++n;
    }
  return n ? std::sqrt(sum / n) : INFINITY;
}

void
add(RunningAverage& h, const Grid& frame, const Grid* start = nullptr, int threads = 1)
{
  updateRunningAverage(h, frame, start, kOrigin, kLength, 9, 1000, 42, threads);
}
} // namespace

TEST(RunningAverage, AStaticSceneIsAveragedOverFramesWithTheNewestWeightedOneThird)
{
  Grid truth;
  const std::vector<Grid> frames = noisyPlanes(12, &truth);
  RunningAverage h;
  for (const Grid& f : frames)
    add(h, f);
  const double raw = rmsRangeDifference(frames.back(), truth);
  const double averaged = rmsRangeDifference(h.average, truth);
  // An exponential average with weight 1/3 leaves sqrt((1/3) / (2 - 1/3)) = 0.45 of the noise.
  EXPECT_LT(averaged, 0.55 * raw) << "raw " << raw << " m, history " << averaged << " m";
  EXPECT_GT(averaged, 0.35 * raw) << "the newest frame keeps its weight of 1/3";
  std::size_t full = 0;
  for (std::uint16_t c : h.count)
    full += c == kLength;
  EXPECT_GT(full, 95 * h.count.size() / 100) << "a static scene's history does not start over";
  // Each point lies on its pixel's ray: the average of ranges, not of points.
  for (std::size_t i = 0; i < truth.size(); i += 97) {
    ASSERT_TRUE(h.average.valid[i]);
    const float r = rangeOf(h.average, i), q = rangeOf(frames.back(), i);
    EXPECT_NEAR(h.average.x[i] / r, frames.back().x[i] / q, 1e-5f);
    EXPECT_NEAR(h.average.z[i] / r, frames.back().z[i] / q, 1e-5f);
  }
}

TEST(RunningAverage, WhatMovedStartsOverAndADriftAlongTheRaysDoesNot)
{
  const std::vector<Grid> frames = noisyPlanes(6);
  RunningAverage h;
  for (int k = 0; k < 4; ++k)
    add(h, frames[k]);
  // The frame drifts 12 mm away along the rays (3 noise sigmas, as a static depth camera's frames
  // can), and a block of the scene comes 5 cm nearer besides (12 sigmas). Without taking the
  // drift out first, it would hide the block (the frame-to-frame noise ratio would take it in).
  auto block = [](int u, int v) { return u >= 60 && u < 100 && v >= 40 && v < 80; };
  Grid next = shifted(shifted(frames[4], -0.05f, block), 0.012f, [](int, int) { return true; });
  const Grid filtered = shifted(next, 0.0005f, [](int, int) { return true; }); // stands for its output
  add(h, next, &filtered);
  std::size_t moved_restarted = 0, moved = 0, still_kept = 0, still = 0;
  for (int v = 0; v < next.height; ++v)
    for (int u = 0; u < next.width; ++u) {
      const std::size_t i = static_cast<std::size_t>(v) * next.width + u;
      if (!next.valid[i])
        continue;
      const bool inner_block = u >= 62 && u < 98 && v >= 42 && v < 78;
      const bool far_from_block = u < 56 || u >= 104 || v < 36 || v >= 84;
      if (inner_block) {
        ++moved;
        // Started over from the filtered frame, counted as 2 of the 3 frames.
        moved_restarted += h.count[i] == kLength - 1 && std::fabs(rangeOf(h.average, i) - rangeOf(filtered, i)) < 1e-6f;
      } else if (far_from_block) {
        ++still;
        still_kept += h.count[i] == kLength;
      }
    }
  EXPECT_EQ(moved_restarted, moved) << "the block's history starts over";
  EXPECT_GT(still_kept, 97 * still / 100) << "a drift of one sigma is not taken for change";
}

TEST(RunningAverage, HolesEmptyAPixelsHistoryAndTheThreadCountChangesNothing)
{
  std::vector<Grid> frames = noisyPlanes(5);
  const std::size_t hole = 60 * 160 + 80;
  Grid& with_hole = frames[3];
  with_hole.x[hole] = with_hole.y[hole] = with_hole.z[hole] = NAN;
  with_hole.valid[hole] = 0;
  RunningAverage one, two;
  for (int k = 0; k < 4; ++k) {
    add(one, frames[k], nullptr, 1);
    add(two, frames[k], nullptr, 2);
  }
  EXPECT_EQ(one.count[hole], 0);
  EXPECT_FALSE(one.average.valid[hole]);
  EXPECT_TRUE(std::isnan(one.average.z[hole]));
  add(one, frames[4], nullptr, 1);
  add(two, frames[4], nullptr, 2);
  EXPECT_EQ(one.count[hole], 1) << "the pixel's history starts again from the frame";
  EXPECT_EQ(rangeOf(one.average, hole), rangeOf(frames[4], hole));
  EXPECT_EQ(one.count, two.count);
  EXPECT_EQ(one.average.x, two.average.x);
  EXPECT_EQ(one.average.z, two.average.z);
  // Another size: the history starts over from the frame.
  Grid small(8, 8);
  for (std::size_t i = 0; i < small.size(); ++i) {
    small.x[i] = 0.01f * (i % 8), small.y[i] = 0.01f * (i / 8), small.z[i] = 1.0f;
    small.valid[i] = 1;
  }
  add(one, small);
  EXPECT_EQ(one.average.width, 8);
  EXPECT_EQ(one.count, std::vector<std::uint16_t>(64, 1));
  Grid wrong(4, 4);
  EXPECT_THROW(updateRunningAverage(one, small, &wrong, kOrigin, kLength, 9, 1000, 42, 1), std::invalid_argument);
}

// The history keeps its maps' storage from call to call (RunningAverage::buffers): a history whose
// buffers were sized by frames of another size averages the next frames as a fresh one does.
TEST(RunningAverage, BuffersKeptFromFramesOfAnotherSizeChangeNothing)
{
  const std::vector<Grid> frames = noisyPlanes(4);
  Grid big(200, 150);
  for (std::size_t i = 0; i < big.size(); ++i) {
    big.x[i] = 0.004f * (static_cast<int>(i % 200) - 100), big.y[i] = 0.004f * (static_cast<int>(i / 200) - 75);
    big.z[i] = 2.0f + 0.001f * static_cast<float>(i % 7);
    big.valid[i] = 1;
  }
  RunningAverage reused, fresh;
  add(reused, big);
  add(reused, big, nullptr, 2); // the buffers now hold 200 x 150 maps
  ASSERT_EQ(reused.buffers.sigma.size(), big.size());
  for (int k = 0; k < 4; ++k) {
    add(reused, frames[k], nullptr, 2);
    add(fresh, frames[k], nullptr, 2);
  }
  EXPECT_EQ(reused.count, fresh.count);
  EXPECT_EQ(reused.average.x, fresh.average.x);
  EXPECT_EQ(reused.average.y, fresh.average.y);
  EXPECT_EQ(reused.average.z, fresh.average.z);
  EXPECT_EQ(reused.average.valid, fresh.average.valid);
  EXPECT_EQ(fresh.count[60 * 160 + 80], kLength) << "the frames were averaged, not started over";
}
