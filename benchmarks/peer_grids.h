// The parameter grids of PCL's smoothers that range_nlm is scored against on generated scenes,
// the choice of each grid's best-balanced setting, and the tally of the scenes range_nlm wins:
// shared by range_nlm_bench --real-noise and --generalisation.
#pragma once

#include <range_nlm/eval/metrics.h>
#include <range_nlm/parameters.h>

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <functional>
#include <map>
#include <ostream>
#include <string>
#include <utility>
#include <vector>

namespace range_nlm
{
namespace tools
{
namespace peer_grids
{

using Cloud = pcl::PointCloud<pcl::PointXYZ>;

/// One smoother of a family at one setting.
struct Smoother
{
  std::string family, setting;
  std::function<Cloud(const Cloud&)> apply;
};

/// `v` with `digits` decimals.
std::string
fixed(double v, int digits);
/// Metres as millimetres with two decimals, "-" if not finite.
std::string
mm(double metres);

/// range_nlm's NonLocalMeansFilter with `parameters` (family "range_nlm").
Smoother
rangeNlm(const std::string& setting, const FilterParameters& parameters);
/// pcl::FastBilateralFilter at one setting (family "FastBilateral").
Smoother
fastBilateral(float sigma_s, float sigma_r);
/// FastBilateral with sigma_s 3, 5, 7, 10, 15 px and sigma_r 0.01, 0.03, 0.05, 0.1 m.
std::vector<Smoother>
fastBilateralGrid();
/// pcl::MovingLeastSquares of order 2 with radius 0.02, 0.03, 0.05 m (family "MLS"), on
/// `threads` threads (0 = all cores).
std::vector<Smoother>
mlsGrid(int threads);

/// One smoother's result on a generated scene, scored against the truth.
struct ScoredRow
{
  std::string family, setting;
  FrameMetrics m;
  Cloud result;
};

/// The row of `family` with the smallest flat + feature RMSE (its best-balanced setting),
/// nullptr if the family has no row.
const ScoredRow*
bestBalanced(const std::vector<ScoredRow>& rows, const std::string& family);

/// Per range_nlm setting: the scenes on which it beats both peers' best-balanced settings on
/// flat and on feature RMSE, and its geometric mean RMSE ratios to FastBilateral's.
class WinTally
{
public:
  /// Adds one scene's result of `setting`; returns whether it wins: flat and feature RMSE at
  /// most FastBilateral's best-balanced and, if there is one, MLS's.
  bool add(const std::string& setting, const FrameMetrics& ours, const FrameMetrics& fast_bilateral,
           const FrameMetrics* mls);
  /// One setting's totals: scenes won of scenes, geometric mean flat and feature RMSE ratio to
  /// FastBilateral's best-balanced.
  struct Summary
  {
    std::string setting;
    int won = 0, scenes = 0;
    double flat_ratio = 0.0, feature_ratio = 0.0;
  };
  /// The totals of each setting of `settings` that has scenes, in that order.
  std::vector<Summary> summaries(const std::vector<std::string>& settings) const;
  /// The Markdown summary table, one line per setting of `settings` that has scenes: "N of M",
  /// flat and feature ratio; `scenes` names what was won ("scenes", "cells"), `peers` what a win
  /// is against (e.g. "FastBilateral and MLS").
  void print(std::ostream& report, const std::vector<std::string>& settings, const std::string& scenes,
             const std::string& peers) const;

private:
  struct Count
  {
    int won = 0, scenes = 0;
    double log_flat = 0.0, log_feature = 0.0;
  };
  std::map<std::string, Count> counts_;
};

} // namespace peer_grids
} // namespace tools
} // namespace range_nlm
