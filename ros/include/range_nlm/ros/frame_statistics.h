/// \file frame_statistics.h
/// \brief What the nodelet's diagnostics report, counted as frames come and go: input and
/// output rates, latency (header stamp to publication) and frames dropped, over the period
/// since the last summary.
#pragma once

#include <cstddef>
#include <vector>

namespace range_nlm_ros
{

class FrameStatistics
{
public:
  /// One period's figures. Rates are 0 when the period is empty; the latency and filter
  /// quantiles are 0 when nothing was published in it.
  struct Summary
  {
    double seconds = 0.0;
    double input_hz = 0.0;
    double output_hz = 0.0;
    double latency_median_ms = 0.0;
    double latency_p95_ms = 0.0;
    double filter_median_ms = 0.0;
    std::size_t dropped = 0;
    std::size_t dropped_total = 0;
    std::size_t published_total = 0;
  };

  /// Starts the first period at `now` (seconds, any clock the caller keeps using).
  explicit FrameStatistics(double now = 0.0) : period_start_(now) {}

  /// A message arrived.
  void received() { ++received_; }
  /// A frame was published `latency_s` after its stamp; the filter took `filter_ms` for it.
  void published(double latency_s, double filter_ms);
  /// A message was dropped (invalid, or not filtered).
  void dropped()
  {
    ++dropped_;
    ++dropped_total_;
  }
  /// The figures since the previous call (or construction), and a new period from `now`.
  Summary summarize(double now);

private:
  double period_start_;
  std::size_t received_ = 0, dropped_ = 0, dropped_total_ = 0, published_total_ = 0;
  std::vector<double> latencies_ms_, filter_ms_;
};

/// The q-quantile (0 <= q <= 1) of `values` by the nearest rank; 0 if empty. Reorders them.
double
quantile(std::vector<double>& values, double q);

} // namespace range_nlm_ros
