// range_nlm_bench --real-noise's depth-image columns (real_noise_comparison.cpp,
// bench::depthImageOutput): the PNG output read back lies on the pixels' rays, is the re-projected
// encoding (not z alone), and the report has a PNG row per range_nlm setting, scene and frame.
#include "bench_support.h"
#include "real_noise_comparison.h"
#include "test_support.h"

#include <range_nlm/io/depth_image.h>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <pcl/io/pcd_io.h>

#include <cmath>
#include <filesystem>
#include <sstream>

#include <unistd.h>

using namespace range_nlm;
namespace fs = std::filesystem;
using Cloud = pcl::PointCloud<pcl::PointXYZ>;

namespace
{
/// A tilted plane with a step, 4 mm noise along the rays, moved the way a frame filtered alone
/// moves: each point along the plane's normal by its height (a perfect filter).
struct TiltedFrame
{
  Cloud input, filtered;
  Eigen::Vector3d normal = Eigen::Vector3d(0.4, 0.0, 1.0).normalized();
};

TiltedFrame
tiltedFrame()
{
  TiltedFrame f;
  const double c = f.normal.dot(Eigen::Vector3d(0, 0, 1.3));
  f.input = test::makeCloud(64, 48, test::plane(f.normal, c), 0.004, 8, 60.0);
  f.filtered = f.input;
  for (pcl::PointXYZ& p : f.filtered) {
    const Eigen::Vector3d x(p.x, p.y, p.z);
    const Eigen::Vector3d q = x - (f.normal.dot(x) - c) * f.normal;
    p = pcl::PointXYZ(float(q.x()), float(q.y()), float(q.z()));
  }
  return f;
}
} // namespace

TEST(RealNoiseComparison, DepthImageOutputIsOnTheRaysAndReprojected)
{
  const TiltedFrame f = tiltedFrame();
  const double scale = 5000.0;
  const Cloud png = tools::bench::depthImageOutput(f.input, f.filtered, scale);
  const Cloud z_only = tools::bench::depthImageOutput(f.input, f.filtered, scale, true);
  for (std::size_t i = 0; i < png.size(); ++i) {
    const Eigen::Vector3d p(f.input[i].x, f.input[i].y, f.input[i].z), q(png[i].x, png[i].y, png[i].z);
    ASSERT_LT(q.normalized().cross(p.normalized()).norm(), 1e-6) << i;
    EXPECT_NEAR(q.z() * scale, std::round(q.z() * scale), 1e-3) << i; // a 16-bit value
  }
  const double c = f.normal.dot(Eigen::Vector3d(0, 0, 1.3));
  // On the plane within the rounding (0.1 mm along the ray), unlike z alone.
  EXPECT_LT(test::planeRmse(png, f.normal, c), 0.1e-3);
  EXPECT_GT(test::planeRmse(z_only, f.normal, c), 0.5e-3);
}

TEST(RealNoiseComparison, ReportHasAPngRowPerSettingSceneAndFrame)
{
  if (test::kAddressSanitizer)
    GTEST_SKIP() << "pcl::FastBilateralFilter's clouds cannot be freed under AddressSanitizer here";
  const fs::path dir = fs::temp_directory_path() / ("range_nlm_real_noise_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const std::string frame = (dir / "tilted.pcd").string();
  ASSERT_EQ(pcl::io::savePCDFileBinary(frame, tiltedFrame().input), 0);
  tools::real_noise::Options options;
  options.width = 96;
  options.height = 72;
  options.models = {"kinect"};
  options.noise_scales = {1.0};
  options.seeds = {1};
  options.include_mls = false;
  options.real_frames = {frame};
  options.threads = 1;
  std::ostringstream log, report, json;
  tools::real_noise::run(options, log, report, &json);
  const nlohmann::json j = nlohmann::json::parse(json.str());
  const std::size_t settings = tools::real_noise::variants().size();
  const nlohmann::json& scene = j.at("generated").at("kinect x1.0 seed 1");
  ASSERT_EQ(scene.at("png").size(), settings);
  ASSERT_EQ(scene.at("png z only").size(), settings);
  const double pcd = scene.at("default")[0], png = scene.at("png")["default"][0];
  EXPECT_NEAR(png, pcd, 0.05 * pcd) << "flat RMSE, mm";
  EXPECT_TRUE(j.at("real").at("tilted.pcd").contains("png default"));
  EXPECT_NE(report.str().find("### PNG output against PCD output"), std::string::npos);
  EXPECT_NE(report.str().find("### Real frames: PNG output against PCD output"), std::string::npos);
  EXPECT_NE(report.str().find("| tilted.pcd | default |"), std::string::npos) << report.str();
  fs::remove_all(dir);
}
