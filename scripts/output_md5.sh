#!/usr/bin/env bash
# Prints the MD5 of every output of range_nlm_denoise over generated scenes and the shipped real
# frames, in each way of running it (static, temporal centred / causal / recursive, sharded, a
# --pass schedule, the paper preset, the direct evaluation, PNG output). A change that must leave
# the output identical to the bit (a refactoring) is checked by running this before and after it
# on the same machine and comparing the two lists:
#
#   bash scripts/output_md5.sh build-before > before.txt
#   bash scripts/output_md5.sh build > after.txt && diff before.txt after.txt
#
# Output can differ between instruction sets (the runtime dispatch picks AVX-512, AVX2 or the
# baseline build), so compare lists made on one machine. Usage: output_md5.sh BUILD_DIR [DATA_DIR]
set -euo pipefail
build=$(realpath "${1:?usage: output_md5.sh BUILD_DIR [DATA_DIR]}")
root=$(realpath "$(dirname "$0")/..")
data=$(realpath "${2:-$root/data}")
denoise="$build/tools/range_nlm_denoise"
synth="$build/tools/range_nlm_synth"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

run() { # NAME ARGS...: runs the denoise tool into $work/out/NAME
  local name=$1
  shift
  "$denoise" --threads 2 --quiet "$@" >/dev/null
}

# Generated scenes: every sensor noise model, three VGA frames each.
for noise in kinect stereo kinect1 tof; do
  "$synth" --output-dir "$work/gen-$noise" --frames 3 --noise "$noise" --seed 7 >/dev/null
  in="$work/gen-$noise/noisy"
  run s --input-dir "$in" --output-dir "$work/out/$noise-static"
  run t1 --input-dir "$in" --output-dir "$work/out/$noise-temporal1" --temporal-radius 1
  run c1 --input-dir "$in" --output-dir "$work/out/$noise-causal1" --temporal-radius 1 --causal
  run r1 --input-dir "$in" --output-dir "$work/out/$noise-recursive1" --temporal-radius 1 --recursive
  # The live preset, frame by frame and in its stream default (recursive, radius 1).
  run ls --input-dir "$in" --output-dir "$work/out/$noise-live-static" --preset live
  run lr --input-dir "$in" --output-dir "$work/out/$noise-live-recursive1" --preset live --temporal-radius 1 --recursive
done
in="$work/gen-stereo/noisy"
run t2 --input-dir "$in" --output-dir "$work/out/stereo-temporal2" --temporal-radius 2
run paper --input-dir "$in" --output-dir "$work/out/stereo-paper" --preset paper --temporal-radius 1
run pass --input-dir "$in" --output-dir "$work/out/stereo-pass" \
  --pass search=9,patch=3,radius=1 --pass search=5,patch=3,radius=0,iterations=1
for k in 0 1; do
  run shard --input-dir "$in" --output-dir "$work/out/stereo-shard-recursive" --temporal-radius 1 --recursive \
    --shard "$k/2" --shard-warmup all
  run shard --input-dir "$in" --output-dir "$work/out/stereo-shard-centred" --temporal-radius 1 --shard "$k/2"
done
# The direct evaluation on a small frame (it costs S^2 P^2 per point).
"$synth" --output-dir "$work/small" --frames 2 --noise kinect1 --width 96 --height 72 --fx 80 --fy 80 --seed 3 >/dev/null
run direct --input-dir "$work/small/noisy" --output-dir "$work/out/small-direct" --direct --temporal-radius 1
run small --input-dir "$work/small/noisy" --output-dir "$work/out/small-fast" --temporal-radius 1

# Real frames: the Kinect sequence, the shipped single frames and depth images.
run kin-s --input-dir "$data/kinect-sequence" --output-dir "$work/out/kinect-sequence-static"
run kin-t --input-dir "$data/kinect-sequence" --output-dir "$work/out/kinect-sequence-temporal1" --temporal-radius 1
run kin-r --input-dir "$data/kinect-sequence" --output-dir "$work/out/kinect-sequence-recursive1" --temporal-radius 1 --recursive
run kin-lr --input-dir "$data/kinect-sequence" --output-dir "$work/out/kinect-sequence-live-recursive1" --preset live \
  --temporal-radius 1 --recursive
run milk --input "$data/milk_cartoon_all_small_clorox.pcd" --output "$work/out/milk.pcd"
# Every folder of depth images (with the intrinsics.txt of it or of its parent), IR images left out.
while IFS= read -r dir; do
  name=${dir#"$data/depth-images/"}
  name=${name//\//-}
  intrinsics=$dir/intrinsics.txt
  [[ -f $intrinsics ]] || intrinsics=$(dirname "$dir")/intrinsics.txt
  mkdir -p "$work/in-$name"
  find "$dir/" -maxdepth 1 -name '*.png' ! -name 'ir_*' -exec cp {} "$work/in-$name/" \;
  for mode in "static-png" "static-pcd --output-format pcd" "temporal1-png --temporal-radius 1"; do
    read -r label extra <<<"$mode"
    # shellcheck disable=SC2086
    run "$name" --input-dir "$work/in-$name" --output-dir "$work/out/$name-$label" --intrinsics "$intrinsics" $extra
  done
done < <(find -L "$data/depth-images" -name '*.png' ! -name 'ir_*' -printf '%h\n' | LC_ALL=C sort -u)
if [[ -f "$data/table_scene_mug_stereo_textured.pcd" ]]; then
  run stereo --input "$data/table_scene_mug_stereo_textured.pcd" --output "$work/out/table_scene_mug_stereo_textured.pcd"
fi

cd "$work/out"
find . -type f | LC_ALL=C sort | xargs md5sum
