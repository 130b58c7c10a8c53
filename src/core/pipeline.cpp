// Orchestration of the kernel: normals, bandwidths, frame weights, offsets and displacement.
#include "fast_math.h"

#include "internal.h"
#include "workspace.h"

#include <algorithm>
#ifdef _OPENMP
#include <omp.h>
#endif
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace range_nlm
{
namespace detail
{
float
expNonPositive(float x)
{
  return expNonPositiveInline(x);
}

float
inverseSquare(float bandwidth)
{
  return inverseSquareInline(bandwidth);
}

/// applyOffsets along the normals for points [0, n), branch-free so that it vectorizes (every
/// load is unconditional): points that do not move keep their coordinates. With Clamped, h is
/// clamped to +/- bound[i] first.
template <bool Clamped>
void
moveAlongNormals(float* __restrict x, float* __restrict y, float* __restrict z, const unsigned char* __restrict valid,
                 const float* __restrict nx, const float* __restrict ny, const float* __restrict nz,
                 const float* __restrict hs, const float* __restrict bound, std::ptrdiff_t n)
{
  const float largest = std::numeric_limits<float>::max();
  for (std::ptrdiff_t i = 0; i < n; ++i) {
    const float raw = hs[i];
    float h = raw;
    if constexpr (Clamped) {
      const float b = bound[i];
      h = h < -b ? -b : h;
      h = h > b ? b : h; // NaN stays NaN
    }
    const float v = valid[i];
    const bool moves = (v > 0.0f) & (h != 0.0f) & (std::fabs(h) <= largest);
    const float px = x[i], py = y[i], pz = z[i];
    const float qx = px - h * nx[i], qy = py - h * ny[i], qz = pz - h * nz[i];
    x[i] = moves ? qx : px;
    y[i] = moves ? qy : py;
    z[i] = moves ? qz : pz;
  }
}

/// applyOffsets along the line of sight for points [0, n), branch-free as moveAlongNormals: each
/// point moves along its ray from the viewpoint onto the plane (q - p) . n = -h, by t = -h / cos
/// with |cos| at least min_cos (at grazing angles h / cos would amplify any normal error); with
/// Clamped, h and t are clamped to +/- limit[i].
template <bool Clamped>
void
moveAlongRays(float* __restrict x, float* __restrict y, float* __restrict z, const unsigned char* __restrict valid,
              const float* __restrict nx, const float* __restrict ny, const float* __restrict nz,
              const float* __restrict hs, const float* __restrict limit, const Viewpoint& viewpoint, float min_cos,
              std::ptrdiff_t n)
{
  const float largest = std::numeric_limits<float>::max();
  const float ox = viewpoint[0], oy = viewpoint[1], oz = viewpoint[2];
  for (std::ptrdiff_t i = 0; i < n; ++i) {
    float h = hs[i];
    if constexpr (Clamped) {
      const float b = limit[i];
      h = h < -b ? -b : h;
      h = h > b ? b : h; // NaN stays NaN
    }
    const float px = x[i], py = y[i], pz = z[i];
    float vx = px - ox, vy = py - oy, vz = pz - oz;
    const float len = std::sqrt(vx * vx + vy * vy + vz * vz);
    const float v = valid[i];
    const bool moves = (v > 0.0f) & (h != 0.0f) & (std::fabs(h) <= largest) & (len > 0.0f);
    vx /= len, vy /= len, vz /= len;
    float c = vx * nx[i] + vy * ny[i] + vz * nz[i];
    const float signed_bound = c < 0.0f ? -min_cos : min_cos;
    c = std::fabs(c) < min_cos ? signed_bound : c;
    float t = -h / c;
    if constexpr (Clamped) {
      const float b = limit[i];
      t = t < -b ? -b : t;
      t = t > b ? b : t;
    }
    x[i] = moves ? px + t * vx : px;
    y[i] = moves ? py + t * vy : py;
    z[i] = moves ? pz + t * vz : pz;
  }
}

int
resolveThreads(int threads)
{
  if (threads > 0)
    return threads;
#ifdef _OPENMP
  return omp_get_max_threads();
#else
  return 1;
#endif
}
} // namespace detail

void
computeOffsets(const Grid& center, const NormalField& normals, const std::vector<FrameTerm>& frames,
               int search_window, int patch_size, Evaluation evaluation, int threads,
               const std::vector<unsigned char>& active, std::vector<float>& offsets,
               const std::vector<float>& patch_gate)
{
  detail::computeOffsets(center, normals, frames, search_window, patch_size, evaluation, threads, active, offsets,
                         patch_gate, nullptr);
}

void
detail::computeOffsets(const Grid& center, const NormalField& normals, const std::vector<FrameTerm>& frames,
                       int search_window, int patch_size, Evaluation evaluation, int threads,
                       const std::vector<unsigned char>& active, std::vector<float>& offsets,
                       const std::vector<float>& patch_gate, std::vector<float>* planes)
{
  for (const FrameTerm& term : frames)
    if (term.grid == nullptr || term.grid->width != center.width || term.grid->height != center.height ||
        (term.patches && (term.patches->width != center.width || term.patches->height != center.height)))
      throw std::invalid_argument("range_nlm: every frame (and patch guide) must have the size of the filtered frame");
  if (!active.empty() && active.size() != center.size())
    throw std::invalid_argument("range_nlm: the active mask must have one entry per point");
  if (!patch_gate.empty() && patch_gate.size() != center.size())
    throw std::invalid_argument("range_nlm: the patch gate must have one entry per point");
  // Both evaluations write every element.
  offsets.resize(center.size());
  threads = detail::resolveThreads(threads);
  if (evaluation == Evaluation::direct)
    detail::computeOffsetsDirect(center, normals, frames, search_window, patch_size, threads, active, offsets,
                                 patch_gate);
  else
    detail::computeOffsetsFast(center, normals, frames, search_window, patch_size, threads, active, offsets,
                               patch_gate, planes);
}

void
detail::copyGrid(const Grid& from, Grid& to, int threads)
{
  if (&from == &to)
    return;
  const std::size_t n = from.size();
  to.width = from.width;
  to.height = from.height;
  to.x.resize(n);
  to.y.resize(n);
  to.z.resize(n);
  to.valid.resize(n);
  const std::ptrdiff_t size = static_cast<std::ptrdiff_t>(n);
  // Blocks of 4096 points: whole cache lines of every array per iteration.
  const std::ptrdiff_t block = 4096;
  (void)threads;
#pragma omp parallel for schedule(static) num_threads(resolveThreads(threads))
  for (std::ptrdiff_t b = 0; b < (size + block - 1) / block; ++b) {
    const std::ptrdiff_t lo = b * block, count = std::min(block, size - lo);
    std::copy_n(&from.x[lo], count, &to.x[lo]);
    std::copy_n(&from.y[lo], count, &to.y[lo]);
    std::copy_n(&from.z[lo], count, &to.z[lo]);
    std::copy_n(&from.valid[lo], count, &to.valid[lo]);
  }
}

void
applyOffsets(Grid& grid, const NormalField& normals, const std::vector<float>& offsets,
             Displacement displacement, const Viewpoint& viewpoint, const std::vector<float>& limit,
             float min_cos)
{
  const std::ptrdiff_t n = static_cast<std::ptrdiff_t>(grid.size());
  if (displacement != Displacement::line_of_sight) { // automatic: one frame here
    const auto move = limit.empty() ? detail::moveAlongNormals<false> : detail::moveAlongNormals<true>;
    const std::ptrdiff_t block = 4096;
#pragma omp parallel for schedule(static)
    for (std::ptrdiff_t lo = 0; lo < n; lo += block)
      move(&grid.x[lo], &grid.y[lo], &grid.z[lo], &grid.valid[lo], &normals.nx[lo], &normals.ny[lo],
           &normals.nz[lo], &offsets[lo], limit.empty() ? nullptr : &limit[lo], std::min(block, n - lo));
    return;
  }
  const auto move = limit.empty() ? detail::moveAlongRays<false> : detail::moveAlongRays<true>;
  const float bound = std::max(min_cos, 1e-3f);
  const std::ptrdiff_t block = 4096;
#pragma omp parallel for schedule(static)
  for (std::ptrdiff_t lo = 0; lo < n; lo += block)
    move(&grid.x[lo], &grid.y[lo], &grid.z[lo], &grid.valid[lo], &normals.nx[lo], &normals.ny[lo], &normals.nz[lo],
         &offsets[lo], limit.empty() ? nullptr : &limit[lo], viewpoint, bound, std::min(block, n - lo));
}

float
temporalDistanceWeight(int k, int center)
{
  return std::ldexp(1.0f, -std::abs(k - center));
}

float
temporalNoiseWeight(float s_k, float s_max)
{
  if (!(s_max > 0.0f))
    return std::exp(-1.0f); // all frames noise-free: equal weights
  const float ratio = s_k / s_max;
  return std::exp(-ratio * ratio);
}

void
detail::rangesOf(const Grid& grid, const Viewpoint& viewpoint, int threads, std::vector<float>& rho)
{
  rho.resize(grid.size());
  const std::ptrdiff_t size = static_cast<std::ptrdiff_t>(grid.size());
  const float vx = viewpoint[0], vy = viewpoint[1], vz = viewpoint[2];
  const float* __restrict x = grid.x.data();
  const float* __restrict y = grid.y.data();
  const float* __restrict z = grid.z.data();
  const unsigned char* __restrict valid = grid.valid.data();
  float* __restrict out = rho.data();
  (void)threads;
#pragma omp parallel for simd schedule(static) num_threads(threads)
  for (std::ptrdiff_t i = 0; i < size; ++i) {
    const float dx = x[i] - vx, dy = y[i] - vy, dz = z[i] - vz;
    const float r = std::sqrt(dx * dx + dy * dy + dz * dz);
    out[i] = valid[i] ? r : 0.0f;
  }
}

const char*
toString(Stage stage)
{
  switch (stage) {
  case Stage::outliers:
    return "outliers";
  case Stage::dilation:
    return "dilation";
  case Stage::neighbour_frames:
    return "neighbour frames";
  case Stage::bandwidths:
    return "bandwidths";
  case Stage::noise_maps:
    return "noise maps";
  case Stage::presmoothing:
    return "pre-smoothing";
  case Stage::normals:
    return "normals";
  case Stage::frame_terms:
    return "frame terms";
  case Stage::offsets:
    return "offsets";
  case Stage::displacement:
    return "displacement";
  }
  return "?";
}

namespace
{

/// Tells the observer (if any) where the phases of one iteration begin and end: start() ends
/// the running phase, if any, and begins the next; the destructor ends the last.
class StageTracker
{
public:
  StageTracker(StageObserver* observer, int iteration) : observer_(observer), iteration_(iteration) {}
  ~StageTracker() { stop(); }
  StageTracker(const StageTracker&) = delete;
  StageTracker& operator=(const StageTracker&) = delete;

  void start(Stage stage)
  {
    stop();
    if (observer_)
      observer_->begin(stage, iteration_);
    stage_ = stage;
    running_ = true;
  }
  void stop()
  {
    if (running_ && observer_)
      observer_->end(stage_, iteration_);
    running_ = false;
  }

private:
  StageObserver* observer_;
  int iteration_;
  Stage stage_ = Stage::neighbour_frames;
  bool running_ = false;
};

Bandwidths
finishBandwidths(Bandwidths b, const FilterParameters& p)
{
  b.distance = p.distance_bandwidth > 0.0f ? p.distance_bandwidth : p.distance_scale * b.mu_d;
  b.similarity = p.similarity_bandwidth > 0.0f ? p.similarity_bandwidth : p.similarity_scale * b.sigma_s;
  return b;
}
} // namespace

FilterRun
runFilter(const std::vector<const Grid*>& frames, int center, const FilterParameters& parameters,
          const Viewpoint& viewpoint, const std::vector<unsigned char>& active)
{
  Workspace workspace;
  runFilter(frames, center, parameters, viewpoint, active, workspace);
  return std::move(workspace.run);
}

namespace
{
void
runContiguous(const std::vector<const Grid*>& frames, int center, const FilterParameters& parameters,
              const Viewpoint& viewpoint, const std::vector<unsigned char>& active, Workspace& workspace);

/// The pixels (u0 + a k, v0 + b k) of a grid-sized array as an array of their own.
template <typename T>
void
subsample(const std::vector<T>& from, int width, int height, int k, int u0, int v0, std::vector<T>& to, int threads)
{
  const int w = (width - u0 + k - 1) / k, h = (height - v0 + k - 1) / k;
  to.resize(static_cast<std::size_t>(w) * h);
  (void)threads;
#pragma omp parallel for schedule(static) num_threads(threads)
  for (int b = 0; b < h; ++b)
    for (int a = 0; a < w; ++a)
      to[static_cast<std::size_t>(b) * w + a] = from[static_cast<std::size_t>(v0 + b * k) * width + u0 + a * k];
}

/// CrossFrameBandwidth::guarded with the range-adaptive model (docs/method.md, "Low-frequency
/// offsets between frames"): a neighbour that differs from the current frame by a slowly varying
/// offset along the rays (FrameChange::offset) is brought to the current frame's level, and the
/// current frame and every neighbour that did not move to the mean level of those frames. The
/// frames' noise is then what is left between them, and the offsets, noise of a camera that did
/// not move, are averaged out. Fills `leveled` and `out` and returns true if some neighbour
/// had such an offset; otherwise returns false and leaves the frames as they are. `moved`
/// receives per frame whether it moved (1) or not (0, an offset counts as not moved), -1 for the
/// current frame and an empty one; it is left empty where nothing was analysed.
bool
levelFrames(const std::vector<const Grid*>& frames, int center, const FilterParameters& parameters,
            const Viewpoint& viewpoint, int threads, std::vector<Grid>& leveled, std::vector<const Grid*>& out,
            std::vector<signed char>& moved)
{
  const int count = static_cast<int>(frames.size());
  moved.clear();
  if (count < 2 || parameters.bandwidth_model != BandwidthModel::range_adaptive ||
      parameters.cross_frame_bandwidth != CrossFrameBandwidth::guarded)
    return false;
  const Grid& current = *frames[center];
  for (const Grid* g : frames)
    if (!g || g->width != current.width || g->height != current.height)
      return false; // runContiguous reports it
  if (current.countValid() == 0)
    return false;
  std::vector<FrameOffset> changes(count);
  std::vector<unsigned char> still(count, 0);
  bool any = false;
  for (int k = 0; k < count; ++k) {
    if (k == center || frames[k]->countValid() == 0)
      continue;
    changes[k] = detail::analyseFrameChange(current, *frames[k], viewpoint, threads);
    still[k] = changes[k].change != FrameChange::motion;
    any = any || changes[k].change == FrameChange::offset;
  }
  // The motion test's answer for every frame of the run (an offset is levelled: not moved).
  moved.assign(count, -1);
  for (int k = 0; k < count; ++k)
    if (k != center && frames[k]->countValid() > 0)
      moved[k] = !still[k];
  if (!any)
    return false;
  // The mean level against the current frame's: the mean of o_k over the current frame (o = 0)
  // and the neighbours that did not move (o = 0 for those without an offset). Not weighted by
  // Psi_d: these frames did not move, so their offsets are noise, best averaged evenly.
  const std::size_t n = current.size();
  const float w = 1.0f / static_cast<float>(1 + std::count(still.begin(), still.end(), 1));
  std::vector<float> mean(n, 0.0f);
  for (int k = 0; k < count; ++k)
    if (changes[k].change == FrameChange::offset) {
      const float* o = changes[k].range_offset.data();
#pragma omp parallel for simd schedule(static) num_threads(threads)
      for (std::size_t i = 0; i < n; ++i)
        mean[i] += w * o[i];
    }
  leveled.resize(count);
  out = frames;
  for (int k = 0; k < count; ++k) {
    if (k != center && !still[k])
      continue;
    const Grid& from = *frames[k];
    Grid& to = leveled[k];
    detail::copyGrid(from, to, threads);
    const float* o = changes[k].change == FrameChange::offset ? changes[k].range_offset.data() : nullptr;
    // Each point along its ray by the mean level minus its frame's offset.
#pragma omp parallel for schedule(static) num_threads(threads)
    for (std::size_t i = 0; i < n; ++i) {
      if (!to.valid[i])
        continue;
      const float dx = to.x[i] - viewpoint[0], dy = to.y[i] - viewpoint[1], dz = to.z[i] - viewpoint[2];
      const float rho = std::sqrt(dx * dx + dy * dy + dz * dz);
      const float target = rho + mean[i] - (o ? o[i] : 0.0f);
      if (!(rho > 0.0f) || !(target > 0.0f))
        continue; // a shift to or behind the viewpoint: the point stays where it is
      const float f = target / rho;
      to.x[i] = viewpoint[0] + dx * f;
      to.y[i] = viewpoint[1] + dy * f;
      to.z[i] = viewpoint[2] + dz * f;
    }
    out[k] = &to;
  }
  return true;
}

void
subsample(const Grid& from, int k, int u0, int v0, Grid& to, int threads)
{
  to.width = (from.width - u0 + k - 1) / k;
  to.height = (from.height - v0 + k - 1) / k;
  subsample(from.x, from.width, from.height, k, u0, v0, to.x, threads);
  subsample(from.y, from.width, from.height, k, u0, v0, to.y, threads);
  subsample(from.z, from.width, from.height, k, u0, v0, to.z, threads);
  subsample(from.valid, from.width, from.height, k, u0, v0, to.valid, threads);
}
} // namespace

int
automaticDilation(const Grid& frame)
{
  return detail::automaticDilation(frame, 1);
}

int
detail::automaticDilation(const Grid& frame, int threads)
{
  const int lag = std::clamp((8 * frame.width + 320) / 640, 2, 8);
  const NoiseCorrelation c = detail::estimateNoiseCorrelation(frame, 4, threads);
  const float near = c.scale[0] * c.scale[0], far = c.scale[lag - 1] * c.scale[lag - 1];
  const int k = far > 0.0f && near < 0.5f * far ? std::clamp((2 * frame.width + 320) / 640, 2, 4) : 1;
  // Strong noise: more than 3.25 pixel footprints at half the reference lag.
  return c.scale_in_footprints[lag / 2 - 1] > 3.25f ? 2 * k : k;
}

void
runFilter(const std::vector<const Grid*>& given, int center, const FilterParameters& parameters,
          const Viewpoint& viewpoint, const std::vector<unsigned char>& active, Workspace& workspace)
{
  if (given.empty() || center < 0 || center >= static_cast<int>(given.size()) || !given[center]) {
    runContiguous(given, center, parameters, viewpoint, active, workspace);
    return;
  }
  // Checked before anything runs with parameters.threads threads (OpenMP crashes on absurd counts).
  parameters.validate();
  // The current frame's isolated outliers first, so that every later phase (noise estimates,
  // frame comparisons, normals) sees them on their neighbours' surface.
  std::vector<const Grid*> frames_in = given;
  workspace.run.outliers_moved = 0; // every path below keeps it
  if (parameters.outlier_sigmas > 0.0f && given[center]->countValid() > 0) {
    StageTracker stage(workspace.observer, 0);
    stage.start(Stage::outliers);
    const Grid& input = *given[center];
    const int threads = detail::resolveThreads(parameters.threads);
    NoiseProfile profile;
    try {
      profile = detail::estimateNoiseProfile(input, parameters.search_window, parameters.bandwidth_samples,
                                             parameters.seed, viewpoint, threads);
    } catch (const UnfilterableFrame&) {
      // Too few points for a noise estimate: nothing to test against (runContiguous reports it).
    }
    const bool sized = active.empty() || active.size() == input.size(); // runContiguous reports a mismatch
    if (!profile.empty() && sized) {
      const std::vector<detail::IsolatedPoint> found =
          detail::findIsolatedPoints(input, profile, parameters.outlier_sigmas, viewpoint, active, threads);
      if (!found.empty()) {
        detail::copyGrid(input, workspace.corrected, threads);
        detail::moveIsolatedPoints(workspace.corrected, found, viewpoint);
        frames_in[center] = &workspace.corrected;
        workspace.run.outliers_moved = found.size();
      }
    }
  }
  std::vector<const Grid*> leveled;
  {
    StageTracker stage(workspace.observer, 0);
    stage.start(Stage::neighbour_frames);
    if (!levelFrames(frames_in, center, parameters, viewpoint, detail::resolveThreads(parameters.threads),
                     workspace.leveled, leveled, workspace.frames_moved))
      leveled = frames_in;
  }
  const std::vector<const Grid*>& frames = leveled;
  const Grid& input = *frames[center];
  const bool empty = input.countValid() == 0;
  int k = parameters.dilation;
  StageTracker split(workspace.observer, 0);
  if (k == 0) {
    split.start(Stage::dilation);
    // Automatic: contiguous windows unless every phase still holds the windows, and nothing to
    // estimate in a frame without a valid point (runContiguous says so).
    const int needed = std::max({parameters.search_window, parameters.patch_size, parameters.normal_window,
                                 parameters.normal_presmooth_window});
    k = empty ? 1 : detail::automaticDilation(input, detail::resolveThreads(parameters.threads));
    if (input.width / k < needed || input.height / k < needed)
      k = 1;
  }
  if (k <= 1 || empty) {
    split.stop();
    runContiguous(frames, center, parameters, viewpoint, active, workspace);
    return;
  }
  split.start(Stage::dilation);
  // The dilated passes: each phase (u mod k, v mod k) of the frames is a grid of its own whose
  // neighbours are k pixels apart, filtered with contiguous windows.
  FilterParameters coarse = parameters;
  coarse.dilation = 1;
  coarse.iterations = std::max(1, parameters.iterations - 1);
  const int threads = detail::resolveThreads(parameters.threads);
  // Kept in the workspace: the next run on frames of this size allocates nothing here.
  Grid& result = workspace.merged;
  detail::copyGrid(input, result, threads);
  std::vector<Grid>& sub = workspace.phase_frames;
  sub.resize(frames.size());
  std::vector<const Grid*> sub_frames(frames.size());
  std::vector<unsigned char> sub_active;
  workspace.phase.resize(1);
  Workspace& phase = workspace.phase.front();
  phase.observer = workspace.observer;
  phase.frames_moved = workspace.frames_moved;
  for (int v0 = 0; v0 < std::min(k, input.height); ++v0)
    for (int u0 = 0; u0 < std::min(k, input.width); ++u0) {
      for (std::size_t f = 0; f < frames.size(); ++f) {
        if (!frames[f] || frames[f]->width != input.width || frames[f]->height != input.height) {
          split.stop();
          runContiguous(frames, center, parameters, viewpoint, active, workspace); // reports the size error
          return;
        }
        subsample(*frames[f], k, u0, v0, sub[f], threads);
        sub_frames[f] = &sub[f];
      }
      if (!active.empty())
        subsample(active, input.width, input.height, k, u0, v0, sub_active, threads);
      split.stop();
      try {
        runContiguous(sub_frames, center, coarse, viewpoint, sub_active, phase);
      } catch (const UnfilterableFrame&) {
        split.start(Stage::dilation);
        continue; // this phase keeps its points
      }
      split.start(Stage::dilation);
      const Grid& out = phase.run.output;
#pragma omp parallel for schedule(static) num_threads(threads)
      for (int b = 0; b < out.height; ++b)
        for (int a = 0; a < out.width; ++a) {
          const std::size_t from = static_cast<std::size_t>(b) * out.width + a;
          const std::size_t to = static_cast<std::size_t>(v0 + b * k) * input.width + u0 + a * k;
          result.x[to] = out.x[from];
          result.y[to] = out.y[from];
          result.z[to] = out.z[from];
        }
    }
  split.stop();
  if (parameters.iterations <= 1) {
    std::swap(workspace.run.output, result);
    workspace.run.bandwidths = phase.run.bandwidths;
    workspace.run.frame_weights = phase.run.frame_weights;
    return;
  }
  // The last pass with contiguous windows on the full frame.
  FilterParameters fine = parameters;
  fine.dilation = 1;
  fine.iterations = 1;
  std::vector<const Grid*> last = frames;
  last[center] = &result;
  runContiguous(last, center, fine, viewpoint, active, workspace);
}

namespace
{
void
runContiguous(const std::vector<const Grid*>& frames, int center, const FilterParameters& parameters,
              const Viewpoint& viewpoint, const std::vector<unsigned char>& active, Workspace& workspace)
{
  if (frames.empty() || center < 0 || center >= static_cast<int>(frames.size()) || !frames[center])
    throw std::invalid_argument("range_nlm: the current frame index is outside the frame list");
  const Grid& input = *frames[center];
  if (input.width <= 0 || input.height <= 0)
    throw std::invalid_argument("range_nlm: the cloud is empty or not organized (width x height = " +
                                std::to_string(input.width) + " x " + std::to_string(input.height) + ")");
  parameters.validateFor(input.width, input.height);
  for (std::size_t k = 0; k < frames.size(); ++k)
    if (!frames[k] || frames[k]->width != input.width || frames[k]->height != input.height) {
      std::ostringstream msg;
      msg << "range_nlm: frame " << k << " is " << (frames[k] ? frames[k]->width : 0) << " x "
          << (frames[k] ? frames[k]->height : 0) << " but the current frame is " << input.width << " x "
          << input.height;
      throw std::invalid_argument(msg.str());
    }
  if (input.countValid() == 0)
    throw UnfilterableFrame("range_nlm: the cloud has no valid point (all NaN); nothing to filter");

  // OpenMP treats num_threads(0) as an error; map 0 to the runtime's default.
  const int threads = detail::resolveThreads(parameters.threads);

  FilterRun& run = workspace.run;
  run.bandwidths.clear();
  run.frame_weights.clear();
  const int count = static_cast<int>(frames.size());
  const bool adaptive = parameters.bandwidth_model == BandwidthModel::range_adaptive;
  const std::size_t n = input.size();
  // The filtered frame starts as the input. A grid of workspace.inputs that no other frame
  // shares is taken over instead of copied (`input` is not used after this).
  Grid* own = nullptr;
  for (Grid& g : workspace.inputs)
    if (&g == &input)
      own = &g;
  for (int k = 0; k < count; ++k)
    if (k != center && frames[k] == &input)
      own = nullptr;
  if (own)
    std::swap(*own, run.output);
  else
    detail::copyGrid(input, run.output, threads);

  // Range of every centre point (the per-point bandwidths are functions of it).
  auto rangesInto = [&](const Grid& g, std::vector<float>& rho) { detail::rangesOf(g, viewpoint, threads, rho); };
  auto medianRange = [&](const Grid& g, const std::vector<float>& rho) {
    return detail::medianOfNonNegative(rho.data(), g.valid.data(), g.size(), threads);
  };

  // Per frame: scalar bandwidths (global model) or a noise profile (range-adaptive model).
  std::vector<Bandwidths> bandwidths(count);
  std::vector<NoiseProfile> profiles(count);
  std::vector<bool> usable(count, true);
  auto estimateFrame = [&](int k, const Grid& g, const NormalField* normals, float rho_median) {
    const std::uint64_t seed = parameters.seed + static_cast<std::uint64_t>(k - center) * 7919u;
    if (adaptive) {
      profiles[k] =
          detail::estimateNoiseProfile(g, parameters.search_window, parameters.bandwidth_samples, seed, viewpoint, threads);
      Bandwidths b;
      b.sigma_s = profiles[k].sigmaAt(rho_median);
      b.mu_d = profiles[k].extentAt(rho_median) * rho_median;
      bandwidths[k] = finishBandwidths(b, parameters);
    } else {
      // A neighbour's normals go into the centre frame's buffer, which is filled afterwards.
      if (!normals)
        detail::estimateNormalsGated(g, parameters.normal_window, viewpoint, threads, {}, 0, workspace.normals,
                                     &workspace.normal_planes);
      bandwidths[k] = finishBandwidths(estimateBandwidths(g, normals ? *normals : workspace.normals,
                                                          parameters.search_window, parameters.bandwidth_samples, seed),
                                       parameters);
    }
  };

  // Neighbour frames are estimated once, from their own data (the range-adaptive model reads
  // their profiles at the centre frame's median range).
  StageObserver* const observer = workspace.observer;
  // With neighbours: the first iteration's ranges (workspace.ranges) and their median, taken
  // before the neighbours' estimates (run.output is still the input).
  float input_rho_median = 0.0f;
  if (count > 1) {
    StageTracker stage(observer, 0);
    stage.start(Stage::neighbour_frames);
    if (adaptive) {
      rangesInto(run.output, workspace.ranges);
      input_rho_median = medianRange(run.output, workspace.ranges);
    }
    for (int k = 0; k < count; ++k) {
      if (k == center)
        continue;
      try {
        estimateFrame(k, *frames[k], nullptr, input_rho_median);
      } catch (const UnfilterableFrame&) {
        usable[k] = false; // an all-NaN neighbour contributes nothing
      }
    }
  }

  std::vector<float>& offsets = workspace.offsets;
  NormalField& normals = workspace.normals;
  std::vector<std::vector<float>>& inverse_d2 = workspace.inverse_d2;
  std::vector<std::vector<float>>& inverse_s2 = workspace.inverse_s2;
  if (inverse_d2.size() < static_cast<std::size_t>(count))
    inverse_d2.resize(count), inverse_s2.resize(count);
  // profile.sigmaAt / extentAt of every point's range into `out`, in blocks by `threads` threads.
  // With ys2 and out2 also that profile into out2, in the same scan.
  auto profileMap = [&](const std::vector<float>& xs, const std::vector<float>& ys, const std::vector<float>& rho,
                        std::vector<float>& out, const std::vector<float>* ys2 = nullptr,
                        std::vector<float>* out2 = nullptr) {
    out.resize(n);
    if (out2)
      out2->resize(n);
    const std::ptrdiff_t size = static_cast<std::ptrdiff_t>(n), block = 4096;
#pragma omp parallel for schedule(static) num_threads(threads)
    for (std::ptrdiff_t lo = 0; lo < size; lo += block)
      detail::interpolateProfile(xs, ys, &rho[lo], &out[lo], static_cast<std::size_t>(std::min(block, size - lo)), ys2,
                                 out2 ? &(*out2)[lo] : nullptr);
  };
  // Per-point distance bandwidths from the profiles' extents (range-adaptive, d not given).
  const bool own_d = adaptive && !(parameters.distance_bandwidth > 0.0f);
  for (int iteration = 0; iteration < parameters.iterations; ++iteration) {
    const Grid& current = run.output;
    StageTracker stage(observer, iteration);
    std::vector<float>& rho = workspace.ranges;
    if (adaptive) {
      stage.start(Stage::bandwidths);
      const bool known = iteration == 0 && count > 1; // the neighbours' stage took them
      if (!known)
        rangesInto(current, rho);
      estimateFrame(center, current, nullptr, known ? input_rho_median : medianRange(current, rho));
    } else {
      stage.start(Stage::normals);
      detail::estimateNormalsGated(current, parameters.normal_window, viewpoint, threads, {}, 0, normals,
                                   &workspace.normal_planes);
      stage.start(Stage::bandwidths);
      estimateFrame(center, current, &normals, 0.0f);
    }
    // Per-point gates of `sigmas` noise sigmas (sig: the local noise sigma times similarity_scale)
    // into `gate`; empty (no gate) for 0.
    auto gateInto = [&](float sigmas, const std::vector<float>& sig,
                        std::vector<float>& gate) -> const std::vector<float>& {
      gate.clear();
      if (sigmas > 0.0f) {
        gate.resize(n);
#pragma omp parallel for schedule(static) num_threads(threads)
        for (std::size_t i = 0; i < n; ++i)
          gate[i] = sigmas * sig[i] / parameters.similarity_scale;
      }
      return gate;
    };
    // Local noise sigma of every centre point: for the pre-smoothing and the displacement limit.
    std::vector<float>& sigma = workspace.sigma;
    stage.start(Stage::noise_maps);
    sigma.resize(n);
    if (!adaptive) {
#pragma omp parallel for schedule(static) num_threads(threads)
      for (std::size_t i = 0; i < n; ++i)
        sigma[i] = bandwidths[center].similarity;
    } else {
      std::vector<float>& at = workspace.profile_sigma;
      // The current frame's extent map for its frame term too, in the same scan.
      profileMap(profiles[center].range, profiles[center].sigma, rho, at, own_d ? &profiles[center].extent : nullptr,
                 own_d ? &workspace.center_extent : nullptr);
#pragma omp parallel for schedule(static) num_threads(threads)
      for (std::size_t i = 0; i < n; ++i)
        sigma[i] = current.valid[i] ? parameters.similarity_scale * at[i] : 0.0f;
    }
    if (parameters.normal_presmooth_window > 1) {
      std::vector<float>& range_sigma = workspace.range_sigma;
      range_sigma.resize(n);
#pragma omp parallel for schedule(static) num_threads(threads)
      for (std::size_t i = 0; i < n; ++i)
        range_sigma[i] = parameters.normal_presmooth_range * sigma[i] / parameters.similarity_scale;
      const std::vector<float>& gate = gateInto(parameters.normal_edge_gate, sigma, workspace.gate);
      stage.start(Stage::presmoothing);
      // The padded planes of the pre-smoothing are those of the normal fits that follow (not
      // needed by then).
      Grid& smooth = workspace.smooth;
      detail::presmoothAlongRays(current, parameters.normal_presmooth_window, range_sigma, viewpoint, threads, smooth,
                                 &workspace.normal_planes);
      stage.start(Stage::normals);
      detail::estimateNormalsGated(smooth, parameters.normal_window, viewpoint, threads, gate, gate.empty() ? 0 : 2,
                                   normals, &workspace.normal_planes, &workspace.first_normals);
    } else if (adaptive) {
      const std::vector<float>& gate = gateInto(parameters.normal_edge_gate, sigma, workspace.gate);
      stage.start(Stage::normals);
      detail::estimateNormalsGated(current, parameters.normal_window, viewpoint, threads, gate, gate.empty() ? 0 : 2,
                                   normals, &workspace.normal_planes, &workspace.first_normals);
    }

    stage.start(Stage::frame_terms);
    float s_max = 0.0f;
    for (int k = 0; k < count; ++k)
      if (usable[k])
        s_max = std::max(s_max, bandwidths[k].similarity);
    std::vector<FrameTerm> terms;
    std::vector<float> weights(count, 0.0f);
    // Guarded: the patch guide the other frames' patches are compared with (docs/method.md, "The
    // patch guide"), the sums of the unchanged frames' points and their weights per pixel,
    // started with the current frame (weight 1).
    Grid& guide = workspace.guide;
    std::vector<float>& guide_weight = workspace.guide_weight;
    int guide_frames = 0; // neighbours in the guide
    int neighbours = 0;   // usable frames other than the current one
    for (int k = 0; k < count; ++k)
      neighbours += usable[k] && k != center ? 1 : 0;
    // Built only where it can be used (kGuideMinFrames): radius 1 does no work for it.
    const bool may_guide = parameters.patch_guide && neighbours >= detail::kGuideMinFrames;
    for (int k = 0; k < count; ++k) {
      if (!usable[k])
        continue;
      weights[k] = temporalDistanceWeight(k, center) * temporalNoiseWeight(bandwidths[k].similarity, s_max);
      FrameTerm term{k == center ? &current : frames[k], bandwidths[k].distance, bandwidths[k].similarity, weights[k]};
      if (adaptive) {
        // Per-point bandwidths from frame k's profile at the centre point's range; a bandwidth
        // given by the user stays global. Another frame's noise is its spatial noise, raised to
        // its frame-to-frame noise where that is larger (spatially correlated noise): its
        // patches then get s from that noise, and its points a d that also spans the distance
        // two samples of one surface point have from frame to frame (2 s^2 more in d^2).
        // The differences along the normals once (alongNormals), for the motion test, the ratio
        // (against the profile's sigma at the centre points' ranges, `sig`) and the per-pixel
        // test of change.
        const bool own_s = !(parameters.similarity_bandwidth > 0.0f);
        const bool guarded = parameters.cross_frame_bandwidth == CrossFrameBandwidth::guarded;
        const bool compared =
            k != center && (guarded || parameters.cross_frame_bandwidth == CrossFrameBandwidth::temporal);
        // The current frame's sigma map is the noise maps' (workspace.profile_sigma).
        std::vector<float>& sig = k == center ? workspace.profile_sigma : workspace.other_sigma;
        // The current frame's extent map is the noise maps' too (workspace.center_extent); another
        // frame's is taken in the scan of its sigma map.
        std::vector<float>& ext = k == center ? workspace.center_extent : workspace.profile_extent;
        if (k != center && (own_d || own_s || compared))
          profileMap(profiles[k].range, profiles[k].sigma, rho, sig, own_d ? &profiles[k].extent : nullptr,
                     own_d ? &ext : nullptr);
        std::vector<float>& along = workspace.along;
        if (compared)
          detail::alongNormals(current, normals, *frames[k], threads, along);
        // Guarded: whether frame k moved is the run's analysis of the input frames
        // (analyseFrameChange, before the levelling) where there is one, else the motion test.
        const std::vector<signed char>& known_moved = workspace.frames_moved;
        const int analysed = guarded && known_moved.size() == static_cast<std::size_t>(count) ? known_moved[k] : -1;
        bool moved = analysed == 1;
        float ratio = 1.0f;
        if (compared && analysed != 1) {
          const detail::FrameComparison comparison =
              detail::compareAlong(along, current.width, current.height, sig.data(), guarded && analysed < 0, threads);
          moved = comparison.moved;
          ratio = std::max(1.0f, comparison.ratio);
        }
        const bool cross = ratio > 1.0f;
        if (own_d) {
          inverse_d2[k].resize(n);
          float* __restrict out = inverse_d2[k].data();
          const float* __restrict e = ext.data();
          const float* __restrict g = sig.data();
          const float* __restrict r = rho.data();
          const float ds = parameters.distance_scale, ss = parameters.similarity_scale * ratio;
          const std::ptrdiff_t size = static_cast<std::ptrdiff_t>(n);
#pragma omp parallel for simd schedule(static) num_threads(threads)
          for (std::ptrdiff_t i = 0; i < size; ++i) {
            const float d = ds * e[i] * r[i];
            const float s = ss * g[i];
            out[i] = detail::inverseSquareInline(cross ? std::sqrt(d * d + 2.0f * s * s) : d);
          }
          // Guarded: no weight from frame k for a point whose surroundings changed from this frame
          // to frame k by far more than the noise (d = 0: only an exact match would keep weight).
          if (k != center && guarded) {
            std::vector<unsigned char>& changed = workspace.changed;
            detail::markChangedPixels(along, current.width, current.height, workspace.profile_sigma.data(), g, ratio,
                                      threads, changed);
            const float none = detail::inverseSquareInline(0.0f);
#pragma omp parallel for simd schedule(static) num_threads(threads)
            for (std::ptrdiff_t i = 0; i < size; ++i)
              out[i] = changed[i] ? none : out[i];
            // A frame that did not move enters the guide with its points where the test found no
            // change within kGuideMargin pixels and the point's own difference is within
            // kGuideTolerance times the test's threshold (the 3 x 3 vote passes a lone pixel that
            // changed, e.g. at the leading edge of an object in a dilated pass), weighted by the
            // inverse of its noise variance relative to the current frame's, (s_c / s_k)^2, at
            // most 1 (a smoothed neighbour does not outweigh the current frame).
            const float s_k = bandwidths[k].similarity, s_c = bandwidths[center].similarity;
            if (may_guide && !moved && s_k > 0.0f && s_c > 0.0f && std::isfinite(s_k) && std::isfinite(s_c)) {
              if (guide_frames++ == 0) {
                detail::copyGrid(current, guide, threads);
                guide_weight.assign(n, 1.0f);
              }
              std::vector<unsigned char>& widened = workspace.widened;
              detail::widenMask(changed, current.width, current.height, detail::kGuideMargin, threads, widened);
              const float w = std::min(1.0f, (s_c / s_k) * (s_c / s_k));
              const Grid& other = *frames[k];
              const float limit = detail::kGuideTolerance * detail::kChangeSigmas * 1.41421356f * ratio;
              const float* __restrict sigma_c = workspace.profile_sigma.data();
              const float* __restrict difference = along.data();
#pragma omp parallel for schedule(static) num_threads(threads)
              for (std::ptrdiff_t i = 0; i < size; ++i)
                if (guide.valid[i] && other.valid[i] && !widened[i] &&
                    std::fabs(difference[i]) <= limit * std::max(sigma_c[i], g[i])) {
                  guide.x[i] += w * other.x[i];
                  guide.y[i] += w * other.y[i];
                  guide.z[i] += w * other.z[i];
                  guide_weight[i] += w;
                }
            }
          }
          term.inverse_distance2 = &inverse_d2[k];
        }
        if (own_s) {
          inverse_s2[k].resize(n);
          float* __restrict out = inverse_s2[k].data();
          const float* __restrict g = sig.data();
          const float ss = parameters.similarity_scale * ratio;
          const std::ptrdiff_t size = static_cast<std::ptrdiff_t>(n);
#pragma omp parallel for simd schedule(static) num_threads(threads)
          for (std::ptrdiff_t i = 0; i < size; ++i)
            out[i] = detail::inverseSquareInline(ss * g[i]);
          term.inverse_similarity2 = &inverse_s2[k];
        }
      }
      terms.push_back(term);
    }
    // With fewer neighbours in it, each would find a large share of its own noise in the guide
    // and its candidates would lean towards that instead (kGuideMinFrames).
    if (guide_frames >= detail::kGuideMinFrames) {
      const std::ptrdiff_t size = static_cast<std::ptrdiff_t>(n);
#pragma omp parallel for schedule(static) num_threads(threads)
      for (std::ptrdiff_t i = 0; i < size; ++i) {
        const float inverse = 1.0f / guide_weight[i];
        guide.x[i] *= inverse;
        guide.y[i] *= inverse;
        guide.z[i] *= inverse;
      }
      for (FrameTerm& term : terms)
        if (term.grid != &current)
          term.patches = &guide;
    }
    if (iteration == 0) {
      run.bandwidths = bandwidths;
      run.frame_weights = weights;
    }
    stage.start(Stage::offsets);
    const std::vector<float>& patch_gate = gateInto(parameters.patch_edge_gate, sigma, workspace.patch_gate);
    detail::computeOffsets(current, normals, terms, parameters.search_window, parameters.patch_size,
                           parameters.evaluation, threads, active, offsets, patch_gate, &workspace.window_planes);
    stage.start(Stage::displacement);
    std::vector<float>& limit = workspace.limit;
    if (parameters.max_displacement > 0.0f) {
      limit.resize(n);
#pragma omp parallel for schedule(static) num_threads(threads)
      for (std::size_t i = 0; i < n; ++i)
        limit[i] = parameters.max_displacement * sigma[i];
    } else {
      limit.clear();
    }
    const Displacement displacement = parameters.displacement != Displacement::automatic ? parameters.displacement
                                      : std::count(usable.begin(), usable.end(), true) > 1 ? Displacement::line_of_sight
                                                  : Displacement::normal;
    applyOffsets(run.output, normals, offsets, displacement, viewpoint, limit, parameters.line_of_sight_min_cos);
  }
}

} // namespace

} // namespace range_nlm
