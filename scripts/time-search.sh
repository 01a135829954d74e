#!/bin/sh
# Time the candidate sweep `momentlab search --m M --no-report` on the embedded default dataset
# (rendering and sampling included, as a user runs it) and record the wall time, the sweep's own
# time and LP solves (its "sweep done in" line), the wall time `--plan` predicted just before on
# the same machine (its forecast is printed first), the command's CPU seconds (user + system), CPU model and thread count in
# reports/search/wall_m<M>.json (with "shared": true when SHARED=1 says other jobs shared the
# cores, so the wall time is an upper bound), which README's
# sweep table and docs/search.md read. The rows go
# to results/search-m<M> (resumed if present: time a fresh folder). Then write the report with
# `momentlab search --m M --report-only --out reports/search --force` (docs/search.md).
# Usage: scripts/time-search.sh M [search arguments…]   (from the repository root, after
# `cargo build --release`); the arguments (e.g. `--lp-budget N`) go to both the plan and the run.
set -eu
m=${1:?usage: scripts/time-search.sh M [search arguments…]}
shift
bin=${MOMENTLAB:-target/release/momentlab}
if [ -e "results/search-m$m/complete.json" ]; then
    echo "time-search.sh: results/search-m$m is already complete; move it away to time a fresh run" >&2
    exit 1
fi
log=$(mktemp)
trap 'rm -f "$log" "$log.cpu"' EXIT
# "plan: * racing (expected)   157.9 M   1.234   26 min 1 s"
planned=$("$bin" search --m "$m" "$@" --plan)
printf '%s\n' "$planned"
plan=$(printf '%s\n' "$planned" | sed -n 's/^plan: \* racing (expected) *[0-9.]* [kMG]* *[0-9.]* *//p')
start=$(date +%s)
{ /usr/bin/time -f '%U %S' -o "$log.cpu" "$bin" search --m "$m" "$@" --no-report 2>&1; echo "$?" > "$log.rc"; } | tee "$log"
end=$(date +%s)
rc=$(cat "$log.rc")
rm -f "$log.rc"
[ "$rc" = 0 ] || { echo "time-search.sh: search failed (exit $rc)" >&2; exit "$rc"; }
# "search: sweep done in 1291.6 s: … 147902464 LP solves planned …"
sweep=$(sed -n 's/^search: sweep done in \([0-9.]*\) s:.*/\1/p' "$log" | tail -n 1)
solves=$(sed -n 's/^search: sweep done in .* \([0-9][0-9]*\) LP solves.*/\1/p' "$log" | tail -n 1)
cpu=$(sed -n 's/^model name[[:space:]]*: //p' /proc/cpuinfo | head -n 1)
threads=${RAYON_NUM_THREADS:-$(nproc)}
cpu_seconds=$(awk '{ printf "%.1f", $1 + $2 }' "$log.cpu")
shared=""
[ "${SHARED:-0}" = 1 ] && shared=',
  "shared": true'
out=reports/search/wall_m$m.json
args=""
[ $# -gt 0 ] && args=" $*"
printf '{\n  "command": "momentlab search --m %s%s --no-report",\n  "seconds": %s,\n  "cpu_seconds": %s,\n  "sweep_seconds": %s,\n  "lp_solves": %s,\n  "plan": "%s",\n  "cpu": "%s",\n  "threads": %s%s\n}\n' \
    "$m" "$args" "$((end - start))" "${cpu_seconds:-null}" "${sweep:-null}" "${solves:-null}" "${plan:-?}" "${cpu:-unknown}" "$threads" "$shared" > "$out.tmp"
mv "$out.tmp" "$out"
echo "$out: $((end - start)) s"
