// range_nlm_bench --accuracy-time: every method timed and scored on a generated and a real frame,
// and options that cannot run refused with the field named.
#include "accuracy_time.h"
#include "test_support.h"

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <sstream>
#include <stdexcept>
#include <string>

using namespace range_nlm::tools::accuracy_time;

namespace
{
Options
smallOptions()
{
  Options o;
  o.width = 96;
  o.height = 72;
  o.runs = 2;
  o.threads = 2;
  return o;
}

void
expectRefused(const Options& o, const std::string& named)
{
  try {
    validate(o);
    ADD_FAILURE() << "accepted; expected a refusal naming " << named;
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find(named), std::string::npos) << e.what();
  }
}
} // namespace

TEST(AccuracyTime, EveryMethodIsTimedAndTheFilterBeatsTheNoisyInput)
{
  if (range_nlm::test::kAddressSanitizer)
    GTEST_SKIP() << "runs PCL's MovingLeastSquares, whose uninstrumented Debian build resizes clouds that an "
                    "AddressSanitizer build cannot free";
  std::ostringstream log;
  const std::vector<Row> rows = run(smallOptions(), log);
  ASSERT_EQ(rows.size(), 10u); // the input, 3 presets, 3 FastBilateral settings, 3 MLS radii
  EXPECT_EQ(rows[0].family, "input");
  EXPECT_TRUE(rows[0].samples_ms.empty());
  std::map<std::string, int> families;
  for (std::size_t i = 1; i < rows.size(); ++i) {
    const Row& r = rows[i];
    ++families[r.family];
    EXPECT_EQ(r.samples_ms.size(), 2u) << r.setting;
    EXPECT_GT(r.median_ms, 0.0) << r.setting;
    EXPECT_TRUE(std::isfinite(r.accuracy_mm)) << r.setting;
    EXPECT_EQ(r.frame, rows[0].frame);
  }
  EXPECT_EQ(families["range_nlm"], 3);
  EXPECT_EQ(families["FastBilateral"], 3);
  EXPECT_EQ(families["MLS"], 3);
  // Every preset smooths the flat parts of the stereo-noise frame.
  for (std::size_t i = 1; i <= 3; ++i)
    EXPECT_LT(rows[i].accuracy_mm, rows[0].accuracy_mm) << rows[i].setting;

  std::ostringstream json;
  printJson(rows, smallOptions(), json);
  EXPECT_NE(json.str().find("\"accuracy_time\""), std::string::npos);
  EXPECT_NE(json.str().find("\"median_ms\": null"), std::string::npos); // the input row has no time
}

TEST(AccuracyTime, TheRealFrameIsScoredByItsPlanes)
{
  if (range_nlm::test::kAddressSanitizer)
    GTEST_SKIP() << "runs PCL's MovingLeastSquares, whose uninstrumented Debian build resizes clouds that an "
                    "AddressSanitizer build cannot free";
  Options o = smallOptions();
  o.runs = 1;
  o.real_frame = RANGE_NLM_SOURCE_DIR "/data/depth-images/realsense-d415-vcl3d/0_M11_depth_0.png";
  std::ostringstream log;
  const std::vector<Row> rows = run(o, log);
  ASSERT_EQ(rows.size(), 20u);
  EXPECT_EQ(rows[10].frame, "0_M11_depth_0.png");
  EXPECT_EQ(rows[10].family, "input");
  EXPECT_EQ(rows[11].setting, "default");
  EXPECT_LT(rows[11].accuracy_mm, rows[10].accuracy_mm);
}

TEST(AccuracyTime, OptionsThatCannotRunAreRefusedByName)
{
  Options o = smallOptions();
  o.runs = 0;
  expectRefused(o, "runs");
  o = smallOptions();
  o.width = 8;
  expectRefused(o, "frame size");
  o = smallOptions();
  o.model = "sonar";
  expectRefused(o, "sonar");
  o = smallOptions();
  o.real_frame = "/nonexistent/frame.pcd";
  expectRefused(o, "/nonexistent/frame.pcd");
}
