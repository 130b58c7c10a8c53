/// \file parameter_setters.h
/// \brief Setters and getters shared by the static and the temporal filter, one pair for every
/// field of FilterParameters (every entry of parameter_registry.h); they write into one
/// FilterParameters, validated when filtering.
#pragma once

#include <range_nlm/parameters.h>

namespace range_nlm
{

class ParameterSetters
{
public:
  /// All parameters at once (validated when filtering). The setters below change one field each;
  /// the initial values are FilterParameters::recommended().
  void setParameters(const FilterParameters& p) { parameters_ = p; }
  const FilterParameters& getParameters() const { return parameters_; }

  /// S, side of the search window, odd, pixels (default 9; paper preset 7).
  void setSearchWindowSize(int s) { parameters_.search_window = s; }
  int getSearchWindowSize() const { return parameters_.search_window; }
  /// See FilterParameters::temporal_search_window.
  void setTemporalSearchWindowSize(int s) { parameters_.temporal_search_window = s; }
  int getTemporalSearchWindowSize() const { return parameters_.temporal_search_window; }
  /// P, side of the similarity patch, odd, pixels (default 3; paper preset 5).
  void setPatchSize(int p) { parameters_.patch_size = p; }
  int getPatchSize() const { return parameters_.patch_size; }
  /// Filter passes; normals and automatic bandwidths are re-estimated before each (default 2;
  /// paper preset 1).
  void setIterations(int n) { parameters_.iterations = n; }
  int getIterations() const { return parameters_.iterations; }
  /// OpenMP threads, 0 = all (default). Output is independent of it.
  void setNumberOfThreads(int n) { parameters_.threads = n; }
  int getNumberOfThreads() const { return parameters_.threads; }
  /// d in cloud units; 0 = automatic (default).
  void setDistanceBandwidth(float d) { parameters_.distance_bandwidth = d; }
  float getDistanceBandwidth() const { return parameters_.distance_bandwidth; }
  /// s in cloud units; 0 = automatic (default).
  void setSimilarityBandwidth(float s) { parameters_.similarity_bandwidth = s; }
  float getSimilarityBandwidth() const { return parameters_.similarity_bandwidth; }
  /// Seed of the bandwidth sample (default 42).
  void setSeed(std::uint64_t seed) { parameters_.seed = seed; }
  std::uint64_t getSeed() const { return parameters_.seed; }
  /// Side of the normal-estimation neighbourhood, odd >= 3 (default 7; paper preset 3, the
  /// one-ring).
  void setNormalWindowSize(int n) { parameters_.normal_window = n; }
  int getNormalWindowSize() const { return parameters_.normal_window; }
  /// Fast (windowed: each window point projected once per pixel, the patch pairs summed in
  /// vector registers; default) or direct (the literal formula, the reference) evaluation. Both
  /// give the same result to float precision.
  void setEvaluation(Evaluation e) { parameters_.evaluation = e; }
  Evaluation getEvaluation() const { return parameters_.evaluation; }
  /// Widest hole (pixels) filled after the last pass, 0 = off (the default). See
  /// FilterParameters::fill_holes.
  void setFillHoles(int max_width) { parameters_.fill_holes = max_width; }
  int getFillHoles() const { return parameters_.fill_holes; }
  /// Isolated outliers moved onto their neighbours' surface before filtering, in noise sigmas;
  /// 0 = off (default 10; paper preset 0). See FilterParameters::outlier_sigmas.
  void setOutlierSigmas(float sigmas) { parameters_.outlier_sigmas = sigmas; }
  float getOutlierSigmas() const { return parameters_.outlier_sigmas; }
  /// Gated patches: pixels of a point's patch farther than this many noise sigmas from its
  /// tangent plane are left out of the patch comparison; 0 = off (default 18; paper preset 0).
  /// See FilterParameters::patch_edge_gate.
  void setPatchEdgeGate(float sigmas) { parameters_.patch_edge_gate = sigmas; }
  float getPatchEdgeGate() const { return parameters_.patch_edge_gate; }
  /// Displacement along the normal, along the line of sight (the point stays on its camera ray),
  /// or automatic: along the line of sight where other frames take part, along the normal for a
  /// frame filtered alone (default; paper preset normal).
  void setDisplacement(Displacement d) { parameters_.displacement = d; }
  Displacement getDisplacement() const { return parameters_.displacement; }

  /// Spacing k of the search window's and patches' pixels; 0 = automatic (default; paper preset
  /// 1). See FilterParameters::dilation.
  void setDilation(int k) { parameters_.dilation = k; }
  int getDilation() const { return parameters_.dilation; }
  /// Scales of the multiscale run (1 = one scale). See FilterParameters::scales.
  void setScales(int scales) { parameters_.scales = scales; }
  int getScales() const { return parameters_.scales; }
  /// Factor on mu_d (or the window extent) for the automatic d, > 0 (default 1.5; paper preset
  /// 0.75).
  void setDistanceScale(float f) { parameters_.distance_scale = f; }
  float getDistanceScale() const { return parameters_.distance_scale; }
  /// Factor on sigma_s (or the local noise sigma) for the automatic s, > 0 (default 3; paper
  /// preset 1).
  void setSimilarityScale(float f) { parameters_.similarity_scale = f; }
  float getSimilarityScale() const { return parameters_.similarity_scale; }
  /// s^2 from the frame's patch spread, this many times its square, at most the scale's s (0 = off;
  /// default 3, paper preset 0). See FilterParameters::similarity_spread.
  void setSimilaritySpread(float f) { parameters_.similarity_spread = f; }
  float getSimilaritySpread() const { return parameters_.similarity_spread; }
  /// Random valid points sampled for the automatic bandwidths, >= 1 (default 1000).
  void setBandwidthSamples(int n) { parameters_.bandwidth_samples = n; }
  int getBandwidthSamples() const { return parameters_.bandwidth_samples; }
  /// Side of the edge-preserving pre-smoothing of the copy the normals come from, odd, pixels;
  /// 0 or 1 = normals from the raw points (default 7; paper preset 0).
  void setNormalPresmoothWindowSize(int n) { parameters_.normal_presmooth_window = n; }
  int getNormalPresmoothWindowSize() const { return parameters_.normal_presmooth_window; }
  /// Range bandwidth of that pre-smoothing in noise sigmas, > 0 (default 3).
  void setNormalPresmoothRange(float sigmas) { parameters_.normal_presmooth_range = sigmas; }
  float getNormalPresmoothRange() const { return parameters_.normal_presmooth_range; }
  /// Gated normals: neighbours farther than this many noise sigmas from a first plane fit are
  /// left out of a second fit; 0 = off (default 3; paper preset 0).
  void setNormalEdgeGate(float sigmas) { parameters_.normal_edge_gate = sigmas; }
  float getNormalEdgeGate() const { return parameters_.normal_edge_gate; }
  /// Smallest |cos(normal, ray)| of the ray step of Displacement::line_of_sight, in [0, 1]
  /// (default 0.5).
  void setLineOfSightMinCos(float c) { parameters_.line_of_sight_min_cos = c; }
  float getLineOfSightMinCos() const { return parameters_.line_of_sight_min_cos; }
  /// How the automatic bandwidths are estimated (default range_adaptive; paper preset global).
  void setBandwidthModel(BandwidthModel m) { parameters_.bandwidth_model = m; }
  BandwidthModel getBandwidthModel() const { return parameters_.bandwidth_model; }
  /// Largest move of a point in noise sigmas (range_adaptive) or in s (global); 0 = unlimited
  /// (default).
  void setMaxDisplacement(float sigmas) { parameters_.max_displacement = sigmas; }
  float getMaxDisplacement() const { return parameters_.max_displacement; }
  /// Similarity bandwidth of the other frames' patches in the temporal filter (default guarded;
  /// paper preset spatial).
  void setCrossFrameBandwidth(CrossFrameBandwidth b) { parameters_.cross_frame_bandwidth = b; }
  CrossFrameBandwidth getCrossFrameBandwidth() const { return parameters_.cross_frame_bandwidth; }
  /// Guarded temporal runs: compare the other frames' patches with the patch guide (default
  /// true; paper preset false). See FilterParameters::patch_guide.
  void setPatchGuide(bool on) { parameters_.patch_guide = on; }
  bool getPatchGuide() const { return parameters_.patch_guide; }
  /// Carry the noise profile and the automatic dilation from frame to frame (default false; live
  /// preset true). See FilterParameters::reuse_estimates.
  void setReuseEstimates(bool on) { parameters_.reuse_estimates = on; }
  bool getReuseEstimates() const { return parameters_.reuse_estimates; }
  /// Also estimate each output point's uncertainty (default false). See
  /// FilterParameters::uncertainty.
  void setEstimateUncertainty(bool on) { parameters_.uncertainty = on; }
  bool getEstimateUncertainty() const { return parameters_.uncertainty; }

protected:
  FilterParameters parameters_ = FilterParameters::recommended();
};

} // namespace range_nlm
