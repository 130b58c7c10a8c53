#!/usr/bin/env bash
# Installs the Debian 12 packages of one set-up weight (if missing), with apt-get (root or sudo):
#   demo  what the demo's tools link: PCL, Eigen, Boost.Program_options, libpng, nlohmann-json
#   all   the demo's plus the test suite, the benchmark's baselines, the ROS 1 and Python parts,
#         the sanitizer and Slurm checks of CI and the plots of docs/
set -euo pipefail
weight=${1:-}
demo=(cmake g++ make libpcl-dev libeigen3-dev libflann-dev libboost-program-options-dev libpng-dev
      nlohmann-json3-dev)
rest=(pcl-tools libgtest-dev clang-14 libclang-rt-14-dev valgrind
      slurm-wlm munge
      # OpenCV's inpainting (its photo module), a baseline of range_nlm_bench --hole-filling
      libopencv-photo-dev
      # ROS 1 (Debian's own Noetic-era packages): the nodelet, range_nlm_node, --input-bag, and
      # for their tests the master (rosmaster) and a nodelet manager (libnodeletlib-tools).
      libroscpp-dev libsensor-msgs-dev libstd-msgs-dev libnodeletlib-dev libnodelet-dev pluginlib-dev
      librosbag-storage-dev catkin python3-rosmaster libnodeletlib-tools
      # image_transport's CameraSubscriber / CameraPublisher, message_filters, live
      # reconfiguration and diagnostics of the nodelet
      libimage-transport-dev libmessage-filters-dev libdynamic-reconfigure-config-init-mutex-dev
      libdiagnostic-updater-dev
      # the command-line tools docs/ros.md uses (roscore, roslaunch, rosrun, rostopic, rosbag,
      # rosnode, rosparam, dynparam) and the camera-rate benchmark
      python3-roslaunch rosbash python3-rostopic python3-rosbag python3-rospy python3-rosnode
      python3-rosparam python3-dynamic-reconfigure python3-diagnostic-msgs python3-sensor-msgs
      image-transport-tools
      # the Python module (python/, docs/python.md) and its tests: pybind11, Python's headers,
      # numpy, Open3D (interop tests and the comparison script), pytest, setuptools (pip install .)
      python3-dev python3-pybind11 python3-numpy python3-open3d python3-pytest python3-setuptools
      # the plots of docs/images (scripts/plot_*.py)
      python3-matplotlib)
case "$weight" in
  demo) packages=("${demo[@]}") ;;
  all) packages=("${demo[@]}" "${rest[@]}") ;;
  *) echo "usage: $0 demo|all (got '${weight}')" >&2; exit 2 ;;
esac
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  SUDO=""
  [[ $(id -u) -ne 0 ]] && SUDO="sudo"
  echo "installing: ${missing[*]}"
  $SUDO apt-get update
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y --no-install-recommends "${missing[@]}"
fi
