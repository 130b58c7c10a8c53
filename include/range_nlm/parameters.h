/// \file parameters.h
/// \brief All parameters of the non-local range filter, with units, defaults and valid ranges.
#pragma once

#include <cstdint>
#include <string>

namespace range_nlm
{

/// How the patch similarity Sim(i, j) is evaluated. Both give the same result to float precision.
enum class Evaluation
{
  /// Box-filtered similarity: for each shift delta the entries of D D^T (D = p_u - p_{u+delta})
  /// are box-filtered over the patch once for all pixels. Cost ~ S^2 per point, independent of P.
  fast,
  /// Literal evaluation of the formula: S^2 * P^2 operations per point. Kept as the reference.
  direct
};

/// Direction along which a point is moved by the filtered normal offset h_i.
enum class Displacement
{
  /// p' = p - h n (the paper): no drift along the surface.
  normal,
  /// p' = p - (h / (n . v)) v with v the unit line of sight from the sensor origin: the point lands
  /// on the same offset plane as with `normal`, but stays on its own camera ray (depth sensors
  /// measure only along the ray). The factor 1/(n . v) is clamped at grazing angles.
  line_of_sight
};

/// Parameters of NonLocalMeansFilter / TemporalNonLocalMeansFilter. Every setter of the filters
/// writes here; `validate()` is the single place where values are checked.
struct FilterParameters
{
  /// Value of `distance_bandwidth` / `similarity_bandwidth` that requests automatic estimation.
  static constexpr float automatic = 0.0f;

  /// S: side of the square search window N(p_i), pixels. Odd, >= 1, no larger than the cloud.
  /// Default 7 (paper, laser scans).
  int search_window = 7;
  /// P: side of the square similarity patch, pixels. Odd, >= 1, no larger than the cloud. Default 5.
  int patch_size = 5;
  /// Number of filter passes; normals (and automatic bandwidths) are re-estimated before each.
  /// >= 1, default 1.
  int iterations = 1;
  /// OpenMP threads; 0 = as many as OpenMP offers. Output does not depend on it. >= 0, default 0.
  int threads = 0;
  /// d: distance bandwidth of Phi_d = exp(-|p_i - p_j|^2 / d^2), cloud units (e.g. metres).
  /// 0 = automatic (d = distance_scale * mu_d, see bandwidth.h). >= 0, default automatic.
  float distance_bandwidth = automatic;
  /// s: similarity bandwidth of Phi_s = exp(-Sim / s^2), cloud units.
  /// 0 = automatic (s = similarity_scale * sigma_s). >= 0, default automatic.
  float similarity_bandwidth = automatic;
  /// Factor on mu_d for the automatic d (paper: 0.75). > 0.
  float distance_scale = 0.75f;
  /// Factor on sigma_s for the automatic s (paper: 1). > 0.
  float similarity_scale = 1.0f;
  /// Seed of the random sample used to estimate the bandwidths. Same seed, same output.
  std::uint64_t seed = 42;
  /// Number of random valid points sampled for the bandwidth estimate. >= 1, default 1000.
  int bandwidth_samples = 1000;
  /// Side of the grid neighbourhood of the least-squares plane fit that gives the normals,
  /// pixels. Odd, >= 3. Default 3 (the one-ring, as in the paper).
  int normal_window = 3;
  /// Side of the window of the edge-preserving depth pre-smoothing applied to the copy from
  /// which normals are estimated (not to the output). 0 or 1 = normals from the raw points
  /// (the paper). Odd or 0.
  int normal_presmooth_window = 0;
  /// Range bandwidth of that pre-smoothing, in units of the estimated noise sigma_s. > 0.
  float normal_presmooth_range = 3.0f;
  /// Direction of the displacement; see Displacement.
  Displacement displacement = Displacement::normal;
  /// Evaluation of the patch similarity; see Evaluation.
  Evaluation evaluation = Evaluation::fast;

  /// Throws std::invalid_argument naming the first invalid parameter and its value.
  void validate() const;
  /// Throws std::invalid_argument if a window does not fit a width x height cloud.
  void validateFor(int width, int height) const;

  /// The literal method of the paper: 3x3 normals from the raw points, motion along the normal,
  /// d = 0.75 mu_d, s = sigma_s.
  static FilterParameters paper();
  /// The project's recommended setting (the default of the tools).
  static FilterParameters recommended();
  /// Parameters of a named preset ("paper" or "default"); throws std::invalid_argument otherwise.
  static FilterParameters preset(const std::string& name);
};

} // namespace range_nlm
