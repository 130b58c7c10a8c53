#!/usr/bin/env bash
# Filters a recording on a Slurm cluster: N shards as a job array, then a check job.
#
#   scripts/slurm/submit.sh IN_DIR OUT_DIR N [range_nlm_denoise options]
#
# Submits range_nlm_array.sbatch as --array=0-(N-1) (task K runs range_nlm_denoise --shard K/N;
# together the shards write exactly what one run would) and range_nlm_check.sbatch with
# --dependency=afterok on the whole array: it checks that every input frame has an output and
# reports frames and times. IN_DIR and OUT_DIR must be on a file system every node sees.
# Environment:
#   RANGE_NLM_CPUS            CPUs per task = OpenMP threads per shard [2]
#   RANGE_NLM_DENOISE         the tool [range_nlm_denoise on PATH, else build/tools/ of this checkout]
#   RANGE_NLM_LOG_DIR         where the task logs go [OUT_DIR.logs]
#   RANGE_NLM_SBATCH_OPTIONS  more sbatch options for both jobs, e.g. "--partition=cpu --time=2:00:00"
#   RANGE_NLM_ARRAY_LIMIT     at most this many shards at once (--array=0-(N-1)%LIMIT) [no limit]
# Prints the two job ids ("array job A, check job C") and where the logs are.
set -euo pipefail
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
usage() {
  echo "usage: $0 IN_DIR OUT_DIR N [range_nlm_denoise options]" >&2
  exit 2
}
(($# >= 3)) || usage
in_dir=$1 out_dir=$2 shards=$3
shift 3
[[ $shards =~ ^[0-9]+$ ]] && ((shards >= 1)) || { echo "$0: N must be a number of shards >= 1, got '$shards'" >&2; exit 2; }
[[ -d $in_dir ]] || { echo "$0: input directory '$in_dir' does not exist" >&2; exit 2; }
cpus=${RANGE_NLM_CPUS:-2}
[[ $cpus =~ ^[0-9]+$ ]] && ((cpus >= 1)) || { echo "$0: RANGE_NLM_CPUS must be >= 1, got '$cpus'" >&2; exit 2; }
tool=${RANGE_NLM_DENOISE:-$(command -v range_nlm_denoise || echo "$here/../../build/tools/range_nlm_denoise")}
[[ -x $tool ]] || { echo "$0: range_nlm_denoise not found at '$tool' (set RANGE_NLM_DENOISE)" >&2; exit 2; }
tool=$(realpath "$tool")
mkdir -p "$out_dir"
in_dir=$(realpath "$in_dir")
out_dir=$(realpath "$out_dir")
log_dir=${RANGE_NLM_LOG_DIR:-$out_dir.logs}
mkdir -p "$log_dir"
log_dir=$(realpath "$log_dir")
read -r -a sbatch_options <<<"${RANGE_NLM_SBATCH_OPTIONS:-}"
array="0-$((shards - 1))${RANGE_NLM_ARRAY_LIMIT:+%$RANGE_NLM_ARRAY_LIMIT}"
submit_epoch=$(date +%s)

array_job=$(sbatch --parsable --job-name=range_nlm --array="$array" --cpus-per-task="$cpus" \
  --output="$log_dir/range_nlm-%A_%a.out" --chdir="$log_dir" \
  --export=ALL,RANGE_NLM_SHARDS="$shards",RANGE_NLM_DENOISE="$tool" "${sbatch_options[@]}" \
  "$here/range_nlm_array.sbatch" "$in_dir" "$out_dir" "$@")
array_job=${array_job%%;*} # "id;cluster" on a multi-cluster setup
check_job=$(sbatch --parsable --job-name=range_nlm_check --dependency="afterok:$array_job" --cpus-per-task=1 \
  --output="$log_dir/range_nlm-check-%j.out" --chdir="$log_dir" "${sbatch_options[@]}" \
  "$here/range_nlm_check.sbatch" "$in_dir" "$out_dir" "$log_dir" "$array_job" "$submit_epoch")
check_job=${check_job%%;*}
echo "range_nlm: array job $array_job ($shards shards, $cpus CPUs each), check job $check_job"
echo "range_nlm: logs in $log_dir (range_nlm-${array_job}_K.out, range_nlm-check-$check_job.out)"
