#!/usr/bin/env bash
# Resubmit the unfinished tasks of a run made by submit.sh, and a new merge job after them.
#
#   scripts/slurm/resubmit.sh RUN_DIR [sbatch options…]
#
# A task is unfinished when RUN_DIR/shard-i/complete.json is missing (failed, cancelled, timed
# out, preempted, never ran). Each resubmitted task resumes from the rows its shard already
# wrote (the sweep is resumable and deterministic: docs/search.md). Cancel the old merge job
# first if it is still pending (with --kill-on-invalid-dep it goes away by itself). Without new
# sbatch options the ones of submit.sh are reused. Prints the two job ids.
set -euo pipefail

here=$(cd "$(dirname "$0")" && pwd)
if [ $# -lt 1 ]; then
    echo "usage: $0 RUN_DIR [sbatch options…]" >&2
    exit 2
fi
run=$(cd "$1" && pwd)
shift
for f in search.args shards; do
    [ -f "$run/$f" ] || { echo "resubmit.sh: $run/$f missing: not a run made by submit.sh" >&2; exit 1; }
done
n=$(cat "$run/shards")
eval "args=($(cat "$run/search.args"))"
if [ $# -gt 0 ]; then sb=("$@"); else eval "sb=($(cat "$run/sbatch.args" 2>/dev/null))"; fi
todo=()
for ((i = 0; i < n; i++)); do
    [ -f "$run/shard-$i/complete.json" ] || todo+=("$i")
done
if [ ${#todo[@]} = 0 ]; then
    echo "resubmit.sh: all $n shards are complete; merge with: sbatch $here/merge.sh $run $n ${args[*]}" >&2
    exit 0
fi
list=$(IFS=,; echo "${todo[*]}")
MOMENTLAB=$(command -v "${MOMENTLAB:-momentlab}") || {
    echo "$(basename "$0"): no momentlab binary (put it on PATH or set MOMENTLAB=/path/to/momentlab)" >&2
    exit 1
}
export MOMENTLAB
array=$(sbatch --parsable --array="$list" "${sb[@]}" \
    --output="$run/logs/search-%A_%a.log" "$here/search-array.sh" "$run" "$n" "${args[@]}")
array=${array%%;*}
merge=$(sbatch --parsable --dependency=afterok:"$array" --kill-on-invalid-dep=yes \
    --output="$run/logs/merge-%j.log" "$here/merge.sh" "$run" "$n" "${args[@]}")
merge=${merge%%;*}
echo "resubmitted: tasks $list as array job $array, merge job $merge → $run/merged"
echo "$array $merge"
