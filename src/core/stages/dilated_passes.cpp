// Stage::dilation: the automatic dilation, the split of the frames into their k^2 phases, the
// contiguous run on each phase and the merge of their results.
#include "stages.h"

#include "../tuned.h"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <exception>
#include <limits>

namespace range_nlm
{
namespace detail
{
namespace
{

/// Every K-th of w values from `from` into `to` (K a constant, so that the strided reads
/// vectorize as shuffles).
template <int K, typename T>
void
everyKth(const T* __restrict from, int w, T* __restrict to)
{
  for (int a = 0; a < w; ++a)
    to[a] = from[a * K];
}

/// The pixels (u0 + a k, v0 + b k) of a grid-sized array as an array of their own.
template <typename T>
void
subsample(const std::vector<T>& from, int width, int height, int k, int u0, int v0, std::vector<T>& to, int threads)
{
  const int w = (width - u0 + k - 1) / k, h = (height - v0 + k - 1) / k;
  to.resize(static_cast<std::size_t>(w) * h);
  (void)threads;
#pragma omp parallel for schedule(static) num_threads(threads)
  for (int b = 0; b < h; ++b) {
    const T* row = from.data() + static_cast<std::size_t>(v0 + b * k) * width + u0;
    T* out = to.data() + static_cast<std::size_t>(b) * w;
    if (k == 2)
      everyKth<2>(row, w, out);
    else if (k == 4)
      everyKth<4>(row, w, out);
    else
      for (int a = 0; a < w; ++a)
        out[a] = row[static_cast<std::size_t>(a) * k];
  }
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

/// The values of phase (u0, v0) (a `phase`-sized array) back to their pixels of `result`, an
/// array of the full frame (`width` wide).
void
mergePhaseValues(const std::vector<float>& from, const Grid& phase, int k, int u0, int v0, int width,
                 std::vector<float>& result, int threads)
{
  (void)threads;
#pragma omp parallel for schedule(static) num_threads(threads)
  for (int b = 0; b < phase.height; ++b)
    for (int a = 0; a < phase.width; ++a)
      result[static_cast<std::size_t>(v0 + b * k) * width + u0 + a * k] =
          from[static_cast<std::size_t>(b) * phase.width + a];
}

/// The filtered points of phase (u0, v0) back to their pixels of `result` (the full frame).
void
mergePhase(const Grid& out, int k, int u0, int v0, Grid& result, int threads)
{
  const int width = result.width;
  (void)threads;
#pragma omp parallel for schedule(static) num_threads(threads)
  for (int b = 0; b < out.height; ++b)
    for (int a = 0; a < out.width; ++a) {
      const std::size_t from = static_cast<std::size_t>(b) * out.width + a;
      const std::size_t to = static_cast<std::size_t>(v0 + b * k) * width + u0 + a * k;
      result.x[to] = out.x[from];
      result.y[to] = out.y[from];
      result.z[to] = out.z[from];
    }
}

/// Every frame is there and has the size of the current one.
bool
sameSize(const std::vector<const Grid*>& frames, const Grid& input)
{
  for (const Grid* g : frames)
    if (!g || g->width != input.width || g->height != input.height)
      return false;
  return true;
}

/// The run's result from the merged phases: with one iteration the merged frame itself, else a
/// last pass with contiguous windows on the full frame.
void
finishDilatedPasses(const std::vector<const Grid*>& frames, int center, const FilterParameters& parameters,
                    const Viewpoint& viewpoint, const std::vector<unsigned char>& active, Workspace& workspace)
{
  if (parameters.iterations <= 1) {
    std::swap(workspace.run.output, workspace.merged);
    workspace.run.bandwidths = workspace.phase.front().run.bandwidths; // (no phase filtered)
    workspace.run.frame_weights = workspace.phase.front().run.frame_weights;
    for (std::size_t p = workspace.phase_filtered.size(); p-- > 0;)
      if (workspace.phase_filtered[p]) {
        workspace.run.bandwidths = workspace.phase_bandwidths[p];
        workspace.run.frame_weights = workspace.phase_weights[p];
        break;
      }
    if (parameters.uncertainty)
      std::swap(workspace.run.uncertainty, workspace.phase_uncertainty);
    else
      workspace.run.uncertainty.clear();
    return;
  }
  FilterParameters fine = parameters;
  fine.dilation = 1;
  fine.iterations = 1;
  std::vector<const Grid*> last = frames;
  last[center] = &workspace.merged;
  const bool correlated = workspace.correlated_input;
  workspace.correlated_input = true;
  runContiguous(last, center, fine, viewpoint, active, workspace);
  workspace.correlated_input = correlated;
}

} // namespace
} // namespace detail

int
automaticDilation(const Grid& frame)
{
  return detail::automaticDilation(frame, 1);
}

int
detail::automaticDilation(const Grid& frame, int threads)
{
  const int width = tuned::kDilationReferenceWidth, rounding = tuned::kDilationReferenceWidth / 2;
  const int lag = dilationReferenceLag(frame.width);
  const NoiseCorrelation c = detail::estimateNoiseCorrelation(frame, tuned::kDilationCorrelationStep, threads);
  // Correlated noise: 2 per reference width, or the correlation length where that is longer (the
  // phases' pixels k apart then lie about a correlation length apart), up to kDilationMax.
  // Below the reference width the lags beyond a few pixels see the frame's curvature and edges
  // more than its noise: the length is not used there.
  const float length = noiseCorrelationLength(c, frame.width);
  const float used = frame.width >= width ? length : 0.0f;
  const int per_width = std::clamp((tuned::kDilationPerWidth * frame.width + rounding) / width,
                                   tuned::kDilationMin, tuned::kDilationMax);
  const int k = length > 0.0f ? std::clamp(std::max(per_width, static_cast<int>(std::lround(used))),
                                           tuned::kDilationMin, tuned::kDilationMax)
                              : 1;
  // Strong noise: the dilation doubles for each doubling of the noise beyond kStrongNoiseFootprints
  // pixel footprints (the window's reach grows with the noise's height). The height is read at
  // half the reference lag, or where the noise is correlated over longer lags than the reference
  // width's R / 2 allows for, at kStrengthLagPerLength correlation lengths (at most R): within a
  // blob the second differences see only part of the noise.
  const float nominal_half = 0.5f * tuned::kDilationReferenceLag * frame.width / width;
  const float reach = std::max(1.0f, tuned::kStrengthLagPerLength * used / nominal_half);
  const int strength_lag = std::clamp(static_cast<int>(std::lround(lag / 2 * reach)), lag / 2, lag);
  const float footprints = c.scale_in_footprints[strength_lag - 1];
  int strong = 1;
  for (float limit = tuned::kStrongNoiseFootprints; footprints > limit && strong < 1024; limit *= 2.0f)
    strong *= 2;
  if (strong == 1)
    return k;
  // The first doubling up to kDilationMax (or twice the per-width dilation, where that is more);
  // the further ones also up to kVeryStrongDilationFactor times a dilation the correlation length
  // chose: blobs that long, under noise that high, leave no detail a patch that wide would lose.
  const int limit = std::max(tuned::kDilationMax, 2 * std::min(k, per_width));
  if (strong == 2)
    return std::min(2 * k, limit);
  return std::min(strong * k,
                  std::max(limit, static_cast<int>(tuned::kVeryStrongDilationFactor * static_cast<float>(k))));
}

int
detail::chooseDilation(const Grid& input, const FilterParameters& parameters, StageTracker& split,
                       Workspace& workspace)
{
  const bool empty = input.countValid() == 0;
  int k = parameters.dilation;
  if (k == 0 && workspace.known_dilation > 0 && !empty) {
    k = workspace.known_dilation; // carried from an earlier frame of the stream
  } else if (k == 0) {
    split.start(Stage::dilation);
    // Automatic: contiguous windows unless every phase still holds the windows, and nothing to
    // estimate in a frame without a valid point (runContiguous says so).
    const int needed = std::max({parameters.search_window, parameters.patch_size, parameters.normal_window,
                                 parameters.normal_presmooth_window});
    k = empty ? 1 : automaticDilation(input, resolveThreads(parameters.threads));
    if (input.width / k < needed || input.height / k < needed)
      k = 1;
    workspace.chosen_dilation = empty ? 0 : k;
  }
  return empty ? 1 : k;
}

namespace detail
{
namespace
{

/// What every phase of one run shares: the frames, the parameters of the phases' runs and where
/// their results go.
struct PhaseRun
{
  const std::vector<const Grid*>& frames;
  int center;
  const FilterParameters& parameters; // the run's
  const FilterParameters& coarse;     // the phases'
  const Viewpoint& viewpoint;
  const std::vector<unsigned char>& active;
  int k;
  Workspace& workspace; // merged, prior_sigma, phase_uncertainty
};

/// The index of phase (u0, v0) in the order the phases are taken in turn (row by row of the
/// k x k phases, at most as many columns as the frame has).
std::size_t
phaseIndex(const PhaseRun& run, int u0, int v0)
{
  const int columns = std::min(run.k, run.frames[run.center]->width);
  return static_cast<std::size_t>(v0) * static_cast<std::size_t>(columns) + static_cast<std::size_t>(u0);
}

/// Buffers of one phase at a time: its frames, its selection and its workspace.
struct PhaseBuffers
{
  std::vector<Grid>* frames;
  std::vector<unsigned char>* active;
  Workspace* workspace;
};

/// Phase (u0, v0): the frames subsampled, the contiguous run on them and the result merged back
/// (with `threads` threads); a phase with too few points to filter keeps them.
void
filterPhase(const PhaseRun& run, int u0, int v0, const PhaseBuffers& buffers, int threads, StageTracker* split)
{
  const Grid& input = *run.frames[run.center];
  std::vector<Grid>& sub = *buffers.frames;
  sub.resize(run.frames.size());
  std::vector<const Grid*> sub_frames(run.frames.size());
  for (std::size_t f = 0; f < run.frames.size(); ++f) {
    subsample(*run.frames[f], run.k, u0, v0, sub[f], threads);
    sub_frames[f] = &sub[f];
  }
  if (!run.active.empty())
    subsample(run.active, input.width, input.height, run.k, u0, v0, *buffers.active, threads);
  else
    buffers.active->clear();
  Workspace& phase = *buffers.workspace;
  // The profiles carried for this phase of the frames (FilterParameters::reuse_estimates).
  Workspace& workspace = run.workspace;
  const std::size_t index = phaseIndex(run, u0, v0);
  phase.profiles = workspace.profiles ? &workspace.carried_profiles[1 + index] : nullptr;
  if (split)
    split->stop();
  try {
    phase.correlated_input = true;
    runContiguous(sub_frames, run.center, run.coarse, run.viewpoint, *buffers.active, phase);
  } catch (const UnfilterableFrame&) {
    if (split)
      split->start(Stage::dilation);
    return;
  }
  if (split)
    split->start(Stage::dilation);
  // Each phase's bandwidths and frame weights: with one iteration the run reports those of the
  // last phase filtered (in the order the phases are taken in turn), whichever thread filtered it.
  workspace.phase_filtered[index] = 1;
  workspace.phase_bandwidths[index] = phase.run.bandwidths;
  workspace.phase_weights[index] = phase.run.frame_weights;
  // Each phase writes its own pixels only, so phases may merge side by side.
  mergePhase(phase.run.output, run.k, u0, v0, workspace.merged, threads);
  if (run.parameters.uncertainty) {
    mergePhaseValues(phase.height_sigma, phase.run.output, run.k, u0, v0, input.width, workspace.prior_sigma,
                     threads);
    mergePhaseValues(phase.run.uncertainty, phase.run.output, run.k, u0, v0, input.width,
                     workspace.phase_uncertainty, threads);
  }
}

/// The buffers of the phases filtered by thread t of `workspace` (in turn: t = 0).
PhaseBuffers
phaseBuffers(Workspace& workspace, std::size_t t)
{
  return PhaseBuffers{&workspace.phase_frames[t], &workspace.phase_active[t], &workspace.phase[t]};
}

/// The phases one after the other, each with all threads; the stage observer sees each phase's
/// stages.
void
filterPhasesInTurn(const PhaseRun& run, int threads, StageTracker& split)
{
  const Grid& input = *run.frames[run.center];
  Workspace& workspace = run.workspace;
  workspace.phase.resize(1);
  workspace.phase_frames.resize(1);
  workspace.phase_active.resize(1);
  Workspace& phase = workspace.phase.front();
  phase.observer = workspace.observer;
  phase.frames_moved = workspace.frames_moved;
  for (int v0 = 0; v0 < std::min(run.k, input.height); ++v0)
    for (int u0 = 0; u0 < std::min(run.k, input.width); ++u0)
      filterPhase(run, u0, v0, phaseBuffers(workspace, 0), threads, &split);
}

/// The phases side by side, one thread each (every thread a whole phase at a time, each in its
/// own workspace): the phases' parallel loops, and the barriers that end them, are gone. That
/// matters most when other processes keep the cores busy, where a descheduled thread holds the
/// other one at every barrier. The result is the same bits as filterPhasesInTurn: a phase's run
/// does not depend on the number of threads, and phases write disjoint pixels.
void
filterPhasesSideBySide(const PhaseRun& run, int threads)
{
  const Grid& input = *run.frames[run.center];
  Workspace& workspace = run.workspace;
  const int columns = std::min(run.k, input.width), rows = std::min(run.k, input.height);
  const int count = columns * rows;
  const std::size_t workers = static_cast<std::size_t>(threads);
  workspace.phase.resize(workers);
  workspace.phase_frames.resize(workers);
  workspace.phase_active.resize(workers);
  for (Workspace& phase : workspace.phase) {
    phase.observer = nullptr;
    phase.frames_moved = workspace.frames_moved;
  }
  // An error other than an unfilterable phase leaves the parallel loop as a value; the first
  // phase's (in the order filterPhasesInTurn takes them) is rethrown, as it would have been.
  std::vector<std::exception_ptr> errors(static_cast<std::size_t>(count));
#pragma omp parallel for schedule(dynamic, 1) num_threads(threads)
  for (int p = 0; p < count; ++p) {
    try {
      const std::size_t t = static_cast<std::size_t>(omp_get_thread_num());
      filterPhase(run, p % columns, p / columns, phaseBuffers(workspace, t), 1, nullptr);
    } catch (...) {
      errors[static_cast<std::size_t>(p)] = std::current_exception();
    }
  }
  for (const std::exception_ptr& error : errors)
    if (error)
      std::rethrow_exception(error);
}

} // namespace
} // namespace detail

void
detail::runDilatedPasses(const std::vector<const Grid*>& frames, int center, const FilterParameters& parameters,
                         const Viewpoint& viewpoint, const std::vector<unsigned char>& active, Workspace& workspace,
                         int k, StageTracker& split)
{
  split.start(Stage::dilation);
  const Grid& input = *frames[center];
  if (!sameSize(frames, input)) {
    split.stop();
    runContiguous(frames, center, parameters, viewpoint, active, workspace); // reports the size error
    return;
  }
  FilterParameters coarse = parameters;
  coarse.dilation = 1;
  coarse.iterations = std::max(1, parameters.iterations - 1);
  const int threads = resolveThreads(parameters.threads);
  // Kept in the workspace: the next run on frames of this size allocates nothing here.
  copyGrid(input, workspace.merged, threads);
  // With the uncertainty: the phases' heights' sigma (the last pass starts from it) and their
  // sigma along the moves; NaN where a phase kept its points unfiltered.
  if (parameters.uncertainty) {
    workspace.prior_sigma.assign(input.size(), std::numeric_limits<float>::quiet_NaN());
    workspace.phase_uncertainty.assign(input.size(), std::numeric_limits<float>::quiet_NaN());
  }
  // Side by side where every thread gets as many phases as the others, without a stage observer
  // (whose stages would interleave).
  const int phases = std::min(k, input.width) * std::min(k, input.height);
  const bool side_by_side = threads > 1 && phases % threads == 0 && !workspace.observer;
  if (side_by_side)
    coarse.threads = 1; // each phase's run on its own thread
  const PhaseRun run{frames, center, parameters, coarse, viewpoint, active, k, workspace};
  const std::size_t count = static_cast<std::size_t>(phases);
  if (workspace.profiles && workspace.carried_profiles.size() < 1 + count) {
    // One list of carried profiles per phase, besides the whole frame's (the first).
    workspace.carried_profiles.resize(1 + count);
    workspace.profiles = &workspace.carried_profiles.front();
  }
  for (Workspace& phase : workspace.phase)
    phase.run.profiles_estimated = 0;
  workspace.phase_filtered.assign(count, 0);
  workspace.phase_bandwidths.resize(count);
  workspace.phase_weights.resize(count);
  if (side_by_side)
    filterPhasesSideBySide(run, threads);
  else
    filterPhasesInTurn(run, threads, split);
  for (Workspace& phase : workspace.phase)
    workspace.run.profiles_estimated += phase.run.profiles_estimated;
  split.stop();
  finishDilatedPasses(frames, center, parameters, viewpoint, active, workspace);
}

} // namespace range_nlm
