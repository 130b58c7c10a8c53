/// \file parameter_setters.h
/// \brief Setters and getters shared by the static and the temporal filter; they write into one
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
  /// Isolated outliers moved onto their neighbours' surface before filtering, in noise sigmas;
  /// 0 = off (default 10; paper preset 0). See FilterParameters::outlier_sigmas.
  void setOutlierSigmas(float sigmas) { parameters_.outlier_sigmas = sigmas; }
  float getOutlierSigmas() const { return parameters_.outlier_sigmas; }
  /// Gated patches: pixels of a point's patch farther than this many noise sigmas from its
  /// tangent plane are left out of the patch comparison; 0 = off (default 18; paper preset 0).
  /// See FilterParameters::patch_edge_gate.
  void setPatchEdgeGate(float sigmas) { parameters_.patch_edge_gate = sigmas; }
  float getPatchEdgeGate() const { return parameters_.patch_edge_gate; }
  /// Displacement along the normal (default) or along the line of sight (the point stays on its
  /// camera ray).
  void setDisplacement(Displacement d) { parameters_.displacement = d; }
  Displacement getDisplacement() const { return parameters_.displacement; }

protected:
  FilterParameters parameters_ = FilterParameters::recommended();
};

} // namespace range_nlm
