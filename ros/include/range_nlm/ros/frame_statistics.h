/// \file frame_statistics.h
/// \brief What the nodelet's diagnostics report, counted as frames come and go: input and
/// output rates, latency (header stamp to publication) and frames dropped, over the period
/// since the last summary.
///
/// The latency is measured against the clock the node runs on (ros::Time::now(): /clock under
/// use_sim_time). A stamp from another clock (a bag played without --clock, or under
/// use_sim_time before the first /clock) gives no latency; such frames are counted apart, so
/// that the quantiles hold real latencies only.
#pragma once

#include <cstddef>
#include <vector>

namespace range_nlm_ros
{

class FrameStatistics
{
public:
  /// The latencies taken as measured: from a moment before the stamp (clocks of two machines
  /// differ a little) to a minute after it. Anything else is a stamp on another clock.
  static constexpr double earliest_latency_s = -1.0;
  static constexpr double latest_latency_s = 60.0;

  /// One period's figures. Rates are 0 when the period is empty; the latency and filter
  /// quantiles are 0 when nothing was published in it (latency: nothing with a stamp on the
  /// node's clock, `latency_frames` 0).
  struct Summary
  {
    double seconds = 0.0;
    double input_hz = 0.0;
    double output_hz = 0.0;
    double latency_median_ms = 0.0;
    double latency_p95_ms = 0.0;
    /// Frames whose latency was measured, and frames whose stamp is on another clock.
    std::size_t latency_frames = 0;
    std::size_t stamps_off_clock = 0;
    double filter_median_ms = 0.0;
    std::size_t dropped = 0;
    std::size_t dropped_total = 0;
    std::size_t published_total = 0;
  };

  /// Starts the first period at `now` (seconds, any clock the caller keeps using).
  explicit FrameStatistics(double now = 0.0) : period_start_(now) {}

  /// A message arrived.
  void received() { ++received_; }
  /// A frame was published `latency_s` after its stamp (now - stamp on the node's clock); the
  /// filter took `filter_ms` for it. A latency outside [earliest_latency_s, latest_latency_s],
  /// or not finite, counts as a stamp off the clock.
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
  std::size_t received_ = 0, dropped_ = 0, dropped_total_ = 0, published_total_ = 0, published_ = 0,
              off_clock_ = 0;
  std::vector<double> latencies_ms_, filter_ms_;
};

/// The q-quantile (0 <= q <= 1) of `values` by the nearest rank; 0 if empty. Reorders them.
double
quantile(std::vector<double>& values, double q);

} // namespace range_nlm_ros
