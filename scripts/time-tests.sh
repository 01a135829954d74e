#!/bin/sh
# Time `cargo test --release` (after a build, so only the tests run) and record the wall time,
# CPU model and thread count in reports/tests_wall_time.json, which README's quick start reads.
# Usage: scripts/time-tests.sh   (from the repository root)
set -eu
cargo test --release --no-run
start=$(date +%s)
cargo test --release
end=$(date +%s)
cpu=$(sed -n 's/^model name[[:space:]]*: //p' /proc/cpuinfo | head -n 1)
threads=${RAYON_NUM_THREADS:-$(nproc)}
printf '{\n  "command": "cargo test --release",\n  "seconds": %s,\n  "cpu": "%s",\n  "threads": %s\n}\n' \
    "$((end - start))" "${cpu:-unknown}" "$threads" > reports/tests_wall_time.json.tmp
mv reports/tests_wall_time.json.tmp reports/tests_wall_time.json
echo "reports/tests_wall_time.json: $((end - start)) s"
