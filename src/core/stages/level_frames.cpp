// Stage::neighbour_frames, once per call: the levelling of low-frequency offsets between frames.
#include "stages.h"

#include <algorithm>
#include <cmath>

namespace range_nlm
{
namespace detail
{
namespace
{

/// analyseFrameChange of every non-empty neighbour against the current frame.
struct FrameChanges
{
  std::vector<FrameOffset> changes;
  /// Per frame: it did not move (an offset counts as not moved).
  std::vector<unsigned char> still;
  /// Some neighbour had an offset.
  bool any_offset = false;
};

FrameChanges
analyseNeighbours(const std::vector<const Grid*>& frames, int center, const Viewpoint& viewpoint, int threads,
                  std::vector<float> (&scratch)[2])
{
  const int count = static_cast<int>(frames.size());
  const Grid& current = *frames[center];
  FrameChanges c;
  c.changes.resize(count);
  c.still.assign(count, 0);
  for (int k = 0; k < count; ++k) {
    if (k == center || frames[k]->countValid() == 0)
      continue;
    c.changes[k] = analyseFrameChange(current, *frames[k], viewpoint, threads, scratch[0], scratch[1]);
    c.still[k] = c.changes[k].change != FrameChange::motion;
    c.any_offset = c.any_offset || c.changes[k].change == FrameChange::offset;
  }
  return c;
}

/// The mean level against the current frame's: the mean of o_k over the current frame (o = 0)
/// and the neighbours that did not move (o = 0 for those without an offset). Not weighted by
/// Psi_d: these frames did not move, so their offsets are noise, best averaged evenly.
std::vector<float>
meanLevel(const FrameChanges& c, std::size_t n, int threads)
{
  (void)threads;
  const float w = 1.0f / static_cast<float>(1 + std::count(c.still.begin(), c.still.end(), 1));
  std::vector<float> mean(n, 0.0f);
  for (const FrameOffset& change : c.changes)
    if (change.change == FrameChange::offset) {
      const float* o = change.range_offset.data();
#pragma omp parallel for simd schedule(static) num_threads(threads)
      for (std::size_t i = 0; i < n; ++i)
        mean[i] += w * o[i];
    }
  return mean;
}

/// `to` = `from` with each point moved along its ray by the mean level minus its frame's
/// offset `o` (null: none).
void
levelFrame(const Grid& from, const float* o, const std::vector<float>& mean, const Viewpoint& viewpoint,
           int threads, Grid& to)
{
  copyGrid(from, to, threads);
  const std::size_t n = from.size();
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
}

/// CrossFrameBandwidth::guarded with the range-adaptive model (docs/method.md, "Low-frequency
/// offsets between frames"): a neighbour that differs from the current frame by a slowly varying
/// offset along the rays (FrameChange::offset) is brought to the current frame's level, and the
/// current frame and every neighbour that did not move to the mean level of those frames. The
/// frames' noise is then what is left between them, and the offsets, noise of a camera that did
/// not move, are averaged out. Fills `leveled` and `out` and returns true if some neighbour
/// had such an offset; otherwise returns false and leaves the frames as they are. `moved`
/// receives per frame whether it moved (1) or not (0, an offset counts as not moved), -1 for the
/// current frame and an empty one; it is left empty where nothing was analysed. `changes`
/// receives the analyses (a default FrameOffset for the current frame and an empty one), or
/// nothing where nothing was analysed.
bool
levelFrames(const std::vector<const Grid*>& frames, int center, const FilterParameters& parameters,
            const Viewpoint& viewpoint, int threads, std::vector<Grid>& leveled, std::vector<const Grid*>& out,
            std::vector<signed char>& moved, std::vector<FrameOffset>& changes, std::vector<float> (&scratch)[2])
{
  const int count = static_cast<int>(frames.size());
  moved.clear();
  changes.clear();
  if (count < 2 || parameters.bandwidth_model != BandwidthModel::range_adaptive ||
      parameters.cross_frame_bandwidth != CrossFrameBandwidth::guarded)
    return false;
  const Grid& current = *frames[center];
  for (const Grid* g : frames)
    if (!g || g->width != current.width || g->height != current.height)
      return false; // runContiguous reports it
  if (current.countValid() == 0)
    return false;
  FrameChanges c = analyseNeighbours(frames, center, viewpoint, threads, scratch);
  // The motion test's answer for every frame of the run (an offset is levelled: not moved).
  moved.assign(count, -1);
  for (int k = 0; k < count; ++k)
    if (k != center && frames[k]->countValid() > 0)
      moved[k] = !c.still[k];
  if (!c.any_offset) {
    changes = std::move(c.changes);
    return false;
  }
  const std::vector<float> mean = meanLevel(c, current.size(), threads);
  leveled.resize(count);
  out = frames;
  for (int k = 0; k < count; ++k) {
    if (k != center && !c.still[k])
      continue;
    const float* o = c.changes[k].change == FrameChange::offset ? c.changes[k].range_offset.data() : nullptr;
    levelFrame(*frames[k], o, mean, viewpoint, threads, leveled[k]);
    out[k] = &leveled[k];
  }
  changes = std::move(c.changes);
  return true;
}

} // namespace
} // namespace detail

std::vector<const Grid*>
detail::levelNeighbourFrames(const std::vector<const Grid*>& frames, int center, const FilterParameters& parameters,
                             const Viewpoint& viewpoint, Workspace& workspace)
{
  std::vector<const Grid*> leveled;
  if (!levelFrames(frames, center, parameters, viewpoint, resolveThreads(parameters.threads), workspace.leveled,
                   leveled, workspace.frames_moved, workspace.frame_changes, workspace.range_scratch))
    leveled = frames;
  return leveled;
}

} // namespace range_nlm
