#include "test_support.h"

#include <range_nlm/nonlocal_means_filter.h>
#include <range_nlm/temporal_nonlocal_means_filter.h>
#include <range_nlm/temporal_stream.h>
#include <range_nlm/eval/metrics.h>
#include <range_nlm/eval/synthetic_scene.h>

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <functional>
#include <limits>
#include <memory>
#include <string>
#include <deque>

using namespace range_nlm;
using Cloud = pcl::PointCloud<pcl::PointXYZ>;

namespace
{
double
maxDistance(const Cloud& a, const Cloud& b)
{
  double m = 0.0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (std::isnan(a[i].z) != std::isnan(b[i].z))
      return INFINITY;
    if (!std::isnan(a[i].z))
      m = std::max(m, double((a[i].getVector3fMap() - b[i].getVector3fMap()).norm()));
  }
  return m;
}

/// A scene with a box (depth 1.0 m) in front of a wall (1.1 m); the box starts at column
/// `box_u` (moving scenes shift it per frame).
test::DepthFunction
boxScene(int box_u)
{
  return [box_u](double, double, int u, int v) {
    return (u >= box_u && u < box_u + 14 && v >= 10 && v < 30) ? 1.0 : 1.1 + 0.0 * u;
  };
}

std::vector<Cloud::ConstPtr>
sequence(int frames, int shift_per_frame, double sigma, std::uint64_t seed)
{
  std::vector<Cloud::ConstPtr> out;
  for (int k = 0; k < frames; ++k)
    out.emplace_back(new Cloud(test::makeCloud(48, 40, boxScene(12 + k * shift_per_frame), sigma, seed + k)));
  return out;
}

Cloud
staticFilter(const Cloud& in, const FilterParameters& p)
{
  NonLocalMeansFilter<pcl::PointXYZ> f;
  f.setParameters(p);
  f.setInputCloud(Cloud::ConstPtr(new Cloud(in)));
  Cloud out;
  f.filter(out);
  return out;
}

/// Mean over pixels of the temporal standard deviation of z.
double
temporalStd(const std::vector<Cloud::Ptr>& frames, std::size_t first, std::size_t last)
{
  double sum = 0.0;
  std::size_t n = frames.front()->size();
  for (std::size_t i = 0; i < n; ++i) {
    double m = 0, m2 = 0;
    for (std::size_t k = first; k <= last; ++k) {
      m += (*frames[k])[i].z;
      m2 += double((*frames[k])[i].z) * (*frames[k])[i].z;
    }
    const double c = double(last - first + 1);
    sum += std::sqrt(std::max(0.0, m2 / c - (m / c) * (m / c)));
  }
  return sum / n;
}
} // namespace

TEST(TemporalFilter, OneFrameEqualsStaticFilter)
{
  Cloud in = test::makeCloud(40, 32, boxScene(10), 0.003, 3);
  test::punchHoles(in, 0.05, 4);
  for (const FilterParameters& p : {FilterParameters::paper(), FilterParameters::recommended()}) {
    TemporalNonLocalMeansFilter<pcl::PointXYZ> t;
    t.setParameters(p);
    t.setFrames({Cloud::ConstPtr(new Cloud(in))}, 0);
    Cloud out;
    t.filter(out);
    EXPECT_LT(maxDistance(out, staticFilter(in, p)), 1e-7);
    ASSERT_EQ(t.getFrameWeights().size(), 1u);
  }
}

TEST(TemporalFilter, FrameWeightsFollowTheFormulas)
{
  // A plane: without depth edges the estimated s follows the noise level.
  const auto plane = test::plane(Eigen::Vector3d(0.1, 0.2, 1.0), 1.0);
  const std::vector<Cloud::ConstPtr> frames{Cloud::ConstPtr(new Cloud(test::makeCloud(48, 40, plane, 0.003, 10))),
                                            Cloud::ConstPtr(new Cloud(test::makeCloud(48, 40, plane, 0.003, 11)))};
  Cloud::Ptr noisier(new Cloud(test::makeCloud(48, 40, plane, 0.006, 99)));
  TemporalNonLocalMeansFilter<pcl::PointXYZ> t;
  t.setFrames({frames[0], frames[1], noisier}, 1);
  Cloud out;
  t.filter(out);
  const auto& w = t.getFrameWeights();
  const auto& b = t.getFrameBandwidths();
  ASSERT_EQ(w.size(), 3u);
  const float s_max = std::max({b[0].similarity, b[1].similarity, b[2].similarity});
  EXPECT_EQ(s_max, b[2].similarity); // the noisier frame has the largest s
  for (int k = 0; k < 3; ++k) {
    const float psi_d = k == 1 ? 1.0f : 0.5f;
    const float ratio = b[k].similarity / s_max;
    EXPECT_FLOAT_EQ(w[k], psi_d * std::exp(-ratio * ratio)) << k;
  }
  EXPECT_LT(w[2], w[0]); // noisier frames count less
}

TEST(TemporalFilter, StreamWindowsAtSequenceStartAndEnd)
{
  const auto frames = sequence(5, 0, 0.003, 20);
  TemporalStream<pcl::PointXYZ> stream(2, false, FilterParameters::recommended());
  std::vector<std::size_t> window_sizes;
  std::size_t produced = 0;
  for (const auto& f : frames) {
    const auto ready = stream.push(f);
    produced += ready.size();
    if (!ready.empty())
      window_sizes.push_back(stream.lastFrameWeights().size());
    EXPECT_LE(stream.heldFrames(), 5u);
  }
  EXPECT_EQ(produced, 3u); // frames 0, 1, 2 are complete once frame t + 2 arrived
  EXPECT_EQ(window_sizes, (std::vector<std::size_t>{3, 4, 5}));
  produced += stream.flush().size();
  EXPECT_EQ(produced, 5u);
  EXPECT_EQ(stream.lastFrameWeights().size(), 3u); // frame 4 sees frames 2, 3, 4
  EXPECT_EQ(stream.heldFrames(), 0u);
}

TEST(TemporalFilter, StreamingEqualsBatchAndDirectCalls)
{
  const auto frames = sequence(4, 0, 0.003, 30);
  const FilterParameters p = FilterParameters::recommended();
  const auto batch = filterSequence<pcl::PointXYZ>(frames, 1, false, p);
  ASSERT_EQ(batch.size(), 4u);
  for (std::size_t t = 0; t < 4; ++t) {
    std::deque<Cloud::ConstPtr> window;
    const std::size_t lo = t == 0 ? 0 : t - 1, hi = std::min<std::size_t>(3, t + 1);
    for (std::size_t k = lo; k <= hi; ++k)
      window.push_back(frames[k]);
    TemporalNonLocalMeansFilter<pcl::PointXYZ> f;
    f.setParameters(p);
    f.setFrames(window, t - lo);
    Cloud out;
    f.filter(out);
    EXPECT_EQ(maxDistance(out, *batch[t]), 0.0) << t;
  }
}

namespace
{
/// Every point of `a` and `b` holds the same bytes.
bool
sameBits(const Cloud& a, const Cloud& b)
{
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(pcl::PointXYZ)) == 0;
}
} // namespace

// The live preset's recursive stream (its history searched over 3 x 3, standing for the whole
// window) gives the direct evaluation's result, with holes and a depth step, and smooths the static
// scene over time more than the same frames filtered one by one.
TEST(TemporalFilter, LiveRecursiveStreamMatchesTheDirectEvaluationAndSteadiesTheScene)
{
  std::vector<Cloud::ConstPtr> frames;
  for (int t = 0; t < 4; ++t) {
    Cloud::Ptr c(new Cloud(test::makeCloud(61, 43, test::step(30, 1.0, 1.06), 0.004, 90 + t)));
    test::punchHoles(*c, 0.05, 190 + t);
    frames.push_back(c);
  }
  FilterParameters p = FilterParameters::live();
  p.threads = 2;
  const auto fast = filterSequence<pcl::PointXYZ>(frames, 1, TemporalWindow::recursive, p);
  p.evaluation = Evaluation::direct;
  const auto direct = filterSequence<pcl::PointXYZ>(frames, 1, TemporalWindow::recursive, p);
  p.evaluation = Evaluation::fast;
  ASSERT_EQ(fast.size(), frames.size());
  for (std::size_t t = 0; t < frames.size(); ++t)
    EXPECT_LT(maxDistance(*fast[t], *direct[t]), 2e-5) << "frame " << t;
  for (int threads : {1, 3}) {
    FilterParameters q = p;
    q.threads = threads;
    const auto other = filterSequence<pcl::PointXYZ>(frames, 1, TemporalWindow::recursive, q);
    for (std::size_t t = 0; t < frames.size(); ++t)
      EXPECT_TRUE(sameBits(*other[t], *fast[t])) << threads << " threads, frame " << t;
  }
  // Frame to frame differences of the last two outputs: the recursive stream's against the
  // single frames'.
  auto change = [](const Cloud& a, const Cloud& b) {
    double sum = 0.0;
    std::size_t n = 0;
    for (std::size_t i = 0; i < a.size(); ++i)
      if (std::isfinite(a[i].z) && std::isfinite(b[i].z))
        sum += (a[i].z - b[i].z) * (a[i].z - b[i].z), ++n;
    return std::sqrt(sum / double(n));
  };
  const auto single = filterSequence<pcl::PointXYZ>(frames, 0, TemporalWindow::centred, p);
  EXPECT_LT(change(*fast[3], *fast[2]), 0.8 * change(*single[3], *single[2]));
}

// The stream gives, to the bit, what the temporal filter gives on the same window: the frames
// t - 1 .. t + 1 (centred) or t - 1 .. t (causal), and in recursive mode the history and frame
// t, the history being the running average (updateRunningAverage) of the frames so far, each
// started from its filtered output, as a cloud.
TEST(TemporalFilter, StreamEqualsTheFilterOnTheSameWindowToTheBit)
{
  const auto frames = sequence(5, 1, 0.003, 40);
  const FilterParameters p = FilterParameters::recommended();
  auto filterWindow = [&p](const std::deque<Cloud::ConstPtr>& window, std::size_t current) {
    TemporalNonLocalMeansFilter<pcl::PointXYZ> f;
    f.setParameters(p);
    f.setFrames(window, current);
    Cloud out;
    f.filter(out);
    return out;
  };
  for (TemporalWindow mode : {TemporalWindow::centred, TemporalWindow::causal}) {
    const auto out = filterSequence<pcl::PointXYZ>(frames, 1, mode, p);
    ASSERT_EQ(out.size(), frames.size());
    for (std::size_t t = 0; t < frames.size(); ++t) {
      const std::size_t lo = t == 0 ? 0 : t - 1;
      const std::size_t hi = mode == TemporalWindow::causal ? t : std::min(frames.size() - 1, t + 1);
      const std::deque<Cloud::ConstPtr> window(frames.begin() + lo, frames.begin() + hi + 1);
      EXPECT_TRUE(sameBits(*out[t], filterWindow(window, t - lo))) << "frame " << t;
    }
  }
  const auto out = filterSequence<pcl::PointXYZ>(frames, 1, TemporalWindow::recursive, p);
  ASSERT_EQ(out.size(), frames.size());
  RunningAverage history;
  const Viewpoint origin{0.0f, 0.0f, 0.0f};
  for (std::size_t t = 0; t < frames.size(); ++t) {
    std::deque<Cloud::ConstPtr> window;
    if (!history.empty()) {
      Cloud::Ptr average(new Cloud);
      fromGrid(*frames[t], history.average, *average);
      window.push_back(average);
    }
    window.push_back(frames[t]);
    const Cloud expected = filterWindow(window, window.size() - 1);
    EXPECT_TRUE(sameBits(*out[t], expected)) << "frame " << t;
    const Grid frame = toGrid(*frames[t]), start = toGrid(expected);
    updateRunningAverage(history, frame, &start, origin, 3, p.search_window, p.bandwidth_samples, p.seed, p.threads);
  }
}

TEST(TemporalFilter, CausalModeUsesNoFutureFrame)
{
  auto frames = sequence(4, 0, 0.003, 40);
  const FilterParameters p = FilterParameters::recommended();
  TemporalStream<pcl::PointXYZ> stream(1, true, p);
  const auto first = stream.push(frames[0]);
  ASSERT_EQ(first.size(), 1u); // no delay
  const auto second = stream.push(frames[1]);
  ASSERT_EQ(second.size(), 1u);
  // Replace the future (frame 2 and 3) with something else: frames 0 and 1 do not change.
  auto other = frames;
  other[2].reset(new Cloud(test::makeCloud(48, 40, boxScene(30), 0.01, 77)));
  other[3].reset(new Cloud(test::makeCloud(48, 40, boxScene(5), 0.01, 78)));
  const auto a = filterSequence<pcl::PointXYZ>(frames, 1, true, p);
  const auto b = filterSequence<pcl::PointXYZ>(other, 1, true, p);
  EXPECT_EQ(maxDistance(*a[0], *b[0]), 0.0);
  EXPECT_EQ(maxDistance(*a[1], *b[1]), 0.0);
  EXPECT_EQ(maxDistance(*a[0], *first[0]), 0.0);
  EXPECT_GT(maxDistance(*a[2], *b[2]), 0.0);
}

TEST(TemporalFilter, StaticSceneIsTemporallySteadier)
{
  const auto frames = sequence(7, 0, 0.004, 50);
  const FilterParameters p = FilterParameters::recommended();
  const auto temporal = filterSequence<pcl::PointXYZ>(frames, 1, false, p);
  std::vector<Cloud::Ptr> single;
  for (const auto& f : frames)
    single.emplace_back(new Cloud(staticFilter(*f, p)));
  const double jitter_single = temporalStd(single, 1, 5);
  const double jitter_temporal = temporalStd(temporal, 1, 5);
  EXPECT_LT(jitter_temporal, 0.8 * jitter_single) << jitter_temporal << " vs " << jitter_single;
}

TEST(TemporalFilter, MovingObjectIsNotSmeared)
{
  const double sigma = 0.003;
  const auto frames = sequence(5, 4, sigma, 60); // 4 px per frame: far beyond the noise
  const FilterParameters p = FilterParameters::recommended();
  const auto temporal = filterSequence<pcl::PointXYZ>(frames, 1, false, p);
  // Error of z against the true depth within 3 px of the box's vertical edges.
  auto edgeError = [&](const Cloud& c, int k) {
    const int box_u = 12 + 4 * k;
    double sum = 0;
    int n = 0;
    for (int v = 12; v < 28; ++v)
      for (int u : {box_u - 3, box_u - 2, box_u - 1, box_u, box_u + 1, box_u + 2, box_u + 11, box_u + 12,
                    box_u + 13, box_u + 14, box_u + 15, box_u + 16}) {
        const double truth = (u >= box_u && u < box_u + 14) ? 1.0 : 1.1;
        const double e = c.at(u, v).z - truth;
        sum += e * e;
        ++n;
      }
    return std::sqrt(sum / n);
  };
  for (int k = 1; k < 4; ++k) {
    const double per_frame = edgeError(staticFilter(*frames[k], p), k);
    const double with_time = edgeError(*temporal[k], k);
    EXPECT_LT(with_time, per_frame * 1.15 + 0.0002) << "frame " << k;
  }
}

TEST(TemporalFilter, MismatchedFrameSizesAreRejected)
{
  const auto frames = sequence(2, 0, 0.003, 70);
  Cloud::Ptr other(new Cloud(test::makeCloud(40, 40, boxScene(12), 0.003, 71)));
  TemporalNonLocalMeansFilter<pcl::PointXYZ> t;
  t.setFrames({frames[0], other, frames[1]}, 0);
  Cloud out;
  try {
    t.filter(out);
    FAIL() << "no error";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("frame 1 is 40 x 40 but the current frame is 48 x 40"), std::string::npos)
        << e.what();
  }
  TemporalStream<pcl::PointXYZ> stream(1, false, FilterParameters::recommended());
  stream.push(frames[0]);
  EXPECT_THROW(stream.push(other), std::invalid_argument);
  EXPECT_THROW(t.setFrames({frames[0]}, 3), std::invalid_argument);
  EXPECT_THROW(TemporalStream<pcl::PointXYZ>(-1, false, FilterParameters()), std::invalid_argument);
}

TEST(TemporalFilter, ANonFiniteViewpointIsRefusedAndTheStreamGoesOn)
{
  const auto frames = sequence(3, 0, 0.003, 70);
  Cloud::Ptr far(new Cloud(*frames[1]));
  far->sensor_origin_[0] = INFINITY;
  TemporalStream<pcl::PointXYZ> stream(0, false, FilterParameters::recommended());
  ASSERT_EQ(stream.push(frames[0]).size(), 1u);
  // Refused before the stream changes, naming the frame, the viewpoint and its value; the frame
  // can be skipped.
  try {
    stream.push(far);
    FAIL() << "no error";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("the viewpoint (sensor origin) of frame 1 must be finite, got (inf, 0, 0)"),
              std::string::npos)
        << e.what();
  }
  EXPECT_EQ(stream.heldFrames(), 0u);
  EXPECT_EQ(stream.push(frames[2]).size(), 1u);
  // The filter on a window refuses it too (runFilter checks the viewpoint of every run).
  TemporalNonLocalMeansFilter<pcl::PointXYZ> t;
  t.setFrames({frames[0], far, frames[2]}, 1);
  Cloud out;
  EXPECT_NE(test::errorOf([&] { t.filter(out); }).find("the viewpoint (sensor origin) must be finite, got (inf, 0, 0)"),
            std::string::npos);
}

// The stream's check of every point runs on the filter's threads: whatever their number, the
// error names the first infinite point in row order, and the frame can be skipped.
TEST(TemporalFilter, AnInfiniteCoordinateIsReportedAtItsFirstPixelWhateverTheThreads)
{
  const auto frames = sequence(2, 0, 0.003, 71);
  Cloud::Ptr bad(new Cloud(*frames[1]));
  const std::uint32_t w = bad->width;
  (*bad)[(bad->height - 2) * w + 9].z = INFINITY; // in the last thread's rows
  (*bad)[3 * w + 6].x = -INFINITY;                // the first in row order
  (*bad)[3 * w + 20].y = INFINITY;
  for (int threads : {1, 2, 3}) {
    FilterParameters p = FilterParameters::recommended();
    p.threads = threads;
    TemporalStream<pcl::PointXYZ> stream(0, false, p);
    ASSERT_EQ(stream.push(frames[0]).size(), 1u);
    EXPECT_NE(test::errorOf([&] { stream.push(bad); })
                  .find("frame 1 has an infinite coordinate at pixel (6, 3); invalid points must be NaN"),
              std::string::npos)
        << threads << " threads";
    EXPECT_EQ(stream.push(frames[1]).size(), 1u) << threads << " threads";
  }
}

// An output the caller lets go of lends its storage to a later output of the stream (no frame
// allocated per frame at camera rate); one it still holds is never touched, a weak pointer to a
// released one expires, and an output may outlive its stream. Every output equals that of a
// stream whose outputs are all kept.
TEST(TemporalFilter, StreamReusesTheStorageOfOutputsLetGoOnly)
{
  const auto frames = sequence(5, 0, 0.003, 72);
  for (TemporalWindow window : {TemporalWindow::recursive, TemporalWindow::causal}) {
    FilterParameters p = FilterParameters::live();
    std::vector<Cloud::Ptr> kept;
    {
      TemporalStream<pcl::PointXYZ> reference(1, window, p);
      for (const auto& f : frames)
        for (auto& out : reference.push(f))
          kept.push_back(out);
    }
    ASSERT_EQ(kept.size(), frames.size());
    TemporalStream<pcl::PointXYZ> stream(1, window, p);
    std::vector<Cloud::Ptr> first = stream.push(frames[0]);
    ASSERT_EQ(first.size(), 1u);
    const Cloud held_copy = *first[0];
    const pcl::PointXYZ* held_points = first[0]->points.data();
    // Held: the next output has storage of its own, and the held one is unchanged.
    std::vector<Cloud::Ptr> second = stream.push(frames[1]);
    ASSERT_EQ(second.size(), 1u);
    EXPECT_NE(second[0]->points.data(), held_points);
    EXPECT_TRUE(sameBits(*first[0], held_copy));
    EXPECT_TRUE(sameBits(*second[0], *kept[1]));
    // Let go of (a weak pointer left): the next output takes its storage, the weak pointer expires.
    const pcl::PointXYZ* released_points = second[0]->points.data();
    std::weak_ptr<Cloud> watcher = second[0];
    second.clear();
    EXPECT_TRUE(watcher.expired());
    // (Had the storage gone back to the heap, this would likely take it.)
    const std::vector<pcl::PointXYZ, Eigen::aligned_allocator<pcl::PointXYZ>> decoy(held_copy.size());
    std::vector<Cloud::Ptr> third = stream.push(frames[2]);
    ASSERT_EQ(third.size(), 1u);
    EXPECT_NE(third[0]->points.data(), decoy.data());
    EXPECT_EQ(third[0]->points.data(), released_points);
    EXPECT_TRUE(sameBits(*third[0], *kept[2]));
    EXPECT_TRUE(sameBits(*first[0], held_copy));
    third.clear();
    for (std::size_t k = 3; k < frames.size(); ++k) {
      std::vector<Cloud::Ptr> out = stream.push(frames[k]);
      ASSERT_EQ(out.size(), 1u);
      EXPECT_TRUE(sameBits(*out[0], *kept[k])) << "frame " << k;
      if (k + 1 == frames.size())
        first.push_back(out[0]); // outlives the stream below
    }
    EXPECT_TRUE(sameBits(*first[0], held_copy));
  }
}

TEST(TemporalFilter, StreamPassesAnAllNanFrameThroughAndGoesOn)
{
  const FilterParameters p = FilterParameters::recommended();
  std::vector<Cloud::ConstPtr> frames = sequence(4, 0, 0.003, 80);
  Cloud::Ptr covered(new Cloud(*frames[1]));
  for (auto& q : covered->points)
    q.x = q.y = q.z = std::numeric_limits<float>::quiet_NaN();
  covered->is_dense = false;
  frames[1] = covered;

  TemporalStream<pcl::PointXYZ> stream(1, false, p);
  std::vector<Cloud::Ptr> out;
  std::vector<std::string> problems;
  auto take = [&](const std::vector<Cloud::Ptr>& ready) {
    ASSERT_EQ(stream.lastOutputs().size(), ready.size());
    for (std::size_t i = 0; i < ready.size(); ++i) {
      out.push_back(ready[i]);
      problems.push_back(stream.lastOutputs()[i].problem);
    }
  };
  for (const auto& f : frames)
    take(stream.push(f));
  take(stream.flush());
  ASSERT_EQ(out.size(), 4u);
  // The covered frame comes out unchanged (all NaN), with the reason; the others are filtered.
  for (const auto& q : out[1]->points)
    EXPECT_TRUE(std::isnan(q.x) && std::isnan(q.y) && std::isnan(q.z));
  EXPECT_NE(problems[1].find("no valid point"), std::string::npos) << problems[1];
  for (std::size_t k : {0u, 2u, 3u})
    EXPECT_TRUE(problems[k].empty()) << k << ": " << problems[k];
  // Bandwidths are reported per output, not the last frame's for every output of a flush.
  EXPECT_GT(stream.lastOutputs().size(), 0u);
  // As a neighbour it contributes nothing: frame 0's window {0, 1} gives frame 0 filtered alone.
  const Cloud alone = staticFilter(*frames[0], p);
  EXPECT_LT(maxDistance(*out[0], alone), 1e-6);
  // A filter call on the covered frame itself says why it cannot filter it.
  NonLocalMeansFilter<pcl::PointXYZ> f;
  f.setInputCloud(covered);
  Cloud unused;
  EXPECT_THROW(f.filter(unused), UnfilterableFrame);
}

TEST(TemporalFilter, RecursiveStreamPassesASparseFrameThroughAndGoesOn)
{
  // A frame with a few scattered points (a nearly covered lens) has no window to estimate its
  // noise from: it comes out unchanged with the reason, the history starts over from it, and the
  // stream goes on. Every window of 9 x 9 pixels holds at most one of its points.
  const FilterParameters p = FilterParameters::recommended();
  std::vector<Cloud::ConstPtr> frames = sequence(5, 0, 0.003, 90);
  Cloud::Ptr sparse(new Cloud(*frames[2]));
  for (std::size_t i = 0; i < sparse->size(); ++i)
    if ((i % sparse->width) % 10 != 0 || (i / sparse->width) % 10 != 0)
      (*sparse)[i].x = (*sparse)[i].y = (*sparse)[i].z = std::numeric_limits<float>::quiet_NaN();
  sparse->is_dense = false;
  frames[2] = sparse;
  TemporalStream<pcl::PointXYZ> stream(1, TemporalWindow::recursive, p);
  for (std::size_t t = 0; t < frames.size(); ++t) {
    std::vector<Cloud::Ptr> out;
    ASSERT_NO_THROW(out = stream.push(frames[t])) << "frame " << t;
    ASSERT_EQ(out.size(), 1u);
    const std::string problem = stream.lastOutputs().front().problem;
    if (t == 2) {
      EXPECT_FALSE(problem.empty());
      EXPECT_EQ(maxDistance(*out[0], *sparse), 0.0) << "passed through unchanged";
    } else {
      EXPECT_TRUE(problem.empty()) << t << ": " << problem;
    }
  }
}

namespace
{
/// A static sequence of the generated boxes scene with a noise model, `frames` frames.
std::vector<SyntheticFrame>
staticScene(NoiseModel noise, int frames, int width, int height)
{
  SceneOptions o;
  o.width = width;
  o.height = height;
  o.fx = o.fy = 525.0 * width / 640.0;
  o.noise = noise;
  o.frames = frames;
  o.seed = 31;
  return renderSequence(o);
}

/// Flat RMSE of the centre frame (2) of a 5-frame sequence filtered with the default and
/// `cross`, at `radius`.
double
centreFlatRmse(const std::vector<SyntheticFrame>& seq, int radius, CrossFrameBandwidth cross)
{
  std::vector<Cloud::ConstPtr> frames;
  for (const SyntheticFrame& f : seq)
    frames.emplace_back(new Cloud(f.noisy));
  FilterParameters p = FilterParameters::recommended();
  p.cross_frame_bandwidth = cross;
  const auto out = filterSequence<pcl::PointXYZ>(frames, radius, false, p);
  return evaluateFrame(seq[2].truth, *out[2]).flat_rmse;
}
} // namespace

TEST(TemporalFilter, TemporalNoiseRatioIsSmallForIndependentNoiseAndLargeForCorrelatedNoise)
{
  const Viewpoint origin{0.0f, 0.0f, 0.0f};
  const FilterParameters p = FilterParameters::recommended();
  auto ratioOf = [&](NoiseModel noise) {
    const std::vector<SyntheticFrame> seq = staticScene(noise, 2, 160, 120);
    const Grid a = toGrid(seq[0].noisy), b = toGrid(seq[1].noisy);
    NormalField n; // the true normals: the ratio is about the noise, not about normal estimation
    for (const auto& q : seq[0].truth) {
      n.nx.push_back(q.normal_x);
      n.ny.push_back(q.normal_y);
      n.nz.push_back(q.normal_z);
    }
    const NoiseProfile profile = estimateNoiseProfile(b, p.search_window, p.bandwidth_samples, 1, origin);
    return estimateTemporalNoiseRatio(a, n, b, profile, origin);
  };
  const float iid = ratioOf(NoiseModel::kinect), correlated = ratioOf(NoiseModel::stereo);
  // Independent noise: at most a little above 1, so max(1, ratio) leaves the paper's weights.
  EXPECT_GT(iid, 0.3f);
  EXPECT_LT(iid, 1.6f);
  EXPECT_GT(correlated, 1.2f) << "iid " << iid << ", stereo " << correlated;
  EXPECT_GT(correlated, 2.0f * iid) << "iid " << iid << ", stereo " << correlated;
}

TEST(TemporalFilter, StaticSceneWithCorrelatedNoiseGainsFromTheOtherFrames)
{
  // Stereo-like noise (80 % of its variance correlated over 4 px): the centre frame of radius 2
  // beats the frame filtered alone by a clear margin, and by much more than with the paper's
  // cross-frame bandwidths, which take the other frames' patches for moved ones.
  const std::vector<SyntheticFrame> seq = staticScene(NoiseModel::stereo, 5, 160, 120);
  const double alone = centreFlatRmse(seq, 0, CrossFrameBandwidth::temporal);
  const double temporal = centreFlatRmse(seq, 2, CrossFrameBandwidth::temporal);
  const double paper = centreFlatRmse(seq, 2, CrossFrameBandwidth::spatial);
  EXPECT_LT(temporal, 0.9 * alone) << "alone " << alone << ", temporal " << temporal;
  EXPECT_LT(temporal, 0.95 * paper) << "paper's cross-frame s " << paper << ", temporal " << temporal;
}

TEST(TemporalFilter, StaticSceneWithIndependentNoiseIsAveragedThroughThePatchGuide)
{
  // Time-of-flight-like noise, independent from frame to frame: at radius 2 the centre frame
  // comes to at most 0.7x the frame filtered alone. The guarded default compares the other
  // frames' patches with the patch guide (the unchanged frames' per-pixel mean), so that their
  // weights no longer lean towards the centre frame's noise; `temporal` cross-frame bandwidths,
  // without the per-pixel test of change and so without a guide, stay above it.
  const std::vector<SyntheticFrame> seq = staticScene(NoiseModel::tof, 5, 640, 480);
  const double alone = centreFlatRmse(seq, 0, CrossFrameBandwidth::guarded);
  const double guided = centreFlatRmse(seq, 2, CrossFrameBandwidth::guarded);
  const double unguided = centreFlatRmse(seq, 2, CrossFrameBandwidth::temporal);
  EXPECT_LT(guided, 0.7 * alone) << "alone " << alone << ", guided " << guided << ", unguided " << unguided;
  EXPECT_LT(guided, 0.95 * unguided) << "alone " << alone << ", guided " << guided << ", unguided " << unguided;
}

TEST(TemporalFilter, PatchGuideNeedsThreeNeighbours)
{
  // The paper preset has no guide, the default has; with two neighbours (radius 1) the guide is
  // not used (each would find a third of the guide to be its own noise), with four (radius 2)
  // it changes the result.
  EXPECT_FALSE(FilterParameters::paper().patch_guide);
  EXPECT_TRUE(FilterParameters::recommended().patch_guide);
  const std::vector<SyntheticFrame> seq = staticScene(NoiseModel::tof, 5, 160, 120);
  std::deque<Cloud::ConstPtr> frames;
  for (const SyntheticFrame& f : seq)
    frames.emplace_back(new Cloud(f.noisy));
  auto centre = [&](bool guide, int radius) {
    FilterParameters p = FilterParameters::recommended();
    p.patch_guide = guide;
    TemporalNonLocalMeansFilter<pcl::PointXYZ> t;
    t.setParameters(p);
    t.setFrames(std::deque<Cloud::ConstPtr>(frames.begin() + 2 - radius, frames.begin() + 3 + radius), radius);
    Cloud out;
    t.filter(out);
    return out;
  };
  EXPECT_EQ(maxDistance(centre(true, 1), centre(false, 1)), 0.0);
  EXPECT_GT(maxDistance(centre(true, 2), centre(false, 2)), 1e-5);
}

TEST(TemporalFilter, APointThatChangedAloneStaysOutOfThePatchGuide)
{
  // Stereo-like noise, a box moving 10 mm per frame, VGA (dilated passes), radius 2: at the
  // box's leading edge the 3 x 3 vote of the per-pixel test of change lets lone pixels of a
  // phase pass, whose points lie on the old background. Kept out of the guide (their own
  // difference is beyond twice the test's threshold), the guided centre frame is at least as
  // good as without the guide (measured: flat / feature 3.03 / 5.57 mm against 3.03 / 5.66); let
  // in, they pull points toward the background (feature 6.17 mm).
  SceneOptions o;
  o.noise = NoiseModel::stereo;
  o.frames = 5;
  o.seed = 1;
  o.motion = Motion::moving_box;
  const std::vector<SyntheticFrame> seq = renderSequence(o);
  std::deque<Cloud::ConstPtr> frames;
  for (const SyntheticFrame& f : seq)
    frames.emplace_back(new Cloud(f.noisy));
  auto centre = [&](bool guide) {
    FilterParameters p = FilterParameters::recommended();
    p.patch_guide = guide;
    TemporalNonLocalMeansFilter<pcl::PointXYZ> t;
    t.setParameters(p);
    t.setFrames(frames, 2);
    Cloud out;
    t.filter(out);
    return evaluateFrame(seq[2].truth, out);
  };
  const FrameMetrics guided = centre(true), unguided = centre(false);
  EXPECT_LT(guided.flat_rmse, 1.02 * unguided.flat_rmse) << guided.flat_rmse << " " << unguided.flat_rmse;
  EXPECT_LT(guided.feature_rmse, 1.02 * unguided.feature_rmse) << guided.feature_rmse << " " << unguided.feature_rmse;
}

TEST(TemporalFilter, RecursiveModeUsesNoFutureFrameAndHoldsBoundedMemory)
{
  const FilterParameters p = FilterParameters::recommended();
  const auto frames = sequence(12, 0, 0.004, 600);
  auto other = frames;
  other[7].reset(new Cloud(test::makeCloud(48, 40, boxScene(30), 0.01, 601)));
  TemporalStream<pcl::PointXYZ> a(2, TemporalWindow::recursive, p), b(2, TemporalWindow::recursive, p);
  std::size_t most_held = 0;
  for (std::size_t t = 0; t < frames.size(); ++t) {
    const auto out_a = a.push(frames[t]);
    const auto out_b = b.push(other[t]);
    ASSERT_EQ(out_a.size(), 1u) << "no output delay";
    ASSERT_EQ(out_b.size(), 1u);
    most_held = std::max(most_held, a.heldFrames());
    if (t < 7)
      EXPECT_EQ(maxDistance(*out_a[0], *out_b[0]), 0.0) << "frame " << t << " saw a future frame";
    else
      EXPECT_GT(maxDistance(*out_a[0], *out_b[0]), 0.0) << "frame " << t << " does not carry the history";
  }
  EXPECT_LE(most_held, 2u); // the history and the current frame, however long the sequence
  // Static scene: the recursive outputs are steadier than frames filtered alone.
  const std::vector<Cloud::ConstPtr> still = sequence(10, 0, 0.004, 700);
  std::vector<Cloud::Ptr> alone, recursive = filterSequence<pcl::PointXYZ>(still, 1, TemporalWindow::recursive, p);
  for (const auto& f : still)
    alone.emplace_back(new Cloud(staticFilter(*f, p)));
  EXPECT_LT(temporalStd(recursive, 3, 9), 0.8 * temporalStd(alone, 3, 9));
}

TEST(TemporalFilter, RecursiveModeDoesNotPileUpTheFiltersBias)
{
  // A static scene of boxes, a sphere and a cylinder (Kinect-like noise) for 14 frames. When each
  // output was the next frame's neighbour, the filter's small bias on curved and steep surfaces
  // fed back into every later frame: the error grew frame by frame and ended above that of the
  // frames filtered alone. The history of input frames keeps it at its level after a few frames.
  SceneOptions o;
  o.width = 320;
  o.height = 240;
  o.fx = o.fy = 525.0 * 320 / 640;
  o.frames = 14;
  o.seed = 3;
  const std::vector<SyntheticFrame> seq = renderSequence(o);
  std::vector<Cloud::ConstPtr> frames;
  for (const SyntheticFrame& f : seq)
    frames.emplace_back(new Cloud(f.noisy));
  const FilterParameters p = FilterParameters::recommended();
  const std::vector<Cloud::Ptr> out = filterSequence<pcl::PointXYZ>(frames, 1, TemporalWindow::recursive, p);
  auto rmse = [&](std::size_t k, const Cloud& c) {
    const FrameMetrics m = evaluateFrame(seq[k].truth, c);
    return std::sqrt(0.5 * (m.flat_rmse * m.flat_rmse + m.feature_rmse * m.feature_rmse));
  };
  const double early = rmse(3, *out[3]), late = rmse(13, *out[13]);
  const double alone = rmse(13, staticFilter(*frames[13], p));
  EXPECT_LT(late, 1.05 * early) << "frame 3 " << early << " m, frame 13 " << late << " m";
  EXPECT_LT(late, 0.85 * alone) << "frame 13 filtered alone " << alone << " m, recursive " << late << " m";
}

TEST(TemporalFilter, RecursiveModeStartsANewHistoryAfterANullFrame)
{
  // A null frame (not wanted) comes out null and ends the history: the frames after it come out
  // exactly as from a stream that starts with them (how a shard of a recording starts its
  // history at a chosen frame). Frames before it are as without the gap.
  FilterParameters p = FilterParameters::recommended();
  p.threads = 1;
  const auto frames = sequence(9, 1, 0.004, 800);
  TemporalStream<pcl::PointXYZ> gap(2, TemporalWindow::recursive, p), whole(2, TemporalWindow::recursive, p),
      fresh(2, TemporalWindow::recursive, p);
  for (std::size_t t = 0; t < frames.size(); ++t) {
    const auto out_whole = whole.push(frames[t]);
    const auto out_gap = gap.push(t == 4 ? nullptr : frames[t], t != 4);
    ASSERT_EQ(out_gap.size(), 1u);
    if (t == 4) {
      EXPECT_FALSE(out_gap[0]) << "the gap comes out null";
      continue;
    }
    if (t < 4) {
      EXPECT_EQ(maxDistance(*out_gap[0], *out_whole[0]), 0.0) << "frame " << t;
      continue;
    }
    const auto out_fresh = fresh.push(frames[t]);
    EXPECT_EQ(maxDistance(*out_gap[0], *out_fresh[0]), 0.0) << "frame " << t << " does not start a new history";
    if (t == 5)
      EXPECT_GT(maxDistance(*out_gap[0], *out_whole[0]), 0.0) << "the whole history would have changed frame 5";
  }
  EXPECT_LE(gap.heldFrames(), 3u);
  // A wanted frame must not be null.
  EXPECT_THROW(gap.push(nullptr, true), std::invalid_argument);
}

// A cloud whose width x height is not its number of points is refused with std::invalid_argument
// by all three entry points (the static filter, the temporal filter as the current frame and as
// a neighbour, the stream), before any point is read: one row too many, a size unrelated to the
// points, one row too few.
TEST(TemporalFilter, CloudsWhoseGridDisagreesWithTheirPointsAreRejectedEverywhere)
{
  const Cloud good = test::makeCloud(64, 48, boxScene(12), 0.003, 90);
  ASSERT_EQ(good.size(), 3072u);
  const std::pair<std::uint32_t, std::uint32_t> shapes[] = {{64, 49}, {100, 100}, {64, 47}};
  for (const auto& shape : shapes) {
    SCOPED_TRACE(std::to_string(shape.first) + " x " + std::to_string(shape.second) + " on 3072 points");
    Cloud::Ptr bad(new Cloud(good));
    bad->width = shape.first;
    bad->height = shape.second;
    const Cloud::ConstPtr fine(new Cloud(good));
    Cloud out;
    auto expectInvalid = [](const std::function<void()>& call) {
      try {
        call();
        ADD_FAILURE() << "no error";
      } catch (const std::invalid_argument& e) {
        EXPECT_NE(std::string(e.what()).find("3072 points"), std::string::npos) << e.what();
      } catch (const std::exception& e) {
        ADD_FAILURE() << "not std::invalid_argument: " << e.what();
      }
    };

    NonLocalMeansFilter<pcl::PointXYZ> f;
    f.setInputCloud(bad);
    expectInvalid([&] { f.filter(out); });

    // setFrames itself refuses the window (the current frame, a neighbour, a window of one)...
    TemporalNonLocalMeansFilter<pcl::PointXYZ> t;
    expectInvalid([&] { t.setFrames({fine, bad, fine}, 1); });
    expectInvalid([&] { t.setFrames({fine, bad, fine}, 0); });
    expectInvalid([&] { t.setFrames({bad}, 0); });
    // ... and a frame changed after setFrames is refused by filter().
    Cloud::Ptr later_bad(new Cloud(good));
    t.setFrames({fine, later_bad, fine}, 0);
    later_bad->width = shape.first;
    later_bad->height = shape.second;
    expectInvalid([&] { t.filter(out); });
    later_bad->width = 64;
    later_bad->height = 48;
    t.setFrames({fine, later_bad}, 1);
    later_bad->points.resize(3072 - 64); // the current frame, a row short
    try {
      t.filter(out);
      ADD_FAILURE() << "no error";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("3008 points"), std::string::npos) << e.what();
    }
    TemporalNonLocalMeansFilter<pcl::PointXYZ> plain; // without setFrames: the input alone
    plain.setInputCloud(bad);
    expectInvalid([&] { plain.filter(out); });

    TemporalStream<pcl::PointXYZ> first(1, false, FilterParameters::recommended());
    expectInvalid([&] { first.push(bad); });
    TemporalStream<pcl::PointXYZ> later(1, false, FilterParameters::recommended());
    later.push(fine);
    expectInvalid([&] { later.push(bad); });
  }
}

TEST(TemporalFilter, StreamReportsTheIsolatedOutliersOfEachFrame)
{
  // Frame 1 of three has two points pushed 30 % toward the sensor along their rays: the stream's
  // record of that frame counts them, the others count none, and the temporal filter's count is
  // its current frame's.
  auto frames = sequence(3, 0, 0.003, 800);
  Cloud spiky = *frames[1];
  for (std::size_t i : {std::size_t(8) * 48 + 9, std::size_t(25) * 48 + 30})
    spiky[i].getVector3fMap() *= 0.7f;
  frames[1].reset(new Cloud(spiky));
  TemporalStream<pcl::PointXYZ> stream(1, TemporalWindow::causal, FilterParameters::recommended());
  std::vector<std::size_t> moved;
  for (const auto& f : frames) {
    ASSERT_EQ(stream.push(f).size(), 1u);
    moved.push_back(stream.lastOutputs().front().outliers_moved);
  }
  EXPECT_EQ(moved, (std::vector<std::size_t>{0, 2, 0}));
}

// Nothing the stream estimated on one frame is carried to another: a stream whose sensor changes
// mid-way (noise 2 mm, then 8 mm on the same scene) gives, on every window, also those that
// straddle the change, the bits the temporal filter gives when it estimates every frame's noise
// afresh.
TEST(TemporalFilter, AStreamWhoseSensorChangesFollowsTheChange)
{
  std::vector<Cloud::ConstPtr> frames;
  for (int k = 0; k < 6; ++k)
    frames.emplace_back(new Cloud(test::makeCloud(48, 40, boxScene(12), k < 3 ? 0.002 : 0.008, 900 + k)));
  const FilterParameters p = FilterParameters::recommended();
  for (TemporalWindow mode : {TemporalWindow::centred, TemporalWindow::causal}) {
    TemporalStream<pcl::PointXYZ> stream(1, mode, p);
    std::vector<Cloud::Ptr> out;
    auto take = [&](const std::vector<Cloud::Ptr>& ready) { out.insert(out.end(), ready.begin(), ready.end()); };
    for (const auto& f : frames)
      take(stream.push(f));
    take(stream.flush());
    ASSERT_EQ(out.size(), frames.size());
    for (std::size_t t = 0; t < frames.size(); ++t) {
      const std::size_t lo = t == 0 ? 0 : t - 1;
      const std::size_t hi = mode == TemporalWindow::causal ? t : std::min(frames.size() - 1, t + 1);
      TemporalNonLocalMeansFilter<pcl::PointXYZ> f;
      f.setParameters(p);
      f.setFrames(std::deque<Cloud::ConstPtr>(frames.begin() + lo, frames.begin() + hi + 1), t - lo);
      Cloud expected;
      f.filter(expected);
      EXPECT_TRUE(sameBits(*out[t], expected)) << "frame " << t;
    }
  }
}
