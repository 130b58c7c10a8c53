/// \file pipeline.h
/// \brief The PCL-free pipeline of the non-local range filter (docs/method.md, "The static
/// filter" and "The temporal filter"): normals, bandwidths, offsets and displacement on Grid
/// frames. The pcl::Filter classes only adapt clouds to these functions.
#pragma once

#include <range_nlm/core/grid.h>
#include <range_nlm/parameters.h>

#include <array>
#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

namespace range_nlm
{

/// The frame's data leave nothing to filter: no valid point, or too few valid neighbours for the
/// noise estimate. The message says which. A std::invalid_argument, so that callers that catch bad
/// input catch it too; TemporalStream passes such frames through unchanged.
struct UnfilterableFrame : std::invalid_argument
{
  using std::invalid_argument::invalid_argument;
};

/// The largest coordinate magnitude of a frame the filter's float arithmetic handles: the squared
/// distances of the points, their plane fits and the weights' exponents stay finite, normal
/// floats. Measured: a frame's output is the same, up to float rounding, with its coordinates
/// scaled by any factor from 1e-12 to 1e12, and unchanged or wrong beyond 1e15 or below 1e-15;
/// these bounds leave a factor of 1000 to spare.
constexpr float kLargestCoordinate = 1e9f;
/// The smallest value the largest coordinate magnitude of a frame may have (see kLargestCoordinate).
constexpr float kSmallestLargestCoordinate = 1e-9f;

/// Throws UnfilterableFrame, naming the magnitude, if the largest coordinate magnitude of the
/// valid points of `frame` is outside [kSmallestLargestCoordinate, kLargestCoordinate]: such a
/// frame is passed through unchanged and reported, never "filtered" with its points unchanged.
/// A frame in other units (kilometres, micrometres) is filtered as in metres; a frame without a
/// valid point passes.
void
checkCoordinateScale(const Grid& frame);

/// Sensor position the normals are oriented toward, in cloud coordinates.
using Viewpoint = std::array<float, 3>;

/// Throws std::invalid_argument ("range_nlm: <what> must be finite, got (inf, 0, 0)") unless
/// every coordinate of `viewpoint` is finite: ranges are measured from it, and a non-finite one
/// leaves no range to filter (the PCD reader refuses a non-finite VIEWPOINT for the same reason).
/// runFilter and TemporalStream::push check theirs with it.
void
checkViewpoint(const Viewpoint& viewpoint, const std::string& what);

/// Least-squares plane normals over a `window` x `window` grid neighbourhood (PCL's
/// solvePlaneParameters on the neighbourhood covariance), oriented toward `viewpoint`.
/// Needs at least 3 valid neighbours; otherwise the normal is NaN. `threads` 0 = all cores
/// (likewise for every `threads` argument below).
NormalField
estimateNormals(const Grid& grid, int window, const Viewpoint& viewpoint, int threads);
/// Gated fit, so that a plane does not straddle a depth edge or a crease: a first fit leaves
/// out neighbours whose range differs from p_i's by more than `gate[i]` (size of the grid); the
/// second leaves out neighbours farther than `gate[i]` from the first fit's plane through p_i.
NormalField
estimateNormals(const Grid& grid, int window, const Viewpoint& viewpoint, int threads,
                const std::vector<float>& gate);

/// Edge-preserving smoothing of the range along each camera ray, used only to estimate normals:
/// rho'_i = sum_j w_ij rho_j / sum_j w_ij over a `window` x `window` neighbourhood with
/// w_ij = exp(-(rho_j - rho_i)^2 / (2 sigma^2)), rho = distance from the viewpoint.
Grid
presmoothAlongRays(const Grid& grid, int window, float sigma, const Viewpoint& viewpoint, int threads);
/// The same with a range bandwidth per point (`sigma[i]`, size of the grid).
Grid
presmoothAlongRays(const Grid& grid, int window, const std::vector<float>& sigma, const Viewpoint& viewpoint,
                   int threads);

/// Automatic bandwidths (docs/method.md, "Automatic bandwidths"), from random valid sample
/// points p_k: mu_d = mean of the largest distance from p_k to the points of its search window,
/// sigma_s = mean of the standard deviation of the offsets of that window to the tangent plane.
struct Bandwidths
{
  float mu_d = 0.0f;
  float sigma_s = 0.0f;
  /// d and s actually used (estimates scaled, or user-given values).
  float distance = 0.0f;
  float similarity = 0.0f;
};

/// Estimates mu_d and sigma_s; deterministic for a given seed. Throws std::invalid_argument if
/// the grid has no valid point.
Bandwidths
estimateBandwidths(const Grid& grid, const NormalField& normals, int search_window, int samples,
                   std::uint64_t seed);

/// Robust noise profile of a frame over range (BandwidthModel::range_adaptive): sampled windows
/// binned by range rho (distance from the viewpoint); per bin the median range, the median
/// plane-fit residual sigma (the square root of the smallest eigenvalue of the window's
/// covariance) and the median window extent (largest distance from the centre) divided by rho.
/// Values between bin centres are interpolated linearly, beyond them held constant.
struct NoiseProfile
{
  std::vector<float> range, sigma, extent;
  bool empty() const { return range.empty(); }
  float sigmaAt(float rho) const;
  float extentAt(float rho) const;
};

/// Estimates the noise profile from `samples` random valid points (deterministic per seed).
/// Throws std::invalid_argument if the grid has no valid point.
NoiseProfile
estimateNoiseProfile(const Grid& grid, int search_window, int samples, std::uint64_t seed,
                     const Viewpoint& viewpoint);

/// Moves the isolated outliers of `grid` along their ray onto their neighbours' surface
/// (FilterParameters::outlier_sigmas). A point agrees with a valid 8-neighbour j if its range is
/// within a tolerance of j's or of the straight continuation 2 rho_j - rho_j' of j and the pixel j'
/// beyond it; the tolerance is the larger of `sigmas` times the profile's sigma at its range and 3
/// pixel footprints (its range times the frame's median angle between adjacent rays). It is on a
/// surface if it agrees with two neighbours, or with one that agrees with another of its own
/// neighbours (two points that agree only with each other are no surface). A point that is not,
/// has at least two valid 8-neighbours and is farther from each of its neighbours on a surface
/// than 4 times the median range step between the points of its 5 x 5 surroundings that are on a
/// surface, gets the median range of its 8-neighbours that are on a surface (of two middle
/// ranges, the one nearer its own; none: it stays); where those lie on both sides of a depth edge,
/// of the side that most points of its 11 x 11 surroundings are nearer to (counted in
/// point-symmetric pairs of valid points that are no outliers). Such points are the mismatches of
/// structured-light block matching and the mixed ("flying") pixels of time-of-flight cameras at
/// depth edges: no patch resembles theirs, so the non-local filter leaves them where they are.
/// Returns the number of points moved; nothing with `sigmas` <= 0 or an empty profile.
std::size_t
correctIsolatedPoints(Grid& grid, const NoiseProfile& profile, float sigmas, const Viewpoint& viewpoint);

/// Whether frame `b` moved against frame `a` (camera or scene motion) rather than differing by
/// noise: the frames are cut into blocks of width / 20 pixels (at least 8); in each block with
/// at least half its pixels valid in both frames, the median m of (p_b - p_a) . n_a and the
/// median |(p_b - p_a) . n_a - m| are taken. Noise, however correlated, leaves m near 0 in
/// blocks holding many noise blobs; motion shifts whole blocks. True if the median |m| over the
/// blocks exceeds the median spread. False with fewer than 4 such blocks.
bool
framesMoved(const Grid& a, const NormalField& normals_a, const Grid& b);

/// How frame `b` differs from frame `a` at the same pixels (CrossFrameBandwidth::guarded;
/// docs/method.md, "Low-frequency offsets between frames").
enum class FrameChange
{
  /// Noise only: the blocks' median range differences are within their spread.
  none,
  /// Whole blocks differ in range, but nothing moved across the image: an offset along the rays
  /// that varies slowly over the frame (an active-stereo camera's depth drifts so from frame to
  /// frame, by more than its noise).
  offset,
  /// Whole blocks differ in range and the frame's structure moved across the image (camera or
  /// scene motion).
  motion
};

/// FrameChange of frame `b` against frame `a`, with the offset field where it is one.
struct FrameOffset
{
  FrameChange change = FrameChange::none;
  /// change == offset: per pixel of the grid, the range of `b` minus the range of `a` (m),
  /// smooth over the frame; empty otherwise.
  std::vector<float> range_offset;
};

/// Tells noise, a slowly varying offset along the rays and motion apart. The frames are cut into
/// blocks of width / 20 pixels (at least 8); in each block with at least half its pixels valid in
/// both frames, the median m of the range differences rho_b - rho_a and their median spread around
/// m are taken (on every other pixel along rows and columns, as everything below). The blocks'
/// median |m| within their median spread: `none` (as framesMoved, along the rays). Otherwise the
/// frame changed, and it moved (`motion`) if
///  - fewer than 24 blocks qualify (too few to tell a drift from blocks that moved), or
///  - its structure moved across the image: a block is structured if shifting `b` by one or two
///    pixels along a row or column makes the mean absolute deviation of its differences 1.5 times
///    larger, and shows a shift if one of those shifts makes it 0.8 times smaller than no shift;
///    at least 8 blocks are structured and at least a quarter of them show a shift, or
///  - the block medians are not smooth over the frame: a quadratic in the image coordinates,
///    fitted to them (weighted by 1 / spread^2, with Huber weights at 2 spreads), leaves their
///    median distance from it above the median spread.
/// Else `offset`, with that quadratic as the offset field.
FrameOffset
analyseFrameChange(const Grid& a, const Grid& b, const Viewpoint& viewpoint);

/// The history of the recursive temporal window (TemporalWindow::recursive): per pixel a running
/// average of its range over the frames since it last changed. Where a pixel's history starts,
/// it starts from the frame's filtered output; after that only input frames enter it, so that
/// the filter's own small bias on curved and steep surfaces does not feed back into every later
/// frame and pile up (it did when each output was the next frame's neighbour).
struct RunningAverage
{
  /// The average, each point on the ray of the pixel's latest point; NaN where count is 0.
  Grid average;
  /// Frames the average stands for per pixel (0: no history).
  std::vector<std::uint16_t> count;
  /// Storage updateRunningAverage reuses from one call to the next (frame-sized maps of its test
  /// of change), so that a stream allocates and clears none per frame. Holds nothing between
  /// calls that the result depends on.
  struct Buffers
  {
    std::vector<float> rho_frame, rho_history, sigma, along, noise, ratios;
    std::vector<unsigned char> changed;
  } buffers;
  bool empty() const { return average.size() == 0; }
};

/// Adds `frame` to `history`; `start` is the frame's filtered output (null if there is none).
/// Every pixel's history starts over where it was empty or of another size, and where
/// analyseFrameChange(frame, history) finds that the camera moved, or the frame has too few points
/// for a noise estimate (estimateNoiseProfile throws UnfilterableFrame). Else, per pixel: an invalid
/// point empties the pixel's history; a pixel without history, or that changed, starts over;
/// otherwise its range becomes r_h + (r_f - r_h) / min(count + 1, max_count), on the frame
/// point's ray. A pixel changed if most of the pixels of its 3 x 3 neighbourhood valid in both
/// differ from the history (less the slowly varying offset along the rays that
/// analyseFrameChange may have found) by more than 2 frame-to-frame sigmas: the frame's noise
/// profile at their range times sqrt(1 + 1 / count), raised by the median ratio of the
/// differences to it where that is above 1 (spatially correlated noise). A pixel starts over
/// from start's point, counted as max_count - 1 frames (so that the next frames come in with
/// weight 1 / max_count), or from the frame's point, counted as 1, where start has none. The
/// profile is `profile` if given (the one the filter used for the frame, so that a frame's noise is
/// estimated once), else estimateNoiseProfile(frame, search_window, samples, seed); the change is
/// `change` if given (the filter's analysis of the same two frames), else analyseFrameChange. By `threads`
/// threads (0 = OpenMP's default), with the same result. Throws std::invalid_argument if start's
/// size is not the frame's.
void
updateRunningAverage(RunningAverage& history, const Grid& frame, const Grid* start, const Viewpoint& viewpoint,
                     int max_count, int search_window, int samples, std::uint64_t seed, int threads,
                     const NoiseProfile* profile = nullptr, const FrameOffset* change = nullptr);

/// How much larger the frame-to-frame noise of frame `b` is than its spatial noise profile says:
/// 1.4826 x the median, over the pixels valid in both frames with a normal, of
/// |(p_b - p_a) . n_a| / profile_b.sigmaAt(rho_a), divided by sqrt(2) (the difference holds the
/// noise of both frames). The difference is taken along the normal, as the patch similarity
/// takes it. About 1 for noise independent from pixel to pixel; larger where the noise is
/// spatially correlated, which a local plane fit mostly mistakes for surface. One ratio for the
/// frame, so a moving object that fills a range interval does not move it. 0 if fewer than 64
/// pixels qualify or the profile is empty.
float
estimateTemporalNoiseRatio(const Grid& a, const NormalField& normals_a, const Grid& b, const NoiseProfile& profile_b,
                           const Viewpoint& viewpoint);

/// How the noise of a frame varies with the pixel lag: the robust scale of the second
/// differences of inverse depth at lags 1 .. 8 pixels along rows and columns (exactly zero on
/// planes, since 1/z is affine in the pixel coordinates on a plane), converted to depth by z^2.
/// For independent per-pixel noise the scale is the same at every lag; for spatially correlated
/// noise it grows with the lag until the lag passes the correlation length.
struct NoiseCorrelation
{
  /// scale[l - 1]: the mean of the smallest 80 % of |w(u - l) - 2 w(u) + w(u + l)| z(u)^2 at
  /// lag l, cloud units (robust to depth edges, and not stuck on the steps of a quantized depth
  /// unit as a median is); 0 where fewer than 64 triples qualified.
  std::array<float, 8> scale{};
  /// Pixel triples sampled per lag.
  std::size_t samples = 0;
  /// The same scale with each triple's difference divided by the pixel footprint at its centre
  /// (the distance between neighbouring pixels' rays at the centre's depth): how many pixel
  /// footprints the noise spans, a number; 0 where fewer than 64 triples qualified.
  std::array<float, 8> scale_in_footprints{};
};

/// NoiseCorrelation of a frame from the valid triples of every `step`-th row and column.
NoiseCorrelation
estimateNoiseCorrelation(const Grid& grid, int step = 4);

/// The length over which the noise of a frame `width` pixels wide is correlated, in pixels, from
/// its NoiseCorrelation: 0 if the noise is not correlated (the variance of the second differences
/// at lag 1 at least half of that at the reference lag R, see automaticDilation), else the lag
/// (interpolated linearly between lags, at most R) where that variance first reaches twice its
/// value at lag 1, or half of its value at lag R if that is less. For noise with correlation
/// rho(l) the variance is 2 sigma^2 (3 - 4 rho(l) + rho(2 l)): flat where rho is close to 1, rising
/// as the lag passes the correlation length, 6 sigma^2 beyond it. For the stereo model's Gaussian
/// correlation exp(-(l / L)^2) over 80 % of the variance this is about 0.6 L.
float
noiseCorrelationLength(const NoiseCorrelation& correlation, int width);

/// The dilation FilterParameters::dilation = 0 (automatic) gives a frame. With the reference lag
/// R = 8 pixels per 640 columns (rounded, in [2, 8]) and the scales of estimateNoiseCorrelation:
/// - if the variance of the second differences at lag 1 is less than half of that at lag R, the
///   noise is correlated over several pixels and the dilation is 2 per 640 columns (rounded, in
///   [2, 4]: 2 in a VGA frame, 4 at 1280 columns and more), or from 640 columns on the
///   correlation length (noiseCorrelationLength, rounded) where that is more, up to 4: the pixels
///   of a phase then lie about a correlation length apart; else 1;
/// - if the noise is strong, i.e. its scale exceeds 3.25 pixel footprints (scale_in_footprints)
///   at lag R / 2, or from 640 columns on where the noise is correlated over longer lags than
///   that (twice the correlation length beyond 4 pixels per 640 columns) at twice the correlation
///   length, at most R, that dilation is doubled, up to 4 (or twice the per-width dilation, where that is more):
///   detail at the pixel scale does not survive such noise, and the dilated passes reach twice as
///   far at the same cost; it is doubled again for each further doubling of the noise (6.5, 13,
///   ... footprints), up to the same limit or 1.5 times a dilation the correlation length chose,
///   where that is more (6 in a VGA frame with blobs of 6-8 pixels under twice the stereo model's
///   noise).
/// The correlation test scales with the width because a frame's details span more pixels the
/// more pixels it has: a dilated 3 x 3 patch must stay small against them, and at long lags a
/// small frame's curvature and edges, not its noise, dominate the differences.
int
automaticDilation(const Grid& frame);

/// One frame of the (temporal) neighbourhood: its points, bandwidths and frame weight
/// Psi_k = Psi_dk * Psi_sk. The static filter is the case of one frame with weight 1.
/// Per-point bandwidths (range_adaptive) are given as maps of 1 / d^2 and 1 / s^2 indexed by
/// the centre point i; when set they replace the scalar bandwidths. `patches`, when set, is the
/// grid the centre patch is taken from when this frame's patches are compared with it (a patch
/// guide: Sim(i, j) = mean over o of |(g_{i+o} - p_{j+o}) . n_i|^2 with g = *patches); it must
/// have the size of the centre frame. Null: the centre frame itself, as in the paper.
struct FrameTerm
{
  const Grid* grid = nullptr;
  float distance_bandwidth = 0.0f;
  float similarity_bandwidth = 0.0f;
  float weight = 1.0f;
  const std::vector<float>* inverse_distance2 = nullptr;
  const std::vector<float>* inverse_similarity2 = nullptr;
  const Grid* patches = nullptr;
  /// The side of this frame's search window N_k(i), odd and at most computeOffsets' search_window;
  /// 0: search_window (FilterParameters::temporal_search_window for the other frames of a window).
  int search_window = 0;
};

/// Computes for every point i of `center` the filtered normal offset
///   h_i = sum_k Psi_k sum_{j in N_k(i)} Phi_dk Phi_sk ((p_i - p_j) . n_i)
///       / sum_k Psi_k sum_{j in N_k(i)} Phi_dk Phi_sk
/// with Sim(i, j) the mean of |(p_{i+o} - p_{j+o}) . n_i|^2 over the valid patch pairs.
/// `active` (size of the grid, may be empty = all) selects the points to compute; h is 0 for
/// other, invalid or normal-less points. All frames must have the size of `center`.
/// `patch_gate` (size of the grid, may be empty = no gate; FilterParameters::patch_edge_gate):
/// pixels o of i's patch with |n_i . (p_{i+o} - p_i)| > patch_gate[i] (p_{i+o} from the frame's
/// patch guide if it names one) count as holes, i.e. their pairs are left out of Sim(i, j).
void
computeOffsets(const Grid& center, const NormalField& normals, const std::vector<FrameTerm>& frames,
               int search_window, int patch_size, Evaluation evaluation, int threads,
               const std::vector<unsigned char>& active, std::vector<float>& offsets,
               const std::vector<float>& patch_gate = {});

/// Moves the active points by their offsets: p' = p - h n, or along the line of sight. With
/// `limit` (size of the grid, may be empty) each displacement is clamped to |p' - p| <= limit[i].
/// Along the line of sight the ray step uses |cos(normal, ray)| bounded below by min_cos.
/// Displacement::automatic moves along the normal here (runFilter resolves it by its frames).
void
applyOffsets(Grid& grid, const NormalField& normals, const std::vector<float>& offsets,
             Displacement displacement, const Viewpoint& viewpoint,
             const std::vector<float>& limit = {},
             float min_cos = FilterParameters{}.line_of_sight_min_cos);

/// Frame weights of the temporal filter: Psi_dk = (1/2)^|k - c|, Psi_sk = exp(-s_k^2 / max s^2).
float
temporalDistanceWeight(int k, int center);
float
temporalNoiseWeight(float s_k, float s_max);

/// Result of a whole filter run on the kernel level.
struct FilterRun
{
  Grid output;
  /// Bandwidths per frame of the first iteration (frame order as given).
  std::vector<Bandwidths> bandwidths;
  /// Psi_k = Psi_dk * Psi_sk per frame of the first iteration.
  std::vector<float> frame_weights;
  /// Isolated outliers of the current frame moved onto their neighbours' surface before
  /// filtering (FilterParameters::outlier_sigmas).
  std::size_t outliers_moved = 0;
  /// With FilterParameters::uncertainty: per point of `output`, the standard deviation of its
  /// error along its direction of movement (the normal, or the ray along the line of sight),
  /// metres; NaN where the point is invalid. Empty otherwise.
  std::vector<float> uncertainty;
  /// Hole filling (FilterParameters::fill_holes): 1 for every point of `output` that was invalid
  /// in the current frame and was given a range by the hole filling, 0 elsewhere; empty when the
  /// hole filling is off.
  std::vector<unsigned char> filled;
  /// FilterParameters::reuse_estimates: the run used the estimates carried from an earlier frame
  /// (false: it estimated them, or reuse is off).
  bool estimates_reused = false;
  /// Noise profiles the run estimated (range-adaptive bandwidths: one per frame of the window, per
  /// pass, and per phase of dilated passes, where not carried from an earlier frame of the stream;
  /// FilterParameters::reuse_estimates).
  int profiles_estimated = 0;
};

/// Runs the complete filter: normals, bandwidths, offsets, displacement, `iterations` times.
/// `frames[center]` is filtered; the others are its temporal neighbours (left unchanged).
/// `active` as in computeOffsets. Throws std::invalid_argument on invalid parameters or data.
FilterRun
runFilter(const std::vector<const Grid*>& frames, int center, const FilterParameters& parameters,
          const Viewpoint& viewpoint, const std::vector<unsigned char>& active);

/// The phases of runFilter. dilation and neighbour_frames run once per call, the others once per
/// iteration, in this order. With a dilation k > 1 the phases of every pass are reported: each of
/// the k^2 dilated passes (on frames of 1/k^2 the points) reports its own, iteration 0.
enum class Stage
{
  /// The current frame's isolated outliers (FilterParameters::outlier_sigmas): a noise profile
  /// and correctIsolatedPoints, once per call.
  outliers,
  /// Dilated passes (FilterParameters::dilation): the automatic dilation's noise correlation
  /// estimate, the split of the frames into their k^2 phases and the merge of the results.
  dilation,
  /// Multiscale runs (FilterParameters::scales): the reduction of the frames to the next coarser
  /// scale and the carry of its corrections to the finer one, once per scale.
  pyramid,
  /// Bandwidths (or noise profiles) of the temporal neighbour frames.
  neighbour_frames,
  /// The current frame's noise profile (range-adaptive model) or bandwidths (global model).
  bandwidths,
  /// Per-point noise sigma, pre-smoothing bandwidths and edge gates.
  noise_maps,
  /// presmoothAlongRays.
  presmoothing,
  /// The normal fits (raw points for the global bandwidths, then gated on the pre-smoothed copy).
  normals,
  /// Frame weights Psi_k and per-point 1 / d^2, 1 / s^2 maps.
  frame_terms,
  /// computeOffsets.
  offsets,
  /// applyOffsets.
  displacement,
  /// The hole filling (FilterParameters::fill_holes), once per call after the last pass.
  hole_filling
};
/// Number of Stage values (hole_filling is the last).
constexpr int kStageCount = static_cast<int>(Stage::hole_filling) + 1;
/// A short name of the stage ("normals", "offsets", ...).
const char*
toString(Stage stage);

/// Told where each phase of runFilter begins and ends (for timing, e.g. range_nlm_bench
/// --breakdown). Calls come from the calling thread, never from inside a parallel region.
class StageObserver
{
public:
  virtual ~StageObserver() = default;
  /// `iteration` counts the filter's iterations from 0 (0 for neighbour_frames).
  virtual void begin(Stage stage, int iteration) = 0;
  virtual void end(Stage stage, int iteration) = 0;
};

/// The buffers of a filter run (src/core/workspace.h; not part of the interface).
struct Workspace;

/// The buffers of a filter run, kept between runs (each filter object owns one). Runs on frames
/// of one size then reuse memory that is already mapped: allocating and first touching the
/// ~40 MB a VGA frame passes through cost about a sixth of the frame's time. Holds the last run's
/// result; the intermediates it keeps are not part of the interface. Copies copy the buffers; a
/// moved-from workspace may only be assigned to or destroyed.
class FilterWorkspace
{
public:
  FilterWorkspace();
  ~FilterWorkspace();
  FilterWorkspace(const FilterWorkspace& other);
  FilterWorkspace(FilterWorkspace&& other) noexcept;
  FilterWorkspace& operator=(const FilterWorkspace& other);
  FilterWorkspace& operator=(FilterWorkspace&& other) noexcept;

  /// The last run's result.
  const FilterRun& result() const;
  /// The noise profile of the last run's current frame as that run estimated it (or carried it,
  /// FilterParameters::reuse_estimates); empty if the run used none (global bandwidths without the
  /// outlier stage) or failed before estimating it.
  const NoiseProfile& currentProfile() const;
  /// analyseFrameChange(current frame, frame k) as the last run made it to level and test its
  /// frames (the current frame as filtered: after the outlier stage), or null where it made none
  /// (one frame, or not the guarded cross-frame bandwidths with the range-adaptive model).
  const FrameOffset* frameChange(int k) const;
  /// Grids for the input frames (the pcl::Filter adaptors convert their clouds into them): a run
  /// whose current frame is one of them takes that grid over as the result's storage instead of
  /// copying it (its contents are not kept), unless another frame is the same grid.
  std::vector<Grid>& inputs();
  /// Told where each phase of every run begins and ends (e.g. for timing, as range_nlm_bench
  /// --breakdown does); null for none. Not owned.
  void setStageObserver(StageObserver* observer);

private:
  friend void runFilter(const std::vector<const Grid*>& frames, int center, const FilterParameters& parameters,
                        const Viewpoint& viewpoint, const std::vector<unsigned char>& active,
                        FilterWorkspace& workspace);
  std::unique_ptr<Workspace> workspace_;
};

/// runFilter with the result in `workspace.result()` and every frame-sized buffer taken from
/// `workspace`. `frames` may point into workspace.inputs(); the current frame's grid there is
/// then taken over as the result's storage (its contents are not kept) unless another frame is
/// the same grid.
void
runFilter(const std::vector<const Grid*>& frames, int center, const FilterParameters& parameters,
          const Viewpoint& viewpoint, const std::vector<unsigned char>& active, FilterWorkspace& workspace);

} // namespace range_nlm
