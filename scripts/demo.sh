#!/usr/bin/env bash
# The main job on a fresh machine: installs what is missing, builds, filters a real Kinect frame
# shipped in data/ (or a generated scene if it is missing) and writes before/after renders to
# demo-output/.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
tools=build/tools
out=demo-output
mkdir -p "$out"
input=data/milk_cartoon_all_small_clorox.pcd
if [[ ! -f "$input" ]]; then
  echo "data/ is missing: generating a scene with range_nlm_synth"
  "$tools/range_nlm_synth" --output-dir "$out/synthetic" --quiet
  input="$out/synthetic/noisy/frame_0000.pcd"
fi
"$tools/range_nlm_denoise" "$input" "$out/denoised.pcd"
"$tools/range_nlm_render" --before "$input" --after "$out/denoised.pcd" "$out/before_after_shaded.png" --mode shaded
# Both frames of a before/after comparison on one colour scale: the render takes it from the
# 'before' frame and prints it; the two coloured clouds for pcl_viewer use the same value.
report=$("$tools/range_nlm_render" --before "$input" --after "$out/denoised.pcd" "$out/before_after_curvature.png" \
  --mode curvature)
echo "$report"
limit=$(sed -n 's/.*curvature scale +-\([0-9.eE+-]*\) .*/\1/p' <<<"$report")
"$tools/range_nlm_render" "$input" "$out/input_curvature.pcd" --mode curvature --curvature-limit "$limit" >/dev/null
"$tools/range_nlm_denoise" "$input" "$out/denoised_curvature.pcd" --colorize curvature --curvature-limit "$limit" --quiet
echo "wrote $out/denoised.pcd, $out/before_after_shaded.png, $out/before_after_curvature.png"
echo "compare in pcl_viewer (one curvature scale, +-$limit 1/unit, for both):"
echo "  pcl_viewer -multiview 1 $out/input_curvature.pcd $out/denoised_curvature.pcd"
