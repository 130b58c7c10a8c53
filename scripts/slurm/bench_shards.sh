#!/usr/bin/env bash
# Frames per second of a sharded run against the number of shards, on the cluster SLURM_CONF
# points at (docs/cluster.md has the figures of the one-node test cluster).
#
#   scripts/slurm/bench_shards.sh IN_DIR WORK_DIR "1 2 4" [range_nlm_denoise options]
#
# For each number of shards N: submit.sh IN_DIR WORK_DIR/N-shards N [options], waits for the check
# job, and prints a Markdown table row from its report: shards, CPUs per task, frames, seconds
# from the first shard start to the last end, frames/s, and the filtering time summed over the
# shards (which grows with N by the halo frames each shard filters too). RANGE_NLM_CPUS and the other variables
# of submit.sh apply. Runs one N at a time so that the runs do not compete.
set -euo pipefail
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
(($# >= 3)) || { echo "usage: $0 IN_DIR WORK_DIR \"N1 N2 ...\" [range_nlm_denoise options]" >&2; exit 2; }
in_dir=$1 work=$2 counts=$3
shift 3
mkdir -p "$work"
echo "| shards | CPUs per task | frames | seconds (first start to last end) | frames/s | filtering, s (sum over shards) |"
echo "|---:|---:|---:|---:|---:|---:|"
for n in $counts; do
  out="$work/$n-shards"
  rm -rf "$out" "$out.logs"
  submitted=$(bash "$here/submit.sh" "$in_dir" "$out" "$n" "$@")
  check_job=$(sed -n 's/.*check job \([0-9]*\).*/\1/p' <<<"$submitted")
  while squeue -h -j "$check_job" 2>/dev/null | grep -q .; do sleep 1; done
  report="$out.logs/range_nlm-check-$check_job.out"
  [[ -f $report ]] || { echo "no report $report (did a shard fail? see $out.logs)" >&2; exit 1; }
  grep -q ", 0 missing" "$report" || { cat "$report" >&2; exit 1; }
  frames=$(sed -n 's/.* \([0-9]*\) frames written.*/\1/p' "$report")
  span=$(sed -n 's/.*, \([0-9.]*\) s from the first shard start.*/\1/p' "$report")
  rate=$(sed -n 's/.*: \([0-9.]*\) frames\/s.*/\1/p' "$report")
  filtering=$(sed -n 's/^time: \([0-9.]*\) s of filtering.*/\1/p' "$report")
  echo "| $n | ${RANGE_NLM_CPUS:-2} | $frames | $span | $rate | $filtering |"
done
