#!/bin/sh
# Time the candidate sweep `momentlab search --m M --no-report` on the embedded default dataset
# (rendering and sampling included, as a user runs it) and record the wall time, CPU model and
# thread count in reports/search/wall_m<M>.json, which README's sweep table reads. The rows go to
# results/search-m<M> (resumed if present: time a fresh folder). Then write the report with
# `momentlab search --m M --report-only --out reports/search --force` (docs/search.md).
# Usage: scripts/time-search.sh M   (from the repository root, after `cargo build --release`)
set -eu
m=${1:?usage: scripts/time-search.sh M}
bin=${MOMENTLAB:-target/release/momentlab}
if [ -e "results/search-m$m/complete.json" ]; then
    echo "time-search.sh: results/search-m$m is already complete; move it away to time a fresh run" >&2
    exit 1
fi
start=$(date +%s)
"$bin" search --m "$m" --no-report
end=$(date +%s)
cpu=$(sed -n 's/^model name[[:space:]]*: //p' /proc/cpuinfo | head -n 1)
threads=${RAYON_NUM_THREADS:-$(nproc)}
out=reports/search/wall_m$m.json
printf '{\n  "command": "momentlab search --m %s --no-report",\n  "seconds": %s,\n  "cpu": "%s",\n  "threads": %s\n}\n' \
    "$m" "$((end - start))" "${cpu:-unknown}" "$threads" > "$out.tmp"
mv "$out.tmp" "$out"
echo "$out: $((end - start)) s"
