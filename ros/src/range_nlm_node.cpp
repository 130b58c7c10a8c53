// range_nlm_node: the nodelet range_nlm/TemporalFilterNodelet run as a node of its own (same
// private topics and parameters), for use without a nodelet manager.
#include <range_nlm/io/process_memory.h>
#include <range_nlm/ros/temporal_filter_nodelet.h>

#include <ros/ros.h>

#include <cstdio>
#include <exception>

int
main(int argc, char** argv)
{
  // Log lines (ROS_INFO goes to stdout) reach a log file or a pipe as they happen.
  std::setvbuf(stdout, nullptr, _IOLBF, 0);
  // A process of its own: its frames' buffers on a kept heap in huge pages (a nodelet shares its
  // manager's process, whose allocator is not the filter's to set).
  range_nlm::io::preferHugePagesForBuffers();
  ros::init(argc, argv, "range_nlm");
  range_nlm_ros::TemporalFilterNodelet filter;
  const nodelet::V_string my_argv(argv + 1, argv + argc);
  try {
    filter.init(ros::this_node::getName(), ros::names::getRemappings(), my_argv);
  } catch (const std::exception&) {
    return 1; // the nodelet logged why
  }
  // The filter takes most of a frame's time: one thread for callbacks keeps frames in order.
  ros::spin();
  return 0;
}
