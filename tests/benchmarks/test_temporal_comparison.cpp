// The static real-sequence part of range_nlm_bench --temporal-comparison (runStatic), on a
// generated static sequence written as PCD files: its rows, the jitter it reports, the holes
// librealsense's filter fills, and the table and JSON it prints.
#include "temporal_comparison.h"
#include "test_support.h"

#include <range_nlm/eval/metrics.h>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <pcl/io/pcd_io.h>

#include <cmath>
#include <filesystem>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include <unistd.h>

using namespace range_nlm;
namespace temporal = range_nlm::tools::temporal;
namespace fs = std::filesystem;

TEST(TemporalComparison, StaticSequenceRowsAndLibrealsenseFills)
{
  if (test::kAddressSanitizer)
    GTEST_SKIP() << "under AddressSanitizer Eigen's aligned allocator differs between this build and "
                    "Debian's PCL, so clouds pcl::FastBilateralFilter resizes cannot be freed here";
  const int w = 96, h = 72;
  const fs::path dir = fs::temp_directory_path() / ("range_nlm_temporal_comparison_" + std::to_string(::getpid())) / "static";
  fs::create_directories(dir);
  std::vector<pcl::PointCloud<pcl::PointXYZ>> frames;
  temporal::Options options;
  options.threads = 1;
  options.static_sequences.emplace_back();
  for (int k = 0; k < 3; ++k) {
    // A plane at 1 m with 3 mm noise, new each frame; 10 holes in the last frame only.
    pcl::PointCloud<pcl::PointXYZ> c = test::makeCloud(w, h, test::plane(Eigen::Vector3d(0, 0, 1), 1.0), 0.003, 40 + k);
    if (k == 2)
      for (int i = 0; i < 10; ++i) {
        const float nan = std::numeric_limits<float>::quiet_NaN();
        c[std::size_t(500 + 37 * i)] = pcl::PointXYZ(nan, nan, nan);
      }
    const std::string path = (dir / (std::to_string(k) + ".pcd")).string();
    ASSERT_EQ(pcl::io::savePCDFileBinary(path, c), 0);
    frames.push_back(c);
    options.static_sequences.back().push_back(path);
  }
  std::ostringstream log;
  const std::vector<temporal::StaticSequenceResult> results = temporal::runStatic(options, log);
  ASSERT_EQ(results.size(), 1u);
  const temporal::StaticSequenceResult& r = results.front();
  EXPECT_EQ(r.name, "static");
  EXPECT_EQ(r.raw_pixels, std::size_t(w * h - 10));
  std::vector<std::string> methods;
  for (const temporal::JitterRow& row : r.rows)
    methods.push_back(row.method);
  const std::vector<std::string> expected{
      "raw",
      "FastBilateral per frame (sigma_s 5, sigma_r 0.03)",
      "FastBilateral per frame (sigma_s 15, sigma_r 0.05)",
      "range_nlm per frame (default)",
      "range_nlm per frame (default), PNG output",
      "range_nlm temporal, radius 1",
      "range_nlm temporal, radius 1, PNG output",
      "range_nlm temporal, radius 1, causal",
      "range_nlm temporal, radius 1, causal, PNG output",
      "range_nlm temporal, radius 1, recursive",
      "range_nlm temporal, radius 1, recursive, PNG output",
      "range_nlm temporal, radius 1, cross-frame temporal",
      "range_nlm temporal, radius 1, cross-frame temporal, PNG output",
      "range_nlm temporal, radius 1, recursive, cross-frame temporal",
      "range_nlm temporal, radius 1, recursive, cross-frame temporal, PNG output",
      "range_nlm live per frame",
      "range_nlm live per frame, PNG output",
      "range_nlm live temporal, radius 1, recursive",
      "range_nlm live temporal, radius 1, recursive, PNG output",
      "librealsense temporal (alpha 0.4, delta 20, persistency 3)",
      "librealsense temporal (alpha 0.1, delta 20, persistency 3)",
      "librealsense temporal (alpha 0.4, delta 100, persistency 3)"};
  ASSERT_EQ(methods, expected);

  // The raw row is the library's jitter of the frames.
  const TemporalJitter raw = temporalJitter(frames);
  EXPECT_DOUBLE_EQ(r.rows[0].common.median, raw.median);
  EXPECT_EQ(r.rows[0].own.pixels, r.raw_pixels);
  // 3 mm noise is far below delta 20 mm: the moving average steadies every pixel.
  const std::size_t librealsense = 19; // the first librealsense row of `expected`
  const temporal::JitterRow& rs = r.rows[librealsense];
  EXPECT_LT(rs.common.median, 0.7 * raw.median) << rs.common.median << " against raw " << raw.median;
  // The holes of the last frame were valid in the 2 frames before: persistency 3 fills them.
  EXPECT_EQ(rs.own.pixels, std::size_t(w * h));
  EXPECT_EQ(rs.common.pixels, r.raw_pixels);
  // range_nlm's temporal filter steadies the plane too, and leaves the holes.
  EXPECT_LT(r.rows[5].common.median, 0.7 * raw.median);
  EXPECT_EQ(r.rows[5].own.pixels, r.raw_pixels);
  EXPECT_GT(r.regions, 0u);
  EXPECT_LT(r.rows[5].last_frame_refit.interior_rms, r.rows[0].last_frame_refit.interior_rms);
  // Each range_nlm row's PNG output (PCD frames: 5000 values per metre) is as steady as the PCD
  // output, within 2 % and the 16-bit rounding's own jitter (0.2 mm / sqrt(12)).
  for (std::size_t m = 3; m <= 17; m += 2) {
    const temporal::JitterRow& pcd = r.rows[m];
    const temporal::JitterRow& png = r.rows[m + 1];
    EXPECT_NEAR(png.common.median, pcd.common.median, 0.02 * pcd.common.median + 0.2e-3 / std::sqrt(12.0))
        << png.method;
    EXPECT_EQ(png.own.pixels, pcd.own.pixels) << png.method;
  }

  std::ostringstream table, json;
  temporal::printTable({}, results, options, table);
  EXPECT_NE(table.str().find("| librealsense temporal (alpha 0.4, delta 20, persistency 3) |"), std::string::npos)
      << table.str();
  temporal::printJson({}, results, json);
  const nlohmann::json j = nlohmann::json::parse(json.str());
  ASSERT_EQ(j.at("real_static").size(), 1u);
  EXPECT_EQ(j["real_static"][0]["rows"].size(), expected.size());
  EXPECT_EQ(j["real_static"][0]["rows"][librealsense]["own_pixels"], w * h);
  EXPECT_NEAR(j["real_static"][0]["rows"][0]["median_jitter_mm"].get<double>(), 1000 * raw.median, 1e-6);
  fs::remove_all(dir.parent_path());
}

TEST(TemporalComparison, StaticSequenceOfOneFrameIsRefused)
{
  temporal::Options options;
  options.static_sequences = {{"only.pcd"}};
  std::ostringstream log;
  try {
    temporal::runStatic(options, log);
    ADD_FAILURE() << "a one-frame sequence was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("only.pcd"), std::string::npos) << e.what();
  }
}
