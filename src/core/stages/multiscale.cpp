// The multiscale run (FilterParameters::scales): the frames reduced to a pyramid whose coarse
// scales are filtered first, where spatially correlated noise is close to white and a pass costs a
// quarter of the scale above; each scale's range corrections are carried up along the rays, then
// the finer scale is filtered. docs/method.md, "Multiscale filtering".
#include "multiscale.h"
#include "stages.h"

#include "../internal.h"
#include "../outliers.h"
#include "../tuned.h"

#include <algorithm>
#include <array>
#include <cmath>

namespace range_nlm
{
namespace detail
{
namespace
{

/// The range of a point from the viewpoint.
float
rangeOf(const Grid& g, std::size_t i, const Viewpoint& v)
{
  const float dx = g.x[i] - v[0], dy = g.y[i] - v[1], dz = g.z[i] - v[2];
  return std::sqrt(dx * dx + dy * dy + dz * dz);
}

/// One 2 x 2 block of `fine` reduced to the mean of its valid points that lie on one surface with
/// the block's lower-median range (so a block across a depth edge takes one side, never a point
/// between the two). `member` (if given) marks the fine pixels that entered the mean.
void
reduceBlock(const Grid& fine, const std::vector<float>& rho, const SurfaceTolerance& tolerance, int a, int b,
            Grid& coarse, std::vector<unsigned char>* member)
{
  std::array<std::size_t, 4> pixels;
  std::array<float, 4> ranges;
  int count = 0;
  for (int dv = 0; dv < 2; ++dv)
    for (int du = 0; du < 2; ++du) {
      const int u = 2 * a + du, v = 2 * b + dv;
      if (u >= fine.width || v >= fine.height)
        continue;
      const std::size_t i = static_cast<std::size_t>(v) * fine.width + u;
      if (member)
        (*member)[i] = 0;
      if (fine.valid[i] && rho[i] > 0.0f) {
        pixels[count] = i;
        ranges[count++] = rho[i];
      }
    }
  const std::size_t c = static_cast<std::size_t>(b) * coarse.width + a;
  if (count == 0) {
    coarse.x[c] = coarse.y[c] = coarse.z[c] = std::nanf("");
    coarse.valid[c] = 0;
    return;
  }
  std::array<float, 4> sorted = ranges;
  std::sort(sorted.begin(), sorted.begin() + count);
  const float reference = sorted[(count - 1) / 2];
  const float tol = tolerance.at(reference);
  float x = 0.0f, y = 0.0f, z = 0.0f;
  int used = 0;
  for (int k = 0; k < count; ++k)
    if (std::fabs(ranges[k] - reference) <= tol) {
      const std::size_t i = pixels[k];
      x += fine.x[i];
      y += fine.y[i];
      z += fine.z[i];
      ++used;
      if (member)
        (*member)[i] = 1;
    }
  coarse.x[c] = x / used;
  coarse.y[c] = y / used;
  coarse.z[c] = z / used;
  coarse.valid[c] = 1;
}

} // namespace

/// `fine` reduced to half its width and height (rounded up), block by block (reduceBlock).
void
reduceFrame(const Grid& fine, const Viewpoint& viewpoint, const SurfaceTolerance& tolerance, int threads,
            std::vector<float>& rho, Grid& coarse, std::vector<unsigned char>* member)
{
  rangesOf(fine, viewpoint, threads, rho);
  coarse.width = (fine.width + 1) / 2;
  coarse.height = (fine.height + 1) / 2;
  const std::size_t n = coarse.size();
  coarse.x.resize(n);
  coarse.y.resize(n);
  coarse.z.resize(n);
  coarse.valid.resize(n);
  if (member)
    member->resize(fine.size());
  (void)threads;
#pragma omp parallel for schedule(static) num_threads(threads)
  for (int b = 0; b < coarse.height; ++b)
    for (int a = 0; a < coarse.width; ++a)
      reduceBlock(fine, rho, tolerance, a, b, coarse, member);
}

namespace
{

/// The coarse scale's range corrections (filtered range - reduced range; NaN where either is
/// invalid) and the reduced ranges.
void
coarseCorrections(const Grid& reduced, const Grid& filtered, const Viewpoint& viewpoint, int threads,
                  std::vector<float>& reduced_rho, std::vector<float>& correction)
{
  const std::ptrdiff_t n = static_cast<std::ptrdiff_t>(reduced.size());
  reduced_rho.resize(reduced.size());
  correction.resize(reduced.size());
  (void)threads;
#pragma omp parallel for schedule(static) num_threads(threads)
  for (std::ptrdiff_t c = 0; c < n; ++c) {
    const bool valid = reduced.valid[c] && filtered.valid[c];
    reduced_rho[c] = reduced.valid[c] ? rangeOf(reduced, c, viewpoint) : 0.0f;
    correction[c] = valid ? rangeOf(filtered, c, viewpoint) - reduced_rho[c] : std::nanf("");
  }
}

/// The bilinear weights at fine pixel (u, v) with range r of the four nearest coarse pixels that
/// hold a correction and whose reduced point lies on one surface with the fine point (within the
/// tolerance at r: never across a depth edge). On a surface so steep that the neighbours' ranges
/// all differ by more than that, the point's own block, if the point entered its mean. Returns
/// the number of coarse pixels taken (0: none).
int
carryWeights(const CarrySource& s, int u, int v, float r, bool member, std::array<std::size_t, 4>& cells,
             std::array<float, 4>& weights)
{
  // Coarse pixel a covers fine columns 2a and 2a + 1: fine column u sits at coarse (u - 0.5) / 2.
  const float cu = std::clamp((u - 0.5f) * 0.5f, 0.0f, static_cast<float>(s.width - 1));
  const float cv = std::clamp((v - 0.5f) * 0.5f, 0.0f, static_cast<float>(s.height - 1));
  const int a0 = std::min(static_cast<int>(cu), s.width - 1), b0 = std::min(static_cast<int>(cv), s.height - 1);
  const float fu = cu - a0, fv = cv - b0;
  const float tol = s.tolerance.at(r);
  int taken = 0;
  for (int db = 0; db < 2; ++db)
    for (int da = 0; da < 2; ++da) {
      const int a = std::min(a0 + da, s.width - 1), b = std::min(b0 + db, s.height - 1);
      const float w = (da ? fu : 1.0f - fu) * (db ? fv : 1.0f - fv);
      const std::size_t c = static_cast<std::size_t>(b) * s.width + a;
      if (!(w > 0.0f) || std::isnan(s.correction[c]) || std::fabs(s.rho[c] - r) > tol)
        continue;
      cells[taken] = c;
      weights[taken++] = w;
    }
  const std::size_t own = static_cast<std::size_t>(v / 2) * s.width + u / 2;
  if (taken == 0 && member && !std::isnan(s.correction[own])) {
    cells[0] = own;
    weights[taken++] = 1.0f;
  }
  return taken;
}

} // namespace

/// `fine` with every active valid point moved along its ray by the carried correction (the
/// weighted mean of the corrections carryWeights takes; none taken: the point stays).
void
carryCorrections(const Grid& fine, const std::vector<float>& fine_rho, const CarrySource& source,
                 const Viewpoint& viewpoint, const std::vector<unsigned char>& active, int threads, Grid& out)
{
  copyGrid(fine, out, threads);
  (void)threads;
#pragma omp parallel for schedule(static) num_threads(threads)
  for (int v = 0; v < fine.height; ++v)
    for (int u = 0; u < fine.width; ++u) {
      const std::size_t i = static_cast<std::size_t>(v) * fine.width + u;
      const float r = fine_rho[i];
      if (!fine.valid[i] || !(r > 0.0f) || (!active.empty() && !active[i]))
        continue;
      std::array<std::size_t, 4> cells;
      std::array<float, 4> weights;
      const int taken = carryWeights(source, u, v, r, source.member[i] != 0, cells, weights);
      if (taken == 0)
        continue;
      float sum = 0.0f, weight = 0.0f;
      for (int k = 0; k < taken; ++k) {
        sum += weights[k] * source.correction[cells[k]];
        weight += weights[k];
      }
      const float scale = (r + sum / weight) / r;
      out.x[i] = viewpoint[0] + (fine.x[i] - viewpoint[0]) * scale;
      out.y[i] = viewpoint[1] + (fine.y[i] - viewpoint[1]) * scale;
      out.z[i] = viewpoint[2] + (fine.z[i] - viewpoint[2]) * scale;
    }
}

namespace
{

/// A coarse pixel is active where one of its fine pixels is (empty: all are).
void
reduceActive(const std::vector<unsigned char>& active, int width, int height, std::vector<unsigned char>& coarse)
{
  coarse.clear();
  if (active.empty())
    return;
  const int w = (width + 1) / 2, h = (height + 1) / 2;
  coarse.assign(static_cast<std::size_t>(w) * h, 0);
  for (int v = 0; v < height; ++v)
    for (int u = 0; u < width; ++u)
      if (active[static_cast<std::size_t>(v) * width + u])
        coarse[static_cast<std::size_t>(v / 2) * w + u / 2] = 1;
}

/// A window of `side` pixels at the finer scale as the odd window that covers the same part of
/// the frame at the coarser one (at least `least`).
int
coarserWindow(int side, int least)
{
  const int half = (side + 1) / 2;
  return std::max(least, half % 2 == 0 ? half + 1 : half);
}

/// The parameters of the coarser scale: one scale fewer; windows that cover the part of the frame
/// the finer scale's cover (a coarse window of the finer size would smooth details twice as large,
/// and carry that up as if it were noise); one iteration (the finer scale iterates); contiguous
/// windows unless a dilation is given (correlated noise is close to white there).
FilterParameters
coarserParameters(const FilterParameters& parameters, int scales)
{
  FilterParameters coarse = parameters;
  coarse.scales = scales - 1;
  coarse.iterations = 1;
  coarse.search_window = coarserWindow(parameters.search_window, 3);
  coarse.normal_window = coarserWindow(parameters.normal_window, 3);
  if (parameters.normal_presmooth_window > 1)
    coarse.normal_presmooth_window = coarserWindow(parameters.normal_presmooth_window, 3);
  if (coarse.dilation == 0)
    coarse.dilation = 1;
  return coarse;
}

/// The parameters of the one-scale run at the finest scale (before its dilation is chosen).
FilterParameters
oneScaleParameters(const FilterParameters& parameters)
{
  FilterParameters fine = parameters;
  fine.scales = 1;
  return fine;
}

} // namespace

int
usableScales(const Grid& input, const FilterParameters& parameters)
{
  const int needed = std::max({parameters.search_window, parameters.patch_size, parameters.normal_window,
                               parameters.normal_presmooth_window, 2});
  int scales = 1, width = input.width, height = input.height;
  while (scales < parameters.scales && (width + 1) / 2 >= needed && (height + 1) / 2 >= needed) {
    width = (width + 1) / 2;
    height = (height + 1) / 2;
    ++scales;
  }
  return scales;
}

void
runMultiscale(const std::vector<const Grid*>& frames, int center, const FilterParameters& parameters,
              const Viewpoint& viewpoint, const std::vector<unsigned char>& active, Workspace& workspace, int scales)
{
  const int threads = resolveThreads(parameters.threads);
  const Grid& input = *frames[center];
  // The finest scale's dilation describes the sensor's noise: chosen on the frame as given, not
  // on the frame with the coarser scales' corrections, whose remaining noise is less correlated.
  FilterParameters fine = oneScaleParameters(parameters);
  {
    StageTracker split(workspace.observer, 0);
    fine.dilation = chooseDilation(input, parameters, split, workspace);
  }
  StageTracker stage(workspace.observer, 0);
  stage.start(Stage::pyramid);
  NoiseProfile profile;
  try {
    // The frame as the call was given it: its profile is known once estimated.
    profile = &input == workspace.profiled
                  ? currentFrameProfile(input, parameters, viewpoint, workspace)
                  : estimateNoiseProfile(input, parameters.search_window, parameters.bandwidth_samples,
                                         parameters.seed, viewpoint, threads);
    workspace.run.profiles_estimated += &input != workspace.profiled;
  } catch (const UnfilterableFrame&) {
    stage.stop();
    runOneScale(frames, center, fine, viewpoint, active, workspace); // reports it
    return;
  }
  rangesOf(input, viewpoint, threads, workspace.ranges);
  const SurfaceTolerance tolerance{profile, medianRayAngle(input, workspace.ranges, threads)};
  std::vector<Grid>& reduced = workspace.pyramid;
  reduced.resize(frames.size());
  std::vector<const Grid*> coarse_frames(frames.size());
  for (std::size_t f = 0; f < frames.size(); ++f) {
    reduceFrame(*frames[f], viewpoint, tolerance, threads, workspace.pyramid_rho, reduced[f],
                static_cast<int>(f) == center ? &workspace.pyramid_member : nullptr);
    coarse_frames[f] = &reduced[f];
  }
  std::vector<unsigned char> coarse_active;
  reduceActive(active, input.width, input.height, coarse_active);
  workspace.levels.resize(1);
  Workspace& coarse = workspace.levels.front();
  coarse.observer = workspace.observer;
  coarse.frames_moved = workspace.frames_moved;
  coarse.profiles = nullptr; // the coarser scales' profiles are estimated on every call
  coarse.run.profiles_estimated = 0;
  stage.stop();
  const FilterParameters coarse_parameters = coarserParameters(parameters, scales);
  try {
    if (scales > 2)
      runMultiscale(coarse_frames, center, coarse_parameters, viewpoint, coarse_active, coarse, scales - 1);
    else
      runOneScale(coarse_frames, center, coarse_parameters, viewpoint, coarse_active, coarse);
  } catch (const UnfilterableFrame&) {
    runOneScale(frames, center, fine, viewpoint, active, workspace);
    return;
  }
  workspace.run.profiles_estimated += coarse.run.profiles_estimated;
  stage.start(Stage::pyramid);
  coarseCorrections(reduced[center], coarse.run.output, viewpoint, threads, workspace.pyramid_rho,
                    workspace.pyramid_correction);
  const CarrySource source{reduced[center].width, reduced[center].height, workspace.pyramid_rho,
                           workspace.pyramid_correction, workspace.pyramid_member, tolerance};
  carryCorrections(input, workspace.ranges, source, viewpoint, active, threads, workspace.carried);
  stage.stop();
  // The finest scale: the one-scale filter on the current frame with the coarser scales'
  // corrections (and its temporal neighbours as they are).
  std::vector<const Grid*> carried = frames;
  carried[center] = &workspace.carried;
  const bool correlated = workspace.correlated_input;
  workspace.correlated_input = true;
  runOneScale(carried, center, fine, viewpoint, active, workspace);
  workspace.correlated_input = correlated;
}

} // namespace detail
} // namespace range_nlm
