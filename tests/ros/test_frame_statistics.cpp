// FrameStatistics: the rates, latency quantiles and drops the nodelet's diagnostics report.
#include <range_nlm/ros/frame_statistics.h>

#include <gtest/gtest.h>

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
