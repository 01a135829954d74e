#!/bin/sh
# How a race's cost depends on its fragment order: run `momentlab search --m M --race-seed S
# --no-report` for each seed S (rows in results/search-m<M>-order<S>, resumed if present) and
# `momentlab search --m M --race-seed S --plan`, and record per order the stage sizes, LP
# solves, winner and tie set, and the LP solves the plan expected (its proxy race) and its
# upper bound, in reports/search/race_orders_m<M>.json, which docs/search.md ("Sizing a run")
# renders.
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
    # "plan: expected from a proxy race … → 10 341 376 LP solves (…"
    # "plan:   racing (keep 0.25, at most)     20.462 M …"
    "$bin" search --m "$m" --race-seed "$s" --plan > "results/search-m$m-order$s.plan" 2>/dev/null ||
        { echo "race-orders.sh: search --m $m --race-seed $s --plan failed" >&2; exit 1; }
done
out=reports/search/race_orders_m$m.json
python3 - "$m" "$out.tmp" "$@" <<'PY'
import json, re, sys
m, out, seeds = sys.argv[1], sys.argv[2], sys.argv[3:]
orders = []
for s in seeds:
    d = f"results/search-m{m}-order{s}"
    c = json.load(open(f"{d}/complete.json"))
    w = c["race"]["winner"]
    rows = [json.loads(l) for l in open(f"{d}/results.jsonl")]
    names = next(r["functions"] for r in rows if r["index"] == w)
    tied = sorted(r["index"] for r in rows if r.get("tied"))
    try:
        plan = open(f"{d}.plan").read()
    except FileNotFoundError:
        plan = ""
    expected = re.search(r"× [0-9]+ → ([0-9 ]+) LP solves", plan)
    bound = re.search(r"racing \(keep [^)]*, at most\) +([0-9.]+) M", plan)
    orders.append({"command": f"momentlab search --m {m} --race-seed {s} --results {d} --no-report",
                   "race_seed": int(s), "stages": c["stages"], "lp_solves": c["lp_solves"],
                   "winner": w, "winner_functions": names, "tied": c["race"]["tied"], "tied_indices": tied,
                   "plan_command": f"momentlab search --m {m} --race-seed {s} --plan",
                   "plan_lp_solves": int(expected.group(1).replace(" ", "")) if expected else None,
                   "plan_upper_bound": round(float(bound.group(1)) * 1e6) if bound else None})
doc = {"script": "scripts/race-orders.sh " + " ".join([m] + seeds), "orders": orders}
open(out, "w").write(json.dumps(doc, indent=2) + "\n")
PY
mv "$out.tmp" "$out"
echo "$out: ${#} orders"
