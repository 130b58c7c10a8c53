// The locks of tools/cli/run_lock.h, taken twice within one process (each lock opens its own file
// description, so two of them conflict as two runs would), and the temporary files --resume removes.
#include "cli/cli.h"
#include "cli/run_lock.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>
#include <unistd.h>
#include <vector>

using namespace range_nlm;
using namespace range_nlm::tools;
namespace fs = std::filesystem;

namespace
{

class RunLock : public ::testing::Test
{
protected:
  void SetUp() override
  {
    dir_ = fs::temp_directory_path() / ("range_nlm_run_lock_" + std::to_string(::getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    for (int k = 0; k < 6; ++k)
      inputs_.push_back((dir_ / ("in/f" + std::to_string(k) + ".pcd")).string());
  }
  void TearDown() override { fs::remove_all(dir_); }

  /// The InputError message of taking the frames lock on [begin, end) ("" if it is taken).
  std::string frameLockRefusal(std::size_t begin, std::size_t end)
  {
    try {
      FrameRangeLock lock(dir_.string(), {begin, end}, inputs_);
    } catch (const InputError& e) {
      return e.what();
    }
    return "";
  }

  fs::path dir_;
  std::vector<std::string> inputs_;
};

void
touch(const fs::path& path)
{
  std::ofstream(path.string()) << "x";
}

} // namespace

TEST_F(RunLock, AnExclusiveDirectoryLockRefusesEveryOtherAndIsReleasedWithItsOwner)
{
  {
    const OutputDirectoryLock held(dir_.string(), true);
    for (const bool exclusive : {true, false}) {
      try {
        OutputDirectoryLock second(dir_.string(), exclusive);
        ADD_FAILURE() << "a second lock was taken (exclusive: " << exclusive << ")";
      } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("is in use by another range_nlm_denoise run"), std::string::npos)
            << e.what();
      }
    }
  }
  EXPECT_NO_THROW(OutputDirectoryLock(dir_.string(), true));
}

TEST_F(RunLock, SharedDirectoryLocksCoexist)
{
  const OutputDirectoryLock first(dir_.string(), false);
  EXPECT_NO_THROW(OutputDirectoryLock(dir_.string(), false));
  EXPECT_THROW(OutputDirectoryLock(dir_.string(), true), InputError);
}

TEST_F(RunLock, AMissingOutputDirectoryIsNamed)
{
  try {
    OutputDirectoryLock lock((dir_ / "missing").string(), true);
    FAIL() << "a missing directory was locked";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("cannot open output directory '" + (dir_ / "missing").string() + "'"),
              std::string::npos)
        << e.what();
  }
}

TEST_F(RunLock, OverlappingFrameRangesConflictAndNameTheHolder)
{
  const FrameRangeLock held(dir_.string(), {2, 4}, inputs_);
  EXPECT_EQ(frameLockRefusal(0, 2), "");
  EXPECT_EQ(frameLockRefusal(4, 6), "");
  const std::string refusal = frameLockRefusal(3, 6);
  EXPECT_NE(refusal.find("frames 3..5 (f3.pcd .. f5.pcd) of output directory"), std::string::npos) << refusal;
  EXPECT_NE(refusal.find("(holding frames 2..3 (f2.pcd .. f3.pcd))"), std::string::npos) << refusal;
  EXPECT_NE(refusal.find("give each run its own shard"), std::string::npos) << refusal;
  EXPECT_TRUE(fs::exists(dir_ / FrameRangeLock::kFileName));
}

TEST_F(RunLock, AnEmptyFrameRangeTakesNoLockAndMakesNoFile)
{
  const FrameRangeLock held(dir_.string(), {3, 3}, inputs_);
  EXPECT_FALSE(fs::exists(dir_ / FrameRangeLock::kFileName));
  EXPECT_EQ(frameLockRefusal(0, 6), "");
}

TEST_F(RunLock, RemoveTemporariesRemovesOnlyTheTemporariesOfTheOutputsGiven)
{
  for (const char* name : {"a.pcd", ".a.pcd.tmp123", ".a.pcd.tmp", ".a.pcd.tmp12x", ".b.pcd.tmp7", ".c.pcd.tmp9"})
    touch(dir_ / name);
  removeTemporaries({(dir_ / "a.pcd").string(), (dir_ / "b.pcd").string()});
  std::vector<std::string> left;
  for (const auto& entry : fs::directory_iterator(dir_))
    left.push_back(entry.path().filename().string());
  std::sort(left.begin(), left.end());
  EXPECT_EQ(left, (std::vector<std::string>{".a.pcd.tmp", ".a.pcd.tmp12x", ".c.pcd.tmp9", "a.pcd"}));
}
