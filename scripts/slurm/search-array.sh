#!/usr/bin/env bash
#SBATCH --job-name=momentlab-search
#SBATCH --cpus-per-task=1
# One shard of a sharded `momentlab search`, as a task of a Slurm job array.
#
#   sbatch --array=0-$((N-1)) [--cpus-per-task=C --time=T --mem=M --partition=P] \
#       scripts/slurm/search-array.sh RUN_DIR N [momentlab search arguments…]
#
# Task i runs `momentlab search --shard i/N --results RUN_DIR/shard-i --no-report ARGS…` with
# rayon on the task's --cpus-per-task (SLURM_CPUS_PER_TASK). RUN_DIR must be on a filesystem
# that every node and the merge job see. A task that fails or is terminated (scancel, time limit,
# preemption) writes RUN_DIR/shard-i/FAILED, which makes the merge refuse; rerunning the task
# (scripts/slurm/resubmit.sh) removes it and resumes from the rows already written.
# $MOMENTLAB names the binary (default: momentlab on PATH). Usually submitted by submit.sh.
set -uo pipefail

if [ $# -lt 2 ]; then
    echo "usage: sbatch --array=0-<N-1> $0 RUN_DIR N [momentlab search arguments…]" >&2
    exit 2
fi
run=$1
n=$2
shift 2
i=${SLURM_ARRAY_TASK_ID:-}
if ! [[ "$n" =~ ^[1-9][0-9]*$ ]] || ! [[ "$i" =~ ^[0-9]+$ ]] || [ "$i" -ge "$n" ]; then
    echo "search-array.sh: need N ≥ 1 and an array task id 0 ≤ i < N (got N = '$n', SLURM_ARRAY_TASK_ID = '$i')" >&2
    exit 2
fi
bin=${MOMENTLAB:-momentlab}
args=()
for a in "$@"; do [ "$a" = --no-report ] || args+=("$a"); done # added below
dir=$run/shard-$i
job="${SLURM_ARRAY_JOB_ID:-?}_$i (job id ${SLURM_JOB_ID:-?}) on $(hostname -s)"
mkdir -p "$dir" || exit 1
rm -f "$dir/FAILED"

fail() { # message
    printf 'shard %s/%s: %s (Slurm task %s, %s)\n' "$i" "$n" "$1" "$job" "$(date -u +%FT%TZ)" >"$dir/FAILED"
}
# Slurm signals every process of the job (scancel, time limit): momentlab stops at once and the
# trap runs when the pipeline below has ended.
trap 'fail "terminated by SIGTERM (scancel, time limit or preemption) before it finished"; exit 143' TERM

echo "search-array.sh: task $job: $bin search --shard $i/$n --results $dir --no-report ${args[*]}" >&2
# stderr goes to the Slurm log and to $dir/stderr.log (its last line names a failure's cause).
exec 3>&1
"$bin" search --shard "$i/$n" --results "$dir" --no-report "${args[@]}" 2>&1 1>&3 | tee -a "$dir/stderr.log" >&2
rc=${PIPESTATUS[0]}
if [ "$rc" != 0 ]; then
    last=$(grep '^error' "$dir/stderr.log" 2>/dev/null | tail -n 1)
    [ -n "$last" ] || last=$(grep -v '^\s*$' "$dir/stderr.log" 2>/dev/null | tail -n 1)
    fail "momentlab search exited with status $rc: ${last:-no message}"
    echo "search-array.sh: task $job failed (status $rc); see $dir/FAILED" >&2
fi
exit "$rc"
