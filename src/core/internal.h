// Internals of the core shared by its translation units and by the tests (not installed).
#pragma once

#include "tuned.h"

#include <range_nlm/core/pipeline.h>

#include "robust_statistics.h"

#include <vector>

namespace range_nlm
{
namespace detail
{
struct RowKernels;

/// exp(x) for x <= 0, accurate to a few ulp, vectorizable; exp(x) = 0 below -87.
float
expNonPositive(float x);
/// 1 / b^2 with b = 0 mapped to a huge finite value (only exact matches keep weight).
float
inverseSquare(float bandwidth);
/// estimateNormals with gate pass 0 (none), 1 (range gate only) or 2 (range, then plane gate).
NormalField
estimateNormalsGated(const Grid& grid, int window, const Viewpoint& viewpoint, int threads,
                     const std::vector<float>& gate, int pass);
/// The same into `normals` (resized as needed), with the padded planes in `planes` and pass 1's
/// normals (pass 2 only) in `first` if given (resized as needed, so that repeated calls reuse
/// them), else in memory of their own.
void
estimateNormalsGated(const Grid& grid, int window, const Viewpoint& viewpoint, int threads,
                     const std::vector<float>& gate, int pass, NormalField& normals, std::vector<float>* planes,
                     NormalField* first = nullptr);
/// Per point, what the weights of computeOffsets say besides the offset h_i (for the per-point
/// uncertainty, FilterParameters::uncertainty): the weighted variance of the candidates' heights
/// about h_i, sum_j w_j (h_j - h_i)^2 / sum_j w_j, and one over their effective number,
/// sum_j w_j^2 / (sum_j w_j)^2 (w_j with the frame weights Psi_k). Both 0 where h_i is 0 because
/// the point is inactive, invalid, has no normal or no candidate.
struct OffsetSpread
{
  std::vector<float> variance, inverse_count;
};

/// computeOffsets with the padded frames of the windowed evaluation in `planes` if given (resized
/// as needed), else in memory of their own; the direct evaluation does not use it. With `spread`
/// also its two sums per point (resized to the grid; the evaluation then takes the kernels that
/// accumulate them, and the offsets are the same bits as without).
void
computeOffsets(const Grid& center, const NormalField& normals, const std::vector<FrameTerm>& frames,
               int search_window, int patch_size, Evaluation evaluation, int threads,
               const std::vector<unsigned char>& active, std::vector<float>& offsets,
               const std::vector<float>& patch_gate, std::vector<float>* planes, OffsetSpread* spread = nullptr);
/// The piecewise linear interpolation of NoiseProfile::sigmaAt / extentAt (ranges xs, values ys)
/// at the n points x into out, with the same result for every point, vectorized.
/// With ys2 and out2 also the profile (xs, *ys2) into out2, in the same scan over the bins.
void
interpolateProfile(const std::vector<float>& xs, const std::vector<float>& ys, const float* x, float* out,
                   std::size_t n, const std::vector<float>* ys2 = nullptr, float* out2 = nullptr);
/// The builds of interpolateProfile this CPU runs (baseline, then AVX2, then AVX-512; for tests),
/// and interpolateProfile with build `build` (< interpolateProfileBuilds()).
std::size_t
interpolateProfileBuilds();
void
interpolateProfileWithBuild(std::size_t build, const std::vector<float>& xs, const std::vector<float>& ys,
                            const float* x, float* out, std::size_t n, const std::vector<float>* ys2 = nullptr,
                            float* out2 = nullptr);
/// interpolateProfile by `threads` threads, in blocks of points (the same result: each point's
/// value depends on that point alone).
void
interpolateProfile(const std::vector<float>& xs, const std::vector<float>& ys, const float* x, float* out,
                   std::size_t n, int threads, const std::vector<float>* ys2 = nullptr, float* out2 = nullptr);
/// estimateNoiseProfile by `threads` threads (0 = OpenMP's default), with the same result.
NoiseProfile
estimateNoiseProfile(const Grid& grid, int search_window, int samples, std::uint64_t seed,
                     const Viewpoint& viewpoint, int threads);
/// The patch spread profile of `grid` (FilterParameters::similarity_spread): at `samples` valid
/// points with a finite normal (drawn with `seed`), Sim(k, j) of the point's P x P patch
/// (`patch_size`) to every other candidate j of its S x S search window, projected on its normal
/// n_k as the filter does; per point the `quantile` of these. The samples are binned by range as
/// the noise profile is (tuned::kProfileSamplesPerBin, kProfileMaxBins); per bin the median range
/// into `range` and the square root of the median of the points' quantiles into `spread`: how far
/// apart (RMS height) the patches of one surface are under this frame's noise and normals. Both
/// empty if no sample has a candidate. The same result for any `threads`.
void
estimatePatchSpread(const Grid& grid, const NormalField& normals, int search_window, int patch_size, int samples,
                    std::uint64_t seed, const Viewpoint& viewpoint, int threads, float quantile,
                    std::vector<float>& range, std::vector<float>& spread);
/// The range |p - viewpoint| of every point of `grid` into `rho` (0 for invalid points), by
/// `threads` threads.
void
rangesOf(const Grid& grid, const Viewpoint& viewpoint, int threads, std::vector<float>& rho);
/// An isolated outlier found by findIsolatedPoints: its index and the range it is moved to.
struct IsolatedPoint
{
  std::size_t index;
  float range;
};
/// The isolated outliers of correctIsolatedPoints among the points with `active` set (every point
/// if empty), in index order, by `threads` threads with the same result; `grid` is not changed.
std::vector<IsolatedPoint>
findIsolatedPoints(const Grid& grid, const NoiseProfile& profile, float sigmas, const Viewpoint& viewpoint,
                   const std::vector<unsigned char>& active, int threads);
/// The same with the points' ranges in `rho` (storage reused).
std::vector<IsolatedPoint>
findIsolatedPoints(const Grid& grid, const NoiseProfile& profile, float sigmas, const Viewpoint& viewpoint,
                   const std::vector<unsigned char>& active, int threads, std::vector<float>& rho);
/// Moves each point along its ray to its new range.
void
moveIsolatedPoints(Grid& grid, const std::vector<IsolatedPoint>& points, const Viewpoint& viewpoint);
/// correctIsolatedPoints on the points with `active` set (every point if empty) by `threads`
/// threads, with the same result.
std::size_t
correctIsolatedPoints(Grid& grid, const NoiseProfile& profile, float sigmas, const Viewpoint& viewpoint,
                      const std::vector<unsigned char>& active, int threads);
/// framesMoved by `threads` threads, with the same result.
bool
framesMoved(const Grid& a, const NormalField& normals_a, const Grid& b, int threads);
/// framesMoved and estimateTemporalNoiseRatio of one pair of frames in one pass over them.
struct FrameComparison
{
  /// framesMoved (false unless `test_motion`).
  bool moved = false;
  /// estimateTemporalNoiseRatio with sigma_b[i] = profile_b.sigmaAt(rho_a[i]) (0 if moved, if
  /// sigma_b is null, or with fewer than 64 pixels).
  float ratio = 0.0f;
};
/// The motion test (if `test_motion`) and, unless the frames moved, the frame-to-frame noise
/// ratio against the per-pixel noise sigma_b (if not null; n = a.size() values, 0 where a is
/// invalid), each as its own function computes it, by `threads` threads.
FrameComparison
compareFrames(const Grid& a, const NormalField& normals_a, const Grid& b, const float* sigma_b, bool test_motion,
              int threads);
/// (p_b - p_a) . n_a of every pixel into `along` (resized to a.size()), NaN where either point is
/// invalid or n_a is not finite; a and b of one size.
void
alongNormals(const Grid& a, const NormalField& normals_a, const Grid& b, int threads, std::vector<float>& along);
/// compareFrames on the differences of alongNormals (a width x height frame).
FrameComparison
compareAlong(const std::vector<float>& along, int width, int height, const float* sigma_b, bool test_motion,
             int threads);
/// The per-pixel test of change of the guarded cross-frame bandwidths (docs/method.md, "A
/// per-pixel test of change"), on the differences `along` of alongNormals(a, normals_a, b) over a
/// width x height frame: changed[i] = 1 where most of the pixels of the 3 x 3 neighbourhood of i
/// that are valid in both frames, with a finite normal n_a, have |(p_b - p_a) . n_a| >
/// kChangeSigmas x sqrt(2) x ratio x max(sigma_a[i], sigma_b[i]) (a frame-to-frame difference far
/// beyond the noise of two samples: sigma_a and sigma_b the spatial noise of each frame at the
/// range of a's point, ratio the frame-to-frame noise ratio of b), else 0; `changed` is resized
/// to along.size() (all 0 if that is not width x height). By `threads` threads, the same for any
/// count.
using tuned::kChangeSigmas;
void
markChangedPixels(const std::vector<float>& along, int width, int height, const float* sigma_a,
                  const float* sigma_b, float ratio, int threads, std::vector<unsigned char>& changed);
/// Pixels within `radius` pixels (Chebyshev distance) of a set pixel of `mask` (width x height):
/// out[i] = 1 if mask[j] for some j of the (2 radius + 1)^2 square around i, else 0; `out` is
/// resized to mask.size() (a copy of mask if that is not width x height or radius <= 0). By
/// `threads` threads, the same for any count.
void
widenMask(const std::vector<unsigned char>& mask, int width, int height, int radius, int threads,
          std::vector<unsigned char>& out);
/// The same vote with the threshold sigmas x sigma[i] (sigma the noise of the difference itself).
void
markChangedPixels(const std::vector<float>& along, int width, int height, const float* sigma, float sigmas,
                  int threads, std::vector<unsigned char>& changed);
/// analyseFrameChange by `threads` threads, with the same result.
FrameOffset
analyseFrameChange(const Grid& a, const Grid& b, const Viewpoint& viewpoint, int threads);
/// The same with the frames' ranges in `rho_a` and `rho_b` (storage reused: nothing allocated or
/// cleared per call when their sizes match).
FrameOffset
analyseFrameChange(const Grid& a, const Grid& b, const Viewpoint& viewpoint, int threads, std::vector<float>& rho_a,
                   std::vector<float>& rho_b);
/// estimateTemporalNoiseRatio by `threads` threads, with the same result.
float
estimateTemporalNoiseRatio(const Grid& a, const NormalField& normals_a, const Grid& b, const NoiseProfile& profile_b,
                           const Viewpoint& viewpoint, int threads);
/// estimateNoiseCorrelation by `threads` threads, with the same result.
NoiseCorrelation
estimateNoiseCorrelation(const Grid& grid, int step, int threads);
/// The automatic dilation's reference lag R for a frame `width` pixels wide:
/// tuned::kDilationReferenceLag per tuned::kDilationReferenceWidth columns, rounded, in
/// [kDilationMinLag, kDilationMaxLag].
int
dilationReferenceLag(int width);
/// automaticDilation by `threads` threads, with the same result.
int
automaticDilation(const Grid& frame, int threads);
/// presmoothAlongRays into `out` (its storage reused), with the padded planes in `planes` if given
/// (resized as needed), else in memory of their own.
void
presmoothAlongRays(const Grid& grid, int window, const std::vector<float>& sigma, const Viewpoint& viewpoint,
                   int threads, Grid& out, std::vector<float>* planes);
/// `to` = `from`, copied by `threads` threads into `to`'s existing storage when the sizes match.
void
copyGrid(const Grid& from, Grid& to, int threads);
/// Thread count for OpenMP: `threads` if > 0, else the runtime's default (1 without OpenMP).
int
resolveThreads(int threads);
/// The smaller search window some frames name (FrameTerm::search_window; computeOffsets allows one
/// such size), else search_window.
int
innerSearch(const std::vector<FrameTerm>& frames, int search_window);
/// The literal evaluation of the offsets (Evaluation::direct).
void
computeOffsetsDirect(const Grid& center, const NormalField& normals, const std::vector<FrameTerm>& frames,
                     int search_window, int patch_size, int threads, const std::vector<unsigned char>& active,
                     std::vector<float>& offsets, const std::vector<float>& patch_gate = {},
                     OffsetSpread* spread = nullptr);
/// The windowed evaluation (Evaluation::fast) with the fastest build of the SIMD kernels.
void
computeOffsetsFast(const Grid& center, const NormalField& normals, const std::vector<FrameTerm>& frames,
                   int search_window, int patch_size, int threads, const std::vector<unsigned char>& active,
                   std::vector<float>& offsets, const std::vector<float>& patch_gate, std::vector<float>* planes,
                   OffsetSpread* spread = nullptr);
/// The windowed evaluation with the given build of the SIMD kernels; `offsets` has the size of
/// the grid. The padded frames go into `planes` if given (resized as needed), else into memory of
/// their own. For tests; computeOffsetsFast takes the fastest build.
void
computeOffsetsWindowed(const RowKernels& kernels, const Grid& center, const NormalField& normals,
                       const std::vector<FrameTerm>& frames, int search_window, int patch_size, int threads,
                       const std::vector<unsigned char>& active, std::vector<float>& offsets,
                       const std::vector<float>& patch_gate = {}, std::vector<float>* planes = nullptr,
                       OffsetSpread* spread = nullptr);

/// A robust noise scale of a frame and the standard error of its logarithm, as measured from the
/// spread of the scale over groups of its samples (carried_estimates.cpp).
struct Scale
{
  float scale = 0.0f;     // 0: too few samples
  float log_error = 0.0f; // standard error of ln(scale)
  std::size_t samples = 0;
};

/// What a sparse look at a frame says of its sensor and ranges (FilterParameters::reuse_estimates):
/// on a lattice of about tuned::kReuseCheckColumns columns, the robust scales of the second
/// differences of inverse depth (times z^2) at lags 1, R / 2 and R (R = dilationReferenceLag, as
/// the automatic dilation looks at them), each with its measured error, and the range quantiles
/// kReuseRangeTail and 1 - kReuseRangeTail of the lattice's valid points.
struct EstimateSignature
{
  int width = 0, height = 0;
  Viewpoint viewpoint{};
  Scale near, half, far;
  float range_low = 0.0f, range_high = 0.0f;
  std::size_t range_samples = 0;
};

/// The estimates a stream carries from frame to frame, with the signature of the frame they were
/// made on and the parameters they depend on.
struct CarriedEstimates
{
  bool valid = false;
  EstimateSignature signature;
  FilterParameters parameters;
  /// The current frame's noise profile (empty: none was estimated) and the automatic dilation
  /// (0: none was chosen).
  NoiseProfile profile;
  int dilation = 0;
  /// Frames filtered with these estimates, the one they were made on included.
  int frames = 0;
};

/// A noise profile a stream carries for one frame of its window (FilterParameters::reuse_estimates):
/// the frame's place in the window (its offset from the current frame: -1 a recursive stream's
/// history or the previous frame) and the pass it was estimated for.
struct CarriedProfile
{
  int offset = 0;
  int iteration = 0;
  NoiseProfile profile;
};

/// What a stream carries for the other frame at `offset` of its windows: the check (signature,
/// parameters, age) that says whether the profiles kept for it still describe the frame there now.
struct CarriedNeighbour
{
  int offset = 0;
  CarriedEstimates check;
};

} // namespace detail
} // namespace range_nlm
