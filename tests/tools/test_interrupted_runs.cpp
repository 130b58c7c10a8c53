// range_nlm_denoise interrupted by a signal, and resumed: no incomplete file ever carries a final
// name, and a resumed run writes exactly what an uninterrupted run writes.
#include "test_support.h"

#include <range_nlm/temporal_stream.h>

#include <pcl/io/pcd_io.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <fcntl.h>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <sys/wait.h>
#include <thread>
#include <unistd.h>
#include <vector>

namespace fs = std::filesystem;
using namespace range_nlm;

namespace
{
const std::string kTool = std::string(RANGE_NLM_TOOLS_DIR) + "/range_nlm_denoise";

struct Result
{
  int status = -1;
  std::string output; // stdout + stderr
};

Result
runTool(const std::string& args)
{
  const test::CommandResult c = test::runCommand(kTool + " " + args);
  return Result{c.status, c.output};
}

/// Starts the tool in the background (output to `log`); returns its pid.
pid_t
startTool(const std::vector<std::string>& args, const std::string& log)
{
  std::vector<std::string> all{kTool};
  all.insert(all.end(), args.begin(), args.end());
  return test::startProcess(all, log);
}

std::string
readBytes(const fs::path& path)
{
  return test::readBytes(path.string());
}

bool
isTemporary(const std::string& name)
{
  return name[0] == '.' && name.find(".tmp") != std::string::npos;
}

/// Final-named (not temporary) files of a directory.
std::vector<std::string>
finalFiles(const fs::path& dir)
{
  std::vector<std::string> names;
  for (const auto& entry : fs::directory_iterator(dir))
    if (!isTemporary(entry.path().filename().string()))
      names.push_back(entry.path().filename().string());
  std::sort(names.begin(), names.end());
  return names;
}

std::vector<std::string>
temporaryFiles(const fs::path& dir)
{
  std::vector<std::string> names;
  for (const auto& entry : fs::directory_iterator(dir))
    if (isTemporary(entry.path().filename().string()))
      names.push_back(entry.path().filename().string());
  return names;
}

std::string
frameName(int k)
{
  char name[16];
  std::snprintf(name, sizeof name, "f%02d.pcd", k);
  return name;
}

/// A sequence of noisy frames of a step scene with holes, the step moving by a column per frame.
void
writeSequence(const fs::path& dir, int frames, int w, int h)
{
  fs::create_directories(dir);
  for (int k = 0; k < frames; ++k) {
    auto cloud = test::makeCloud(w, h, test::step(w / 3 + k % (w / 3), 1.0, 1.3), 0.004, 100 + k);
    test::punchHoles(cloud, 0.03, 300 + k);
    pcl::io::savePCDFileBinary((dir / frameName(k)).string(), cloud);
  }
}

/// Runs to completion; every output of `out` is byte-identical to `reference` and no temporary
/// file is left.
void
expectSameOutputs(const fs::path& out, const fs::path& reference)
{
  const std::vector<std::string> names = finalFiles(reference);
  EXPECT_EQ(finalFiles(out), names);
  for (const std::string& name : names)
    EXPECT_TRUE(readBytes(out / name) == readBytes(reference / name)) << name << " differs from the uninterrupted run";
  EXPECT_TRUE(temporaryFiles(out).empty());
}

/// Sequences and their uninterrupted results, shared by the tests: a long one of larger frames to
/// interrupt, a short one of small frames for the many schedules of the resume tests. Under the
/// sanitizers, which slow the filter down about tenfold, the long sequence has smaller frames, so
/// that a run still takes seconds.
class InterruptedRuns : public ::testing::Test
{
protected:
  static constexpr int kFrames = 40, kWidth = test::kAddressSanitizer ? 64 : 160, kHeight = test::kAddressSanitizer ? 48 : 120;
  static constexpr int kShortFrames = 16;
  static void SetUpTestSuite()
  {
    root_ = fs::temp_directory_path() / ("range_nlm_interrupted_" + std::to_string(::getpid()));
    fs::remove_all(root_);
    writeSequence(root_ / "long", kFrames, kWidth, kHeight);
    writeSequence(root_ / "short", kShortFrames, 64, 48);
  }
  static void TearDownTestSuite() { fs::remove_all(root_); }
  static std::string in(bool short_sequence = false) { return (root_ / (short_sequence ? "short" : "long")).string(); }
  static std::string options(const std::string& extra) { return "--search-window 5 --patch 3 --quiet " + extra; }

  /// The uninterrupted result for `extra` options (computed once per sequence and option set).
  static fs::path reference(const std::string& extra, bool short_sequence = false)
  {
    const std::string key = in(short_sequence) + " " + extra;
    auto found = references_.find(key);
    if (found != references_.end())
      return found->second;
    const fs::path out = root_ / ("ref" + std::to_string(references_.size()));
    const Result r = runTool("--input-dir " + in(short_sequence) + " --output-dir " + out.string() + " " + options(extra));
    EXPECT_EQ(r.status, 0) << r.output;
    EXPECT_EQ(finalFiles(out).size(), std::size_t(short_sequence ? kShortFrames : kFrames));
    references_[key] = out;
    return out;
  }

  /// Starts a run with `extra` options, sends `signal` once `outputs` results are written, and
  /// checks the directory: every final-named file is a complete result, identical to the
  /// uninterrupted run's, and the run was really cut short. Returns the number of results.
  std::size_t interrupt(const fs::path& out, const std::string& extra, int signal, std::size_t outputs)
  {
    const fs::path ref = reference(extra);
    std::vector<std::string> args{"--input-dir", in(), "--output-dir", out.string()};
    std::istringstream words(options(extra));
    for (std::string w; words >> w;)
      args.push_back(w);
    const pid_t pid = startTool(args, (root_ / "log.txt").string());
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::minutes(5);
    int status = 0;
    bool exited = false;
    while (std::chrono::steady_clock::now() < deadline) {
      if (::waitpid(pid, &status, WNOHANG) == pid) {
        exited = true;
        break;
      }
      if (fs::exists(out) && finalFiles(out).size() >= outputs)
        break;
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    if (!exited) {
      ::kill(pid, signal);
      ::waitpid(pid, &status, 0);
    }
    EXPECT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == signal)
        << "the run ended before it could be interrupted: " << readBytes(root_ / "log.txt");
    const std::vector<std::string> written = finalFiles(out);
    EXPECT_GE(written.size(), outputs);
    EXPECT_LT(written.size(), std::size_t(kFrames));
    for (const std::string& name : written) {
      pcl::PointCloud<pcl::PointXYZ> cloud;
      EXPECT_EQ(pcl::io::loadPCDFile((out / name).string(), cloud), 0) << name;
      EXPECT_EQ(cloud.size(), std::size_t(kWidth * kHeight)) << name;
      EXPECT_TRUE(readBytes(out / name) == readBytes(ref / name)) << name << " is not the complete result";
    }
    return written.size();
  }

  /// Resumes in `out`; checks the result is the uninterrupted one and `finished` frames were skipped.
  void resume(const fs::path& out, const std::string& extra, std::size_t finished)
  {
    const Result r = runTool("--input-dir " + in() + " --output-dir " + out.string() + " " + options(extra) +
                             " --resume --json");
    ASSERT_EQ(r.status, 0) << r.output;
    const nlohmann::json summary = test::jsonLine(r.output);
    EXPECT_EQ(summary["frames"], kFrames - finished) << r.output;
    EXPECT_EQ(summary["skipped"], finished) << r.output;
    expectSameOutputs(out, reference(extra));
  }

  static fs::path root_;
  static std::map<std::string, fs::path> references_;
};
fs::path InterruptedRuns::root_;
std::map<std::string, fs::path> InterruptedRuns::references_;
} // namespace

TEST_F(InterruptedRuns, SigintLeavesOnlyCompleteOutputsAndResumeFinishesTheRun)
{
  const fs::path out = root_ / "sigint";
  const std::size_t written = interrupt(out, "", SIGINT, 2);
  resume(out, "", written);
}

TEST_F(InterruptedRuns, SigintDuringOneLargeFrameEndsTheRunWithoutWaitingForTheFrame)
{
  // One large frame (a few seconds): SIGINT ends the run at once, and its output, written to a
  // temporary name first, never appears under its final name.
  const int w = test::kAddressSanitizer ? 400 : 1600, h = test::kAddressSanitizer ? 300 : 1200;
  const fs::path in = root_ / "one-large-frame";
  fs::create_directories(in);
  pcl::io::savePCDFileBinary((in / frameName(0)).string(),
                             test::makeCloud(w, h, test::step(w / 3, 1.0, 1.3), 0.004, 7));
  const auto start = std::chrono::steady_clock::now();
  const Result whole_run = runTool("--input-dir " + in.string() + " --output-dir " + (root_ / "one-whole").string());
  ASSERT_EQ(whole_run.status, 0) << whole_run.output;
  const auto whole = std::chrono::steady_clock::now() - start;
  const fs::path out = root_ / "one-interrupted";
  const auto started = std::chrono::steady_clock::now();
  const pid_t pid =
      startTool({"--input-dir", in.string(), "--output-dir", out.string()}, (root_ / "one-log.txt").string());
  std::this_thread::sleep_for(whole / 4);
  ::kill(pid, SIGINT);
  int status = 0;
  ::waitpid(pid, &status, 0);
  const auto stopped = std::chrono::steady_clock::now() - started;
  EXPECT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == SIGINT) << readBytes(root_ / "one-log.txt");
  EXPECT_LT(stopped, whole * 6 / 10) << "SIGINT at a quarter of the frame ended the run after "
                                     << std::chrono::duration<double>(stopped).count() << " s of "
                                     << std::chrono::duration<double>(whole).count() << " s";
  EXPECT_TRUE(!fs::exists(out) || finalFiles(out).empty());
}

TEST_F(InterruptedRuns, SigkillDuringTemporalRunThenResumeIsByteIdentical)
{
  const fs::path out = root_ / "sigkill";
  const std::size_t written = interrupt(out, "--temporal-radius 1", SIGKILL, 1);
  resume(out, "--temporal-radius 1", written);
}

TEST_F(InterruptedRuns, ResumeRedoesBrokenOutputsRemovesTemporariesAndKeepsFinishedFiles)
{
  // Any subset of finished frames, with the debris a killed run can leave, for every kind of
  // schedule: static, centred and causal temporal windows, and two temporal passes.
  for (const std::string extra : {std::string(""), std::string("--temporal-radius 1"),
                                  std::string("--temporal-radius 2 --causal"),
                                  std::string("--pass search=5,patch=3,radius=1 --pass search=3,patch=3,radius=1")}) {
    SCOPED_TRACE(extra);
    const fs::path ref = reference(extra, true);
    const fs::path out = root_ / "partial";
    fs::remove_all(out);
    fs::create_directories(out);
    std::size_t finished = 0;
    for (int k : {0, 1, 2, 6, 8, 9, 13, 15}) {
      fs::copy_file(ref / frameName(k), out / frameName(k));
      fs::last_write_time(out / frameName(k), fs::file_time_type::clock::now() - std::chrono::hours(1));
      ++finished;
    }
    const std::string full = readBytes(ref / frameName(10));
    std::ofstream(out / frameName(10), std::ios::binary) << full.substr(0, full.size() / 2); // cut short
    std::ofstream(out / frameName(11), std::ios::binary) << full.substr(0, 100);             // header only
    pcl::PointCloud<pcl::PointXYZ> small(8, 6, pcl::PointXYZ(0, 0, 1));
    pcl::io::savePCDFileBinary((out / frameName(12)).string(), small); // another size
    std::ofstream(out / ("." + frameName(3) + ".tmp4242"), std::ios::binary) << full.substr(0, 1000);
    std::ofstream(out / ("." + frameName(9) + ".tmp17"), std::ios::binary) << full;
    std::ofstream(out / ".notes.tmp", std::ios::binary) << "not ours\n";
    std::map<std::string, fs::file_time_type> before;
    for (const std::string& name : finalFiles(out))
      before[name] = fs::last_write_time(out / name);

    const Result r = runTool("--input-dir " + in(true) + " --output-dir " + out.string() + " " + options(extra) +
                             " --resume --json");
    ASSERT_EQ(r.status, 0) << r.output;
    const nlohmann::json summary = test::jsonLine(r.output);
    EXPECT_EQ(summary["frames"], kShortFrames - finished) << r.output;
    EXPECT_EQ(summary["skipped"], finished) << r.output;
    for (int k : {0, 1, 2, 6, 8, 9, 13, 15})
      EXPECT_EQ(fs::last_write_time(out / frameName(k)), before[frameName(k)]) << frameName(k) << " was rewritten";
    ASSERT_TRUE(fs::exists(out / ".notes.tmp")); // only the run's own temporaries are removed
    fs::remove(out / ".notes.tmp");
    expectSameOutputs(out, ref);
  }
}

TEST_F(InterruptedRuns, ResumeWithEverythingFinishedWritesNothing)
{
  const fs::path ref = reference("--temporal-radius 1", true);
  const fs::path out = root_ / "done";
  fs::copy(ref, out);
  const Result r = runTool("--input-dir " + in(true) + " --output-dir " + out.string() + " " +
                           options("--temporal-radius 1") + " --resume");
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_EQ(r.output, ""); // --quiet
  const Result shown = runTool("--input-dir " + in(true) + " --output-dir " + out.string() +
                               " --search-window 5 --patch 3 --temporal-radius 1 --resume");
  EXPECT_NE(shown.output.find("f00.pcd: skipped (complete output exists)\n"), std::string::npos) << shown.output;
  EXPECT_EQ(std::count(shown.output.begin(), shown.output.end(), '\n'), kShortFrames);
  expectSameOutputs(out, ref);
}

TEST_F(InterruptedRuns, ResumeRefusesTheInputAsOutput)
{
  const Result r = runTool("--input-dir " + in(true) + " --output-dir " + in(true) + " --overwrite --resume");
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << r.output;
  EXPECT_NE(r.output.find("--resume cannot be used when the output is the input"), std::string::npos) << r.output;
}

TEST_F(InterruptedRuns, ToolStreamsLikeTheLibrary)
{
  // The tool's pass streams (which can skip finished frames) give TemporalStream's results.
  for (const bool causal : {false, true}) {
    SCOPED_TRACE(causal ? "causal" : "centred");
    const std::string extra = causal ? "--temporal-radius 2 --causal" : "--temporal-radius 1";
    const fs::path ref = reference(extra, true);
    std::vector<pcl::PointCloud<pcl::PointXYZ>::ConstPtr> frames;
    for (int k = 0; k < 8; ++k) {
      pcl::PointCloud<pcl::PointXYZ>::Ptr frame(new pcl::PointCloud<pcl::PointXYZ>);
      ASSERT_EQ(pcl::io::loadPCDFile(in(true) + "/" + frameName(k), *frame), 0);
      frames.push_back(frame);
    }
    // The first frames of the tool's run see the same windows as a stream over the first 8 frames
    // as long as they do not reach its end.
    FilterParameters p = FilterParameters::recommended();
    p.search_window = 5;
    p.patch_size = 3;
    const auto results = filterSequence<pcl::PointXYZ>(frames, causal ? 2 : 1, causal, p);
    ASSERT_EQ(results.size(), frames.size());
    for (int k = 0; k < (causal ? 8 : 7); ++k) {
      pcl::PointCloud<pcl::PointXYZ> tool;
      ASSERT_EQ(pcl::io::loadPCDFile((ref / frameName(k)).string(), tool), 0);
      ASSERT_EQ(tool.size(), results[k]->size());
      int differ = 0;
      for (std::size_t i = 0; i < tool.size(); ++i) {
        const auto &a = tool[i], &b = (*results[k])[i];
        const bool same = std::isnan(a.z) ? (std::isnan(b.x) && std::isnan(b.y) && std::isnan(b.z))
                                          : (a.x == b.x && a.y == b.y && a.z == b.z);
        differ += !same;
      }
      EXPECT_EQ(differ, 0) << frameName(k);
    }
  }
}
