// Long recordings through range_nlm_denoise and TemporalStream: frames that cannot be filtered or
// read do not stop a run, every message names its own file, a killed run resumes to the clean
// result, and memory stays flat.
#include "test_support.h"

#include <range_nlm/temporal_stream.h>

#include <pcl/io/pcd_io.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cstring>
#include <cmath>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>
#include <set>
#include <string>
#include <sys/resource.h>
#include <sys/wait.h>
#include <thread>
#include <vector>

namespace fs = std::filesystem;
using namespace range_nlm;
using Cloud = pcl::PointCloud<pcl::PointXYZ>;

namespace
{

const std::string kTool = std::string(RANGE_NLM_TOOLS_DIR) + "/range_nlm_denoise";
constexpr int kWidth = 32, kHeight = 24;

Cloud
goodFrame(int k, int width = kWidth, int height = kHeight)
{
  Cloud cloud = test::makeCloud(width, height, test::step(width / 3 + k % (width / 3), 1.0, 1.3), 0.004, 500 + k);
  test::punchHoles(cloud, 0.03, 900 + k);
  return cloud;
}

Cloud
allNan()
{
  const float nan = std::numeric_limits<float>::quiet_NaN();
  Cloud cloud(kWidth, kHeight, pcl::PointXYZ(nan, nan, nan));
  cloud.is_dense = false;
  return cloud;
}

std::string
frameName(int k)
{
  char name[24];
  std::snprintf(name, sizeof name, "noisy_%04d.pcd", k);
  return name;
}

/// The kinds of frames a long recording may hold.
enum class Kind
{
  good,
  all_nan,   // cannot be filtered: written unchanged
  truncated, // cannot be read
  other_size,
  infinite,
  empty_file
};

bool
readable(Kind kind)
{
  return kind == Kind::good || kind == Kind::all_nan;
}

void
writeFrame(const fs::path& dir, int k, Kind kind)
{
  const std::string path = (dir / frameName(k)).string();
  switch (kind) {
  case Kind::good:
    pcl::io::savePCDFileBinary(path, goodFrame(k));
    break;
  case Kind::all_nan:
    pcl::io::savePCDFileBinary(path, allNan());
    break;
  case Kind::truncated: {
    pcl::io::savePCDFileBinary(path, goodFrame(k));
    fs::resize_file(path, fs::file_size(path) / 2);
    break;
  }
  case Kind::other_size:
    pcl::io::savePCDFileBinary(path, goodFrame(k, kWidth + 4, kHeight));
    break;
  case Kind::infinite: {
    Cloud cloud = goodFrame(k);
    cloud.at(5, 7).z = std::numeric_limits<float>::infinity();
    pcl::io::savePCDFileBinary(path, cloud);
    break;
  }
  case Kind::empty_file:
    std::ofstream(path, std::ios::binary);
    break;
  }
}

/// A recording of `frames` frames with bad frames of every kind at random places (never the
/// first, so that the sequence's size is a good frame's).
std::vector<Kind>
writeRecording(const fs::path& dir, int frames, int bad_per_kind, std::uint64_t seed)
{
  fs::create_directories(dir);
  std::vector<Kind> kinds(frames, Kind::good);
  std::mt19937_64 rng(seed);
  std::uniform_int_distribution<int> place(1, frames - 1);
  for (Kind kind : {Kind::all_nan, Kind::truncated, Kind::other_size, Kind::infinite, Kind::empty_file})
    for (int i = 0; i < bad_per_kind;) {
      const int k = place(rng);
      if (kinds[k] == Kind::good) {
        kinds[k] = kind;
        ++i;
      }
    }
  for (int k = 0; k < frames; ++k)
    writeFrame(dir, k, kinds[k]);
  return kinds;
}

struct ToolRun
{
  int status = -1;
  std::string output;
  long peak_rss_kb = 0;
};

/// Runs the tool to its end; its output and peak resident memory.
ToolRun
runTool(const std::vector<std::string>& args, const fs::path& log)
{
  std::vector<std::string> all{kTool};
  all.insert(all.end(), args.begin(), args.end());
  const pid_t pid = test::startProcess(all, log.string());
  int status = 0;
  struct rusage usage = {};
  ::wait4(pid, &status, 0, &usage);
  return ToolRun{WIFEXITED(status) ? WEXITSTATUS(status) : -1, test::readBytes(log.string()), usage.ru_maxrss};
}

std::size_t
occurrences(const std::string& text, const std::string& what)
{
  std::size_t n = 0;
  for (std::size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1))
    ++n;
  return n;
}

std::vector<std::string>
hiddenFiles(const fs::path& dir)
{
  std::vector<std::string> names;
  for (const auto& entry : fs::directory_iterator(dir))
    if (entry.path().filename().string()[0] == '.')
      names.push_back(entry.path().filename().string());
  return names;
}

class LongRuns : public ::testing::Test
{
protected:
  void SetUp() override
  {
    dir_ = fs::temp_directory_path() / ("range_nlm_long_runs_" + std::to_string(::getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path dir_;
};

} // namespace

TEST_F(LongRuns, AnAllNanFrameIsWrittenUnchangedAndTheRunGoesOn)
{
  // Four generated frames and one all-NaN frame of the same size (a covered lens), static and
  // temporal: the run ends with 0, the NaN frame comes out NaN and is named, the others are filtered.
  const fs::path in = dir_ / "in";
  fs::create_directories(in);
  for (int k = 0; k < 5; ++k)
    writeFrame(in, k, k == 3 ? Kind::all_nan : Kind::good);
  for (const std::string radius : {"0", "1"}) {
    SCOPED_TRACE("radius " + radius);
    const fs::path out = dir_ / ("out" + radius);
    const ToolRun r = runTool({"--input-dir", in.string(), "--output-dir", out.string(), "--temporal-radius", radius},
                          dir_ / "log.txt");
    ASSERT_EQ(r.status, 0) << r.output;
    EXPECT_NE(r.output.find(frameName(3) + ": not filtered, written unchanged (range_nlm: the cloud has no valid point"),
              std::string::npos)
        << r.output;
    Cloud nan_out, neighbour;
    ASSERT_EQ(pcl::io::loadPCDFile((out / frameName(3)).string(), nan_out), 0);
    for (const auto& q : nan_out)
      EXPECT_TRUE(std::isnan(q.x) && std::isnan(q.y) && std::isnan(q.z));
    for (int k : {0, 1, 2, 4}) {
      ASSERT_EQ(pcl::io::loadPCDFile((out / frameName(k)).string(), neighbour), 0) << k;
      const Cloud input = goodFrame(k);
      double moved = 0.0;
      for (std::size_t i = 0; i < input.size(); ++i) {
        EXPECT_EQ(std::isnan(input[i].z), std::isnan(neighbour[i].z)) << "frame " << k << ", point " << i;
        if (!std::isnan(input[i].z))
          moved += std::fabs(input[i].z - neighbour[i].z);
      }
      EXPECT_GT(moved, 0.0) << "frame " << k << " was not filtered";
    }
  }
  // Static: the NaN frame's neighbours are exactly what they are in a run without it.
  const fs::path alone = dir_ / "alone";
  fs::create_directories(alone);
  fs::copy_file(in / frameName(2), alone / frameName(2));
  ASSERT_EQ(runTool({"--input-dir", alone.string(), "--output-dir", (dir_ / "alone_out").string()}, dir_ / "log.txt").status, 0);
  EXPECT_EQ(test::readBytes((dir_ / "alone_out" / frameName(2)).string()),
            test::readBytes((dir_ / "out0" / frameName(2)).string()));
  // A single all-NaN frame too.
  const ToolRun single = runTool({(in / frameName(3)).string(), (dir_ / "single.pcd").string()}, dir_ / "log.txt");
  EXPECT_EQ(single.status, 0) << single.output;
  EXPECT_NE(single.output.find("not filtered, written unchanged"), std::string::npos) << single.output;
}

TEST_F(LongRuns, UnreadableFramesStopTheRunOrAreSkippedWithKeepGoing)
{
  const fs::path in = dir_ / "in";
  fs::create_directories(in);
  for (int k = 0; k < 6; ++k)
    writeFrame(in, k, k == 2 ? Kind::truncated : Kind::good);
  const std::string bad = (in / frameName(2)).string();

  // By default: exit 1, the message names the truncated frame (not a neighbour read ahead),
  // every frame that does not need it is written, nothing after it.
  ToolRun r = runTool({"--input-dir", in.string(), "--output-dir", (dir_ / "stop").string(), "--temporal-radius", "1"},
                  dir_ / "log.txt");
  EXPECT_EQ(r.status, 1) << r.output;
  EXPECT_NE(r.output.find("range_nlm_denoise: error: '" + bad + "': truncated PCD body"), std::string::npos)
      << r.output;
  EXPECT_TRUE(fs::exists(dir_ / "stop" / frameName(0)));
  for (int k : {2, 3, 4, 5})
    EXPECT_FALSE(fs::exists(dir_ / "stop" / frameName(k))) << k;
  EXPECT_TRUE(hiddenFiles(dir_ / "stop").empty());

  // --keep-going: exit 3, the frame listed once at the end, every other frame written.
  r = runTool({"--input-dir", in.string(), "--output-dir", (dir_ / "go").string(), "--keep-going"}, dir_ / "log.txt");
  EXPECT_EQ(r.status, 3) << r.output;
  EXPECT_EQ(occurrences(r.output, frameName(2)), 1u) << r.output;
  EXPECT_NE(r.output.find("1 frame(s) could not be read and were skipped:\n  '" + bad + "': truncated PCD body"),
            std::string::npos)
      << r.output;
  for (int k = 0; k < 6; ++k)
    EXPECT_EQ(fs::exists(dir_ / "go" / frameName(k)), k != 2) << k;
  // Static, so each good output is the one of a run without the bad frame.
  fs::remove(bad);
  ASSERT_EQ(runTool({"--input-dir", in.string(), "--output-dir", (dir_ / "clean").string()}, dir_ / "log.txt").status, 0);
  for (int k : {0, 1, 3, 4, 5})
    EXPECT_EQ(test::readBytes((dir_ / "go" / frameName(k)).string()),
              test::readBytes((dir_ / "clean" / frameName(k)).string()))
        << k;

  // JSON lists it; the summary parses.
  writeFrame(in, 2, Kind::empty_file);
  r = runTool({"--input-dir", in.string(), "--output-dir", (dir_ / "json").string(), "--keep-going", "--json"},
              dir_ / "log.txt");
  EXPECT_EQ(r.status, 3) << r.output;
  const nlohmann::json summary = test::jsonLine(r.output);
  EXPECT_EQ(summary["frames"], 5);
  ASSERT_EQ(summary["unreadable"].size(), 1u);
  EXPECT_EQ(summary["unreadable"][0]["file"], frameName(2));
  EXPECT_NE(summary["unreadable"][0]["error"].get<std::string>().find("file is empty"), std::string::npos);
}

TEST_F(LongRuns, SingleFrameOutputProblemsAreNamed)
{
  writeFrame(dir_, 0, Kind::good);
  const std::string in = (dir_ / frameName(0)).string();
  ToolRun r = runTool({in, in}, dir_ / "log.txt");
  EXPECT_EQ(r.status, 1) << r.output;
  EXPECT_NE(r.output.find("'" + in + "' is the input file; refusing to overwrite the input (use --overwrite)"),
            std::string::npos)
      << r.output;
  const std::string before = test::readBytes(in);
  r = runTool({in, in, "--overwrite"}, dir_ / "log.txt");
  EXPECT_EQ(r.status, 0) << r.output;
  EXPECT_NE(test::readBytes(in), before);
  fs::create_directories(dir_ / "somewhere");
  r = runTool({in, (dir_ / "somewhere").string()}, dir_ / "log.txt");
  EXPECT_EQ(r.status, 1) << r.output;
  EXPECT_NE(r.output.find("is a directory"), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("Success"), std::string::npos) << r.output;
}

TEST_F(LongRuns, JsonSummaryParsesWithHostileFileNames)
{
  const fs::path in = dir_ / "in";
  fs::create_directories(in);
  const std::vector<std::string> names{"quote\"d.pcd", "back\\slash.pcd", "tab\tbed.pcd", "new\nline.pcd"};
  for (std::size_t k = 0; k < names.size(); ++k)
    pcl::io::savePCDFileBinary((in / names[k]).string(), goodFrame(int(k)));
  const ToolRun r = runTool({"--input-dir", in.string(), "--output-dir", (dir_ / "out").string(), "--json"},
                        dir_ / "log.txt");
  ASSERT_EQ(r.status, 0) << r.output;
  const nlohmann::json summary = test::jsonLine(r.output);
  std::set<std::string> files;
  for (const auto& o : summary["outputs"])
    files.insert(o["file"].get<std::string>());
  EXPECT_EQ(files, std::set<std::string>(names.begin(), names.end()));
}

TEST_F(LongRuns, ASecondRunOnTheSameOutputDirectoryIsRefused)
{
  const fs::path in = dir_ / "in";
  fs::create_directories(in);
  for (int k = 0; k < 40; ++k)
    pcl::io::savePCDFileBinary((in / frameName(k)).string(), goodFrame(k, 160, 120));
  const fs::path out = dir_ / "out";
  const pid_t first =
      test::startProcess({kTool, "--input-dir", in.string(), "--output-dir", out.string(), "--quiet"},
                         (dir_ / "first.txt").string());
  // Once the first run has written something, a resumed run on the same directory must not touch
  // its files: it is refused.
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::minutes(2);
  while (std::chrono::steady_clock::now() < deadline && !fs::exists(out / frameName(0)))
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  const ToolRun second = runTool({"--input-dir", in.string(), "--output-dir", out.string(), "--resume"}, dir_ / "log.txt");
  int status = 0;
  ::waitpid(first, &status, 0);
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << test::readBytes((dir_ / "first.txt").string());
  EXPECT_EQ(second.status, 4) << second.output;
  EXPECT_NE(second.output.find("is in use by another range_nlm_denoise run"), std::string::npos) << second.output;
  for (int k = 0; k < 40; ++k)
    EXPECT_TRUE(fs::exists(out / frameName(k))) << k;
  EXPECT_TRUE(hiddenFiles(out).empty());
}

TEST_F(LongRuns, ProgressShowsTheTimeLeftOnStderrUnlessQuiet)
{
  writeFrame(dir_, 0, Kind::good);
  Cloud big = goodFrame(0, 200, 150);
  pcl::io::savePCDFileBinary((dir_ / "big.pcd").string(), big);
  // A slow single frame (direct evaluation of a wide window): about 4 s on a quiet machine, well
  // past the 2 s after which progress is shown.
  const std::vector<std::string> slow{(dir_ / "big.pcd").string(), (dir_ / "out.pcd").string(), "--direct",
                                      "--search-window", "21", "--patch", "7", "--dilation", "1", "--threads", "1"};
  ToolRun r = runTool(slow, dir_ / "log.txt");
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("range_nlm_denoise: "), std::string::npos) << r.output;
  EXPECT_NE(r.output.find(" left"), std::string::npos) << r.output;
  std::vector<std::string> quiet = slow;
  quiet.push_back("--quiet");
  r = runTool(quiet, dir_ / "log.txt");
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_EQ(r.output, "");
}

TEST_F(LongRuns, SoakBadFramesKillAndResume)
{
  // A few hundred small frames with bad ones of every kind at random places, temporal radius 1,
  // --keep-going: the clean run, then a run killed with SIGKILL halfway and resumed.
  const int frames = test::kAddressSanitizer ? 120 : 300;
  const fs::path in = dir_ / "in";
  const std::vector<Kind> kinds = writeRecording(in, frames, 3, 2024);
  // One thread: hundreds of tiny frames are all OpenMP barriers, which crawl when the test runs
  // beside others on two cores (the output does not depend on the thread count).
  const std::vector<std::string> options{"--temporal-radius", "1", "--keep-going", "--search-window", "7",
                                         "--threads", "1"};
  auto args = [&](const fs::path& out, std::vector<std::string> extra) {
    std::vector<std::string> all{"--input-dir", in.string(), "--output-dir", out.string()};
    all.insert(all.end(), options.begin(), options.end());
    all.insert(all.end(), extra.begin(), extra.end());
    return all;
  };
  const fs::path clean = dir_ / "clean";
  const ToolRun reference = runTool(args(clean, {}), dir_ / "clean.txt");
  ASSERT_EQ(reference.status, 3) << reference.output;

  // Every bad frame is reported once by name; the readable ones are all written.
  for (int k = 0; k < frames; ++k) {
    SCOPED_TRACE(frameName(k));
    if (kinds[k] == Kind::good)
      EXPECT_EQ(occurrences(reference.output, frameName(k)), 1u); // its per-frame line
    else
      EXPECT_EQ(occurrences(reference.output, frameName(k)), 1u) << reference.output;
    EXPECT_EQ(fs::exists(clean / frameName(k)), readable(kinds[k]));
  }
  EXPECT_TRUE(hiddenFiles(clean).empty());

  // Killed halfway, then resumed: byte for byte the clean result, no temporary file left.
  const fs::path resumed = dir_ / "resumed";
  std::vector<std::string> all{kTool};
  for (const std::string& a : args(resumed, {"--quiet"}))
    all.push_back(a);
  const pid_t pid = test::startProcess(all, (dir_ / "killed.txt").string());
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::minutes(5);
  int status = 0;
  bool exited = false;
  while (std::chrono::steady_clock::now() < deadline) {
    if (::waitpid(pid, &status, WNOHANG) == pid) {
      exited = true;
      break;
    }
    if (fs::exists(resumed) && std::distance(fs::directory_iterator(resumed), fs::directory_iterator()) >= frames / 2)
      break;
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  ASSERT_FALSE(exited) << "the run ended before it could be killed";
  ::kill(pid, SIGKILL);
  ::waitpid(pid, &status, 0);
  const ToolRun after = runTool(args(resumed, {"--resume", "--json"}), dir_ / "resumed.txt");
  EXPECT_EQ(after.status, 3) << after.output;
  const nlohmann::json summary = test::jsonLine(after.output);
  EXPECT_GT(summary["skipped"].get<int>(), 0);
  for (int k = 0; k < frames; ++k) {
    SCOPED_TRACE(frameName(k));
    if (readable(kinds[k]))
      EXPECT_EQ(test::readBytes((resumed / frameName(k)).string()), test::readBytes((clean / frameName(k)).string()));
    else
      EXPECT_FALSE(fs::exists(resumed / frameName(k)));
  }
  EXPECT_TRUE(hiddenFiles(resumed).empty());
  EXPECT_EQ(summary["unreadable"].size(),
            std::size_t(std::count_if(kinds.begin(), kinds.end(), [](Kind k) { return !readable(k); })));

  // Resident memory stays flat: the whole recording peaks no higher than its first third. Not
  // under AddressSanitizer, whose quarantine keeps freed memory resident by design.
  if (test::kAddressSanitizer)
    return;
  const fs::path third = dir_ / "third";
  fs::create_directories(third);
  for (int k = 0; k < frames / 3; ++k)
    fs::copy_file(in / frameName(k), third / frameName(k));
  const ToolRun small = runTool({"--input-dir", third.string(), "--output-dir", (dir_ / "third_out").string(),
                             "--temporal-radius", "1", "--keep-going", "--search-window", "7", "--threads", "1",
                             "--quiet"},
                            dir_ / "third.txt");
  EXPECT_LE(reference.peak_rss_kb, small.peak_rss_kb + 8 * 1024)
      << "peak RSS " << reference.peak_rss_kb << " kB over " << frames << " frames, " << small.peak_rss_kb
      << " kB over " << frames / 3;
}

TEST_F(LongRuns, StreamSoakSkipsRefusedFramesAndPassesUnfilterableOnesThrough)
{
  // TemporalStream over a few hundred frames with all-NaN frames (passed through) and frames it
  // refuses at push (another size, an infinity): the stream goes on, and its outputs are exactly
  // those of a stream that never saw the refused frames.
  const int frames = test::kAddressSanitizer ? 100 : 300;
  std::mt19937_64 rng(7);
  std::uniform_int_distribution<int> kind(0, 9);
  FilterParameters p = FilterParameters::recommended();
  p.threads = 1; // tiny frames: see SoakBadFramesKillAndResume
  TemporalStream<pcl::PointXYZ> noisy(1, false, p), clean(1, false, p);
  std::vector<Cloud::Ptr> a, b;
  std::vector<std::string> problems;
  std::size_t refused = 0, nan_frames = 0;
  for (int k = 0; k < frames; ++k) {
    const int roll = kind(rng);
    Cloud::Ptr frame(new Cloud(roll == 0 ? allNan() : roll == 1 ? goodFrame(k, kWidth + 2, kHeight) : goodFrame(k)));
    if (roll == 2)
      frame->at(3, 4).y = -std::numeric_limits<float>::infinity();
    const bool refuse = roll == 1 || roll == 2;
    try {
      for (auto& out : noisy.push(frame))
        a.push_back(out);
      for (const auto& info : noisy.lastOutputs())
        problems.push_back(info.problem);
      EXPECT_FALSE(refuse) << "frame " << k << " was not refused";
    } catch (const std::invalid_argument& e) {
      EXPECT_TRUE(refuse) << "frame " << k << ": " << e.what();
      EXPECT_NE(std::string(e.what()).find("frame " + std::to_string(k - refused)), std::string::npos) << e.what();
      ++refused;
      continue;
    }
    nan_frames += roll == 0;
    for (auto& out : clean.push(frame))
      b.push_back(out);
    EXPECT_LE(noisy.heldFrames(), 3u);
  }
  for (auto& out : noisy.flush())
    a.push_back(out);
  for (const auto& info : noisy.lastOutputs())
    problems.push_back(info.problem);
  for (auto& out : clean.flush())
    b.push_back(out);
  ASSERT_EQ(a.size(), std::size_t(frames) - refused);
  ASSERT_EQ(a.size(), b.size());
  EXPECT_GT(refused, 0u);
  EXPECT_GT(nan_frames, 0u);
  std::size_t reported = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i]->size(), b[i]->size());
    EXPECT_EQ(0, std::memcmp(a[i]->points.data(), b[i]->points.data(), a[i]->size() * sizeof(pcl::PointXYZ))) << i;
    reported += !problems[i].empty();
  }
  EXPECT_EQ(reported, nan_frames);
}

TEST_F(LongRuns, DepthImageDirectoriesKeepGoingToo)
{
  // 16-bit depth PNGs: an unreadable one is named and skipped with --keep-going, an all-zero one
  // (no measurement) is written unchanged, the rest filtered.
  const fs::path in = dir_ / "png";
  fs::create_directories(in);
  for (int k = 0; k < 4; ++k) {
    Cloud cloud = goodFrame(k);
    if (k == 2)
      cloud = allNan();
    pcl::io::savePCDFileBinary((dir_ / "tmp.pcd").string(), cloud);
    const ToolRun c = runTool({(dir_ / "tmp.pcd").string(), (in / ("d" + std::to_string(k) + ".png")).string(),
                               "--output-format", "png", "--line-of-sight", "--depth-scale", "1000", "--quiet"},
                              dir_ / "log.txt");
    ASSERT_EQ(c.status, 0) << c.output;
  }
  const std::string broken = (in / "d1.png").string();
  fs::resize_file(broken, fs::file_size(broken) / 2);
  const ToolRun r = runTool({"--input-dir", in.string(), "--output-dir", (dir_ / "out").string(), "--keep-going",
                             "--depth-scale", "1000", "--line-of-sight"},
                            dir_ / "log.txt");
  EXPECT_EQ(r.status, 3) << r.output;
  EXPECT_EQ(occurrences(r.output, "d1.png"), 1u) << r.output;
  EXPECT_NE(r.output.find("'" + broken + "'"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("d2.png: not filtered, written unchanged"), std::string::npos) << r.output;
  for (const char* name : {"d0.png", "d2.png", "d3.png"})
    EXPECT_TRUE(fs::exists(dir_ / "out" / name)) << name;
  EXPECT_FALSE(fs::exists(dir_ / "out" / "d1.png"));
}
