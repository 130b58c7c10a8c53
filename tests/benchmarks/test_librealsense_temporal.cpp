// The reimplementation of librealsense's temporal filter (benchmarks/librealsense_temporal.h)
// against the semantics of src/proc/temporal-filter.{h,cpp}: the exponential moving average and
// its float arithmetic truncated to 16 bits, the edge threshold, the persistency modes with their
// 8-frame history, the reset on a size change, and the cloud adaptor.
#include "librealsense_temporal.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <stdexcept>
#include <vector>

using range_nlm::tools::librealsense::TemporalFilter;
using range_nlm::tools::librealsense::TemporalFilterParameters;
using Image = std::vector<std::uint16_t>;

namespace
{
TemporalFilterParameters
parameters(float alpha, int delta, int persistence)
{
  TemporalFilterParameters p;
  p.alpha = alpha;
  p.delta = delta;
  p.persistence = persistence;
  return p;
}

/// Runs one pixel's depth sequence through a 1 x 1 filter; returns the outputs.
Image
runPixel(TemporalFilter& filter, const Image& inputs)
{
  Image out;
  for (std::uint16_t v : inputs) {
    std::uint16_t d = v;
    filter.process(&d, 1, 1);
    out.push_back(d);
  }
  return out;
}

Image
runPixel(const TemporalFilterParameters& p, const Image& inputs)
{
  TemporalFilter filter(p);
  return runPixel(filter, inputs);
}
} // namespace

TEST(LibrealsenseTemporal, DefaultsAreTheSources)
{
  const TemporalFilterParameters p;
  EXPECT_FLOAT_EQ(p.alpha, 0.4f);
  EXPECT_EQ(p.delta, 20);
  EXPECT_EQ(p.persistence, 3);
  EXPECT_DOUBLE_EQ(p.depth_unit, 0.001);
}

TEST(LibrealsenseTemporal, ConstantSequenceStaysConstantForEveryDepthAtTheDefaultAlpha)
{
  // Every 16-bit depth once (and 0): 10 frames of the same image come out unchanged.
  const int w = 256, h = 256;
  Image input(w * h);
  for (int i = 0; i < w * h; ++i)
    input[i] = static_cast<std::uint16_t>(i);
  TemporalFilter filter;
  for (int frame = 0; frame < 10; ++frame) {
    Image d = input;
    filter.process(d.data(), w, h);
    ASSERT_EQ(d, input) << "frame " << frame;
  }
}

TEST(LibrealsenseTemporal, SmallStepIsAveragedInFloatAndTruncated)
{
  // |1002 - 1000| < 20: 0.4f * 1002 + (1 - 0.4f) * 1000 = 1000.8 in float, truncated to 1000
  // (rounding would give 1001); the next frame averages with that stored 1000.
  EXPECT_EQ(runPixel(TemporalFilterParameters{}, {1000, 1002, 1002}), (Image{1000, 1000, 1000}));
  // 0.4 * 1010 + 0.6 * 1000 = 1004; then 0.4 * 1010 + 0.6 * 1004 = 1006.4 -> 1006; then
  // 1007.6 -> 1007: each output is averaged with the stored (truncated) last one.
  EXPECT_EQ(runPixel(TemporalFilterParameters{}, {1000, 1010, 1010, 1010}), (Image{1000, 1004, 1006, 1007}));
  // A step down: 0.4 * 990 + 0.6 * 1000 = 996.
  EXPECT_EQ(runPixel(TemporalFilterParameters{}, {1000, 990}), (Image{1000, 996}));
  // Alpha 0.1: 0.1f * 1019 + 0.9f' * 1000 = 1001.9 -> 1001.
  EXPECT_EQ(runPixel(parameters(0.1f, 20, 3), {1000, 1019}), (Image{1000, 1001}));
  // Alpha 1 is no filter; alpha 0 holds the first value while the input stays within delta.
  EXPECT_EQ(runPixel(parameters(1.0f, 20, 3), {1000, 1013, 995}), (Image{1000, 1013, 995}));
  EXPECT_EQ(runPixel(parameters(0.0f, 20, 3), {1000, 1013, 1019, 985}), (Image{1000, 1000, 1000, 1000}));
}

TEST(LibrealsenseTemporal, TruncationLetsAConstantInputSinkAtSmallAlpha)
{
  // The source's float -> uint16 cast truncates: with alpha 0.1, 0.1f * 1001 + 0.9f' * 1001 is
  // just below 1001, so a constant 1001 is stored as 1000 after one frame and stays there
  // (0.1 * 1001 + 0.9 * 1000 = 1000.1). A rounding implementation would keep 1001.
  EXPECT_EQ(runPixel(parameters(0.1f, 20, 3), {1001, 1001, 1001, 1001}), (Image{1001, 1000, 1000, 1000}));
}

TEST(LibrealsenseTemporal, StepOfDeltaOrMoreIsTakenAsItIs)
{
  // |1020 - 1000| = 20 is not < delta 20: taken as is, and it becomes the new last value.
  EXPECT_EQ(runPixel(TemporalFilterParameters{}, {1000, 1020, 1020}), (Image{1000, 1020, 1020}));
  EXPECT_EQ(runPixel(TemporalFilterParameters{}, {1000, 1019}), (Image{1000, 1007})); // 1007.6
  EXPECT_EQ(runPixel(TemporalFilterParameters{}, {1000, 980, 1500, 1510}), (Image{1000, 980, 1500, 1504}));
  // The threshold is the parameter's: delta 5 takes a step of 5 as is, averages one of 4.
  EXPECT_EQ(runPixel(parameters(0.4f, 5, 3), {1000, 1005, 1009}), (Image{1000, 1005, 1006}));
}

TEST(LibrealsenseTemporal, PersistencyThreeFillsAHoleOnlyAfterTwoValidFramesOfTheLastFour)
{
  // Valid at frames 0 and 1, then holes: frames 2, 3, 4 see 2 valid frames among their last 4
  // and are filled with the last value; frame 5 sees only frame 1: no fill.
  EXPECT_EQ(runPixel(TemporalFilterParameters{}, {1000, 1000, 0, 0, 0, 0, 0}),
            (Image{1000, 1000, 1000, 1000, 1000, 0, 0}));
  // One valid frame is not enough.
  EXPECT_EQ(runPixel(TemporalFilterParameters{}, {1000, 0, 0}), (Image{1000, 0, 0}));
  // Two valid frames apart: at frame 3, frames 0 and 2 of the last four were valid.
  EXPECT_EQ(runPixel(TemporalFilterParameters{}, {1000, 0, 1005, 0}), (Image{1000, 0, 1002, 1002}));
  // A jump (>= delta) forgets the history: after it only one frame counts, no fill.
  EXPECT_EQ(runPixel(TemporalFilterParameters{}, {1000, 1000, 1000, 1100, 0}), (Image{1000, 1000, 1000, 1100, 0}));
  // A fill does not count as valid: 2 valid, 2 filled, then the history runs out.
  // The last value outlives the gap: 1010 is averaged with it (1004); the frames of the gap
  // were cleared from the history, so the hole after it is not filled.
  EXPECT_EQ(runPixel(TemporalFilterParameters{}, {1000, 1000, 0, 0, 0, 0, 1010, 0}),
            (Image{1000, 1000, 1000, 1000, 1000, 0, 1004, 0}));
}

TEST(LibrealsenseTemporal, EveryPersistencyModeFillsAsItsDescriptionSays)
{
  // The pixel is valid at the frames marked 1, a hole elsewhere; a hole at frame t is filled if
  // the frames t-1 .. t-n (n the mode's window) hold at least k valid ones.
  struct Mode
  {
    int persistence, window, needed;
  };
  const Mode modes[] = {{1, 8, 8}, {2, 3, 2}, {3, 4, 2}, {4, 8, 2}, {5, 2, 1}, {6, 5, 1}, {7, 8, 1}};
  std::mt19937 random(5);
  for (const Mode& mode : modes) {
    for (int trial = 0; trial < 200; ++trial) {
      // A random validity pattern of 40 frames; valid frames all at depth 1000 (no jumps).
      std::vector<int> valid(40);
      const int density = trial % 4; // from sparse to almost always valid
      for (int& v : valid)
        v = std::uniform_int_distribution<int>(0, 4)(random) < 1 + density ? 1 : 0;
      Image inputs;
      for (int v : valid)
        inputs.push_back(v ? 1000 : 0);
      const Image out = runPixel(parameters(0.4f, 20, mode.persistence), inputs);
      bool seen = false;
      for (std::size_t t = 0; t < valid.size(); ++t) {
        std::uint16_t expected = 1000;
        if (!valid[t]) {
          int count = 0;
          for (int k = 1; k <= mode.window; ++k)
            count += t >= std::size_t(k) ? valid[t - k] : 0;
          expected = seen && count >= mode.needed ? 1000 : 0;
        }
        seen = seen || valid[t];
        ASSERT_EQ(out[t], expected) << "persistency " << mode.persistence << ", trial " << trial << ", frame " << t;
      }
    }
  }
}

TEST(LibrealsenseTemporal, PersistencyZeroNeverFillsAndEightAlwaysDoes)
{
  EXPECT_EQ(runPixel(parameters(0.4f, 20, 0), {1000, 1000, 1000, 1000, 1000, 1000, 1000, 1000, 1000, 0, 0}),
            (Image{1000, 1000, 1000, 1000, 1000, 1000, 1000, 1000, 1000, 0, 0}));
  Image inputs{1000};
  inputs.resize(20, 0);
  Image expected(20, 1000);
  EXPECT_EQ(runPixel(parameters(0.4f, 20, 8), inputs), expected);
  EXPECT_EQ(runPixel(parameters(0.4f, 20, 8), {0, 0}), (Image{0, 0}));
}

TEST(LibrealsenseTemporal, PersistenceMapIsTheSourcesRotatedTable)
{
  // Mode 3, read while the frame index is 2 (bit 2 = this frame, still holding frame t-8):
  // bits 1 and 0 are frames t-1 and t-2, bits 7 and 6 frames t-3 and t-4.
  const auto map = TemporalFilter::persistenceMap(3);
  const unsigned phase2 = 1u << 2;
  EXPECT_TRUE(map[0b00000011] & phase2);  // t-1, t-2
  EXPECT_TRUE(map[0b10000010] & phase2);  // t-1, t-3
  EXPECT_TRUE(map[0b11000000] & phase2);  // t-3, t-4
  EXPECT_FALSE(map[0b00100010] & phase2); // t-1 and t-5: only one of the last four
  EXPECT_FALSE(map[0b00111100] & phase2); // t-5 .. t-8 (bit 2 is frame t-8)
  for (int mode = 0; mode <= 8; ++mode) {
    const auto m = TemporalFilter::persistenceMap(mode);
    EXPECT_EQ(m[0], mode == 8 ? 0xff : 0) << "mode " << mode;
    EXPECT_EQ(m[0xff], mode == 0 ? 0 : 0xff) << "mode " << mode;
  }
}

TEST(LibrealsenseTemporal, FrameSizeChangeResetsTheState)
{
  TemporalFilter filter(parameters(0.4f, 20, 8)); // always fills a hole with a last value
  Image a(4 * 3, 1000);
  filter.process(a.data(), 4, 3);
  Image b(4 * 3, 0);
  filter.process(b.data(), 4, 3);
  EXPECT_EQ(b, Image(4 * 3, 1000)) << "the same size keeps the last values";
  Image c(3 * 4, 0);
  filter.process(c.data(), 3, 4);
  EXPECT_EQ(c, Image(3 * 4, 0)) << "3 x 4 after 4 x 3 (same pixel count) starts afresh";
  Image d(3 * 4, 1010);
  filter.process(d.data(), 3, 4);
  EXPECT_EQ(d, Image(3 * 4, 1010)) << "no last value to average with";
  filter.reset();
  Image e(3 * 4, 0);
  filter.process(e.data(), 3, 4);
  EXPECT_EQ(e, Image(3 * 4, 0)) << "reset() forgets the last values";
}

TEST(LibrealsenseTemporal, PixelsAreIndependent)
{
  TemporalFilter filter;
  Image f0{1000, 2000, 0, 3000};
  filter.process(f0.data(), 2, 2);
  Image f1{1010, 2100, 500, 0};
  filter.process(f1.data(), 2, 2);
  EXPECT_EQ(f1, (Image{1004, 2100, 500, 0}));
}

TEST(LibrealsenseTemporal, StaticNoiseIsReducedAsTheMovingAverageSays)
{
  // A static pixel with Gaussian noise (sigma 20 units, delta 100 = 3.5 sigma of a difference):
  // after warm-up the average has variance alpha / (2 - alpha) of the input's, std 0.5 sigma at
  // alpha 0.4. The truncation biases it down: each step loses the fraction of 0.4 * cur + 0.6 *
  // last, on the lattice 0, 0.2, .., 0.8 (mean 0.4), and the average settles 0.4 / alpha = 1 unit
  // low (a little more: float sums landing just below an integer lose a whole unit). Rounding
  // would leave no bias.
  const int pixels = 20000, frames = 40;
  std::mt19937 random(3);
  std::normal_distribution<double> noise(0.0, 20.0);
  TemporalFilter filter(parameters(0.4f, 100, 3));
  double variance = 0.0, mean = 0.0;
  int counted = 0;
  for (int t = 0; t < frames; ++t) {
    Image d(pixels);
    for (auto& v : d)
      v = static_cast<std::uint16_t>(std::lround(10000.0 + noise(random)));
    filter.process(d.data(), pixels, 1);
    if (t < 10)
      continue; // warm-up: the first frame is the raw one
    // The pixels are independent: the spread over them at one frame is the stationary one.
    double s = 0.0, s2 = 0.0;
    for (std::uint16_t v : d)
      s += v, s2 += double(v) * v;
    const double m = s / pixels;
    mean += m;
    variance += s2 / pixels - m * m;
    ++counted;
  }
  EXPECT_NEAR(std::sqrt(variance / counted), 0.5 * 20.0, 0.4);
  EXPECT_NEAR(mean / counted, 10000.0 - 1.0, 0.15);
}

TEST(LibrealsenseTemporal, CloudAdaptorWorksInDepthUnitsAlongEachRay)
{
  // A 2 x 1 cloud: one pixel steady at 1 m, one on a slanted ray stepping 1 mm -> 11 mm.
  pcl::PointCloud<pcl::PointXYZ> frame(2, 1);
  auto set = [&](float z0, float z1) {
    frame[0] = pcl::PointXYZ(0.5f * z0, -0.25f * z0, z0);
    frame[1] = pcl::PointXYZ(-0.2f * z1, 0.1f * z1, z1);
  };
  TemporalFilter filter;
  set(1.0f, 2.0f);
  const pcl::PointCloud<pcl::PointXYZ> out0 = filter.filter(frame);
  EXPECT_EQ(out0[0].z, 1.0f);
  EXPECT_TRUE(out0.is_dense);
  EXPECT_EQ(out0[1].x, frame[1].x) << "a point already at its depth is kept";
  set(1.01f, 2.0f + 0.05f); // +10 units: averaged; +50 units: taken as is
  const pcl::PointCloud<pcl::PointXYZ> out1 = filter.filter(frame);
  EXPECT_FLOAT_EQ(out1[0].z, 1.004f);
  EXPECT_FLOAT_EQ(out1[0].x, 0.5f * 1.004f) << "moved along its ray";
  EXPECT_FLOAT_EQ(out1[0].y, -0.25f * 1.004f);
  EXPECT_FLOAT_EQ(out1[1].z, 2.05f);
  EXPECT_TRUE(out1.is_dense);
  // Holes (NaN in x, y and z): the first pixel, valid in 2 of the last 4 frames, is filled with
  // its last value on its ray; the second had a jump at frame 1, which left one valid frame in
  // its history: NaN in x, y and z.
  const float nan = std::numeric_limits<float>::quiet_NaN();
  frame[0] = frame[1] = pcl::PointXYZ(nan, nan, nan);
  for (int t = 2; t <= 4; ++t) {
    const pcl::PointCloud<pcl::PointXYZ> out = filter.filter(frame);
    EXPECT_FLOAT_EQ(out[0].z, 1.004f) << "frame " << t;
    EXPECT_FLOAT_EQ(out[0].x, 0.5f * 1.004f) << "frame " << t;
    EXPECT_FLOAT_EQ(out[0].y, -0.25f * 1.004f) << "frame " << t;
    EXPECT_TRUE(std::isnan(out[1].x) && std::isnan(out[1].y) && std::isnan(out[1].z)) << "frame " << t;
    EXPECT_FALSE(out.is_dense);
  }
  EXPECT_TRUE(std::isnan(filter.filter(frame)[0].z)) << "frame 5: only frame 1 valid of t-1 .. t-4";
}

TEST(LibrealsenseTemporal, DepthUnitSetsTheScaleOfDelta)
{
  // A 0.5 mm step at a 0.1 mm unit is 5 units: averaged; 2.8 mm is 28 units, above delta.
  TemporalFilterParameters p;
  p.depth_unit = 0.0001;
  TemporalFilter fine(p);
  pcl::PointCloud<pcl::PointXYZ> frame(1, 1);
  frame[0] = pcl::PointXYZ(0.0f, 0.0f, 1.0f);
  fine.filter(frame);
  frame[0].z = 1.0005f;
  EXPECT_FLOAT_EQ(fine.filter(frame)[0].z, 1.0002f);
  frame[0].z = 1.003f; // 28 units from 10002: taken as is
  EXPECT_FLOAT_EQ(fine.filter(frame)[0].z, 1.003f);
}

TEST(LibrealsenseTemporal, BadParametersAndInputAreRefusedByName)
{
  auto message = [](const TemporalFilterParameters& p) {
    try {
      TemporalFilter f(p);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_NE(message(parameters(1.5f, 20, 3)).find("alpha 1.5"), std::string::npos);
  EXPECT_NE(message(parameters(0.4f, 0, 3)).find("delta 0"), std::string::npos);
  EXPECT_NE(message(parameters(0.4f, 101, 3)).find("delta 101"), std::string::npos);
  EXPECT_NE(message(parameters(0.4f, 20, 9)).find("persistence 9"), std::string::npos);
  TemporalFilterParameters p;
  p.depth_unit = 0.0;
  EXPECT_NE(message(p).find("depth_unit 0"), std::string::npos);

  TemporalFilter filter(parameters(0.4f, 20, 8)); // a hole takes the last value
  pcl::PointCloud<pcl::PointXYZ> near(1, 1);
  near[0] = pcl::PointXYZ(0.0f, 0.0f, 1.0f);
  filter.filter(near);
  pcl::PointCloud<pcl::PointXYZ> far(1, 1);
  far[0] = pcl::PointXYZ(0.0f, 0.0f, 70.0f); // 70000 mm
  try {
    filter.filter(far);
    ADD_FAILURE() << "70 m at 1 mm units accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("pixel (0, 0)"), std::string::npos) << e.what();
  }
  // The refused frame left no trace: a hole after it takes the 1 m of the frame before.
  pcl::PointCloud<pcl::PointXYZ> hole(1, 1);
  hole[0] = pcl::PointXYZ(std::nanf(""), std::nanf(""), std::nanf(""));
  EXPECT_EQ(filter.filter(hole)[0].z, 1.0f);
  pcl::PointCloud<pcl::PointXYZ> unorganized;
  unorganized.push_back(pcl::PointXYZ(0.0f, 0.0f, 1.0f));
  unorganized.push_back(pcl::PointXYZ(0.0f, 0.0f, 1.0f));
  unorganized.width = 3;
  EXPECT_THROW(filter.filter(unorganized), std::invalid_argument);
}
