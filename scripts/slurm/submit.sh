#!/usr/bin/env bash
# Submit a sharded `momentlab search` to Slurm: a job array of N tasks and the merge job that
# runs when all of them succeeded (--dependency=afterok, --kill-on-invalid-dep=yes).
#
#   scripts/slurm/submit.sh RUN_DIR N [sbatch options…] -- [momentlab search arguments…]
#
#   e.g. scripts/slurm/submit.sh /shared/me/m4 16 --cpus-per-task=8 --time=02:00:00 \
#            --partition=compute -- --m 4 --exhaustive
#
# sbatch options apply to the array tasks (size them with `momentlab search --plan`); the merge
# job gets one CPU. Logs: RUN_DIR/logs/search-<job>_<task>.log and merge-<job>.log. The search
# arguments are saved in RUN_DIR/search.args for resubmit.sh. Prints the two job ids.
# $MOMENTLAB names the binary (default: momentlab on PATH); it is exported to the jobs.
set -euo pipefail

here=$(cd "$(dirname "$0")" && pwd)
if [ $# -lt 2 ]; then
    echo "usage: $0 RUN_DIR N [sbatch options…] -- [momentlab search arguments…]" >&2
    exit 2
fi
run=$1
n=$2
shift 2
if ! [[ "$n" =~ ^[1-9][0-9]*$ ]]; then
    echo "submit.sh: N = '$n': expected a positive number of shards" >&2
    exit 2
fi
sb=()
while [ $# -gt 0 ] && [ "$1" != -- ]; do
    sb+=("$1")
    shift
done
[ "${1:-}" = -- ] && shift
mkdir -p "$run/logs"
run=$(cd "$run" && pwd)
quote() { if [ $# -gt 0 ]; then printf '%q ' "$@"; fi; }
if [ -e "$run/search.args" ] && [ "$(cat "$run/search.args")" != "$(quote "$@")" ]; then
    echo "submit.sh: $run was submitted with other search arguments ($(cat "$run/search.args")); use another RUN_DIR" >&2
    exit 1
fi
if [ -e "$run/shards" ] && [ "$(cat "$run/shards")" != "$n" ]; then
    echo "submit.sh: $run was submitted with $(cat "$run/shards") shards, not $n; use another RUN_DIR" >&2
    exit 1
fi
quote "$@" >"$run/search.args"
printf '%s\n' "$n" >"$run/shards"
quote "${sb[@]}" >"$run/sbatch.args"
MOMENTLAB=$(command -v "${MOMENTLAB:-momentlab}") || {
    echo "$(basename "$0"): no momentlab binary (put it on PATH or set MOMENTLAB=/path/to/momentlab)" >&2
    exit 1
}
export MOMENTLAB

array=$(sbatch --parsable --array=0-$((n - 1)) "${sb[@]}" \
    --output="$run/logs/search-%A_%a.log" "$here/search-array.sh" "$run" "$n" "$@")
array=${array%%;*}
merge=$(sbatch --parsable --dependency=afterok:"$array" --kill-on-invalid-dep=yes \
    --output="$run/logs/merge-%j.log" "$here/merge.sh" "$run" "$n" "$@")
merge=${merge%%;*}
echo "submitted: array job $array (tasks 0-$((n - 1))), merge job $merge → $run/merged"
echo "$array $merge"
