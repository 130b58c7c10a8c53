// What the stages of the filter pipeline share (src/core/stages/): the frames of one run, its
// parameters and per-frame estimates, the workspace's buffers and the state of one iteration.
#pragma once

#include "internal.h"
#include "workspace.h"

#include <range_nlm/core/pipeline.h>

#include <cstddef>
#include <vector>

namespace range_nlm
{
namespace detail
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

/// One contiguous run of the filter (runContiguous) as its stages see it: the frames and
/// parameters it was given, what the stages estimated per frame, and the state of the running
/// iteration. Frame-sized buffers live in `workspace`, so that a run on frames of one size
/// reuses memory that is already mapped.
struct FrameContext
{
  FrameContext(const std::vector<const Grid*>& frames_, int center_, const FilterParameters& parameters_,
               const Viewpoint& viewpoint_, const std::vector<unsigned char>& active_, Workspace& workspace_);

  const std::vector<const Grid*>& frames;
  /// Index of the filtered frame in `frames`.
  const int center;
  const FilterParameters& parameters;
  const Viewpoint& viewpoint;
  /// The points to filter (every point if empty).
  const std::vector<unsigned char>& active;
  Workspace& workspace;
  /// OpenMP treats num_threads(0) as an error: 0 is mapped to the runtime's default.
  const int threads;
  /// Frames, and points per frame.
  const int count;
  const std::size_t n;
  /// The range-adaptive bandwidth model (else the global one).
  const bool adaptive;
  /// Per-point distance bandwidths from the profiles' extents (range-adaptive, d not given).
  const bool own_d;
  /// Per-point similarity bandwidths from the profiles' sigmas (range-adaptive, s not given).
  const bool own_s;

  /// Per frame: scalar bandwidths (global model) or a noise profile (range-adaptive model), and
  /// whether it has points to contribute (an all-NaN neighbour has none).
  std::vector<Bandwidths> bandwidths;
  std::vector<NoiseProfile> profiles;
  std::vector<bool> usable;
  /// With neighbours: the median of the first iteration's ranges (workspace.ranges), taken
  /// before the neighbours' estimates (run.output is still the input then).
  float input_rho_median = 0.0f;

  /// The running iteration: its number, the frames' terms and weights Psi_k, whether the patch
  /// guide may be built (tuned::kGuideMinFrames usable neighbours) and the neighbours in it.
  int iteration = 0;
  std::vector<FrameTerm> terms;
  std::vector<float> weights;
  bool may_guide = false;
  int guide_frames = 0;

  /// The frame being filtered (workspace.run.output).
  const Grid& current() const { return workspace.run.output; }
};

} // namespace detail
} // namespace range_nlm
