#!/usr/bin/env bash
# Screenshot of the real pcl_viewer showing two clouds side by side (-multiview 1), rendered in a
# virtual X server, so it works on machines without a display.
#
# Usage: scripts/screenshot_viewer.sh BEFORE.pcd AFTER.pcd OUT.png
#
# The camera sits at the sensor (origin) looking along +z with y down, as a depth camera sees
# the scene. Clouds with an rgb field (e.g. range_nlm_render IN.pcd OUT.pcd --mode curvature, or
# range_nlm_denoise --colorize curvature) are shown in their colours.
#
# Environment (optional):
#   VIEWER_SIZE        window size WxH in pixels, two viewports side by side [1280x480]
#   VIEWER_FOVY        vertical field of view in radians [0.9; a Kinect frame is 0.86]
#   VIEWER_POINT_SIZE  point size in pixels [2]
#   VIEWER_CAM         full pcl_viewer -cam string, overrides the three above for the camera
#   VIEWER_TIMEOUT     seconds to wait for the viewer to draw [90]
#
# Needs the Debian packages pcl-tools (pcl_viewer), xvfb (xvfb-run), imagemagick (import) and
# x11-utils (xwininfo).
set -euo pipefail

usage() {
  echo "usage: $0 BEFORE.pcd AFTER.pcd OUT.png" >&2
  exit 2
}

size=${VIEWER_SIZE:-1280x480}
fovy=${VIEWER_FOVY:-0.9}
point_size=${VIEWER_POINT_SIZE:-2}
timeout_s=${VIEWER_TIMEOUT:-90}

if [[ ${1:-} == --inside-xvfb ]]; then
  # Second stage, run by xvfb-run with DISPLAY set.
  before=$2 after=$3 out=$4 log=$5
  width=${size%x*} height=${size#*x}
  cam=${VIEWER_CAM:-"0.01,100/0,0,1/0,0,0/0,-1,0/${fovy}/${width},${height}/0,0"}
  pcl_viewer -multiview 1 "$before" "$after" -ps "$point_size" -ps "$point_size" -cam "$cam" >"$log" 2>&1 &
  viewer=$!
  trap 'kill "$viewer" 2>/dev/null || true; wait "$viewer" 2>/dev/null || true' EXIT
  deadline=$((SECONDS + timeout_s))
  window=""
  while [[ -z $window ]]; do
    if ! kill -0 "$viewer" 2>/dev/null; then
      echo "$0: pcl_viewer exited before opening its window:" >&2
      cat "$log" >&2
      exit 1
    fi
    ((SECONDS < deadline)) || { echo "$0: pcl_viewer opened no window within ${timeout_s} s" >&2; exit 1; }
    # pcl_viewer's top-level window is a VTK render window (class "vtk"; its title changes).
    window=$(xwininfo -root -tree 2>/dev/null | awk '/\("vtk" "Vtk"\)/ {print $1; exit}')
    [[ -n $window ]] || sleep 0.5
  done
  # Rendered when two captures a second apart are identical and not blank.
  previous=""
  shot="${out}.capture.png"
  while :; do
    ((SECONDS < deadline)) || { echo "$0: pcl_viewer did not finish drawing within ${timeout_s} s" >&2; exit 1; }
    sleep 1
    import -window "$window" "$shot"
    digest=$(convert "$shot" rgb:- | md5sum)
    colours=$(convert "$shot" -format '%k' info:)
    if [[ $digest == "$previous" && $colours -gt 16 ]]; then
      break
    fi
    previous=$digest
  done
  mv -f "$shot" "$out"
  exit 0
fi

[[ $# -eq 3 ]] || usage
before=$1 after=$2 out=$3
for f in "$before" "$after"; do
  [[ -f $f ]] || { echo "$0: '$f': no such file" >&2; exit 1; }
done
[[ $size =~ ^[0-9]+x[0-9]+$ ]] || { echo "$0: VIEWER_SIZE must be WxH, got '$size'" >&2; exit 2; }
for tool in pcl_viewer xvfb-run import convert xwininfo; do
  command -v "$tool" >/dev/null || {
    echo "$0: '$tool' not found (apt-get install pcl-tools xvfb imagemagick x11-utils)" >&2
    exit 1
  }
done
out_dir=$(dirname "$out")
[[ -d $out_dir ]] || { echo "$0: output directory '$out_dir' does not exist" >&2; exit 1; }

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
# pcl_viewer labels each viewport with the path it was given: show the file names only.
before_name=$(basename "$before") after_name=$(basename "$after")
if [[ $before_name == "$after_name" ]]; then
  before_name="before_$before_name" after_name="after_$after_name"
fi
ln -s "$(realpath "$before")" "$work/$before_name"
ln -s "$(realpath "$after")" "$work/$after_name"
out_path=$(realpath "$out")
script=$(realpath "$0")
# -a: a free display number; the screen is as large as the window.
(cd "$work" && xvfb-run -a -s "-screen 0 ${size}x24" \
  env VIEWER_SIZE="$size" VIEWER_FOVY="$fovy" VIEWER_POINT_SIZE="$point_size" VIEWER_TIMEOUT="$timeout_s" \
  ${VIEWER_CAM:+VIEWER_CAM="$VIEWER_CAM"} \
  bash "$script" --inside-xvfb "$before_name" "$after_name" "$out_path" "$work/viewer.log")
echo "$out: $(identify -format '%w x %h' "$out") screenshot of pcl_viewer -multiview 1 $before $after"
