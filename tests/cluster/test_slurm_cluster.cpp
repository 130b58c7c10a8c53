// range_nlm_denoise on a real Slurm cluster: a one-node cluster (munged, slurmctld, slurmd) is
// brought up on 127.0.0.1 with every file in a temporary directory, scripts/slurm/submit.sh
// filters a recording as a job array of shards plus a check job, one shard is cancelled, the
// check job fails naming what is missing, submit.sh --rerun submits that shard again, and the
// outputs must be byte-identical to one run on this machine; numbers with leading zeros are
// decimal. Skipped, saying so, where slurm-wlm and munge are
// not installed (scripts/setup.sh installs them).
#include "test_support.h"

#include <pcl/io/pcd_io.h>

#include <gtest/gtest.h>

#include <arpa/inet.h>
#include <netinet/in.h>
#include <pwd.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <memory>
#include <random>
#include <regex>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

namespace fs = std::filesystem;
using namespace range_nlm;
using Clock = std::chrono::steady_clock;

namespace
{

const std::string kTool = std::string(RANGE_NLM_TOOLS_DIR) + "/range_nlm_denoise";
const fs::path kScripts = fs::path(RANGE_NLM_SOURCE_DIR) / "scripts" / "slurm";

/// The path of an installed program (PATH, then the sbin directories), or "".
std::string
findProgram(const std::string& name)
{
  std::string path = std::getenv("PATH") ? std::getenv("PATH") : "";
  path += ":/usr/sbin:/sbin:/usr/local/sbin";
  std::stringstream dirs(path);
  for (std::string dir; std::getline(dirs, dir, ':');)
    if (!dir.empty() && ::access((fs::path(dir) / name).c_str(), X_OK) == 0)
      return (fs::path(dir) / name).string();
  return "";
}

/// The last lines of a log file.
std::string
tail(const fs::path& file, std::size_t lines = 15)
{
  std::vector<std::string> all;
  std::ifstream in(file);
  for (std::string line; std::getline(in, line);)
    all.push_back(line);
  std::string text = "--- " + file.string() + "\n";
  for (std::size_t i = all.size() > lines ? all.size() - lines : 0; i < all.size(); ++i)
    text += all[i] + "\n";
  return text;
}

bool
running(pid_t pid)
{
  return pid > 0 && ::waitpid(pid, nullptr, WNOHANG) == 0;
}

/// Ends a process this test started: SIGTERM, then SIGKILL after five seconds.
void
stop(pid_t& pid)
{
  if (pid <= 0)
    return;
  ::kill(pid, SIGTERM);
  const auto deadline = Clock::now() + std::chrono::seconds(5);
  while (Clock::now() < deadline && ::waitpid(pid, nullptr, WNOHANG) == 0)
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  if (::waitpid(pid, nullptr, WNOHANG) == 0) {
    ::kill(pid, SIGKILL);
    ::waitpid(pid, nullptr, 0);
  }
  pid = -1;
}

/// A one-node Slurm cluster on 127.0.0.1 with its own munged; everything in `dir`. Torn down
/// (jobs cancelled, daemons ended) by the destructor, however the test ends.
class SlurmCluster
{
public:
  explicit SlurmCluster(const fs::path& dir) : dir_(dir)
  {
    try {
      start();
    } catch (...) {
      tearDown();
      throw;
    }
  }
  ~SlurmCluster() { tearDown(); }

  SlurmCluster(const SlurmCluster&) = delete;
  SlurmCluster& operator=(const SlurmCluster&) = delete;

  /// The daemons' logs, for a failure message.
  std::string logs() const
  {
    std::string text;
    for (const char* name : {"munged.out", "slurmctld.out", "slurmctld.log", "slurmd.out", "slurmd.log"})
      if (fs::exists(dir_ / "log" / name))
        text += tail(dir_ / "log" / name);
    return text;
  }

private:
  void start()
  {
    fs::create_directories(dir_ / "munge-key");
    fs::permissions(dir_ / "munge-key", fs::perms::owner_all, fs::perm_options::replace);
    fs::create_directories(dir_ / "munge-socket");
    fs::permissions(dir_ / "munge-socket", fs::perms::owner_all | fs::perms::group_read | fs::perms::group_exec |
                                                fs::perms::others_read | fs::perms::others_exec,
                    fs::perm_options::replace);
    for (const char* sub : {"state", "spool", "log"})
      fs::create_directories(dir_ / sub);

    // A fresh munge key: 1024 random bytes, readable by its owner only.
    const fs::path key = dir_ / "munge-key" / "munge.key";
    {
      std::random_device random;
      std::ofstream out(key, std::ios::binary);
      for (int i = 0; i < 1024; ++i)
        out.put(static_cast<char>(random() & 0xff));
    }
    fs::permissions(key, fs::perms::owner_read, fs::perm_options::replace);
    const fs::path socket = dir_ / "munge-socket" / "munge.socket";
    munged_ = test::startProcess({findProgram("munged"), "--foreground", "--force", "--socket=" + socket.string(),
                                  "--key-file=" + key.string(), "--pid-file=" + (dir_ / "munged.pid").string(),
                                  "--log-file=" + (dir_ / "log" / "munged.log").string(),
                                  "--seed-file=" + (dir_ / "munge-key" / "munged.seed").string()},
                                 (dir_ / "log" / "munged.out").string());
    waitFor([&] { return fs::exists(socket); }, 20, "munged to create its socket", munged_);

    const passwd* user = ::getpwuid(::geteuid());
    const std::string user_name = user ? user->pw_name : "root";
    const fs::path conf = dir_ / "slurm.conf";
    std::ofstream(conf) << "ClusterName=rnlmtest\n"
                        << "SlurmctldHost=localhost(127.0.0.1)\n"
                        << "SlurmctldPort=" << test::freePort() << "\n"
                        << "SlurmdPort=" << test::freePort() << "\n"
                        << "SlurmUser=" << user_name << "\nSlurmdUser=" << user_name << "\n"
                        << "AuthType=auth/munge\nCredType=cred/munge\n"
                        << "AuthInfo=socket=" << socket.string() << "\n"
                        << "StateSaveLocation=" << (dir_ / "state").string() << "\n"
                        << "SlurmdSpoolDir=" << (dir_ / "spool").string() << "\n"
                        << "SlurmctldPidFile=" << (dir_ / "slurmctld.pid").string() << "\n"
                        << "SlurmdPidFile=" << (dir_ / "slurmd.pid").string() << "\n"
                        << "SlurmctldLogFile=" << (dir_ / "log" / "slurmctld.log").string() << "\n"
                        << "SlurmdLogFile=" << (dir_ / "log" / "slurmd.log").string() << "\n"
                        << "ProctrackType=proctrack/linuxproc\nTaskPlugin=task/none\n"
                        << "JobAcctGatherType=jobacct_gather/none\nAccountingStorageType=accounting_storage/none\n"
                        << "JobCompType=jobcomp/none\nMpiDefault=none\n"
                        << "SelectType=select/cons_tres\nSelectTypeParameters=CR_CPU\n"
                        << "SchedulerType=sched/backfill\nReturnToService=2\n"
                        // CPUs=2 whatever the machine has, so that the node is not drained.
                        << "SlurmdParameters=config_overrides\n"
                        << "NodeName=localhost NodeAddr=127.0.0.1 CPUs=2 State=UNKNOWN\n"
                        << "PartitionName=debug Nodes=localhost Default=YES MaxTime=INFINITE State=UP\n";
    ::setenv("SLURM_CONF", conf.c_str(), 1); // for the daemons, sbatch, squeue, sinfo and the jobs
    slurmctld_ = test::startProcess({findProgram("slurmctld"), "-D", "-f", conf.string()},
                                    (dir_ / "log" / "slurmctld.out").string());
    slurmd_ = test::startProcess({findProgram("slurmd"), "-D", "-f", conf.string(), "-N", "localhost"},
                                 (dir_ / "log" / "slurmd.out").string());
    waitFor([] { return test::runCommand("sinfo -h -n localhost -o %t").output == "idle\n"; }, 60,
            "sinfo to show the node idle", slurmd_);
  }

  /// Cancels what is left of the jobs, then ends the daemons this test started.
  void tearDown()
  {
    if (running(slurmctld_) && running(slurmd_)) {
      test::runCommand("scancel --quiet --user=$(id -un)");
      waitFor([] { return test::runCommand("squeue -h").output.empty(); }, 15, "", -1, false);
    }
    stop(slurmd_);
    stop(slurmctld_);
    stop(munged_);
    ::unsetenv("SLURM_CONF");
  }

  /// Waits up to `seconds` for `done`; throws (with the logs) if it does not come or the process
  /// `watched` ends first.
  template <typename Done>
  void waitFor(const Done& done, int seconds, const std::string& what, pid_t watched, bool required = true) const
  {
    const auto deadline = Clock::now() + std::chrono::seconds(seconds);
    while (Clock::now() < deadline) {
      if (done())
        return;
      if (watched > 0 && !running(watched))
        throw std::runtime_error("a daemon ended while waiting for " + what + "\n" + logs());
      std::this_thread::sleep_for(std::chrono::milliseconds(200));
    }
    if (required)
      throw std::runtime_error("no " + what + " after " + std::to_string(seconds) + " s\n" + logs());
  }

  fs::path dir_;
  pid_t munged_ = -1, slurmctld_ = -1, slurmd_ = -1;
};

std::string
frameName(int k)
{
  char name[24];
  std::snprintf(name, sizeof name, "depth_%04d.pcd", k);
  return name;
}

std::vector<std::string>
frameFiles(const fs::path& dir)
{
  std::vector<std::string> names;
  for (const auto& entry : fs::directory_iterator(dir))
    if (entry.path().filename().string()[0] != '.')
      names.push_back(entry.path().filename().string());
  std::sort(names.begin(), names.end());
  return names;
}

class SlurmClusterTest : public ::testing::Test
{
protected:
  void SetUp() override
  {
    for (const char* program : {"munged", "slurmctld", "slurmd", "sbatch", "squeue", "sinfo", "scancel"})
      if (findProgram(program).empty())
        GTEST_SKIP() << "skipped: '" << program << "' not found; the one-node Slurm cluster test needs the Debian "
                     << "packages slurm-wlm and munge (scripts/setup.sh installs them)";
    if (::geteuid() != 0)
      GTEST_SKIP() << "skipped: the one-node Slurm cluster test runs slurmd, which needs root (as in CI)";
    dir_ = fs::temp_directory_path() / ("range_nlm_slurm_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override
  {
    if (!dir_.empty())
      fs::remove_all(dir_);
  }
  fs::path dir_;
};

/// The first task log in `logs` that reports a failed range_nlm_denoise ("" if none).
std::string
failedTask(const fs::path& logs)
{
  if (fs::exists(logs))
    for (const auto& entry : fs::directory_iterator(logs)) {
      const std::string text = test::readBytes(entry.path().string());
      if (text.find("exit_status=") != std::string::npos && text.find("exit_status=0") == std::string::npos)
        return entry.path().string() + ":\n" + text;
    }
  return "";
}

/// Waits until the cluster has no job left; false after `seconds`, or as soon as a task in
/// `logs` has failed (the check job would then wait for ever on its afterok dependency).
bool
waitForJobs(int seconds, const fs::path& logs = fs::path())
{
  const auto deadline = Clock::now() + std::chrono::seconds(seconds);
  while (Clock::now() < deadline) {
    if (test::runCommand("squeue -h").output.empty())
      return true;
    if (!logs.empty() && !failedTask(logs).empty())
      return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(250));
  }
  return false;
}

} // namespace

TEST_F(SlurmClusterTest, JobArrayOfShardsWritesWhatOneMachineWrites)
{
  // A recording of a few dozen small frames: a step that moves, noise and holes.
  constexpr int kFrames = 30;
  const fs::path in = dir_ / "recording";
  fs::create_directories(in);
  for (int k = 0; k < kFrames; ++k) {
    auto cloud = test::makeCloud(40, 30, test::step(8 + k % 20, 1.0, 1.3), 0.005, 11 + k);
    test::punchHoles(cloud, 0.03, 51 + k);
    pcl::io::savePCDFileBinary((in / frameName(k)).string(), cloud);
  }
  // A two-pass temporal schedule: halo 2 + 1 frames on each side of a shard.
  const std::string options = "--search-window 5 --patch 3 --normal-window 3 --iterations 1 "
                              "--pass search=5,patch=3,radius=2 --pass search=3,patch=3,radius=1";
  const fs::path single = dir_ / "single";
  const test::CommandResult one =
      test::runCommand(kTool + " --input-dir " + in.string() + " --output-dir " + single.string() + " --quiet " + options);
  ASSERT_EQ(one.status, 0) << one.output;

  std::unique_ptr<SlurmCluster> cluster;
  try {
    cluster = std::make_unique<SlurmCluster>(dir_ / "cluster");
  } catch (const std::exception& e) {
    FAIL() << "the one-node Slurm cluster did not come up: " << e.what();
  }

  // Four shards, one CPU each, one at a time (so that shard 2 is still pending when it is
  // cancelled): the check job runs after the array however its tasks end, and fails.
  const fs::path out = dir_ / "sharded";
  const fs::path logs = dir_ / "sharded.logs";
  const test::CommandResult submitted =
      test::runCommand("RANGE_NLM_CPUS=1 RANGE_NLM_ARRAY_LIMIT=1 RANGE_NLM_DENOISE=" + kTool + " bash " +
                       (kScripts / "submit.sh").string() + " " + in.string() + " " + out.string() + " 4 " + options);
  ASSERT_EQ(submitted.status, 0) << submitted.output << cluster->logs();
  std::smatch ids;
  ASSERT_TRUE(std::regex_search(submitted.output, ids, std::regex("array job ([0-9]+) .*check job ([0-9]+)")))
      << submitted.output;
  const std::string array_job = ids[1], check_job = ids[2];
  const test::CommandResult cancelled = test::runCommand("scancel " + array_job + "_2");
  ASSERT_EQ(cancelled.status, 0) << cancelled.output;
  ASSERT_TRUE(waitForJobs(90)) << "jobs left after 90 s:\n" << test::runCommand("squeue").output << cluster->logs();
  const std::string failed = test::readBytes((logs / ("range_nlm-check-" + check_job + ".out")).string());
  EXPECT_NE(failed.find("30 input frames in " + in.string() + ", 23 outputs in " + out.string() + ", 7 missing"),
            std::string::npos)
      << failed << cluster->logs();
  EXPECT_NE(failed.find("shards: 3 task logs, 3 shards done"), std::string::npos) << failed;
  EXPECT_NE(failed.find("range_nlm check: FAILED (re-run the failed shards: scripts/slurm/submit.sh --rerun " +
                        logs.string() + ")"),
            std::string::npos)
      << failed;
  for (int k : {0, 1, 3}) {
    const std::string task = test::readBytes((logs / ("range_nlm-" + array_job + "_" + std::to_string(k) + ".out")).string());
    EXPECT_NE(task.find("shard " + std::to_string(k) + "/4, 1 thread(s)"), std::string::npos) << task;
    EXPECT_NE(task.find("exit_status=0"), std::string::npos) << task;
  }

  // The rerun helper submits exactly shard 2 again, with the recorded N and options.
  const test::CommandResult rerun = test::runCommand("bash " + (kScripts / "submit.sh").string() + " --rerun " + logs.string());
  ASSERT_EQ(rerun.status, 0) << rerun.output;
  ASSERT_TRUE(std::regex_search(rerun.output, ids, std::regex("re-running shards 2 of 4: array job ([0-9]+), check job ([0-9]+)")))
      << rerun.output;
  const std::string rerun_job = ids[1], recheck_job = ids[2];
  ASSERT_TRUE(waitForJobs(60, logs)) << test::runCommand("squeue").output << failedTask(logs) << cluster->logs();
  const std::string rerun_log = test::readBytes((logs / ("range_nlm-" + rerun_job + "_2.out")).string());
  EXPECT_NE(rerun_log.find("shard 2/4"), std::string::npos) << rerun_log;
  EXPECT_NE(rerun_log.find("\"frames\":7,"), std::string::npos) << rerun_log;
  const std::string check = test::readBytes((logs / ("range_nlm-check-" + recheck_job + ".out")).string());
  EXPECT_NE(check.find("30 input frames in " + in.string() + ", 30 outputs in " + out.string() + ", 0 missing"),
            std::string::npos)
      << check;
  EXPECT_NE(check.find("shards: 4 task logs, 4 shards done; failed: none; not finished: none"), std::string::npos)
      << check;
  // Each shard reads and filters its halo too: of the 30 frames, more are read than written, and
  // the two passes filter more than twice as many.
  std::smatch counts;
  ASSERT_TRUE(std::regex_search(check, counts, std::regex("frames: 30 written, 0 skipped \\(--resume\\); ([0-9]+) read, "
                                                          "([0-9]+) filtered over all passes")))
      << check;
  EXPECT_GT(std::stoi(counts[1]), 30) << check;
  EXPECT_GT(std::stoi(counts[2]), 60) << check;
  EXPECT_NE(check.find("range_nlm check: OK"), std::string::npos) << check;
  EXPECT_EQ(check.find("temporary files"), std::string::npos) << check;
  EXPECT_NE(test::runCommand("bash " + (kScripts / "submit.sh").string() + " --rerun " + logs.string())
                .output.find("nothing to re-run"),
            std::string::npos);
  ASSERT_EQ(frameFiles(out), frameFiles(single));
  for (const std::string& name : frameFiles(single))
    EXPECT_TRUE(test::readBytes((out / name).string()) == test::readBytes((single / name).string()))
        << name << " differs from the single-machine run";

  // The array script submitted by hand without RANGE_NLM_DENOISE, the tool not on PATH: it takes
  // the tool of the checkout it was submitted from (build/tools/), or says that there is none.
  const test::CommandResult by_sbatch = test::runCommand(
      "env -u RANGE_NLM_DENOISE PATH=/usr/bin:/bin sbatch --parsable --array=2 --cpus-per-task=1 --output=" +
      (logs / "hand-%A_%a.txt").string() + " --export=ALL,RANGE_NLM_SHARDS=4 " +
      (kScripts / "range_nlm_array.sbatch").string() + " " + in.string() + " " + out.string() + " " + options);
  ASSERT_EQ(by_sbatch.status, 0) << by_sbatch.output;
  ASSERT_TRUE(waitForJobs(60)) << test::runCommand("squeue").output << cluster->logs();
  const std::string hand_log = test::readBytes(
      (logs / ("hand-" + by_sbatch.output.substr(0, by_sbatch.output.find_first_of(";\n")) + "_2.txt")).string());
  // Whichever build the test runs from (the sanitizer build too), the script looks in build/tools/.
  std::error_code ec;
  if (fs::exists(fs::path(RANGE_NLM_SOURCE_DIR) / "build" / "tools" / "range_nlm_denoise", ec)) {
    EXPECT_NE(hand_log.find("exit_status=0"), std::string::npos) << hand_log;
    EXPECT_NE(hand_log.find("\"skipped\":7,"), std::string::npos) << hand_log; // --resume: all there
  } else {
    EXPECT_NE(hand_log.find("range_nlm_denoise not found at"), std::string::npos) << hand_log;
    EXPECT_NE(hand_log.find("exit_status=2"), std::string::npos) << hand_log;
  }

  // The check script also runs by hand, outside Slurm and without the array job ids; a leftover
  // temporary file is reported.
  const std::string check_by_hand = "bash " + (kScripts / "range_nlm_check.sbatch").string() + " " + in.string() +
                                    " " + out.string() + " " + logs.string();
  const test::CommandResult by_hand = test::runCommand(check_by_hand);
  EXPECT_EQ(by_hand.status, 0) << by_hand.output;
  EXPECT_NE(by_hand.output.find("shards: 4 task logs, 4 shards done"), std::string::npos) << by_hand.output;
  fs::remove(out / frameName(29));
  std::ofstream(out / ("." + frameName(29) + ".tmp4242")) << "half";
  const test::CommandResult missing = test::runCommand(check_by_hand);
  EXPECT_EQ(missing.status, 1) << missing.output;
  EXPECT_NE(missing.output.find("1 missing\n  missing: " + frameName(29)), std::string::npos) << missing.output;
  EXPECT_NE(missing.output.find("temporary files left by interrupted tasks: 1"), std::string::npos) << missing.output;
}

TEST_F(SlurmClusterTest, NumbersWithLeadingZerosAreDecimal)
{
  // N = 010 is ten shards (range_nlm_denoise --shard K/010 reads shard K of 10): an array of
  // eight tasks would leave shards 8 and 9 unfiltered, with nothing for --rerun to re-run.
  constexpr int kFrames = 12;
  const fs::path in = dir_ / "recording";
  fs::create_directories(in);
  for (int k = 0; k < kFrames; ++k)
    pcl::io::savePCDFileBinary((in / frameName(k)).string(),
                               test::makeCloud(20, 15, test::step(8, 1.0, 1.3), 0.005, 11 + k));
  std::unique_ptr<SlurmCluster> cluster;
  try {
    cluster = std::make_unique<SlurmCluster>(dir_ / "cluster");
  } catch (const std::exception& e) {
    FAIL() << "the one-node Slurm cluster did not come up: " << e.what();
  }
  const fs::path out = dir_ / "sharded";
  const fs::path logs = dir_ / "sharded.logs";
  const std::string submit = "bash " + (kScripts / "submit.sh").string();
  const test::CommandResult submitted =
      test::runCommand("RANGE_NLM_CPUS=01 RANGE_NLM_ARRAY_LIMIT=02 RANGE_NLM_DENOISE=" + kTool + " " + submit + " " +
                       in.string() + " " + out.string() + " 010 --search-window 3 --patch 3 --normal-window 3");
  ASSERT_EQ(submitted.status, 0) << submitted.output << cluster->logs();
  std::smatch ids;
  ASSERT_TRUE(std::regex_search(submitted.output, ids, std::regex("array job ([0-9]+) .*check job ([0-9]+)")))
      << submitted.output;
  EXPECT_NE(submitted.output.find("(10 shards, 1 CPUs each)"), std::string::npos) << submitted.output;
  const std::string array_job = ids[1], check_job = ids[2];
  ASSERT_TRUE(waitForJobs(180, logs)) << test::runCommand("squeue").output << failedTask(logs) << cluster->logs();
  for (int k = 0; k < 10; ++k) {
    const std::string task =
        test::readBytes((logs / ("range_nlm-" + array_job + "_" + std::to_string(k) + ".out")).string());
    EXPECT_NE(task.find("shard " + std::to_string(k) + "/10, 1 thread(s)"), std::string::npos) << k << ": " << task;
    EXPECT_NE(task.find("exit_status=0"), std::string::npos) << k << ": " << task;
  }
  const std::string check = test::readBytes((logs / ("range_nlm-check-" + check_job + ".out")).string());
  EXPECT_NE(check.find("12 input frames in " + in.string() + ", 12 outputs in " + out.string() + ", 0 missing"),
            std::string::npos)
      << check;
  EXPECT_NE(check.find("shards: 10 task logs, 10 shards done; failed: none; not finished: none"), std::string::npos)
      << check;
  EXPECT_NE(
      test::runCommand(submit + " --rerun " + logs.string()).output.find("every one of the 10 shards has finished"),
      std::string::npos);

  // 08 is 8, not an octal error (the input directory is checked after N); a number that is not
  // one is refused naming it.
  const test::CommandResult eight =
      test::runCommand("RANGE_NLM_DENOISE=" + kTool + " " + submit + " " + (dir_ / "none").string() + " " +
                       (dir_ / "eight").string() + " 08");
  EXPECT_EQ(eight.status, 2) << eight.output;
  EXPECT_NE(eight.output.find("input directory '" + (dir_ / "none").string() + "' does not exist"), std::string::npos)
      << eight.output;
  for (const std::string& variable : {"RANGE_NLM_CPUS", "RANGE_NLM_ARRAY_LIMIT"}) {
    const test::CommandResult refused = test::runCommand(variable + "=0x2 RANGE_NLM_DENOISE=" + kTool + " " + submit +
                                                         " " + in.string() + " " + (dir_ / "bad").string() + " 2");
    EXPECT_EQ(refused.status, 2) << refused.output;
    EXPECT_NE(refused.output.find(variable + " must be >= 1, got '0x2'"), std::string::npos) << refused.output;
  }
}
