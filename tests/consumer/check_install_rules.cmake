# Whether the install rules leave out what a build leaves out: configures SOURCE_DIR into
# WORK_DIR with the ROS and Python parts (and tests, tools, benchmark) off, and fails if any of its
# install scripts would install a ROS file (the ROS library or node, package.xml, the launch file,
# the nodelet plugin list, the ament index, the catkin marker) or the Python module. As a control
# of the patterns, the install scripts of the full build BUILD_DIR must name the ROS files when
# that build found ROS (ROS_FOUND).
set(ros_patterns "librange_nlm_ros" "range_nlm_node" "ament_index" "/.catkin" "nodelet_plugins.xml"
                 "package.xml" "ros/launch")
set(python_patterns ".cpython-" "range_nlm_python" "site-packages" "dist-packages")

function(install_scripts_text dir out)
  file(GLOB_RECURSE scripts ${dir}/cmake_install.cmake)
  if(NOT scripts)
    message(FATAL_ERROR "no cmake_install.cmake under ${dir}")
  endif()
  set(text "")
  foreach(script ${scripts})
    file(READ ${script} part)
    string(APPEND text "${part}")
  endforeach()
  set(${out} "${text}" PARENT_SCOPE)
endfunction()

file(REMOVE_RECURSE ${WORK_DIR})
execute_process(COMMAND ${CMAKE_COMMAND} -S ${SOURCE_DIR} -B ${WORK_DIR} -DCMAKE_BUILD_TYPE=Release
                        -DRANGE_NLM_BUILD_ROS=OFF -DRANGE_NLM_BUILD_PYTHON=OFF -DRANGE_NLM_BUILD_TESTS=OFF
                        -DRANGE_NLM_BUILD_BENCHMARKS=OFF -DRANGE_NLM_BUILD_TOOLS=OFF
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(rc)
  message(FATAL_ERROR "configure with ROS and Python off failed: ${out}${err}")
endif()
install_scripts_text(${WORK_DIR} without)
foreach(pattern ${ros_patterns} ${python_patterns})
  string(FIND "${without}" "${pattern}" at)
  if(NOT at EQUAL -1)
    message(FATAL_ERROR "with RANGE_NLM_BUILD_ROS=OFF and RANGE_NLM_BUILD_PYTHON=OFF the install still names '${pattern}'")
  endif()
endforeach()
foreach(needed "range_nlmConfig.cmake" "range_nlm_range_nlmTargets")
  string(FIND "${without}" "${needed}" at)
  if(at EQUAL -1)
    message(FATAL_ERROR "with ROS and Python off the install lost the library's '${needed}'")
  endif()
endforeach()

if(ROS_FOUND)
  install_scripts_text(${BUILD_DIR} full)
  foreach(pattern ${ros_patterns})
    string(FIND "${full}" "${pattern}" at)
    if(at EQUAL -1)
      message(FATAL_ERROR "the full build found ROS but its install does not name '${pattern}': the check's "
                          "patterns are out of date with ros/CMakeLists.txt")
    endif()
  endforeach()
endif()
message(STATUS "install rules: ROS and Python parts left out when switched off")
