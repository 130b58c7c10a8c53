// range_nlm_denoise end to end.
#include "test_support.h"

#include <pcl/io/pcd_io.h>

#include <gtest/gtest.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <unistd.h>

namespace fs = std::filesystem;
using namespace range_nlm;

namespace
{
using Result = test::CommandResult;


class DenoiseTool : public ::testing::Test
{
protected:
  void SetUp() override
  {
    dir_ = fs::temp_directory_path() /
           ("range_nlm_tool_" + std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()) + "_" +
            std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_ / "in");
  }
  void TearDown() override { fs::remove_all(dir_); }

  /// A noisy box scene with colours, 40 x 30, some NaN.
  pcl::PointCloud<pcl::PointXYZRGBA> frame(std::uint64_t seed, int w = 40, int h = 30)
  {
    auto xyz = test::makeCloud(w, h, [](double, double, int u, int v) { return (u > 15 && v > 10) ? 1.0 : 1.2; },
                               0.003, seed);
    test::punchHoles(xyz, 0.05, seed + 100);
    pcl::PointCloud<pcl::PointXYZRGBA> c(w, h);
    for (std::size_t i = 0; i < c.size(); ++i) {
      c[i].x = xyz[i].x, c[i].y = xyz[i].y, c[i].z = xyz[i].z;
      c[i].r = std::uint8_t(i), c[i].g = std::uint8_t(i / 3), c[i].b = 200, c[i].a = 255;
    }
    c.is_dense = false;
    return c;
  }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  fs::path dir_;
};
} // namespace

TEST_F(DenoiseTool, HelpListsEveryOptionWithDefaults)
{
  const Result r = test::runDenoise("--help");
  EXPECT_EQ(r.status, 0);
  for (const char* option : {"--search-window", "--patch", "--iterations", "--threads", "--distance-bandwidth",
                             "--similarity-bandwidth", "--seed", "--input-dir", "--output-dir", "--temporal-radius",
                             "--causal", "--pass", "--preset", "--line-of-sight", "--along-normal", "--outlier-sigmas",
                             "--patch-gate"})
    EXPECT_NE(r.output.find(option), std::string::npos) << option;
  EXPECT_NE(r.output.find("(=42)"), std::string::npos);
}

TEST_F(DenoiseTool, SingleFrameKeepsFieldsAndNaNs)
{
  const auto in = frame(1);
  pcl::io::savePCDFileBinaryCompressed(path("in/a.pcd"), in);
  const Result r = test::runDenoise(path("in/a.pcd") + " " + path("out.pcd"));
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("d = "), std::string::npos);
  EXPECT_NE(r.output.find("ms"), std::string::npos);
  pcl::PointCloud<pcl::PointXYZRGBA> out;
  ASSERT_EQ(pcl::io::loadPCDFile(path("out.pcd"), out), 0);
  ASSERT_EQ(out.width, in.width);
  ASSERT_EQ(out.height, in.height);
  int moved = 0;
  for (std::size_t i = 0; i < in.size(); ++i) {
    EXPECT_EQ(out[i].rgba, in[i].rgba);
    EXPECT_EQ(std::isnan(out[i].z), std::isnan(in[i].z));
    if (!std::isnan(in[i].z) && out[i].z != in[i].z)
      ++moved;
  }
  EXPECT_GT(moved, 500);
  std::ifstream header(path("out.pcd"));
  std::string text((std::istreambuf_iterator<char>(header)), {});
  EXPECT_NE(text.find("DATA binary\n"), std::string::npos);
}

TEST_F(DenoiseTool, DirectoryModeFiltersEveryFrameInNameOrder)
{
  for (int k = 0; k < 3; ++k)
    pcl::io::savePCDFileBinary(path("in/f" + std::to_string(k) + ".pcd"), frame(10 + k));
  const Result r = test::runDenoise("--input-dir " + path("in") + " --output-dir " + path("out"));
  ASSERT_EQ(r.status, 0) << r.output;
  for (int k = 0; k < 3; ++k)
    EXPECT_TRUE(fs::exists(path("out/f" + std::to_string(k) + ".pcd")));
  EXPECT_LT(r.output.find("f0.pcd"), r.output.find("f1.pcd"));
  EXPECT_LT(r.output.find("f1.pcd"), r.output.find("f2.pcd"));
}

TEST_F(DenoiseTool, TemporalAndPassScheduleProduceOneOutputPerFrame)
{
  for (int k = 0; k < 4; ++k) {
    auto c = frame(20 + k);
    if (k == 2) // an isolated outlier, 30 % nearer along its ray
      c.at(5, 20).getVector3fMap() *= 0.7f;
    pcl::io::savePCDFileBinary(path("in/f" + std::to_string(k) + ".pcd"), c);
  }
  Result r = test::runDenoise("--input-dir " + path("in") + " --output-dir " + path("t") + " --temporal-radius 1 --json");
  ASSERT_EQ(r.status, 0) << r.output;
  const nlohmann::json summary = test::jsonLine(r.output);
  EXPECT_EQ(summary["frames"], 4) << r.output;
  // Each output carries its own bandwidths, also the frames that come out of the final flush.
  ASSERT_EQ(summary["outputs"].size(), 4u);
  for (int k = 0; k < 4; ++k) {
    EXPECT_EQ(summary["outputs"][k]["file"], "f" + std::to_string(k) + ".pcd");
    EXPECT_GT(summary["outputs"][k]["similarity_bandwidth"].get<double>(), 0.0);
    EXPECT_EQ(summary["outputs"][k]["outliers_moved"], k == 2 ? 1 : 0) << r.output;
  }
  EXPECT_NE(summary["outputs"][2]["similarity_bandwidth"], summary["outputs"][3]["similarity_bandwidth"]);
  r = test::runDenoise("--input-dir " + path("in") + " --output-dir " + path("p") +
              " --pass search=9,patch=5,radius=1 --pass search=5,patch=3,radius=0 --quiet");
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_EQ(r.output, "");
  for (int k = 0; k < 4; ++k) {
    EXPECT_TRUE(fs::exists(path("t/f" + std::to_string(k) + ".pcd")));
    EXPECT_TRUE(fs::exists(path("p/f" + std::to_string(k) + ".pcd")));
  }
  r = test::runDenoise("--input-dir " + path("in") + " --output-dir " + path("q") + " --pass search=9,patch=4");
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.output.find("patch_size = 4"), std::string::npos) << r.output;
}

TEST_F(DenoiseTool, UsageErrorsExitWithTwo)
{
  pcl::io::savePCDFileBinary(path("in/a.pcd"), frame(2));
  for (const std::string& args : {std::string("--search-window 6 ") + path("in/a.pcd") + " " + path("o.pcd"),
                                  std::string("--patch 0 ") + path("in/a.pcd") + " " + path("o.pcd"),
                                  std::string("--bogus"), std::string(""), path("in/a.pcd"),
                                  std::string("--preset fancy ") + path("in/a.pcd") + " " + path("o.pcd"),
                                  std::string("--outlier-sigmas -1 ") + path("in/a.pcd") + " " + path("o.pcd"),
                                  std::string("--patch-gate -2 ") + path("in/a.pcd") + " " + path("o.pcd"),
                                  std::string("--line-of-sight --along-normal ") + path("in/a.pcd") + " " +
                                      path("o.pcd")}) {
    const Result r = test::runDenoise(args);
    EXPECT_EQ(r.status, 2) << args << ": " << r.output;
    if (args.rfind("--outlier-sigmas", 0) == 0)
      EXPECT_NE(r.output.find("outlier_sigmas = -1"), std::string::npos) << r.output;
    if (args.rfind("--patch-gate", 0) == 0)
      EXPECT_NE(r.output.find("patch_edge_gate = -2"), std::string::npos) << r.output;
    EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << r.output;
    EXPECT_FALSE(fs::exists(path("o.pcd")));
  }
}

TEST_F(DenoiseTool, InputErrorsExitWithOneAndWriteNothing)
{
  Result r = test::runDenoise(path("missing.pcd") + " " + path("o.pcd"));
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.output.find("missing.pcd"), std::string::npos);
  EXPECT_FALSE(fs::exists(path("o.pcd")));

  std::ofstream(path("in/broken.pcd")) << "# .PCD v0.7\nVERSION 0.7\nFIELDS x y\n";
  r = test::runDenoise(path("in/broken.pcd") + " " + path("o.pcd"));
  EXPECT_EQ(r.status, 1) << r.output;
  EXPECT_NE(r.output.find("broken.pcd"), std::string::npos);
  EXPECT_FALSE(fs::exists(path("o.pcd")));

  fs::create_directories(path("empty"));
  r = test::runDenoise("--input-dir " + path("empty") + " --output-dir " + path("out"));
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.output.find("holds no .pcd frame"), std::string::npos) << r.output;

  // Frames of another size stop the run; frames already written stay valid.
  fs::create_directories(path("seq"));
  pcl::io::savePCDFileBinary(path("seq/a.pcd"), frame(3));
  pcl::io::savePCDFileBinary(path("seq/b.pcd"), frame(4, 30, 30));
  r = test::runDenoise("--input-dir " + path("seq") + " --output-dir " + path("seq_out"));
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.output.find("b.pcd': frame is 30 x 30 but the sequence is 40 x 30"), std::string::npos) << r.output;
  pcl::PointCloud<pcl::PointXYZRGBA> written;
  EXPECT_EQ(pcl::io::loadPCDFile(path("seq_out/a.pcd"), written), 0);
  EXPECT_FALSE(fs::exists(path("seq_out/b.pcd")));
  for (const auto& entry : fs::directory_iterator(path("seq_out")))
    EXPECT_EQ(entry.path().filename().string().find(".tmp"), std::string::npos);

  // Unorganized input.
  pcl::PointCloud<pcl::PointXYZ> line;
  for (int i = 0; i < 10; ++i)
    line.push_back(pcl::PointXYZ(i, 0, 1));
  pcl::io::savePCDFileBinary(path("in/line.pcd"), line);
  r = test::runDenoise(path("in/line.pcd") + " " + path("o.pcd"));
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.output.find("not organized"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(path("o.pcd")));
}
