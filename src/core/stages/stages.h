// The stages of runFilter, in the order they run (docs/method.md, "The static filter" and "The
// temporal filter"). Each lives in the file of its name under src/core/stages/.
#pragma once

#include "../frame_context.h"

#include <vector>

namespace range_nlm
{
namespace detail
{

// Once per call, on the frames as given (runFilter).

/// FilterParameters::reuse_estimates, at the start of a call: the signature of `frame` (empty
/// with reuse off or no valid point), and where the carried estimates still hold, the noise
/// profile in workspace.current_profile and the dilation in workspace.known_dilation
/// (workspace.run.estimates_reused set). With reuse off, or a frame without a valid point, the
/// carried estimates are dropped.
/// (carried_estimates.cpp)
EstimateSignature
takeCarriedEstimates(const Grid& frame, const FilterParameters& parameters, const Viewpoint& viewpoint,
                     Workspace& workspace);

/// At the end of a call: keeps the estimates the call made (its profile and automatic dilation)
/// with `signature` for the next frames, unless it reused carried ones or has no signature.
/// (carried_estimates.cpp)
void
keepEstimates(const EstimateSignature& signature, const FilterParameters& parameters, Workspace& workspace);

/// FilterParameters::reuse_estimates: drops every noise profile carried for the frames of the
/// windows (the current frame's in the dilation's phases, the other frames'). (carried_estimates.cpp)
void
forgetFrameProfiles(Workspace& workspace);

/// FilterParameters::reuse_estimates, once per call after the levelling: for each other frame of
/// the window, whether the profiles carried for its place (its offset from the current frame) still
/// hold, by the check carriedEstimatesHold makes of the current frame; where not, they are dropped
/// and the frame's signature is kept for the next calls. (carried_estimates.cpp)
void
checkNeighbourProfiles(const std::vector<const Grid*>& frames, int center, const FilterParameters& parameters,
                       const Viewpoint& viewpoint, Workspace& workspace);

/// The noise profile carried in workspace.profiles for the frame at `offset` from the current one
/// in pass `iteration`, or null (none carried, or nothing carried in this call). And keepProfile
/// adds one there (nothing if no list is in use). (carried_estimates.cpp)
const NoiseProfile*
carriedProfile(const Workspace& workspace, int offset, int iteration);
void
keepProfile(Workspace& workspace, int offset, int iteration, const NoiseProfile& profile);

/// The signature of `frame` (`scratch` holds the samples of its four parts, taken side by side on
/// up to `threads` threads). (carried_estimates.cpp)
EstimateSignature
estimateSignature(const Grid& frame, const Viewpoint& viewpoint, std::vector<float> (&scratch)[4], int threads);

/// Whether `carried` still describes `frame` (signature `now`) under `parameters`: made with the
/// same parameters on a frame of the same size and viewpoint less than tuned::kReuseMaxFrames
/// frames ago; each of the three scales within tuned::kReuseTestSigmas combined standard errors of
/// the carried one (on the log scale); and no more of the lattice's ranges outside the carried
/// quantiles than their share, 2 kReuseRangeTail, plus kReuseTestSigmas binomial standard errors.
/// (carried_estimates.cpp)
bool
carriedEstimatesHold(const CarriedEstimates& carried, const EstimateSignature& now, const Grid& frame,
                     const FilterParameters& parameters);


/// The current frame's noise profile as the call was given the frame (workspace.current_profile):
/// estimated on `frame` (the frame, or its copy) the first time, known afterwards. Throws
/// UnfilterableFrame as estimateNoiseProfile does. (frame_bandwidths.cpp)
const NoiseProfile&
currentFrameProfile(const Grid& frame, const FilterParameters& parameters, const Viewpoint& viewpoint,
                    Workspace& workspace);

/// The current frame `input` with its isolated outliers moved onto their neighbours' surface
/// (FilterParameters::outlier_sigmas) as tested against `profile` (its noise profile; empty:
/// nothing to test against), so that every later stage (noise estimates, frame comparisons,
/// normals) sees them there: workspace.corrected if some moved, else `input`. Sets
/// workspace.run.outliers_moved. (correct_outliers.cpp)
const Grid*
correctOutliersStage(const Grid& input, const NoiseProfile& profile, const FilterParameters& parameters,
                     const Viewpoint& viewpoint, const std::vector<unsigned char>& active, Workspace& workspace);

/// The frames with low-frequency offsets between them levelled (levelFrames) in
/// workspace.leveled, or `frames` as they are; workspace.frames_moved receives the frames'
/// motion analysis, and workspace.frame_changes each frame's analyseFrameChange against the
/// current frame (empty where none was made). (level_frames.cpp)
std::vector<const Grid*>
levelNeighbourFrames(const std::vector<const Grid*>& frames, int center, const FilterParameters& parameters,
                     const Viewpoint& viewpoint, Workspace& workspace);

/// The dilation the run uses: FilterParameters::dilation, or the automatic one (timed as
/// Stage::dilation on `split`; workspace.known_dilation instead where the carried estimates gave
/// one, see FilterParameters::reuse_estimates); 1 for a frame without a valid point. The
/// automatic one goes to workspace.chosen_dilation. (dilated_passes.cpp)
int
chooseDilation(const Grid& input, const FilterParameters& parameters, StageTracker& split, Workspace& workspace);

/// The dilated passes with dilation k > 1: each phase (u mod k, v mod k) of the frames filtered
/// as a grid of its own whose neighbours are k pixels apart, the phases merged, then (with more
/// than one iteration) a last contiguous pass on the full frame. The split and merge are timed
/// as Stage::dilation on `split`. (dilated_passes.cpp)
void
runDilatedPasses(const std::vector<const Grid*>& frames, int center, const FilterParameters& parameters,
                 const Viewpoint& viewpoint, const std::vector<unsigned char>& active, Workspace& workspace, int k,
                 StageTracker& split);

/// The scales the multiscale run uses: FilterParameters::scales, fewer where the coarsest would be
/// narrower than the windows. (multiscale.cpp)
int
usableScales(const Grid& input, const FilterParameters& parameters);
/// The multiscale run with `scales` > 1 scales: the frames reduced to half size (2 x 2 blocks,
/// each the mean of its points on one surface), filtered there (recursively, `scales` - 1
/// scales, contiguous windows unless a dilation is given), the current frame's range
/// corrections carried up along the rays, then runOneScale on it. Reduction and carry are timed
/// as Stage::pyramid. (multiscale.cpp)
void
runMultiscale(const std::vector<const Grid*>& frames, int center, const FilterParameters& parameters,
              const Viewpoint& viewpoint, const std::vector<unsigned char>& active, Workspace& workspace, int scales);
/// The filter at one scale: the dilated passes with the dilation chooseDilation gives, else
/// runContiguous. (pipeline.cpp)
void
runOneScale(const std::vector<const Grid*>& frames, int center, const FilterParameters& parameters,
            const Viewpoint& viewpoint, const std::vector<unsigned char>& active, Workspace& workspace);
/// The filter with contiguous windows: the stages below, `iterations` times. (pipeline.cpp)
void
runContiguous(const std::vector<const Grid*>& frames, int center, const FilterParameters& parameters,
              const Viewpoint& viewpoint, const std::vector<unsigned char>& active, Workspace& workspace);

// Once per contiguous run.

/// Bandwidths (global model) or noise profiles (range-adaptive model) of the neighbour frames,
/// from their own data; the range-adaptive model reads their profiles at the current frame's
/// median range, kept with the ranges for the first iteration. (frame_bandwidths.cpp)
void
estimateNeighbourFrames(FrameContext& ctx);

// Once per iteration.

/// The normals of the current frame's raw points (global model: its bandwidths need them).
/// (normal_fits.cpp)
void
fitRawNormals(FrameContext& ctx);

/// The current frame's noise profile (range-adaptive model) or bandwidths (global model, from
/// the raw normals). (frame_bandwidths.cpp)
void
estimateCurrentFrame(FrameContext& ctx);

/// The per-point noise sigma of the current frame (workspace.sigma, times similarity_scale;
/// range-adaptive: with the profile's sigma and extent maps), and the pre-smoothing bandwidths
/// and normal gate where the stages after it use them. (noise_maps.cpp)
void
computeNoiseMaps(FrameContext& ctx);

/// The profile (xs, ys) at every range of `rho` into `out`, by ctx.threads threads; with ys2
/// and out2 also the profile (xs, *ys2) into out2, in the same scan. (noise_maps.cpp)
void
profileMap(const FrameContext& ctx, const std::vector<float>& xs, const std::vector<float>& ys,
           const std::vector<float>& rho, std::vector<float>& out, const std::vector<float>* ys2 = nullptr,
           std::vector<float>* out2 = nullptr);

/// Per-point gates of `sigmas` noise sigmas (sig: the local noise sigma times similarity_scale)
/// into `gate`; empty (no gate) for 0. (noise_maps.cpp)
const std::vector<float>&
gateInto(const FrameContext& ctx, float sigmas, const std::vector<float>& sig, std::vector<float>& gate);

/// The current frame pre-smoothed along the rays (workspace.smooth), for the normal fits.
/// (normal_fits.cpp)
void
presmoothCurrentFrame(FrameContext& ctx);

/// The normals of `points` (the current frame or its pre-smoothed copy) with the normal gate of
/// the noise maps. (normal_fits.cpp)
void
fitGatedNormals(FrameContext& ctx, const Grid& points);

/// The frame terms of the iteration (ctx.terms, ctx.weights): frame weights Psi_k and, in the
/// range-adaptive model, per-point 1 / d^2 and 1 / s^2 maps and the patch guide. (frame_terms.cpp)
void
buildFrameTerms(FrameContext& ctx);

/// Guarded: adds neighbour k's unchanged points to the patch guide (docs/method.md, "The patch
/// guide"); `sig` is its noise sigma map, `ratio` its frame-to-frame noise ratio, `moved`
/// whether it moved. (patch_guide.cpp)
void
addToPatchGuide(FrameContext& ctx, int k, const std::vector<float>& sig, float ratio, bool moved);

/// The patch guide's weighted sums made means, and named as the other frames' patch reference,
/// where enough neighbours entered it. (patch_guide.cpp)
void
finishPatchGuide(FrameContext& ctx);

/// The offsets h of the current frame's points (workspace.offsets). (offsets.cpp)
void
computeFrameOffsets(FrameContext& ctx);

/// The direction the current frame's points move in: FilterParameters::displacement, automatic
/// resolved by the frames (along the ray with neighbours, else along the normal).
/// (displacement.cpp)
Displacement
resolvedDisplacement(const FrameContext& ctx);

/// The current frame's points moved by their offsets. (displacement.cpp)
void
displaceCurrentFrame(FrameContext& ctx);

// With FilterParameters::uncertainty, after the offsets and after the displacement.

/// The standard deviation of each point's height along its normal after this pass
/// (workspace.height_sigma) from the one before it (the first pass: workspace.prior_sigma where
/// finite, else the noise sigma) and the pass's weights (workspace.spread). (uncertainty.cpp)
void
propagateUncertainty(FrameContext& ctx);

/// workspace.height_sigma along the direction the points moved in, into
/// workspace.run.uncertainty. (uncertainty.cpp)
void
uncertaintyAlongMoves(FrameContext& ctx, Displacement displacement);
// Once per call, after the last pass (runFilter).

/// FilterParameters::fill_holes: the holes of workspace.run.output (8-connected regions of
/// invalid pixels, not touching the frame's border, active per `active`) at most fill_holes
/// pixels wide get a range each from the non-local candidates whose patches match the hole's
/// border on the pixel's depth level (a surface that spans the hole along the pixel's row or
/// column, else the occluded side of the edge), on the pixel's ray; sets workspace.run.filled. The edge
/// and candidate scales come from the noise profile of `input`, the frame as given.
/// (hole_filling.cpp)
void
fillHoles(const Grid& input, const FilterParameters& parameters, const Viewpoint& viewpoint,
          const std::vector<unsigned char>& active, Workspace& workspace);

} // namespace detail
} // namespace range_nlm
