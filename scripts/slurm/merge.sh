#!/usr/bin/env bash
#SBATCH --job-name=momentlab-merge
#SBATCH --cpus-per-task=1
# The merge job of a sharded sweep: after every array task of search-array.sh succeeded,
#
#   sbatch --dependency=afterok:<array job id> scripts/slurm/merge.sh RUN_DIR N [search arguments…]
#
# merges RUN_DIR/shard-0 … shard-(N-1) into RUN_DIR/merged (`momentlab merge`, which refuses a
# failed, unfinished or missing shard with a one-line error), then writes the report into
# RUN_DIR/report (`momentlab search --report-only` with the same search arguments) unless the
# arguments contain --no-report. Usually submitted by submit.sh / resubmit.sh.
set -euo pipefail

if [ $# -lt 2 ]; then
    echo "usage: sbatch $0 RUN_DIR N [momentlab search arguments…]" >&2
    exit 2
fi
run=$1
n=$2
shift 2
if ! [[ "$n" =~ ^[1-9][0-9]*$ ]]; then
    echo "merge.sh: N = '$n': expected a positive number of shards" >&2
    exit 2
fi
bin=${MOMENTLAB:-momentlab}
dirs=()
for ((i = 0; i < n; i++)); do dirs+=("$run/shard-$i"); done
"$bin" merge "${dirs[@]}" --out "$run/merged"
for a in "$@"; do
    if [ "$a" = --no-report ]; then exit 0; fi
done
# --report-only rebuilds the dataset from the same arguments; --shard/--results/--out are replaced.
args=()
skip=0
for a in "$@"; do
    if [ "$skip" = 1 ]; then skip=0; continue; fi
    case "$a" in
    --shard | --results | --out | --report) skip=1 ;;
    --shard=* | --results=* | --out=* | --report=*) ;;
    *) args+=("$a") ;;
    esac
done
"$bin" search "${args[@]}" --results "$run/merged" --out "$run/report" --report-only
