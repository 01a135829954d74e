#!/bin/sh
# How a race's cost depends on its fragment order: run `momentlab search --m M --race-seed S
# --no-report` for each seed S (rows in results/search-m<M>-order<S>, resumed if present) and
# `momentlab search --m M --race-seed S --plan`, and record per order the stage sizes, LP
# solves, winner and tie set, and the LP solves the plan expected (its proxy race) and its
# upper bound, in reports/search/race_orders_m<M>.json, which docs/search.md ("Sizing a run")
# renders. With PLANS_ONLY=1 only the plans are rerun, and only their fields of the existing
# JSON are updated (the races are machine-independent; a plan takes seconds to minutes).
# Usage: scripts/race-orders.sh M SEED...   (from the repository root, after `cargo build --release`)
set -eu
m=${1:?usage: scripts/race-orders.sh M SEED...}
shift
[ "$#" -gt 0 ] || { echo "race-orders.sh: give at least one seed" >&2; exit 1; }
bin=${MOMENTLAB:-target/release/momentlab}
for s in "$@"; do
    echo "race-orders.sh: m = $m, race seed $s" >&2
    mkdir -p results
    [ "${PLANS_ONLY:-0}" = 1 ] || "$bin" search --m "$m" --race-seed "$s" --results "results/search-m$m-order$s" --no-report >/dev/null 2>&1 ||
        { echo "race-orders.sh: search --m $m --race-seed $s failed" >&2; exit 1; }
    # "plan: expected from 64 runs of the race … stages …; 8 497 560 LP solves (80 % of the runs between 6.657 M and 10.367 M; …"
    # "plan: proxy race on 1/8 … its LP solves × 8 = 10 340 864"
    # "plan:   racing (at most)     20.462 M …"
    "$bin" search --m "$m" --race-seed "$s" --plan > "results/search-m$m-order$s.plan" 2>/dev/null ||
        { echo "race-orders.sh: search --m $m --race-seed $s --plan failed" >&2; exit 1; }
done
out=reports/search/race_orders_m$m.json
python3 - "$m" "$out.tmp" "${PLANS_ONLY:-0}" "$@" <<'PY'
import json, re, sys
m, out, plans_only, seeds = sys.argv[1], sys.argv[2], sys.argv[3] == "1", sys.argv[4:]
def plan_fields(d):
    try:
        plan = open(f"{d}.plan").read()
    except FileNotFoundError:
        plan = ""
    num = lambda g: int(g.replace(" ", ""))
    expected = re.search(r"expected from [0-9]+ runs of the race .*?; ([0-9 ]+) LP solves \(80 % of the runs between ([0-9.]+) M and ([0-9.]+) M", plan)
    proxy = re.search(r"its LP solves × [0-9]+ = ([0-9 ]+)", plan)
    bound = re.search(r"racing \(at most\) +([0-9.]+) M", plan)
    return {"plan_command": f"momentlab search --m {m} --race-seed {s} --plan",
            "plan_lp_solves": num(expected.group(1)) if expected else None,
            "plan_range": [round(float(expected.group(k)) * 1e6) for k in (2, 3)] if expected else None,
            "plan_proxy_lp_solves": num(proxy.group(1)) if proxy else None,
            "plan_upper_bound": round(float(bound.group(1)) * 1e6) if bound else None}
if plans_only:
    doc = json.load(open(out[:-len(".tmp")]))
    for o in doc["orders"]:
        if str(o["race_seed"]) in seeds:
            s = str(o["race_seed"])
            o.update(plan_fields(f"results/search-m{m}-order{s}"))
    open(out, "w").write(json.dumps(doc, indent=2) + "\n")
    sys.exit(0)
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
                   "winner": w, "winner_functions": names, "tied": c["race"]["tied"], "tied_indices": tied,
                   **plan_fields(d)})
doc = {"script": "scripts/race-orders.sh " + " ".join([m] + seeds), "orders": orders}
open(out, "w").write(json.dumps(doc, indent=2) + "\n")
PY
mv "$out.tmp" "$out"
echo "$out: ${#} orders"
