// The buffers of a filter run (private: the public API holds them through FilterWorkspace).
#pragma once

#include "internal.h"

#include <range_nlm/core/pipeline.h>

#include <vector>

namespace range_nlm
{

/// The buffers of a filter run, kept between runs (each filter object owns one). Runs on frames
/// of one size then reuse memory that is already mapped: allocating and first touching the
/// ~40 MB a VGA frame passes through cost about a sixth of the frame's time. Holds the last run's
/// result and intermediates; its contents are not part of the interface.
struct Workspace
{
  /// The input frames as grids (filled by the pcl::Filter adaptors).
  std::vector<Grid> inputs;
  /// The last run's result.
  FilterRun run;
  /// The normals, and the first of the gated fits' two passes.
  NormalField normals, first_normals;
  /// Offsets, local noise sigmas (times similarity_scale), displacement limits, patch gates.
  std::vector<float> offsets, sigma, limit, patch_gate;
  /// Per-point ranges, profile values (the current frame's sigma and extent, another frame's sigma
  /// and extent) and per-frame bandwidth maps of a run.
  std::vector<float> ranges, profile_sigma, center_extent, other_sigma, profile_extent, range_sigma, gate;
  /// A neighbour's differences to the current frame along its normals, and the pixels of the
  /// current frame that changed against it (guarded cross-frame bandwidths).
  std::vector<float> along;
  std::vector<unsigned char> changed;
  std::vector<std::vector<float>> inverse_d2, inverse_s2;
  /// FilterParameters::similarity_spread: the current frame's patch spread profile (ranges,
  /// spreads) and per point the factor on a frame's sigma that gives s (else empty).
  std::vector<float> spread_range, spread_value, similarity_factor;
  /// Whether the current frame of this workspace's runs carries noise that is not the sensor's,
  /// independent from pixel to pixel (no patch spread then, FilterParameters::similarity_spread):
  /// a phase of dilated passes (chosen for correlated or strong noise), the contiguous last pass
  /// after them, and a multiscale run's finest scale (the coarser scales' corrections carried in).
  bool correlated_input = false;
  /// Guarded: the patch guide (FrameTerm::patches), its per-pixel weights, and a neighbour's
  /// changed pixels widened by the guide's margin.
  Grid guide;
  std::vector<float> guide_weight;
  std::vector<unsigned char> widened;
  /// The pre-smoothed copy the normals are fitted on.
  Grid smooth;
  /// Dilated passes: the frames of one phase, the merged result of all phases, and the
  /// workspace of the phases' runs (one element once used).
  std::vector<std::vector<Grid>> phase_frames; // per thread of the phases side by side
  std::vector<std::vector<unsigned char>> phase_active;
  Grid merged;
  std::vector<Workspace> phase;
  /// Per phase of the running call (in the order the phases are taken in turn): whether it was
  /// filtered, and its bandwidths and frame weights.
  std::vector<unsigned char> phase_filtered;
  std::vector<std::vector<Bandwidths>> phase_bandwidths;
  std::vector<std::vector<float>> phase_weights;
  /// Multiscale runs: the frames reduced to the next coarser scale, the current frame's fine
  /// pixels that entered their block's mean, ranges and corrections of the coarser scale, the
  /// current frame with the coarser scale's corrections carried up, and the workspace of the
  /// coarser scale's run (one element once used).
  std::vector<Grid> pyramid;
  std::vector<unsigned char> pyramid_member;
  std::vector<float> pyramid_rho, pyramid_correction;
  Grid carried;
  std::vector<Workspace> levels;
  /// The current frame with its isolated outliers moved (FilterParameters::outlier_sigmas).
  Grid corrected;
  /// Ranges of whole frames, written before they are read: the two frames of an analysis of
  /// change between frames, and the outlier test's.
  std::vector<float> range_scratch[2];
  /// Per-point uncertainty (FilterParameters::uncertainty): the weights' spread and effective
  /// number of candidates of a pass, the standard deviation of each point's height along its
  /// normal after the passes so far, and the one the next contiguous run starts from (the dilated
  /// passes' merged result; empty: the noise profile's sigma).
  detail::OffsetSpread spread;
  std::vector<float> height_sigma, prior_sigma;
  /// Dilated passes: the merged phases' sigma along their moves (the result with one iteration).
  std::vector<float> phase_uncertainty;
  /// The frames brought to a common level (levelling of low-frequency offsets between frames),
  /// and per frame whether it moved against the current one (-1: not analysed).
  std::vector<Grid> leveled;
  std::vector<signed char> frames_moved;
  /// analyseFrameChange of each other frame against the current one as the levelling made it in
  /// the last call (per frame of the window; empty: none made).
  std::vector<FrameOffset> frame_changes;
  /// Padded planes of the normal fits and of the windowed evaluation.
  std::vector<float> normal_planes, window_planes;
  /// The current frame's noise profile as the running call was given the frame, estimated once
  /// per call (by the outlier stage, or by the first pass): the grid it stands for (null: none)
  /// and the profile (empty: not yet estimated). It stands for the frame after the outlier stage
  /// and the levelling too: moving a few isolated points, or all points by a slowly varying offset
  /// along their rays, does not change the frame's noise.
  const Grid* profiled = nullptr;
  NoiseProfile current_profile;
  /// FilterParameters::reuse_estimates: the estimates carried from the stream's earlier frames,
  /// the dilation the carried estimates give the running call (0: none, estimate it), the
  /// automatic dilation the running call chose (0: none), and the check's sampled ranges.
  detail::CarriedEstimates estimates;
  int known_dilation = 0, chosen_dilation = 0;
  std::vector<float> signature_scratch[4];
  /// The noise profiles carried per frame of the window and per pass (estimateFrame): one list for
  /// the runs on the whole frame, [0], and one per phase of the dilated passes, [1 + phase]; the
  /// checks of the other frames they stand for; and the list the runs on this workspace read and
  /// add to in the running call (null: every profile is estimated; set by runFilter for its own
  /// runs and by the dilated passes for each phase's).
  std::vector<std::vector<detail::CarriedProfile>> carried_profiles;
  std::vector<detail::CarriedNeighbour> carried_neighbours;
  std::vector<detail::CarriedProfile>* profiles = nullptr;
  /// If set, told where each phase of a run begins and ends. Not owned.
  StageObserver* observer = nullptr;
};

/// runFilter with the result in `workspace.run` and every frame-sized buffer taken from
/// `workspace`. `frames` may point into workspace.inputs; the current frame's grid there is then
/// taken over as the result's storage (its contents are not kept) unless another frame is the
/// same grid.
void
runFilter(const std::vector<const Grid*>& frames, int center, const FilterParameters& parameters,
          const Viewpoint& viewpoint, const std::vector<unsigned char>& active, Workspace& workspace);

} // namespace range_nlm
