// range_nlm_denoise --shard K/N: the shards of a recording together write exactly what one run
// writes, byte for byte, whatever the schedule; they share an output directory while runs that
// would write the same frames are refused; a shard resumes alone; recursive shards stay within
// 1 mm of one run.
#include "test_support.h"

#include <pcl/io/pcd_io.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <csignal>
#include <fcntl.h>
#include <map>
#include <string>
#include <sys/wait.h>
#include <thread>
#include <unistd.h>
#include <vector>

namespace fs = std::filesystem;
using namespace range_nlm;
using Cloud = pcl::PointCloud<pcl::PointXYZ>;

namespace
{

const std::string kTool = std::string(RANGE_NLM_TOOLS_DIR) + "/range_nlm_denoise";

std::string
frameName(int k)
{
  char name[24];
  std::snprintf(name, sizeof name, "scan_%03d.pcd", k);
  return name;
}

/// A step moving by a column per frame, noisy, with holes.
void
writeSequence(const fs::path& dir, int frames, int w, int h)
{
  fs::create_directories(dir);
  for (int k = 0; k < frames; ++k) {
    Cloud cloud = test::makeCloud(w, h, test::step(w / 4 + k % (w / 2), 1.0, 1.25), 0.005, 40 + k);
    test::punchHoles(cloud, 0.03, 70 + k);
    pcl::io::savePCDFileBinary((dir / frameName(k)).string(), cloud);
  }
}

/// The frame files of a directory (no hidden file: temporaries, the shards' lock file), sorted.
std::vector<std::string>
frameFiles(const fs::path& dir)
{
  std::vector<std::string> names;
  if (fs::exists(dir))
    for (const auto& entry : fs::directory_iterator(dir))
      if (entry.path().filename().string()[0] != '.')
        names.push_back(entry.path().filename().string());
  std::sort(names.begin(), names.end());
  return names;
}

/// True if a run holds frames [first, first + count) of the output directory `dir` (the byte
/// range of its lock file that range_nlm_denoise --shard locks).
bool
framesHeld(const fs::path& dir, std::size_t first, std::size_t count)
{
  const int fd = ::open((dir / ".range_nlm_denoise.lock").c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0)
    return false;
  struct flock probe = {};
  probe.l_type = F_WRLCK;
  probe.l_whence = SEEK_SET;
  probe.l_start = static_cast<off_t>(first);
  probe.l_len = static_cast<off_t>(count);
  const bool held = ::fcntl(fd, F_OFD_GETLK, &probe) == 0 && probe.l_type != F_UNLCK;
  ::close(fd);
  return held;
}

std::vector<std::string>
temporaries(const fs::path& dir)
{
  std::vector<std::string> names;
  for (const auto& entry : fs::directory_iterator(dir))
    if (entry.path().filename().string().find(".tmp") != std::string::npos)
      names.push_back(entry.path().filename().string());
  return names;
}

/// Same frame files, byte for byte, and no temporary left.
void
expectSameOutputs(const fs::path& out, const fs::path& reference, const std::string& what)
{
  const std::vector<std::string> names = frameFiles(reference);
  ASSERT_FALSE(names.empty());
  EXPECT_EQ(frameFiles(out), names) << what;
  for (const std::string& name : names)
    EXPECT_TRUE(test::readBytes((out / name).string()) == test::readBytes((reference / name).string()))
        << what << ": " << name << " differs from the single run";
  EXPECT_TRUE(temporaries(out).empty()) << what;
}

/// Largest |z_a - z_b| over the frames of two output directories (infinity if a point is NaN in
/// one only).
double
maxDepthDifference(const fs::path& a, const fs::path& b)
{
  double worst = 0.0;
  for (const std::string& name : frameFiles(a)) {
    Cloud ca, cb;
    EXPECT_EQ(pcl::io::loadPCDFile((a / name).string(), ca), 0) << name;
    EXPECT_EQ(pcl::io::loadPCDFile((b / name).string(), cb), 0) << name;
    EXPECT_EQ(ca.size(), cb.size()) << name;
    for (std::size_t i = 0; i < std::min(ca.size(), cb.size()); ++i) {
      const float za = ca[i].z, zb = cb[i].z;
      if (std::isnan(za) && std::isnan(zb))
        continue;
      worst = std::max(worst, std::isnan(za) != std::isnan(zb) ? INFINITY : std::abs(double(za) - zb));
    }
  }
  return worst;
}

class ShardedRuns : public ::testing::Test
{
protected:
  static constexpr int kFrames = 23;
  static void SetUpTestSuite()
  {
    root_ = fs::temp_directory_path() / ("range_nlm_sharded_" + std::to_string(::getpid()));
    fs::remove_all(root_);
    writeSequence(root_ / "in", kFrames, 32, 24);
  }
  static void TearDownTestSuite() { fs::remove_all(root_); }

  static std::string in() { return (root_ / "in").string(); }
  static std::string common(const std::string& schedule)
  {
    return "--input-dir " + in() + " --search-window 5 --patch 3 --normal-window 3 --iterations 1 --threads 1 --quiet " +
           schedule;
  }
  static test::CommandResult denoise(const std::string& args) { return test::runCommand(kTool + " " + args); }

  /// The single run of `schedule` (computed once per schedule).
  static fs::path single(const std::string& schedule)
  {
    auto found = singles_.find(schedule);
    if (found != singles_.end())
      return found->second;
    const fs::path out = root_ / ("single" + std::to_string(singles_.size()));
    const test::CommandResult r = denoise(common(schedule) + " --output-dir " + out.string());
    EXPECT_EQ(r.status, 0) << r.output;
    EXPECT_EQ(frameFiles(out).size(), std::size_t(kFrames));
    return singles_[schedule] = out;
  }

  /// Runs the N shards of `schedule` one after the other into a fresh directory.
  static fs::path sharded(const std::string& schedule, int count, const std::string& name)
  {
    const fs::path out = root_ / name;
    fs::remove_all(out);
    for (int k = 0; k < count; ++k) {
      const test::CommandResult r = denoise(common(schedule) + " --output-dir " + out.string() + " --shard " +
                                            std::to_string(k) + "/" + std::to_string(count));
      EXPECT_EQ(r.status, 0) << "shard " << k << "/" << count << ": " << r.output;
    }
    return out;
  }

  static fs::path root_;
  static std::map<std::string, fs::path> singles_;
};
fs::path ShardedRuns::root_;
std::map<std::string, fs::path> ShardedRuns::singles_;

} // namespace

TEST_F(ShardedRuns, ShardsTogetherAreByteIdenticalToOneRunForEverySchedule)
{
  const std::vector<std::string> schedules{
      "", // static: no halo
      "--temporal-radius 3 --causal",
      // Two passes: the halo is the sum of the radii, 2 + 1 on each side.
      "--pass search=5,patch=3,radius=2 --pass search=3,patch=3,radius=1",
      "--temporal-radius 1 --causal --pass search=5,patch=3,radius=2 --pass search=5,patch=3,radius=1",
      "--pass search=5,patch=3,radius=1 --pass search=3,patch=3,radius=0 --pass search=5,patch=3,radius=2"};
  // 23 frames in 4 shards of 6 or 5 frames. (Under AddressSanitizer, ten times slower, the
  // first three schedules.)
  for (std::size_t i = 0; i < (test::kAddressSanitizer ? 3 : schedules.size()); ++i) {
    const std::string& schedule = schedules[i];
    expectSameOutputs(sharded(schedule, 4, "shards"), single(schedule), "'" + schedule + "' in 4 shards");
  }
  // Shards of 3 or 2 frames, smaller than the halo of 3 on each side.
  expectSameOutputs(sharded(schedules[2], 10, "shards"), single(schedules[2]), "10 shards");
}

TEST_F(ShardedRuns, TheHaloIsNeeded)
{
  // The frames of one shard filtered on their own, without the halo, differ from the single run
  // at the shard's borders: the byte-for-byte comparisons above are not comparing like with like.
  const std::string schedule = "--pass search=5,patch=3,radius=2 --pass search=3,patch=3,radius=1";
  const fs::path alone_in = root_ / "alone_in";
  fs::create_directories(alone_in);
  for (int k = 6; k < 12; ++k) // shard 1 of 4
    fs::copy_file(root_ / "in" / frameName(k), alone_in / frameName(k), fs::copy_options::overwrite_existing);
  const fs::path alone = root_ / "alone";
  const test::CommandResult r =
      test::runCommand(kTool + " --input-dir " + alone_in.string() + " --output-dir " + alone.string() +
                       " --search-window 5 --patch 3 --normal-window 3 --threads 1 --quiet " + schedule);
  ASSERT_EQ(r.status, 0) << r.output;
  const fs::path one = single(schedule);
  EXPECT_FALSE(test::readBytes((alone / frameName(6)).string()) == test::readBytes((one / frameName(6)).string()));
  EXPECT_FALSE(test::readBytes((alone / frameName(11)).string()) == test::readBytes((one / frameName(11)).string()));
  const fs::path shards = sharded(schedule, 4, "halo_shards");
  EXPECT_TRUE(test::readBytes((shards / frameName(6)).string()) == test::readBytes((one / frameName(6)).string()));
}

TEST_F(ShardedRuns, EachShardWritesOnlyItsOwnFramesAndSaysWhichInJson)
{
  const std::string schedule = "--temporal-radius 2";
  const fs::path out = root_ / "json";
  fs::remove_all(out);
  const test::CommandResult r = denoise(common(schedule) + " --output-dir " + out.string() + " --shard 1/4 --json");
  ASSERT_EQ(r.status, 0) << r.output;
  const nlohmann::json summary = test::jsonLine(r.output);
  // 23 frames in 4 shards: 6, 6, 6, 5; shard 1 writes frames 6 .. 11 and reads 4 .. 13.
  EXPECT_EQ(summary["frames"], 6);
  EXPECT_EQ(summary["skipped"], 0);
  EXPECT_EQ(summary["shard"]["index"], 1);
  EXPECT_EQ(summary["shard"]["count"], 4);
  EXPECT_EQ(summary["shard"]["sequence_frames"], kFrames);
  EXPECT_EQ(summary["shard"]["first_frame"], 6);
  EXPECT_EQ(summary["shard"]["first_frame_read"], 4);
  EXPECT_EQ(summary["shard"]["frames_read"], 10);
  std::vector<std::string> expected;
  for (int k = 6; k < 12; ++k)
    expected.push_back(frameName(k));
  EXPECT_EQ(frameFiles(out), expected);
  EXPECT_FALSE(summary["shard"].contains("warmup")) << "no recursive pass, no warm-up";
  // Without --json the first line says the same.
  const test::CommandResult plain =
      test::runCommand(kTool + " --input-dir " + in() + " --output-dir " + out.string() +
                       " --search-window 5 --patch 3 --normal-window 3 --threads 1 --temporal-radius 2 --shard 3/4 --resume");
  ASSERT_EQ(plain.status, 0) << plain.output;
  EXPECT_EQ(plain.output.rfind("shard 3/4: frames 18..22 of 23 (scan_018.pcd .. scan_022.pcd), reading frames 16..22\n", 0),
            0u)
      << plain.output;
}

TEST_F(ShardedRuns, MoreShardsThanFramesLeavesEmptyShardsThatSucceed)
{
  const std::string schedule = "--temporal-radius 1";
  const fs::path out = root_ / "many";
  fs::remove_all(out);
  const test::CommandResult empty = denoise(common(schedule) + " --output-dir " + out.string() + " --shard 30/31 --json");
  ASSERT_EQ(empty.status, 0) << empty.output;
  EXPECT_EQ(test::jsonLine(empty.output)["frames"], 0);
  EXPECT_EQ(test::jsonLine(empty.output)["shard"]["frames"], 0);
  EXPECT_TRUE(frameFiles(out).empty());
  const test::CommandResult said =
      test::runCommand(kTool + " --input-dir " + in() + " --output-dir " + out.string() + " --temporal-radius 1 --shard 25/31");
  EXPECT_EQ(said.status, 0) << said.output;
  EXPECT_NE(said.output.find("shard 25/31: no frames to write (23 frames, 31 shards)"), std::string::npos) << said.output;
  expectSameOutputs(sharded(schedule, 31, "many"), single(schedule), "31 shards of 23 frames");
}

TEST_F(ShardedRuns, AShardResumesAloneToTheSameBytes)
{
  const std::string schedule = "--pass search=5,patch=3,radius=2 --pass search=3,patch=3,radius=1";
  const fs::path out = sharded(schedule, 3, "resume"); // frames 0..7, 8..15, 16..22
  // Shard 1 failed half-way: two outputs missing, one truncated, a temporary left behind.
  fs::remove(out / frameName(9));
  fs::remove(out / frameName(14));
  fs::resize_file(out / frameName(12), 100);
  std::ofstream(out / ("." + frameName(9) + ".tmp12345")) << "partial";
  // Another shard's temporary is not this shard's to remove.
  std::ofstream(out / ("." + frameName(2) + ".tmp999")) << "partial";
  const auto untouched = fs::last_write_time(out / frameName(8));
  const test::CommandResult r = denoise(common(schedule) + " --output-dir " + out.string() + " --shard 1/3 --resume --json");
  ASSERT_EQ(r.status, 0) << r.output;
  const nlohmann::json summary = test::jsonLine(r.output);
  EXPECT_EQ(summary["frames"], 3);
  EXPECT_EQ(summary["skipped"], 5);
  EXPECT_EQ(fs::last_write_time(out / frameName(8)), untouched);
  EXPECT_TRUE(fs::exists(out / ("." + frameName(2) + ".tmp999")));
  fs::remove(out / ("." + frameName(2) + ".tmp999"));
  expectSameOutputs(out, single(schedule), "shard 1 resumed");
}

TEST_F(ShardedRuns, BadShardOptionsAreRefusedNamingTheValue)
{
  const fs::path out = root_ / "bad";
  const std::string base = common("--temporal-radius 1") + " --output-dir " + out.string();
  struct Case
  {
    std::string args, message;
  };
  const std::vector<Case> cases{
      {"--shard 4/4", "--shard '4/4': K must be less than N"},
      {"--shard 1/0", "--shard '1/0': the number of shards N must be at least 1"},
      {"--shard -1/4", "--shard '-1/4': expected K/N"},
      {"--shard two/4", "--shard 'two/4': expected K/N"},
      {"--shard slurm", "--shard slurm: SLURM_ARRAY_TASK_ID is not set"},
      {"--shard 0/2 --shard-warmup 4", "--shard-warmup 4 applies to --recursive runs only"},
      {"--shard-warmup 4 --recursive", "--shard-warmup 4 needs --shard"},
      {"--shard 0/2 --recursive --shard-warmup -3", "--shard-warmup must be a number of frames >= 0 or 'all', got '-3'"},
      {"--shard 0/2 --recursive --shard-warmup 2x", "got '2x'"},
  };
  for (const Case& c : cases) {
    // Run outside any Slurm job, whatever the environment of the test.
    const test::CommandResult r =
        test::runCommand("env -u SLURM_ARRAY_TASK_ID -u SLURM_ARRAY_TASK_COUNT " + kTool + " " + base + " " + c.args);
    EXPECT_EQ(r.status, 2) << c.args << ": " << r.output;
    EXPECT_NE(r.output.find(c.message), std::string::npos) << c.args << ": " << r.output;
  }
  const test::CommandResult into_input =
      denoise(common("") + " --output-dir " + in() + " --overwrite --shard 0/2");
  EXPECT_EQ(into_input.status, 2) << into_input.output;
  EXPECT_NE(into_input.output.find("--shard cannot write into the input directory"), std::string::npos)
      << into_input.output;
  const test::CommandResult single_frame =
      test::runCommand(kTool + " " + in() + "/" + frameName(0) + " " + (root_ / "one.pcd").string() + " --shard 0/2");
  EXPECT_EQ(single_frame.status, 2) << single_frame.output;
  EXPECT_NE(single_frame.output.find("--shard cuts a directory of frames"), std::string::npos) << single_frame.output;
  EXPECT_TRUE(frameFiles(out).empty());
}

TEST_F(ShardedRuns, SlurmArrayVariablesChooseTheShard)
{
  const std::string schedule = "--temporal-radius 2";
  const fs::path out = root_ / "slurm_env";
  fs::remove_all(out);
  // --array=10-13: task 12 is shard 2 of 4.
  const test::CommandResult r = test::runCommand(
      "env SLURM_ARRAY_TASK_ID=12 SLURM_ARRAY_TASK_MIN=10 SLURM_ARRAY_TASK_MAX=13 SLURM_ARRAY_TASK_COUNT=4 "
      "SLURM_ARRAY_TASK_STEP=1 " +
      kTool + " " + common(schedule) + " --output-dir " + out.string() + " --shard slurm --json");
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_EQ(test::jsonLine(r.output)["shard"]["index"], 2);
  EXPECT_EQ(test::jsonLine(r.output)["shard"]["count"], 4);
  for (const std::string& name : frameFiles(out))
    EXPECT_TRUE(test::readBytes((out / name).string()) == test::readBytes((single(schedule) / name).string())) << name;
  EXPECT_EQ(frameFiles(out).size(), 6u); // frames 12 .. 17
  EXPECT_EQ(frameFiles(out).front(), frameName(12));
}

TEST_F(ShardedRuns, ShardsShareTheOutputDirectoryButNotTheirFrames)
{
  // Larger frames, so that a shard is still running while the others start.
  const int w = test::kAddressSanitizer ? 64 : 160, h = test::kAddressSanitizer ? 48 : 120;
  const fs::path big = root_ / "big_in";
  writeSequence(big, 40, w, h);
  const std::string options = "--input-dir " + big.string() + " --temporal-radius 1 --threads 1 --quiet";
  const fs::path ref = root_ / "big_single";
  ASSERT_EQ(test::runCommand(kTool + " " + options + " --output-dir " + ref.string()).status, 0);

  const fs::path out = root_ / "big_shards";
  auto start = [&](const std::string& shard, const std::string& log) {
    std::vector<std::string> args{kTool, "--output-dir", out.string(), "--shard", shard};
    std::istringstream words(options);
    for (std::string word; words >> word;)
      args.push_back(word);
    return test::startProcess(args, (root_ / log).string());
  };
  // All four shards at once, and while they run (each held still with SIGSTOP as soon as it has
  // written its first frame, so that it holds its frames and cannot end first, however slowly
  // the others start): the same shard again, a shard of another count overlapping them, and a
  // run over the whole recording are refused.
  std::vector<pid_t> shards;
  for (int k = 0; k < 4; ++k)
    shards.push_back(start(std::to_string(k) + "/4", "shard" + std::to_string(k) + ".txt"));
  std::vector<bool> held(4, false);
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::minutes(2);
  while (std::chrono::steady_clock::now() < deadline && std::count(held.begin(), held.end(), true) < 4) {
    const std::vector<std::string> names = frameFiles(out);
    for (int k = 0; k < 4; ++k)
      for (int f = 10 * k; f < 10 * k + 10 && !held[k]; ++f) {
        char name[32];
        std::snprintf(name, sizeof name, "scan_%03d.pcd", f);
        if (std::binary_search(names.begin(), names.end(), std::string(name))) {
          ::kill(shards[k], SIGSTOP);
          held[k] = true;
        }
      }
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  for (int k = 0; k < 4; ++k)
    if (!held[k])
      ::kill(shards[k], SIGSTOP);
  const std::size_t written = frameFiles(out).size();
  for (int k = 0; k < 4; ++k)
    EXPECT_TRUE(held[k] && framesHeld(out, 10 * k, 10))
        << "shard " << k << "/4 wrote no frame within two minutes, or does not hold its frames";
  const test::CommandResult again = test::runCommand(kTool + " " + options + " --output-dir " + out.string() + " --shard 2/4");
  const test::CommandResult overlapping =
      test::runCommand(kTool + " " + options + " --output-dir " + out.string() + " --shard 0/2 --resume");
  const test::CommandResult whole = test::runCommand(kTool + " " + options + " --output-dir " + out.string() + " --resume");
  for (pid_t pid : shards)
    ::kill(pid, SIGCONT);
  for (int k = 0; k < 4; ++k) {
    int status = 0;
    ::waitpid(shards[k], &status, 0);
    EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0)
        << "shard " << k << ": " << test::readBytes((root_ / ("shard" + std::to_string(k) + ".txt")).string());
  }
  ASSERT_LT(written, 40u) << "the shards ended before they could be held";
  EXPECT_EQ(again.status, 4) << again.output;
  EXPECT_NE(again.output.find("frames 20..29 (scan_020.pcd .. scan_029.pcd) of output directory"), std::string::npos)
      << again.output;
  EXPECT_NE(again.output.find("are being written by another range_nlm_denoise run (holding frames 20..29"),
            std::string::npos)
      << again.output;
  EXPECT_EQ(overlapping.status, 4) << overlapping.output;
  EXPECT_NE(overlapping.output.find("are being written by another range_nlm_denoise run"), std::string::npos)
      << overlapping.output;
  EXPECT_EQ(whole.status, 4) << whole.output;
  EXPECT_NE(whole.output.find("is in use by another range_nlm_denoise run"), std::string::npos) << whole.output;
  expectSameOutputs(out, ref, "four concurrent shards");
  // Once they are done, the same shard may run again (it finds its frames finished).
  const test::CommandResult later =
      test::runCommand(kTool + " " + options + " --output-dir " + out.string() + " --shard 2/4 --resume --json");
  EXPECT_EQ(later.status, 0) << later.output;
  EXPECT_EQ(test::jsonLine(later.output)["skipped"], 10);
}

TEST_F(ShardedRuns, RecursiveShardsStayCloseToOneRunAndReplayingTheWholeHistoryIsExact)
{
  // Recursive mode carries the history of every earlier frame along, so a shard that starts its history
  // --shard-warmup frames early differs slightly from one run; 'all' replays from frame 0.
  const std::string schedule = "--temporal-radius 1 --recursive";
  const fs::path one = single(schedule);
  const fs::path exact = sharded(schedule + " --shard-warmup all", 4, "recursive_all");
  expectSameOutputs(exact, one, "recursive, warm-up 'all'");
  const double cold = maxDepthDifference(sharded(schedule + " --shard-warmup 0", 4, "recursive_cold"), one);
  const double warm = maxDepthDifference(sharded(schedule, 4, "recursive_default"), one); // 8 frames
  // The tolerance docs/cluster.md states for the default warm-up of 8 x the radius: 3 mm here,
  // on a scene at 1 - 1.25 m with 5 mm of noise; shards without warm-up exceed it.
  EXPECT_LE(warm, 0.003) << "max |dz| with the default warm-up";
  EXPECT_GT(cold, 0.003) << "max |dz| without warm-up";
  std::cout << "recursive shards, max |dz| from one run: " << cold << " m without warm-up, " << warm
            << " m with the default warm-up\n";
  EXPECT_GT(cold, warm) << "without warm-up a shard starts its history cold and differs more";
  EXPECT_GT(cold, 0.0);
  // Shard 2 (frames 12 .. 17) replays 8 frames of history from frame 4.
  const test::CommandResult json = denoise(common(schedule) + " --output-dir " + (root_ / "recursive_json").string() +
                                           " --shard 2/4 --json");
  ASSERT_EQ(json.status, 0) << json.output;
  EXPECT_EQ(test::jsonLine(json.output)["shard"]["warmup"], 8);
  EXPECT_EQ(test::jsonLine(json.output)["shard"]["first_frame_read"], 4);
  EXPECT_EQ(test::jsonLine(json.output)["frames"], 6);
  // Shard 1 starts at frame 6: its warm-up of 8 frames reaches back to frame 0, so it is exact.
  for (int k = 6; k < 12; ++k)
    EXPECT_TRUE(test::readBytes((root_ / "recursive_default" / frameName(k)).string()) ==
                test::readBytes((one / frameName(k)).string()))
        << frameName(k);
}

TEST_F(ShardedRuns, RecursiveRunResumesWhenItsLastFramesAreFinished)
{
  // A recursive pass reads nothing after the last frame it still has to write: those frames
  // reach its stream as gaps, which end its history instead of failing the run.
  const std::string schedule = "--temporal-radius 2 --recursive";
  const fs::path out = root_ / "recursive_resume";
  fs::remove_all(out);
  fs::copy(single(schedule), out);
  fs::remove(out / frameName(1));
  const test::CommandResult r = denoise(common(schedule) + " --output-dir " + out.string() + " --resume --json");
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_EQ(test::jsonLine(r.output)["frames"], 1);
  expectSameOutputs(out, single(schedule), "recursive run resumed");
}
