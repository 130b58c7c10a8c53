// The bag job of a range_nlm_denoise built without ROS 1 (RANGE_NLM_BUILD_ROS=OFF, or the ROS
// packages missing): bag mode is refused as a usage error.
#include "cli/bag_job.h"

#include "cli/cli.h"

namespace range_nlm
{
namespace tools
{

int
runBagJob(const boost::program_options::variables_map& vm)
{
  std::string option = "--input-bag";
  for (const char* name : {"input-bag", "output-bag", "topic"})
    if (vm.count(name)) {
      option = std::string("--") + name;
      break;
    }
  throw UsageError(option + ": this range_nlm_denoise was built without ROS support (no ROS 1 rosbag reading; "
                            "install the ROS packages of scripts/setup.sh and rebuild with RANGE_NLM_BUILD_ROS=ON)");
}

} // namespace tools
} // namespace range_nlm
