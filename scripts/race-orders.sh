#!/bin/sh
# How a race's cost depends on its fragment order: run `momentlab search --m M --race-seed S
# --no-report` for each seed S (rows in results/search-m<M>-order<S>, resumed if present) and
# record per order the stage sizes, LP solves, winner and tie set in
# reports/search/race_orders_m<M>.json, which docs/search.md ("Sizing a run") cites.
# Usage: scripts/race-orders.sh M SEED...   (from the repository root, after `cargo build --release`)
set -eu
m=${1:?usage: scripts/race-orders.sh M SEED...}
shift
[ "$#" -gt 0 ] || { echo "race-orders.sh: give at least one seed" >&2; exit 1; }
bin=${MOMENTLAB:-target/release/momentlab}
for s in "$@"; do
    echo "race-orders.sh: m = $m, race seed $s" >&2
    "$bin" search --m "$m" --race-seed "$s" --results "results/search-m$m-order$s" --no-report >/dev/null 2>&1 ||
        { echo "race-orders.sh: search --m $m --race-seed $s failed" >&2; exit 1; }
done
out=reports/search/race_orders_m$m.json
python3 - "$m" "$out.tmp" "$@" <<'PY'
import json, sys
m, out, seeds = sys.argv[1], sys.argv[2], sys.argv[3:]
orders = []
for s in seeds:
    d = f"results/search-m{m}-order{s}"
    c = json.load(open(f"{d}/complete.json"))
    w = c["race"]["winner"]
    rows = [json.loads(l) for l in open(f"{d}/results.jsonl")]
    names = next(r["functions"] for r in rows if r["index"] == w)
    tied = sorted(r["index"] for r in rows if r.get("tied"))
    orders.append({"command": f"momentlab search --m {m} --race-seed {s} --results {d} --no-report",
                   "race_seed": int(s), "stages": c["stages"], "lp_solves": c["lp_solves"],
                   "winner": w, "winner_functions": names, "tied": c["race"]["tied"], "tied_indices": tied})
doc = {"script": "scripts/race-orders.sh " + " ".join([m] + seeds), "orders": orders}
open(out, "w").write(json.dumps(doc, indent=2) + "\n")
PY
mv "$out.tmp" "$out"
echo "$out: ${#} orders"
