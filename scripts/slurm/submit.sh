#!/usr/bin/env bash
# Filters a recording on a Slurm cluster: N shards as a job array, then a check job.
#
#   scripts/slurm/submit.sh IN_DIR OUT_DIR N [range_nlm_denoise options]
#   scripts/slurm/submit.sh --rerun LOG_DIR
#
# Submits range_nlm_array.sbatch as --array=0-(N-1) (task K runs range_nlm_denoise --shard K/N
# --resume; together the shards write exactly what one run would) and range_nlm_check.sbatch
# with --dependency=afterany on the whole array: it runs however the tasks end, checks that every
# input frame has an output and every shard finished, and reports frames and times (exit status
# 1 if not). IN_DIR and OUT_DIR must be on a file system every node sees. The submission is
# recorded in LOG_DIR/range_nlm-submission.sh; --rerun LOG_DIR submits again, with the same N,
# options and environment, exactly the shards that have no successful task log, and a new check
# job over every log.
# Environment:
#   RANGE_NLM_CPUS            CPUs per task = OpenMP threads per shard [2]
#   RANGE_NLM_DENOISE         the tool [range_nlm_denoise on PATH, else build/tools/ of this checkout]
#   RANGE_NLM_LOG_DIR         where the task logs go [OUT_DIR.logs]
#   RANGE_NLM_SBATCH_OPTIONS  more sbatch options for both jobs, e.g. "--partition=cpu --time=2:00:00"
#   RANGE_NLM_ARRAY_LIMIT     at most this many shards at once (--array=0-(N-1)%LIMIT) [no limit]
# Prints the two job ids ("array job A, check job C") and where the logs are.
set -euo pipefail
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
# shellcheck source-path=SCRIPTDIR source=output_file.sh
source "$here/output_file.sh"
usage() {
  echo "usage: $0 IN_DIR OUT_DIR N [range_nlm_denoise options]" >&2
  echo "       $0 --rerun LOG_DIR" >&2
  exit 2
}

# sbatch the array `$1` (e.g. 0-3 or 1,3) of the recorded settings; prints the array job id.
submit_shards() {
  local id
  id=$(sbatch --parsable --job-name=range_nlm --array="$1${array_limit:+%$array_limit}" --cpus-per-task="$cpus" \
    --output="$log_dir/range_nlm-%A_%a.out" --chdir="$log_dir" \
    --export=ALL,RANGE_NLM_SHARDS="$shards",RANGE_NLM_DENOISE="$tool" "${sbatch_options[@]}" \
    "$here/range_nlm_array.sbatch" "$in_dir" "$out_dir" "${tool_options[@]}")
  echo "${id%%;*}" # "id;cluster" on a multi-cluster setup
}

# sbatch the check job after the array job `$1`, over the logs of the array jobs `$2`.
submit_check() {
  local id
  id=$(sbatch --parsable --job-name=range_nlm_check --dependency="afterany:$1" --cpus-per-task=1 \
    --output="$log_dir/range_nlm-check-%j.out" --chdir="$log_dir" "${sbatch_options[@]}" \
    "$here/range_nlm_check.sbatch" "$in_dir" "$out_dir" "$log_dir" "$2" "$submit_epoch")
  echo "${id%%;*}"
}

# Prints each argument quoted for the shell, after a space.
quote() {
  local word
  for word in "$@"; do
    printf ' %q' "$word"
  done
}

# Writes the settings of the submission (array jobs `$1`), to be sourced by --rerun (through
# write_output: never half-written, a link followed, a directory refused).
record() {
  {
    echo "# range_nlm sharded run, submitted $(date -u +%Y-%m-%dT%H:%M:%SZ) by:"
    printf '#  '
    quote "$0" "${command_line[@]}"
    echo
    printf 'in_dir=%q\nout_dir=%q\nshards=%q\ncpus=%q\ntool=%q\nlog_dir=%q\narray_limit=%q\narray_jobs=%q\n' \
      "$in_dir" "$out_dir" "$shards" "$cpus" "$tool" "$log_dir" "$array_limit" "$1"
    printf 'sbatch_options=('
    quote "${sbatch_options[@]}"
    printf ' )\ntool_options=('
    quote "${tool_options[@]}"
    printf ' )\n'
  } | write_output "$log_dir/range_nlm-submission.sh"
}

# The shards 0 .. N-1 without a task log that ends in exit_status=0, comma-separated.
unfinished_shards() {
  local k list=
  for ((k = 0; k < shards; k++)); do
    grep -qx 'exit_status=0' "$log_dir"/range_nlm-*_"$k".out 2>/dev/null || list+=${list:+,}$k
  done
  echo "$list"
}

command_line=("$@")
submit_epoch=$(date +%s)
if [[ ${1:-} == --rerun ]]; then
  (($# == 2)) || usage
  record_file=$(realpath "$2")/range_nlm-submission.sh
  [[ -f $record_file ]] || { echo "$0: '$record_file' not found: not the log directory of a submission" >&2; exit 2; }
  # shellcheck source=/dev/null
  source "$record_file"
  shards=$((10#$shards)) # decimal, also in a record written with the count as it was given
  todo=$(unfinished_shards)
  if [[ -z $todo ]]; then
    echo "range_nlm: every one of the $shards shards has finished; nothing to re-run"
    exit 0
  fi
  array_job=$(submit_shards "$todo")
  array_jobs+=,$array_job
  check_job=$(submit_check "$array_job" "$array_jobs")
  record "$array_jobs"
  echo "range_nlm: re-running shards $todo of $shards: array job $array_job, check job $check_job"
  echo "range_nlm: logs in $log_dir"
  exit 0
fi

(($# >= 3)) || usage
in_dir=$1 out_dir=$2 shards=$3
shift 3
tool_options=("$@")
# Numbers are decimal, leading zeros or not (010 is 10, as range_nlm_denoise --shard reads it; bash
# arithmetic would read it as octal 8).
decimal() { [[ $1 =~ ^[0-9]{1,9}$ ]] && echo $((10#$1)); }
given=$shards
shards=$(decimal "$given") && ((shards >= 1)) || { echo "$0: N must be a number of shards >= 1, got '$given'" >&2; exit 2; }
[[ -d $in_dir ]] || { echo "$0: input directory '$in_dir' does not exist" >&2; exit 2; }
cpus=$(decimal "${RANGE_NLM_CPUS:-2}") && ((cpus >= 1)) || { echo "$0: RANGE_NLM_CPUS must be >= 1, got '${RANGE_NLM_CPUS:-}'" >&2; exit 2; }
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
array_limit=
if [[ -n ${RANGE_NLM_ARRAY_LIMIT:-} ]]; then
  array_limit=$(decimal "$RANGE_NLM_ARRAY_LIMIT") && ((array_limit >= 1)) ||
    { echo "$0: RANGE_NLM_ARRAY_LIMIT must be >= 1, got '$RANGE_NLM_ARRAY_LIMIT'" >&2; exit 2; }
fi

array_job=$(submit_shards "0-$((shards - 1))")
check_job=$(submit_check "$array_job" "$array_job")
record "$array_job"
echo "range_nlm: array job $array_job ($shards shards, $cpus CPUs each), check job $check_job"
echo "range_nlm: logs in $log_dir (range_nlm-${array_job}_K.out, range_nlm-check-$check_job.out)"
