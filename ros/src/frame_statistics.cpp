#include <range_nlm/ros/frame_statistics.h>

#include <algorithm>
#include <cmath>

namespace range_nlm_ros
{

double
quantile(std::vector<double>& values, double q)
{
  if (values.empty())
    return 0.0;
  const std::size_t rank = static_cast<std::size_t>(std::ceil(q * static_cast<double>(values.size())));
  const std::size_t index = std::min(values.size() - 1, rank == 0 ? 0 : rank - 1);
  std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(index), values.end());
  return values[index];
}

void
FrameStatistics::published(double latency_s, double filter_ms)
{
  ++published_total_;
  ++published_;
  if (std::isfinite(latency_s) && latency_s >= earliest_latency_s && latency_s <= latest_latency_s)
    latencies_ms_.push_back(latency_s * 1000.0);
  else
    ++off_clock_;
  filter_ms_.push_back(filter_ms);
}

FrameStatistics::Summary
FrameStatistics::summarize(double now)
{
  Summary s;
  s.seconds = now - period_start_;
  if (s.seconds > 0.0) {
    s.input_hz = static_cast<double>(received_) / s.seconds;
    s.output_hz = static_cast<double>(published_) / s.seconds;
  }
  s.latency_median_ms = quantile(latencies_ms_, 0.5);
  s.latency_p95_ms = quantile(latencies_ms_, 0.95);
  s.latency_frames = latencies_ms_.size();
  s.stamps_off_clock = off_clock_;
  s.filter_median_ms = quantile(filter_ms_, 0.5);
  s.dropped = dropped_;
  s.dropped_total = dropped_total_;
  s.published_total = published_total_;
  period_start_ = now;
  received_ = dropped_ = published_ = off_clock_ = 0;
  latencies_ms_.clear();
  filter_ms_.clear();
  return s;
}

} // namespace range_nlm_ros
