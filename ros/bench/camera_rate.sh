#!/usr/bin/env bash
# The camera-rate benchmark of the ROS nodelet: a real master, a nodelet manager with
# range_nlm/TemporalFilterNodelet loaded, and a VGA bag (the frames of data/kinect-sequence,
# looped) replayed at 30 Hz, each message stamped when it is sent. Prints, per mode (the live
# preset static and recursive radius 1, each with queue_size 1 (its default) and 2, the default
# preset static, and the live preset on 16UC1 depth images static and recursive): output rate, latency
# from stamp to receipt (median, 95th percentile), frames dropped and how old the previous
# output's frame is.
#
#   ros/bench/camera_rate.sh [BUILD_DIR [SECONDS [RATE_HZ]]]      (defaults: build 10 30)
#
# It is a benchmark, not a test: run it on a quiet machine; docs/ros.md has its figures.
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
build=$(cd "${1:-$root/build}" && pwd)
seconds=${2:-10}
rate=${3:-30}
devel=$build/ros/devel
player=$devel/lib/range_nlm/range_nlm_ros_camera_rate
make_bag=$devel/bin/range_nlm_make_bag
nodelet=/usr/lib/nodelet/nodelet
[[ -x $player ]] || { echo "camera_rate.sh: $player is missing (build the target range_nlm_ros_camera_rate)" >&2; exit 2; }
[[ -x $make_bag ]] || { echo "camera_rate.sh: $make_bag is missing (build the target range_nlm_make_bag)" >&2; exit 2; }
[[ -x $nodelet ]] || nodelet=$(command -v nodelet) || { echo "camera_rate.sh: no nodelet executable (libnodeletlib-tools)" >&2; exit 2; }

work=$(mktemp -d /tmp/range_nlm_camera_rate.XXXXXX)
pids=()
cleanup() {
  for pid in "${pids[@]}"; do kill -INT "$pid" 2>/dev/null || true; done
  for _ in $(seq 50); do
    local alive=0
    for pid in "${pids[@]}"; do kill -0 "$pid" 2>/dev/null && alive=1; done
    ((alive)) || break
    sleep 0.1
  done
  for pid in "${pids[@]}"; do kill -KILL "$pid" 2>/dev/null || true; done
  wait 2>/dev/null || true
  rm -rf "$work"
}
trap cleanup EXIT

port=$(/usr/bin/python3 -c 'import socket; s = socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])')
export ROS_MASTER_URI=http://127.0.0.1:$port ROS_IP=127.0.0.1 ROS_HOSTNAME=127.0.0.1
export ROS_HOME=$work ROS_LOG_DIR=$work/log AMENT_PREFIX_PATH=$devel
# Every process of the graph on glibc's huge pages for its frame buffers, as the launch file sets
# up the processes it starts (RANGE_NLM_HUGE_PAGES=0: without).
if [[ ${RANGE_NLM_HUGE_PAGES:-1} != 0 ]]; then
  export GLIBC_TUNABLES=glibc.malloc.hugetlb=1
fi
# The filter's OpenMP threads sleep between frames, as the launch file sets it up.
export OMP_WAIT_POLICY=${OMP_WAIT_POLICY:-passive}
unset ROS_NAMESPACE
rosmaster --core -p "$port" >"$work/master.log" 2>&1 &
pids+=($!)
for _ in $(seq 100); do
  /usr/bin/python3 -c "import socket; socket.create_connection(('127.0.0.1', $port), 0.2)" 2>/dev/null && break
  sleep 0.1
done

"$make_bag" "$work/vga.bag" "$root"/data/kinect-sequence/*.pcd --topic /camera/depth/points --rate 30 >/dev/null
"$nodelet" manager __name:=camera_rate_manager >"$work/manager.log" 2>&1 &
pids+=($!)

echo "range_nlm nodelet at $rate Hz, VGA PointCloud2 (x y z rgba), $(nproc) cores, load average $(cut -d' ' -f1-3 /proc/loadavg)"
# run_mode NAME NODE_ARGS...: the nodelet on PointCloud2 (input, output); with PLAY=play-depth on
# 16UC1 depth images and their CameraInfo (depth/image, depth_filtered/image; give _input:=depth).
run_mode() {
  local name=$1
  shift
  "$nodelet" load range_nlm/TemporalFilterNodelet camera_rate_manager "__name:=$name" "$@" >"$work/$name.log" 2>&1 &
  local loader=$!
  pids+=("$loader")
  printf '%-28s ' "$name ($*):"
  local in=input out=output
  [[ ${PLAY:-play} == play-depth ]] && in=depth/image out=depth_filtered/image
  "$player" "${PLAY:-play}" "$work/vga.bag" "/$name/$in" "/$name/$out" "$seconds" "$rate" ||
    { echo "failed; manager log:"; tail -20 "$work/manager.log"; }
  kill -INT "$loader" 2>/dev/null || true
  wait "$loader" 2>/dev/null || true
}
# The node's default, the live preset (queues of one frame, the newest): each frame alone, then its
# stream default (recursive, radius 1); each also with queues of two frames.
run_mode live_static _temporal_radius:=0
run_mode live_static_queue2 _temporal_radius:=0 _queue_size:=2
run_mode live_recursive
run_mode live_recursive_queue2 _queue_size:=2
# The accuracy setting for recorded data, for comparison.
run_mode default_static _preset:=default _temporal_radius:=0
# The live preset on depth images (16UC1 with CameraInfo, as realsense2_camera publishes them):
# each filtered point is put back on its pixel's ray before its depth is written.
PLAY=play-depth run_mode live_static_depth _input:=depth _temporal_radius:=0
PLAY=play-depth run_mode live_recursive_depth _input:=depth
