// range_nlm_bench --uncertainty-calibration: the binning by predicted standard deviation, and the
// calibration of the per-point uncertainty on a generated scene.
#include "uncertainty_calibration.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <sstream>
#include <vector>

using namespace range_nlm;
using namespace range_nlm::tools::uncertainty_calibration;

TEST(CalibrationBins, EqualCountsSortedByPredictionWithRmsPerBin)
{
  // Predictions 4, 3, 2, 1 (one NaN and one unselected point left out), errors twice them.
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const std::vector<float> predicted{4, 3, nan, 2, 1, 7};
  const std::vector<double> error{8, -6, 1, 4, -2, 1};
  const std::vector<unsigned char> selected{1, 1, 1, 1, 1, 0};
  const std::vector<Bin> bins = calibrationBins(predicted, error, selected, 2);
  ASSERT_EQ(bins.size(), 2u);
  EXPECT_EQ(bins[0].points, 2u);
  EXPECT_DOUBLE_EQ(bins[0].predicted, std::sqrt((1.0 + 4.0) / 2));
  EXPECT_DOUBLE_EQ(bins[0].actual, std::sqrt((4.0 + 16.0) / 2));
  EXPECT_DOUBLE_EQ(bins[1].predicted, std::sqrt((9.0 + 16.0) / 2));
  EXPECT_DOUBLE_EQ(bins[1].ratio(), 2.0);
  EXPECT_DOUBLE_EQ(worstRatio(bins), 2.0);
  // More bins than points: one point each.
  EXPECT_EQ(calibrationBins(predicted, error, selected, 10).size(), 4u);
}

TEST(CalibrationBins, TheWorstRatioIsTheFarthestFromOneOnALogScale)
{
  std::vector<Bin> bins(3);
  bins[0] = {1.0, 1.2, 5};
  bins[1] = {1.0, 0.7, 5}; // 1 / 0.7 = 1.43 > 1.2
  bins[2] = {1.0, 1.3, 5};
  EXPECT_DOUBLE_EQ(worstRatio(bins), 0.7);
  EXPECT_TRUE(std::isnan(worstRatio({})));
}

TEST(UncertaintyCalibration, FlatPointsUnderIndependentNoiseAreCalibratedWithin25Percent)
{
  // The steps scene (no detail below the noise, which the estimate cannot see), a frame alone,
  // Kinect-like noise: every decile of the flat points within 25 % (docs/quality.md).
  Options o;
  o.width = 320;
  o.height = 240;
  o.models = {"kinect"};
  o.scenes = {"steps"};
  o.temporal = false;
  o.threads = 2;
  std::ostringstream log;
  const std::vector<Row> rows = run(o, log);
  ASSERT_EQ(rows.size(), 1u);
  ASSERT_EQ(rows[0].flat.size(), 10u);
  for (const Bin& b : rows[0].flat) {
    EXPECT_GT(b.ratio(), 0.75) << b.predicted << " " << b.actual;
    EXPECT_LT(b.ratio(), 1.25) << b.predicted << " " << b.actual;
  }
  // The estimate follows the error over a range of noise levels (near and far surfaces).
  EXPECT_GT(rows[0].flat.back().predicted, 2.5 * rows[0].flat.front().predicted);
}
