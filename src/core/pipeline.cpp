// runFilter: the pipeline of stages (src/core/stages/) over the frames, and the kernel functions
// the stages share (computeOffsets, copyGrid, ranges, frame weights).
#include "fast_math.h"

#include "stages/stages.h"
#include "workspace.h"

#include <algorithm>
#ifdef _OPENMP
#include <omp.h>
#endif
#include <cmath>
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

int
threadCount(int threads)
{
  return detail::resolveThreads(threads);
}

void
computeOffsets(const Grid& center, const NormalField& normals, const std::vector<FrameTerm>& frames,
               int search_window, int patch_size, Evaluation evaluation, int threads,
               const std::vector<unsigned char>& active, std::vector<float>& offsets,
               const std::vector<float>& patch_gate)
{
  detail::computeOffsets(center, normals, frames, search_window, patch_size, evaluation, threads, active, offsets,
                         patch_gate, nullptr, nullptr);
}

void
detail::computeOffsets(const Grid& center, const NormalField& normals, const std::vector<FrameTerm>& frames,
                       int search_window, int patch_size, Evaluation evaluation, int threads,
                       const std::vector<unsigned char>& active, std::vector<float>& offsets,
                       const std::vector<float>& patch_gate, std::vector<float>* planes, OffsetSpread* spread)
{
  for (const FrameTerm& term : frames)
    if (term.grid == nullptr || term.grid->width != center.width || term.grid->height != center.height ||
        (term.patches && (term.patches->width != center.width || term.patches->height != center.height)))
      throw std::invalid_argument("range_nlm: every frame (and patch guide) must have the size of the filtered frame");
  const int inner = detail::innerSearch(frames, search_window);
  for (const FrameTerm& term : frames)
    if (term.search_window < 0 || term.search_window > search_window ||
        (term.search_window > 0 && term.search_window % 2 == 0) ||
        (term.search_window > 0 && term.search_window != search_window && term.search_window != inner)) {
      std::ostringstream msg;
      msg << "range_nlm: a frame's search window " << term.search_window
          << " must be 0 (the search window) or odd and at most the search window " << search_window
          << ", and the frames may name one smaller window only";
      throw std::invalid_argument(msg.str());
    }
  if (!active.empty() && active.size() != center.size())
    throw std::invalid_argument("range_nlm: the active mask must have one entry per point");
  if (!patch_gate.empty() && patch_gate.size() != center.size())
    throw std::invalid_argument("range_nlm: the patch gate must have one entry per point");
  // Both evaluations write every element.
  offsets.resize(center.size());
  if (spread) {
    spread->variance.resize(center.size());
    spread->inverse_count.resize(center.size());
  }
  threads = detail::resolveThreads(threads);
  if (evaluation == Evaluation::direct)
    detail::computeOffsetsDirect(center, normals, frames, search_window, patch_size, threads, active, offsets,
                                 patch_gate, spread);
  else
    detail::computeOffsetsFast(center, normals, frames, search_window, patch_size, threads, active, offsets,
                               patch_gate, planes, spread);
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
  case Stage::pyramid:
    return "pyramid";
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
  case Stage::hole_filling:
    return "hole filling";
  }
  return "?";
}

namespace
{
/// The frames, the current frame's index and size and the parameters, checked before anything
/// runs on them.
void
checkFrames(const std::vector<const Grid*>& frames, int center, const FilterParameters& parameters)
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
  checkCoordinateScale(input);
}

} // namespace

void
checkCoordinateScale(const Grid& frame)
{
  // The largest magnitude over the valid points, -1 if there is none (a select per point, so that
  // the scan vectorizes: it runs on every frame of a stream).
  float largest = -1.0f;
  const std::ptrdiff_t n = static_cast<std::ptrdiff_t>(frame.size());
  const float* __restrict x = frame.x.data();
  const float* __restrict y = frame.y.data();
  const float* __restrict z = frame.z.data();
  const unsigned char* __restrict valid = frame.valid.data();
#pragma omp simd reduction(max : largest)
  for (std::ptrdiff_t i = 0; i < n; ++i) {
    const float m = std::max(std::max(std::fabs(x[i]), std::fabs(y[i])), std::fabs(z[i]));
    largest = std::max(largest, valid[i] ? m : -1.0f);
  }
  const bool any = largest >= 0.0f;
  if (!any || (largest >= kSmallestLargestCoordinate && largest <= kLargestCoordinate))
    return; // a frame without a valid point is reported as such
  std::ostringstream msg;
  msg << "range_nlm: the cloud's coordinates reach " << (largest > kLargestCoordinate ? "" : "only ") << largest
      << " in magnitude; the filter's float arithmetic (squared distances) needs the largest coordinate between "
      << kSmallestLargestCoordinate << " and " << kLargestCoordinate
      << ": rescale the cloud (e.g. to metres) to filter it";
  throw UnfilterableFrame(msg.str());
}

namespace
{

/// The filtered frame starts as the input. A grid of workspace.inputs that no other frame shares
/// is taken over instead of copied (the input is not used after this).
void
startOutput(const detail::FrameContext& ctx)
{
  const Grid& input = *ctx.frames[ctx.center];
  FilterRun& run = ctx.workspace.run;
  run.bandwidths.clear();
  run.frame_weights.clear();
  Grid* own = nullptr;
  for (Grid& g : ctx.workspace.inputs)
    if (&g == &input)
      own = &g;
  for (int k = 0; k < ctx.count; ++k)
    if (k != ctx.center && ctx.frames[k] == &input)
      own = nullptr;
  if (own)
    std::swap(*own, run.output);
  else
    detail::copyGrid(input, run.output, ctx.threads);
}
} // namespace

detail::FrameContext::FrameContext(const std::vector<const Grid*>& frames_, int center_,
                                   const FilterParameters& parameters_, const Viewpoint& viewpoint_,
                                   const std::vector<unsigned char>& active_, Workspace& workspace_)
    : frames(frames_), center(center_), parameters(parameters_), viewpoint(viewpoint_), active(active_),
      workspace(workspace_), threads(resolveThreads(parameters_.threads)), count(static_cast<int>(frames_.size())),
      n(frames_[center_]->size()), adaptive(parameters_.bandwidth_model == BandwidthModel::range_adaptive),
      own_d(adaptive && !(parameters_.distance_bandwidth > 0.0f)), own_s(!(parameters_.similarity_bandwidth > 0.0f)),
      bandwidths(count), profiles(count), usable(count, true)
{
}

void
checkViewpoint(const Viewpoint& viewpoint, const std::string& what)
{
  if (std::isfinite(viewpoint[0]) && std::isfinite(viewpoint[1]) && std::isfinite(viewpoint[2]))
    return;
  std::ostringstream msg;
  msg << "range_nlm: " << what << " must be finite, got (" << viewpoint[0] << ", " << viewpoint[1] << ", "
      << viewpoint[2] << ")";
  throw std::invalid_argument(msg.str());
}

FilterRun
runFilter(const std::vector<const Grid*>& frames, int center, const FilterParameters& parameters,
          const Viewpoint& viewpoint, const std::vector<unsigned char>& active)
{
  Workspace workspace;
  runFilter(frames, center, parameters, viewpoint, active, workspace);
  return std::move(workspace.run);
}

void
runFilter(const std::vector<const Grid*>& given, int center, const FilterParameters& parameters,
          const Viewpoint& viewpoint, const std::vector<unsigned char>& active, Workspace& workspace)
{
  workspace.profiled = nullptr;
  if (given.empty() || center < 0 || center >= static_cast<int>(given.size()) || !given[center]) {
    detail::runContiguous(given, center, parameters, viewpoint, active, workspace);
    return;
  }
  // Checked before anything runs with parameters.threads threads (OpenMP crashes on absurd counts).
  parameters.validate();
  checkViewpoint(viewpoint, "the viewpoint (sensor origin)");
  // Before any path whose parts (the phases of a dilation, the scales) may skip what they cannot
  // filter: a frame out of the float arithmetic's range is reported, not passed over in parts.
  checkCoordinateScale(*given[center]);
  std::vector<const Grid*> frames = given;
  workspace.run.outliers_moved = 0; // every path below keeps it
  workspace.run.profiles_estimated = 0;
  workspace.frame_changes.clear();
  workspace.prior_sigma.clear();
  // The hole filling reads the frame as given after the passes, which may take its grid over.
  Grid as_given;
  if (parameters.fill_holes > 0)
    as_given = *given[center];
  // The current frame's profile starts unknown; the other frames' are estimated where they are
  // used, each with a sample of its own.
  workspace.profiled = given[center];
  workspace.current_profile = NoiseProfile();
  // A stream's frames share their sensor (FilterParameters::reuse_estimates).
  const detail::EstimateSignature signature =
      detail::takeCarriedEstimates(*given[center], parameters, viewpoint, workspace);
  if (parameters.outlier_sigmas > 0.0f && given[center]->countValid() > 0) {
    detail::StageTracker stage(workspace.observer, 0);
    stage.start(Stage::outliers);
    NoiseProfile none;
    const NoiseProfile* profile = &none;
    try {
      profile = &detail::currentFrameProfile(*given[center], parameters, viewpoint, workspace);
    } catch (const UnfilterableFrame&) {
      // Too few points for a noise estimate: nothing to test against (runContiguous reports it).
    }
    frames[center] = detail::correctOutliersStage(*given[center], *profile, parameters, viewpoint, active, workspace);
    workspace.profiled = frames[center];
  }
  {
    detail::StageTracker stage(workspace.observer, 0);
    stage.start(Stage::neighbour_frames);
    frames = detail::levelNeighbourFrames(frames, center, parameters, viewpoint, workspace);
    detail::checkNeighbourProfiles(frames, center, parameters, viewpoint, workspace);
  }
  // A levelled frame keeps its noise profile: the levelling moves its points by a slowly varying
  // offset along the rays, which the local planes of the estimate take up.
  workspace.profiled = frames[center];
  const int scales = detail::usableScales(*frames[center], parameters);
  if (scales > 1 && frames[center]->countValid() > 0)
    detail::runMultiscale(frames, center, parameters, viewpoint, active, workspace, scales);
  else
    detail::runOneScale(frames, center, parameters, viewpoint, active, workspace);
  detail::keepEstimates(signature, parameters, workspace);
  // After the last pass, so that the holes' borders are compared and carried over denoised.
  workspace.run.filled.clear();
  if (parameters.fill_holes > 0) {
    detail::StageTracker stage(workspace.observer, 0);
    stage.start(Stage::hole_filling);
    detail::fillHoles(as_given, parameters, viewpoint, active, workspace);
  }
  workspace.profiled = nullptr;
}

void
detail::runOneScale(const std::vector<const Grid*>& frames, int center, const FilterParameters& parameters,
                    const Viewpoint& viewpoint, const std::vector<unsigned char>& active, Workspace& workspace)
{
  StageTracker split(workspace.observer, 0);
  const int k = chooseDilation(*frames[center], parameters, split, workspace);
  if (k <= 1) {
    split.stop();
    runContiguous(frames, center, parameters, viewpoint, active, workspace);
    return;
  }
  // The phases of a dilation given explicitly must hold the windows (the message names it).
  parameters.validateFor(frames[center]->width, frames[center]->height);
  runDilatedPasses(frames, center, parameters, viewpoint, active, workspace, k, split);
}

void
detail::runContiguous(const std::vector<const Grid*>& frames, int center, const FilterParameters& parameters,
                      const Viewpoint& viewpoint, const std::vector<unsigned char>& active, Workspace& workspace)
{
  checkFrames(frames, center, parameters);
  FrameContext ctx(frames, center, parameters, viewpoint, active, workspace);
  startOutput(ctx);
  if (!parameters.uncertainty)
    workspace.run.uncertainty.clear();
  if (ctx.count > 1) {
    StageTracker stage(workspace.observer, 0);
    stage.start(Stage::neighbour_frames);
    estimateNeighbourFrames(ctx);
  }
  for (ctx.iteration = 0; ctx.iteration < parameters.iterations; ++ctx.iteration) {
    StageTracker stage(workspace.observer, ctx.iteration);
    if (!ctx.adaptive) {
      stage.start(Stage::normals);
      fitRawNormals(ctx);
    }
    stage.start(Stage::bandwidths);
    estimateCurrentFrame(ctx);
    stage.start(Stage::noise_maps);
    computeNoiseMaps(ctx);
    if (parameters.normal_presmooth_window > 1) {
      stage.start(Stage::presmoothing);
      presmoothCurrentFrame(ctx);
      stage.start(Stage::normals);
      fitGatedNormals(ctx, workspace.smooth);
    } else if (ctx.adaptive) {
      stage.start(Stage::normals);
      fitGatedNormals(ctx, ctx.current());
    }
    stage.start(Stage::frame_terms);
    buildFrameTerms(ctx);
    stage.start(Stage::offsets);
    computeFrameOffsets(ctx);
    if (parameters.uncertainty)
      propagateUncertainty(ctx);
    stage.start(Stage::displacement);
    displaceCurrentFrame(ctx);
    if (parameters.uncertainty)
      uncertaintyAlongMoves(ctx, resolvedDisplacement(ctx));
  }
  workspace.prior_sigma.clear(); // the dilated passes' result, used by this run only
}

} // namespace range_nlm
