/// \file parameters.h
/// \brief All parameters of the non-local range filter, with units, defaults and valid ranges.
#pragma once

#include <cstdint>
#include <string>

namespace range_nlm
{

/// How the automatic bandwidths are chosen.
enum class BandwidthModel
{
  /// One d and one s for the frame: d = distance_scale * mean of the largest window distance,
  /// s = similarity_scale * mean of the window's standard deviation about the tangent plane
  /// (the paper). Windows straddling depth edges drag both up.
  global,
  /// d and s per point from a robust noise profile of the frame: the sampled windows are binned by
  /// range (distance from the sensor), and per bin the median plane-fit residual (sigma) and the
  /// median window extent per unit range are taken. Then s_i = similarity_scale * sigma(rho_i)
  /// and d_i = distance_scale * extent(rho_i) * rho_i. Depth-camera noise grows with range and
  /// the pixel footprint grows with range; a single global value suits neither near nor far.
  range_adaptive
};

/// How the patch similarity Sim(i, j) is evaluated. Both give the same result to float precision.
enum class Evaluation
{
  /// Windowed evaluation: pixels are taken 16 (8, 4) at a time, one per vector lane; each point of
  /// the (S + P - 1)^2 window is projected once on the pixel's normal, then every patch pair
  /// costs one or two vector operations from registers and a small cache-resident scratch.
  fast,
  /// Literal evaluation of the formula: S^2 * P^2 operations per point. Kept as the reference.
  direct
};

/// Similarity bandwidth of the other frames' patches in the temporal filter.
enum class CrossFrameBandwidth
{
  /// Each frame's own s (its spatial noise estimate), as for the current frame (the paper).
  spatial,
  /// The frame's spatial noise raised by its frame-to-frame noise ratio (estimateTemporalNoiseRatio,
  /// from the differences to the current frame at the same pixel, along the normal) where that
  /// is larger; d grows to span the frame-to-frame distance of one surface point too. Under
  /// spatially correlated noise a frame looks locally smoother than it is, so its spatial s is
  /// too small for the frame-to-frame differences of a static scene, and the paper's weights
  /// reject the other frames' patches as if they had moved. Patches that really moved still
  /// differ by many times that noise; with noise independent from pixel to pixel the ratio is
  /// about 1 and nothing changes. Always, also when the frames moved: for a static camera.
  temporal,
  /// temporal, except against a frame that moved (framesMoved in core/pipeline.h: whole blocks
  /// of the frame shifted against the current one), which keeps its spatial s as in the paper.
  /// Averaging a moved frame's surfaces along the current normals would shift the current
  /// surfaces toward them. Frames whose depth only drifted by a smooth offset along the rays
  /// (analyseFrameChange: FrameChange::offset, an active-stereo camera standing still) are
  /// first brought to their mean level, and then count as not moved. And per pixel (with the
  /// automatic distance bandwidth of the range-adaptive model): a frame gives no weight to a
  /// point whose 3 x 3 surroundings mostly differ from it by more than 3 standard deviations of
  /// the frame-to-frame noise (an object that moved in front of a still scene; docs/method.md,
  /// "A per-pixel test of change"). The default.
  guarded
};

/// Direction along which a point is moved by the filtered normal offset h_i.
enum class Displacement
{
  /// p' = p - h n (the paper): no drift along the surface.
  normal,
  /// p' = p - (h / (n . v)) v with v the unit line of sight from the sensor origin: the point lands
  /// on the same offset plane as with `normal`, but stays on its own camera ray (depth sensors
  /// measure only along the ray). The factor 1/(n . v) is clamped at grazing angles.
  line_of_sight,
  /// line_of_sight where other frames take part (temporal filter), normal for a frame filtered
  /// alone (the default). Along its normal a point keeps the part of its own noise that lies
  /// along the surface's tilt against the normal estimate; filtered alone that part is as noisy
  /// as its neighbours, but with other frames averaged in it is what is left.
  automatic
};

/// Parameters of NonLocalMeansFilter / TemporalNonLocalMeansFilter. Every setter of the filters
/// writes here; `validate()` is the single place where values are checked, against the ranges of
/// the parameter registry (parameter_registry.h), which also names each field for the tools, ROS
/// and the docs.
struct FilterParameters
{
  /// Value of `distance_bandwidth` / `similarity_bandwidth` that requests automatic estimation.
  static constexpr float automatic = 0.0f;

  // The defaults below are the project's recommended setting, measured on generated scenes
  // against ground truth (docs/quality.md; the levers in docs/method.md); paper() gives the
  // literal method (7 / 5 / 1 and no extensions).

  /// S: side of the square search window N(p_i), pixels. Odd, >= 1, no larger than the cloud.
  /// Default 9 (paper: 7).
  int search_window = 9;
  /// P: side of the square similarity patch, pixels. Odd, >= 1, no larger than the cloud.
  /// Default 3 (paper: 5); a small patch keeps points next to an edge similar to their own side.
  int patch_size = 3;
  /// Side of the search window in the other frames of a temporal window (a stream's history or
  /// neighbour frames), pixels: odd; 0, or search_window and wider, = search_window. The current frame
  /// keeps search_window; a neighbour's candidates near i are the same surface seen again, so a
  /// small window there keeps most of the temporal averaging at a fraction of the cost
  /// (docs/method.md, "The live preset"). Default 0 (live: 3).
  int temporal_search_window = 0;
  /// Spacing of the pixels of the search window and of the patches (a dilated window): the
  /// candidates of p_(u,v) are p_(u + a k, v + b k) for |a|, |b| <= S / 2, and the patch offsets
  /// are multiples of k, so that with spatially correlated noise the window reaches past the
  /// noise's correlation length at the same cost. With k > 1 the first iterations - 1 passes
  /// (at least one) filter each phase (u mod k, v mod k) of the frame as a frame of its own, and a
  /// last pass with contiguous windows follows if iterations > 1. 0 = automatic: from the
  /// frame's noise correlation, 1 for independent noise, 2 for correlated noise in a VGA frame
  /// (its correlation length where that is longer, up to 4), 4 from 1280 columns on, more for
  /// strong noise (automaticDilation in core/pipeline.h), and 1 where a phase would be
  /// narrower than the windows. 1 = contiguous windows
  /// (the paper). >= 0, default 0.
  int dilation = 0;
  /// Scales of the multiscale run: with s > 1 the frames are reduced s - 1 times to half their
  /// width and height (each 2 x 2 block the mean of its points on one surface); the coarsest
  /// scale is filtered with these parameters (contiguous windows unless `dilation` is given),
  /// and each finer scale gets the coarser one's range corrections carried up along the rays,
  /// then one pass of its own on the current frame. Noise correlated over L pixels is close to
  /// white at the scale where a pixel covers L, and a pass there costs 1 / 4^(s-1) of one at full
  /// resolution. Fewer scales where the coarsest would be narrower than the windows. 1 = one
  /// scale (the paper). 1 ... 6, default 1.
  int scales = 1;
  /// Number of filter passes; normals and automatic bandwidths are re-estimated before each.
  /// >= 1, default 2 (paper: 1).
  int iterations = 2;
  /// Largest accepted `threads`: OpenMP tries to start every thread asked for, and tens of
  /// thousands of them exhaust the stacks and crash.
  static constexpr int max_threads = 1024;
  /// OpenMP threads; 0 = as many as OpenMP offers. Output does not depend on it.
  /// 0 ... max_threads (1024), default 0.
  int threads = 0;
  /// d: distance bandwidth of Phi_d = exp(-|p_i - p_j|^2 / d^2), cloud units (e.g. metres).
  /// 0 = automatic (d = distance_scale * mu_d, see estimateBandwidths in core/pipeline.h). >= 0, default automatic.
  float distance_bandwidth = automatic;
  /// s: similarity bandwidth of Phi_s = exp(-Sim / s^2), cloud units.
  /// 0 = automatic (s = similarity_scale * sigma_s). >= 0, default automatic.
  float similarity_bandwidth = automatic;
  /// Factor on mu_d (or the window extent) for the automatic d. > 0, default 1.5 (paper: 0.75).
  float distance_scale = 1.5f;
  /// Factor on sigma_s (or the local noise sigma) for the automatic s. > 0, default 3 (paper: 1).
  float similarity_scale = 3.0f;
  /// Range-adaptive model with automatic s: s_i^2 = similarity_spread * spread(rho_i)^2, at most
  /// (similarity_scale * sigma(rho_i))^2, where spread(rho) is the frame's patch spread at that
  /// range: the median over sampled points of a low quantile of Sim(k, j) to the candidates of
  /// their search window, projected on the normals the filter uses (estimatePatchSpread in
  /// src/core/internal.h) -- how far apart the patches of one surface are under this frame's
  /// noise and normal errors. Only in the first pass over the sensor's own noise (not after a
  /// pass, nor in dilated or multiscale runs, where neighbouring patches share their noise).
  /// 0 = off (s = similarity_scale * sigma). >= 0, default 3 (paper: 0): with independent noise
  /// and exact normals s = 2 sigma, up to today's 3 sigma as the normals' tilt errors grow
  /// (measured on the ridges and boxes scenes, docs/quality.md "Small features at low noise").
  float similarity_spread = 3.0f;
  /// Seed of the random sample used to estimate the bandwidths. Same seed, same output.
  std::uint64_t seed = 42;
  /// Largest accepted `bandwidth_samples` (the parameter registry says why).
  static constexpr int max_bandwidth_samples = 100000;
  /// Number of random valid points sampled for the bandwidth estimate (drawn with replacement).
  /// 1 ... max_bandwidth_samples (100000), default 1000.
  int bandwidth_samples = 1000;
  /// Side of the grid neighbourhood of the least-squares plane fit that gives the normals,
  /// pixels. Odd, >= 3. Default 7 (paper: 3, the one-ring).
  int normal_window = 7;
  /// Side of the window of the edge-preserving depth pre-smoothing applied to the copy from
  /// which normals are estimated (not to the output). 0 or 1 = normals from the raw points
  /// (the paper). Odd or 0, default 7.
  int normal_presmooth_window = 7;
  /// Range bandwidth of that pre-smoothing, in units of the estimated noise sigma_s. > 0.
  float normal_presmooth_range = 3.0f;
  /// Gated normals: neighbours farther than this many noise sigmas from a first plane fit through
  /// the point are left out of a second fit (so it does not straddle depth edges or creases);
  /// 0 = off (paper). >= 0, default 3.
  float normal_edge_gate = 3.0f;
  /// Gated patches: pixels of a centre's patch farther than this many noise sigmas from its
  /// tangent plane (|n_i . (p_{i+o} - p_i)|) are left out of Sim(i, j), as holes are, so that a
  /// point next to a depth edge is compared by the part of its patch on its own surface (the
  /// other surface's pixels match no candidate away from the edge and would leave the point
  /// almost unfiltered). 0 = off (paper). >= 0, default 18.
  float patch_edge_gate = 18.0f;
  /// Smallest |cos| between normal and line of sight used by Displacement::line_of_sight: the
  /// ray step h / cos is computed with |cos| bounded below by it (at grazing angles 1 / cos would
  /// amplify any normal error); points always stay on their ray. In [0, 1], default 0.5.
  float line_of_sight_min_cos = 0.5f;
  /// How automatic bandwidths are estimated; see BandwidthModel.
  /// Default range_adaptive (paper: global).
  BandwidthModel bandwidth_model = BandwidthModel::range_adaptive;
  /// Largest displacement of a point, in units of its noise sigma (range_adaptive) or of s
  /// (global); 0 = unlimited (the paper). A denoiser never needs to move a point by many noise
  /// sigmas; larger moves come from normals that straddle a depth edge. >= 0.
  float max_displacement = 0.0f;
  /// Isolated outliers: before filtering, a point of the current frame farther in range than this
  /// many noise sigmas (of the frame's noise profile at its range; at least 3 pixel footprints)
  /// from each of its valid 8-neighbours and from the straight continuation of each neighbour's
  /// line through it (or near only one neighbour that is near none of its own others), and well
  /// beyond the range steps of its 5 x 5 surroundings, is moved along its ray to the median range
  /// of the neighbours that lie on a surface (correctIsolatedPoints in core/pipeline.h). These are
  /// the block
  /// matching mismatches of structured-light sensors and the mixed ("flying") pixels of
  /// time-of-flight cameras at depth edges, which no patch resembles, so that the non-local
  /// weights leave them where they are. No point is removed. 0 = off (the paper). >= 0,
  /// default 10.
  float outlier_sigmas = 10.0f;
  /// Direction of the displacement; see Displacement. Default automatic (paper: normal).
  Displacement displacement = Displacement::automatic;
  /// Similarity bandwidth of the other frames' patches (temporal filter, range-adaptive model
  /// with automatic s); see CrossFrameBandwidth. Default guarded (paper: spatial).
  CrossFrameBandwidth cross_frame_bandwidth = CrossFrameBandwidth::guarded;
  /// With the guarded cross-frame bandwidths: compare the other frames' patches with a patch
  /// guide, per pixel the mean of the current frame and the neighbours that did not move where
  /// the per-pixel test of change found nothing within kGuideMargin pixels and the point itself
  /// is within the test's threshold (FrameTerm::patches; docs/method.md, "The patch guide"),
  /// instead of the current frame's own noisy patch, to which the non-local weights would
  /// otherwise lean. Used when at least three neighbours enter the guide (radius 2 and more;
  /// tuned::kGuideMinFrames in src/core/tuned.h). Default true (paper: false).
  bool patch_guide = true;
  /// Evaluation of the patch similarity; see Evaluation.
  Evaluation evaluation = Evaluation::fast;
  /// Also estimate each output point's uncertainty: the standard deviation of its error along
  /// its direction of movement, metres, from the weights of the passes (docs/method.md, "Per-point
  /// uncertainty"); FilterRun::uncertainty, the filters' getUncertainty(). Off: no work for it and
  /// the same output. Default false.
  bool uncertainty = false;
  /// Hole filling after the filter's last pass: every hole (an 8-connected region of invalid
  /// pixels that does not touch the frame's border) at most this many pixels wide (the widest
  /// of its pixels' shorter run of hole pixels along its row or its column) gets ranges from the
  /// non-local candidates whose patches match its border, on its pixels' rays; a hole on a depth
  /// edge takes the far side's surface, never a value between the sides (docs/method.md, "Hole
  /// filling"). Filled points are reported (FilterRun::filled). 0 = off (the paper). 0 ... 64,
  /// default 0.
  int fill_holes = 0;

  /// Carry what describes the sensor -- the current frame's noise profile and the automatic
  /// dilation -- from one call to the next on the same filter object or stream, instead of
  /// estimating them on every frame: they are estimated afresh when a sparse check of the frame
  /// (its noise at lags 1, R / 2 and R, its range distribution) disagrees with the frame they were
  /// made on beyond the check's sampling error, when the size, viewpoint or a parameter they depend
  /// on changed, and at least every tuned::kReuseMaxFrames frames (docs/method.md, "Estimates
  /// carried in a stream"). An output then depends on the frames before it. Default false (live:
  /// true).
  bool reuse_estimates = false;

  /// Throws std::invalid_argument naming the first invalid parameter (in the order of the fields)
  /// and its value.
  void validate() const;
  /// Throws std::invalid_argument if a window does not fit a width x height cloud.
  void validateFor(int width, int height) const;

  /// The literal method of the paper: 7x7 search, 5x5 patch, one pass, 3x3 normals from the raw
  /// points, motion along the normal, global d = 0.75 mu_d and s = sigma_s.
  static FilterParameters paper();
  /// The project's recommended setting (the defaults above; the default of the tools).
  static FilterParameters recommended();
  /// The setting for live cameras, designed for a frame budget (docs/method.md, "The live
  /// preset"): less accurate than recommended(), about the time of PCL's FastBilateralFilterOMP
  /// per VGA frame. The default of the ROS node.
  static FilterParameters live();
  /// Parameters of a named preset ("default", "live" or "paper"); throws std::invalid_argument
  /// otherwise.
  static FilterParameters preset(const std::string& name);
};

/// The number of threads FilterParameters::threads stands for: `threads` if > 0, else OpenMP's
/// default (1 in a build without OpenMP).
int
threadCount(int threads);

} // namespace range_nlm
