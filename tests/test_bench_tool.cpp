// range_nlm_bench end to end: the rows it times and its option checks.
#include "test_support.h"

#include <gtest/gtest.h>

#include <string>

using namespace range_nlm;

TEST(BenchTool, NoDirectTimesTheFastPathAndThePeersOnly)
{
  if (test::kAddressSanitizer)
    GTEST_SKIP() << "under AddressSanitizer Eigen's aligned allocator differs between this build and "
                    "Debian's PCL, so the cloud pcl::MovingLeastSquares resizes cannot be freed here";
  const test::CommandResult r =
      test::runTool("range_nlm_bench", "--config static --preset paper --runs 1 --no-direct --json");
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("\"method\": \"range_nlm fast\""), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("\"method\": \"pcl FastBilateralFilterOMP\""), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("\"method\": \"pcl MovingLeastSquares\""), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("range_nlm direct"), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("\"error\""), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("\"median_ms\": 0,"), std::string::npos) << r.output;
}

TEST(BenchTool, RejectsContradictoryDirectOptions)
{
  const test::CommandResult r = test::runTool("range_nlm_bench", "--all --no-direct");
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_NE(r.output.find("--all and --no-direct"), std::string::npos) << r.output;
}
