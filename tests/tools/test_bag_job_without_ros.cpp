// range_nlm_denoise built without ROS 1 (tools/cli/bag_job_without_ros.cpp): bag mode is refused
// as a usage error naming the option given, and nothing is written. Built only without ROS.
#include "test_support.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <string>
#include <unistd.h>
#include <vector>

namespace fs = std::filesystem;
using namespace range_nlm;

TEST(BagJobWithoutRos, EachBagOptionIsRefusedByName)
{
  const fs::path dir = fs::temp_directory_path() / ("range_nlm_bag_job_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  const std::string out = (dir / "out.bag").string();
  const std::vector<std::string> commands = {
      "--input-bag " + (dir / "in.bag").string() + " --topic /points --output-bag " + out, "--output-bag " + out,
      "--topic /points"};
  for (const std::string& args : commands) {
    const test::CommandResult r = test::runDenoise(args);
    EXPECT_EQ(r.status, 2) << args << "\n" << r.output;
    const std::string option = args.substr(0, args.find(' '));
    EXPECT_NE(r.output.find(option + ": this range_nlm_denoise was built without ROS support"), std::string::npos)
        << r.output;
  }
  EXPECT_FALSE(fs::exists(out));
  fs::remove_all(dir);
}
