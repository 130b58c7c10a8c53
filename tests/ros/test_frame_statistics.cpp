// FrameStatistics: the rates, latency quantiles and drops the nodelet's diagnostics report.
#include <range_nlm/ros/frame_statistics.h>

#include <gtest/gtest.h>

#include <limits>

using range_nlm_ros::FrameStatistics;

TEST(FrameStatistics, RatesLatencyAndDropsOverOnePeriod)
{
  FrameStatistics statistics(100.0);
  for (int i = 0; i < 30; ++i)
    statistics.received();
  // 20 frames published with latencies 10, 20, ..., 200 ms; 10 dropped.
  for (int i = 1; i <= 20; ++i)
    statistics.published(i * 0.010, 40.0 + i);
  for (int i = 0; i < 10; ++i)
    statistics.dropped();
  const FrameStatistics::Summary s = statistics.summarize(102.0);
  EXPECT_DOUBLE_EQ(s.seconds, 2.0);
  EXPECT_DOUBLE_EQ(s.input_hz, 15.0);
  EXPECT_DOUBLE_EQ(s.output_hz, 10.0);
  EXPECT_NEAR(s.latency_median_ms, 100.0, 1e-9); // rank ceil(0.5 * 20) = 10
  EXPECT_NEAR(s.latency_p95_ms, 190.0, 1e-9);    // rank 19
  EXPECT_DOUBLE_EQ(s.filter_median_ms, 50.0);
  EXPECT_EQ(s.dropped, 10u);
  EXPECT_EQ(s.dropped_total, 10u);
  EXPECT_EQ(s.published_total, 20u);
}

TEST(FrameStatistics, ANewPeriodStartsEmptyButKeepsTheTotals)
{
  FrameStatistics statistics(0.0);
  statistics.received();
  statistics.published(0.05, 30.0);
  statistics.dropped();
  statistics.summarize(1.0);
  statistics.dropped();
  const FrameStatistics::Summary s = statistics.summarize(3.0);
  EXPECT_DOUBLE_EQ(s.seconds, 2.0);
  EXPECT_DOUBLE_EQ(s.input_hz, 0.0);
  EXPECT_DOUBLE_EQ(s.output_hz, 0.0);
  EXPECT_DOUBLE_EQ(s.latency_median_ms, 0.0);
  EXPECT_EQ(s.dropped, 1u);
  EXPECT_EQ(s.dropped_total, 2u);
  EXPECT_EQ(s.published_total, 1u);
}

TEST(FrameStatistics, QuantileByNearestRank)
{
  std::vector<double> values = {5, 1, 4, 2, 3};
  EXPECT_EQ(range_nlm_ros::quantile(values, 0.0), 1);
  EXPECT_EQ(range_nlm_ros::quantile(values, 0.5), 3);
  EXPECT_EQ(range_nlm_ros::quantile(values, 0.95), 5);
  std::vector<double> none;
  EXPECT_EQ(range_nlm_ros::quantile(none, 0.5), 0);
}

TEST(FrameStatistics, StampsOnAnotherClockGiveNoLatencyButCountAsPublished)
{
  FrameStatistics statistics(0.0);
  // A bag's stamps near 0 against the wall clock (the node without use_sim_time), a stamp in the
  // future, one not finite, and two measured ones.
  statistics.published(1.8e9, 40.0);
  statistics.published(-5.0, 40.0);
  statistics.published(std::numeric_limits<double>::quiet_NaN(), 40.0);
  statistics.published(0.030, 40.0);
  statistics.published(0.050, 40.0);
  const FrameStatistics::Summary s = statistics.summarize(1.0);
  EXPECT_DOUBLE_EQ(s.output_hz, 5.0);
  EXPECT_EQ(s.latency_frames, 2u);
  EXPECT_EQ(s.stamps_off_clock, 3u);
  EXPECT_NEAR(s.latency_median_ms, 30.0, 1e-9);
  EXPECT_NEAR(s.latency_p95_ms, 50.0, 1e-9);
  EXPECT_EQ(s.published_total, 5u);
  // The next period starts with none off the clock.
  statistics.published(0.020, 40.0);
  const FrameStatistics::Summary next = statistics.summarize(2.0);
  EXPECT_EQ(next.stamps_off_clock, 0u);
  EXPECT_EQ(next.latency_frames, 1u);
  EXPECT_NEAR(next.latency_median_ms, 20.0, 1e-9);
}
