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
"$tools/range_nlm_render" --before "$input" --after "$out/denoised.pcd" "$out/before_after_curvature.png" --mode curvature
"$tools/range_nlm_denoise" "$input" "$out/denoised_curvature.pcd" --colorize curvature --quiet
echo "wrote $out/denoised.pcd, $out/before_after_shaded.png, $out/before_after_curvature.png"
echo "inspect with: pcl_viewer -multiview 1 $input $out/denoised_curvature.pcd"
