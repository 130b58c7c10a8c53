#!/usr/bin/env bash
# The sanitizer part of CI, run after scripts/test.sh:
#  1. the whole test suite under AddressSanitizer (with LeakSanitizer) and UndefinedBehaviorSanitizer
#     in build-asan (RANGE_NLM_SANITIZE=ON), without the ROS 1 glue;
#  2. the PCD-reading and filtering fuzzer (fuzz/fuzz_pcd_filter, clang + libFuzzer) for 60 s from
#     the seed corpus in fuzz/corpus, in build-fuzz;
#  3. range_nlm_denoise (the Release build of scripts/test.sh) under valgrind on a tiny three-frame
#     sequence, static and temporal.
# Any sanitizer report, fuzzer finding, failing test or leak fails the script.
set -euo pipefail
cd "$(dirname "$0")/.."
start=$SECONDS
step() { echo "== $* [$((SECONDS - start)) s]"; }

step "AddressSanitizer + UndefinedBehaviorSanitizer build (build-asan)"
# Without the ROS 1 glue: roscpp and rosbag are not built with the sanitizers (their own
# allocations at exit would read as leaks); the ROS tests run in the Release suite.
# Without the Python module either: an ASan-built extension cannot be loaded by Debian's Python.
cmake -S . -B build-asan -DCMAKE_BUILD_TYPE=RelWithDebInfo -DRANGE_NLM_SANITIZE=ON -DRANGE_NLM_BUILD_ROS=OFF \
  -DRANGE_NLM_BUILD_PYTHON=OFF >/dev/null
cmake --build build-asan -j2
step "test suite under AddressSanitizer + UndefinedBehaviorSanitizer"
# The tools the tests start inherit these: a leak, an error or undefined behaviour in a child also
# makes its test fail (LeakSanitizer exits with status 23).
export ASAN_OPTIONS=detect_leaks=1:abort_on_error=0:detect_stack_use_after_return=1:strict_init_order=1
export UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1
ctest --test-dir build-asan --output-on-failure -j2 --timeout 1500
unset ASAN_OPTIONS UBSAN_OPTIONS

step "fuzzer build (build-fuzz, clang-14)"
CC=clang-14 CXX=clang++-14 cmake -S . -B build-fuzz -DCMAKE_BUILD_TYPE=RelWithDebInfo -DRANGE_NLM_FUZZ=ON \
  -DRANGE_NLM_BUILD_TESTS=OFF -DRANGE_NLM_BUILD_ROS=OFF -DRANGE_NLM_BUILD_PYTHON=OFF >/dev/null
cmake --build build-fuzz --target fuzz_pcd_filter -j2
step "fuzzing for 60 s"
# New inputs go to a scratch corpus; the seeds in fuzz/corpus stay as they are. A finding is
# written to build-fuzz/crash-* and fails the step.
rm -rf build-fuzz/corpus && mkdir -p build-fuzz/corpus
build-fuzz/fuzz/fuzz_pcd_filter -max_total_time=60 -timeout=30 -rss_limit_mb=4096 -print_final_stats=1 \
  -artifact_prefix=build-fuzz/ build-fuzz/corpus fuzz/corpus

step "leak check of range_nlm_denoise under valgrind"
cmake --build build --target range_nlm_denoise -j2
seq_dir=$(mktemp -d)
trap 'rm -rf "$seq_dir"' EXIT
mkdir -p "$seq_dir/in"
for k in 0 1 2; do
  # A noisy plane with a step and a hole, 24 x 18, as ascii PCD.
  awk -v k="$k" 'BEGIN {
    w = 24; h = 18; srand(17 + k);
    printf "# .PCD v0.7\nVERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n";
    printf "WIDTH %d\nHEIGHT %d\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS %d\nDATA ascii\n", w, h, w * h;
    for (v = 0; v < h; ++v)
      for (u = 0; u < w; ++u) {
        if (u == 5 && v == 7) { print "nan nan nan"; continue }
        z = (u < 12 + k ? 1.0 : 1.2) + 0.004 * (rand() - 0.5);
        printf "%.6f %.6f %.6f\n", (u - w / 2) * z / 50, (v - h / 2) * z / 50, z
      }
  }' > "$seq_dir/in/f$k.pcd"
done
for mode in "" "--temporal-radius 1"; do
  # shellcheck disable=SC2086
  # OMP_WAIT_POLICY set: the tool does not restart itself for its directory run (it would leave
  # valgrind behind).
  OMP_WAIT_POLICY=passive valgrind --quiet --leak-check=full --errors-for-leak-kinds=definite,indirect \
    --show-leak-kinds=definite,indirect --error-exitcode=3 \
    build/tools/range_nlm_denoise --input-dir "$seq_dir/in" --output-dir "$seq_dir/out" \
    --search-window 5 --patch 3 --normal-window 3 --threads 2 --quiet $mode
  test "$(ls "$seq_dir/out" | wc -l)" -eq 3
  rm -rf "$seq_dir/out"
done
step "sanitizers, fuzzing and leak check passed"
