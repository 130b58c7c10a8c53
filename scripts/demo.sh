#!/usr/bin/env bash
# The main job on a fresh machine, in its light weight: installs only what the filter's tools
# need (scripts/install_packages.sh demo), builds only the three tools it runs in build-demo/
# (no tests, benchmark, ROS or Python parts), filters a real Kinect frame shipped in data/ (or a
# generated scene if it is missing) and writes before/after renders to demo-output/.
# scripts/test.sh installs and builds everything else.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install_packages.sh demo
build=build-demo
cmake -S . -B "$build" -DCMAKE_BUILD_TYPE=Release -DRANGE_NLM_BUILD_TESTS=OFF -DRANGE_NLM_BUILD_BENCHMARKS=OFF \
  -DRANGE_NLM_BUILD_ROS=OFF -DRANGE_NLM_BUILD_PYTHON=OFF >/dev/null
cmake --build "$build" -j2 --target range_nlm_denoise range_nlm_render range_nlm_synth
tools=$build/tools
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
echo "the tools are in $tools/ (bash scripts/test.sh builds everything in build/)"
echo "compare in pcl_viewer (Debian: pcl-tools; one curvature scale, +-$limit 1/unit, for both):"
echo "  pcl_viewer -multiview 1 $out/input_curvature.pcd $out/denoised_curvature.pcd"
echo "demo finished in ${SECONDS} s"
