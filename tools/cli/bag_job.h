// range_nlm_denoise --input-bag: filtering one topic of a rosbag. The tool calls it through this
// declaration only; a build with ROS 1 links the implementation of ros/src/bag_job.cpp, a build
// without links tools/cli/bag_job_without_ros.cpp, which refuses the options.
#pragma once

#include <boost/program_options/variables_map.hpp>

namespace range_nlm
{
namespace tools
{

/// True if the command line asks for bag mode (--input-bag, --output-bag or --topic).
inline bool
wantsBagJob(const boost::program_options::variables_map& vm)
{
  return vm.count("input-bag") || vm.count("output-bag") || vm.count("topic");
}

/// Filters the --topic PointCloud2 messages of --input-bag into --output-bag (static or temporal,
/// one pass), copying every other message, and reports it as range_nlm_denoise does. Returns the
/// exit status: 0 done, 3 some messages of the topic were not organized clouds and were copied
/// unchanged (--keep-going). Throws UsageError for options bag mode does not take (or, in a build
/// without ROS 1, for bag mode itself), InputError for a bag that cannot be read or written.
int
runBagJob(const boost::program_options::variables_map& vm);

} // namespace tools
} // namespace range_nlm
