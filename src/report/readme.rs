//! The figures of README.md, rendered from the committed artefacts under `reports/`.
//!
//! README holds marked blocks `<!-- generated:NAME -->` … `<!-- end -->`; [`render`] writes the
//! exact text of each block from the artefacts, [`blocks`] reads README's blocks and [`splice`]
//! replaces them. tests/project/readme_figures.rs asserts that README's blocks equal the rendered
//! ones (and rewrites them with `MOMENTLAB_UPDATE_README=1`), so a changed artefact fails the
//! test until README is regenerated.

use anyhow::{anyhow, bail, Context, Result};
use serde_json::Value;
use std::fmt::Write as _;
use std::path::Path;

const OPEN: &str = "<!-- generated:";
const CLOSE: &str = "<!-- end -->";

/// The names of the blocks [`render`] knows, in README order.
pub const NAMES: [&str; 7] = [
    "quickstart",
    "techniques",
    "paper",
    "sweeps",
    "tune",
    "theta",
    "gpu-bench",
];

/// Nanoseconds at a sensible precision: integers from 100 ns, three significant digits below.
pub fn fmt_ns(x: f64) -> String {
    if !x.is_finite() {
        "n/a".into()
    } else if x >= 100.0 {
        format!("{x:.0}")
    } else if x >= 10.0 {
        format!("{x:.1}")
    } else {
        format!("{x:.2}")
    }
}

fn read_json(path: &Path) -> Result<Value> {
    let s = read(path)?;
    serde_json::from_str(&s).with_context(|| format!("parsing {}", path.display()))
}

fn read(path: &Path) -> Result<String> {
    crate::artefact::read_text(path, crate::artefact::Limit::ARTEFACT)
}

fn f(v: &Value, key: &str, file: &Path) -> Result<f64> {
    v.get(key)
        .and_then(Value::as_f64)
        .ok_or_else(|| anyhow!("{}: no number '{key}'", file.display()))
}

/// Render block `name` from the artefacts under `reports` (the repository's `reports/`).
pub fn render(name: &str, reports: &Path) -> Result<String> {
    match name {
        "quickstart" => quickstart(reports),
        "techniques" => techniques(reports),
        "paper" => paper(reports),
        "sweeps" => sweeps(reports),
        "tune" => tune(reports),
        "theta" => theta(reports),
        "gpu" => super::gpu::docs_block(reports),
        "gpu-bench" => super::gpu::readme_bench(reports),
        "race-times" => race_times(reports),
        "race-orders" => race_orders(reports),
        "stability" => super::docs_figures::stability(reports),
        "theta-comparison" => super::docs_figures::theta_comparison(reports),
        "theta-basis" => super::docs_figures::theta_basis(reports),
        "quantize-alpha" => super::docs_figures::quantize_alpha(reports),
        "quantize-usable" => super::docs_figures::quantize_usable(reports),
        "theta-fig5" => super::docs_figures::theta_fig5(reports),
        "gpu-cost" => crate::gpu::cost::docs_block(reports),
        "lp-families" => super::docs_figures::lp_families(reports),
        "dataset" => super::docs_figures::dataset(reports),
        _ => bail!("unknown README block '{name}'"),
    }
}

/// Wall times of the two set-up commands: `reports/default/run.json` (written by
/// `momentlab reproduce`) and `reports/tests_wall_time.json` (scripts/time-tests.sh).
fn quickstart(reports: &Path) -> Result<String> {
    let mut s = String::new();
    let run = reports.join("default/run.json");
    if run.is_file() {
        let v = read_json(&run)?;
        let p = v.get("provenance").cloned().unwrap_or(Value::Null);
        let _ = writeln!(
            s,
            "`reproduce` took {:.0} s wall on {} threads ({}; reports/default/run.json).",
            f(&v, "seconds", &run)?,
            p.get("threads").and_then(Value::as_u64).unwrap_or(0),
            p.get("cpu")
                .and_then(Value::as_str)
                .unwrap_or("unknown CPU")
        );
    } else {
        s.push_str(
            "`reproduce` records its wall time in reports/default/run.json (not yet written).\n",
        );
    }
    let tests = reports.join("tests_wall_time.json");
    if tests.is_file() {
        let v = read_json(&tests)?;
        let _ = writeln!(
            s,
            "`cargo test --release` ran in {:.0} s wall after its build, on {} threads ({}; reports/tests_wall_time.json, `scripts/time-tests.sh`).",
            f(&v, "seconds", &tests)?,
            v.get("threads").and_then(Value::as_u64).unwrap_or(0),
            v.get("cpu").and_then(Value::as_str).unwrap_or("unknown CPU")
        );
    } else {
        s.push_str("`scripts/time-tests.sh` records the tests' wall time in reports/tests_wall_time.json (not yet written).\n");
    }
    Ok(s)
}

/// Display name of a technique id.
fn display(name: &str) -> String {
    match name {
        "hamburger4" => "Hamburger 4MSM".into(),
        "hausdorff4" => "Hausdorff 4MSM".into(),
        "hamburger6" => "6MSM".into(),
        "tmsm" => "TMSM (closed form)".into(),
        "vsm" => "VSM".into(),
        "esm" => "ESM".into(),
        "evsm" => "EVSM".into(),
        "csm" => "CSM".into(),
        n => match n.strip_prefix("lp:") {
            Some("z,z^2,z^3,z^4") => "Algorithm 1, b_MSM".into(),
            Some("sin(2πz),cos(2πz),sin(4πz),cos(4πz)") => "Algorithm 1, b_TMSM".into(),
            Some(b) => format!("Algorithm 1, ({})", b.replace(',', ", ")),
            None => n.into(),
        },
    }
}

/// Techniques against PCF: closed forms in f32, LP candidates (f64), from
/// `reports/default/evaluate/*.json`, sorted by error.
fn techniques(reports: &Path) -> Result<String> {
    let dir = reports.join("default/evaluate");
    let mut files: Vec<_> = std::fs::read_dir(&dir)
        .with_context(|| format!("reading {}", dir.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|e| e == "json"))
        .collect();
    files.sort();
    let mut rows = Vec::new();
    for file in &files {
        let v = read_json(file)?;
        let name = v.get("name").and_then(Value::as_str).unwrap_or("?");
        let prec = v.get("precision").and_then(Value::as_str).unwrap_or("?");
        let lp = name.starts_with("lp:");
        if (lp && prec != "f64") || (!lp && prec != "f32") {
            continue;
        }
        let frags = f(&v, "fragments", file)?;
        let scaled = match v.get("error_scaled").and_then(Value::as_array) {
            Some(a) if a.len() == 2 => format!(
                "{:.2} / {:.2} %",
                100.0 * a[0].as_f64().unwrap_or(f64::NAN),
                100.0 * a[1].as_f64().unwrap_or(f64::NAN)
            ),
            _ => "–".into(),
        };
        rows.push((
            f(&v, "error", file)?,
            display(name),
            scaled,
            f(&v, "ns_per_fragment", file)?,
            f(&v, "bits_per_texel", file)?,
            frags,
        ));
    }
    rows.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut s = String::from(
        "| technique | error | at PCF ε/3, 3ε | ns / fragment | bits / texel | fragments |\n| --- | ---: | ---: | ---: | ---: | ---: |\n",
    );
    for (e, n, scaled, ns, bits, frags) in rows {
        let _ = writeln!(
            s,
            "| {n} | {:.2} % | {scaled} | {} | {bits:.0} | {frags:.0} |",
            100.0 * e,
            fmt_ns(ns)
        );
    }
    Ok(s)
}

/// The paper's line of the m = 4 sweep report (the paper's numbers, quoted as the paper's).
fn paper(reports: &Path) -> Result<String> {
    let file = reports.join("search/search_m4.md");
    let text = read(&file)?;
    let line = text
        .lines()
        .find(|l| l.starts_with("Paper ("))
        .ok_or_else(|| anyhow!("{}: no 'Paper (' line", file.display()))?;
    Ok(format!("{line}\n"))
}

/// What README and docs/search.md quote of a committed sweep report (search_m<m>.md).
struct SweepSummary {
    candidates: String,
    functions: String,
    error: String,
    se: String,
    sampled: String,
    tied: String,
    /// "- b_MSM (LP): …" lines, without the prefix.
    msm: Vec<String>,
    /// Candidates an LP budget (`--lp-budget`) left unresolved at the end of the race.
    unresolved: Option<String>,
}

impl SweepSummary {
    /// The tie column: the tied set, or the unresolved one of a race an LP budget ended.
    fn tied_or_unresolved(&self) -> String {
        match &self.unresolved {
            Some(n) => format!("{n} unresolved (LP budget)"),
            None => self.tied.clone(),
        }
    }

    /// The note on a race an LP budget ended.
    fn unresolved_note(&self, m: usize) -> Option<String> {
        self.unresolved.as_ref().map(|n| {
            format!(
                "m = {m}: an LP budget (`--lp-budget`, the command in wall_m{m}.json) ended the race \
                 with {n} candidates unresolved: none of them was eliminated, and the best candidate \
                 is among them; its winner is the best of them by the error on the fragments each \
                 was scored on"
            )
        })
    }
}

/// reports/search/search_m<m>.md, None when absent.
fn sweep_summary(reports: &Path, m: usize) -> Result<Option<SweepSummary>> {
    let file = reports.join(format!("search/search_m{m}.md"));
    if !file.is_file() {
        return Ok(None);
    }
    let text = read(&file)?;
    let missing = |what: &str| anyhow!("{}: no {what}", file.display());
    let w = text
        .lines()
        .find_map(|l| l.strip_prefix("The winner of "))
        .ok_or_else(|| missing("winner line"))?;
    // "<N> scored candidates is <index> = (<functions>) with <e> % ± <se> %…"
    let (count, rest) = w
        .split_once(" scored candidates is ")
        .ok_or_else(|| missing("candidate count"))?;
    let open = rest
        .find("= (")
        .ok_or_else(|| missing("winner functions"))?;
    let close = rest
        .rfind(") with ")
        .ok_or_else(|| missing("winner error"))?;
    let err = rest[close + ") with ".len()..]
        .split(" %")
        .take(2)
        .map(|x| x.trim_start_matches(" ± ").trim().to_string())
        .collect::<Vec<_>>();
    let sampled = text
        .split_once("dataset holds ")
        .and_then(|x| x.1.split_whitespace().next())
        .ok_or_else(|| missing("sample size"))?;
    let tied = text
        .lines()
        .find_map(|l| l.strip_suffix(" candidates are statistically tied for first."))
        .unwrap_or("–");
    Ok(Some(SweepSummary {
        candidates: count.to_string(),
        functions: rest[open + 3..close].to_string(),
        error: err.first().cloned().unwrap_or_else(|| "?".into()),
        se: err.get(1).cloned().unwrap_or_else(|| "?".into()),
        sampled: sampled.to_string(),
        tied: tied.to_string(),
        msm: text
            .lines()
            .filter_map(|l| l.strip_prefix("- b_MSM (LP): "))
            .map(|x| x.trim_end_matches('.').to_string())
            .collect(),
        unresolved: text.lines().find_map(|l| {
            let rest = l
                .split_once("**Unresolved**: the LP budget ended the race with ")?
                .1;
            rest.split_once(" candidates left").map(|x| x.0.to_string())
        }),
    }))
}

/// reports/search/wall_m<m>.json (`scripts/time-search.sh M`), None when absent.
fn sweep_wall(reports: &Path, m: usize) -> Result<Option<(Value, std::path::PathBuf)>> {
    let file = reports.join(format!("search/wall_m{m}.json"));
    if !file.is_file() {
        return Ok(None);
    }
    Ok(Some((read_json(&file)?, file)))
}

/// " (shared cores)" for a wall-time file measured while other jobs shared the cores
/// (`"shared": true`), else "".
fn shared(v: &Value) -> &'static str {
    if v.get("shared").and_then(Value::as_bool) == Some(true) {
        " (shared cores)"
    } else {
        ""
    }
}

/// ", CPU <time>" for a wall-time file that records the command's CPU seconds (user +
/// system, `cpu_seconds`), else "".
fn cpu_time(v: &Value) -> String {
    v.get("cpu_seconds")
        .and_then(Value::as_f64)
        .map_or_else(String::new, |c| format!(", CPU {}", minutes(c)))
}

/// The host line of the wall-time files: threads and CPU model.
fn host(v: &Value) -> (u64, String) {
    (
        v.get("threads").and_then(Value::as_u64).unwrap_or(0),
        v.get("cpu")
            .and_then(Value::as_str)
            .unwrap_or("?")
            .to_string(),
    )
}

/// The wall time `--plan` forecast (wall_m<M>.json's "plan") and its difference to the
/// measured `secs`, e.g. "58 s (+4 %)"; "–" when not recorded.
fn plan_vs(v: &Value, secs: f64) -> String {
    let plan = v.get("plan").and_then(Value::as_str);
    match plan.and_then(|p| Some((p, parse_duration(p)?))) {
        Some((p, planned)) => format!("{p} ({:+.0} %)", 100.0 * (planned / secs - 1.0)),
        None => "–".to_string(),
    }
}

/// The full sweeps of reports/search: one row per m from `search_m<m>.md`, with the wall time
/// of the race from `wall_m<m>.json` (scripts/time-search.sh).
fn sweeps(reports: &Path) -> Result<String> {
    let mut s = String::from(
        "| m | candidates | fragments sampled | tied for first | winner | error ± s.e. | race wall time | `--plan` forecast (vs the wall time) |\n| ---: | ---: | ---: | ---: | --- | ---: | ---: | ---: |\n",
    );
    let mut hosts = None;
    let mut notes = Vec::new();
    let mut budget = Vec::new();
    for m in 2..=4 {
        let Some(x) = sweep_summary(reports, m)? else {
            continue;
        };
        let (wall, plan) = match sweep_wall(reports, m)? {
            Some((v, file)) => {
                hosts = Some(host(&v));
                let secs = f(&v, "seconds", &file)?;
                (minutes(secs) + shared(&v), plan_vs(&v, secs))
            }
            None => ("–".to_string(), "–".to_string()),
        };
        let _ = writeln!(
            s,
            "| {m} | {} | {} | {} | ({}) | {} % ± {} % | {wall} | {plan} |",
            x.candidates,
            x.sampled,
            x.tied_or_unresolved(),
            x.functions,
            x.error,
            x.se
        );
        notes.extend(x.msm.iter().map(|l| format!("m = {m}: b_MSM (LP) {l}")));
        budget.extend(x.unresolved_note(m));
    }
    if let Some((threads, cpu)) = hosts {
        let _ = writeln!(
            s,
            "\nWall time of `momentlab search --m M --no-report` on the default dataset (rendering included), {threads} threads ({cpu}; reports/search/wall_m<M>.json, `scripts/time-search.sh M`); the forecast is the expected row of `search --m M --plan`, run by the script just before on the same machine.{}",
            budget.iter().map(|c| format!(" {c}.")).collect::<String>()
        );
    }
    for n in notes {
        let _ = writeln!(s, "\n{n}.");
    }
    Ok(s)
}

/// docs/search.md's table of the committed races' cost: LP solves, the sweep's and the whole
/// command's wall time (wall_m<M>.json), winner and tie set (search_m<M>.md).
fn race_times(reports: &Path) -> Result<String> {
    let mut notes = Vec::new();
    let mut s = String::from(
        "| race | LP solves | sweep | whole command | `--plan` (vs the command) | winner | error | tied |\n| --- | ---: | ---: | ---: | ---: | --- | ---: | ---: |\n",
    );
    let mut hosts = None;
    for m in 2..=4 {
        let (Some(x), Some((v, file))) = (sweep_summary(reports, m)?, sweep_wall(reports, m)?)
        else {
            continue;
        };
        hosts = Some(host(&v));
        notes.extend(x.unresolved_note(m));
        let solves = f(&v, "lp_solves", &file)?;
        let secs = f(&v, "seconds", &file)?;
        let plan = plan_vs(&v, secs);
        let _ = writeln!(
            s,
            "| m = {m} | {:.1} M | {} | {} | {plan} | ({}) | {} % | {} |",
            solves / 1e6,
            minutes(f(&v, "sweep_seconds", &file)?),
            minutes(secs) + shared(&v) + &cpu_time(&v),
            x.functions,
            x.error,
            x.tied_or_unresolved()
        );
    }
    if let Some((threads, cpu)) = hosts {
        let _ = writeln!(
            s,
            "\n{threads} threads ({cpu}); reports/search/wall_m<M>.json, written by `scripts/time-search.sh M`."
        );
    }
    for n in notes {
        let _ = writeln!(s, "\n{n}.");
    }
    Ok(s)
}

/// docs/search.md's table of one race run in several fragment orders (`--race-seed`): stage
/// sizes, LP solves against their mean, the LP solves `--plan` expected (its simulated runs,
/// with their 80 % range) and its proxy race's own × S against the run's, winner, tie set and how many of its candidates the first order's tie set
/// holds, from
/// reports/search/race_orders_m<M>.json (`scripts/race-orders.sh M SEED…`).
fn race_orders(reports: &Path) -> Result<String> {
    let mut s = String::new();
    for m in 2..=4 {
        let file = reports.join(format!("search/race_orders_m{m}.json"));
        if !file.is_file() {
            continue;
        }
        if !s.is_empty() {
            s.push('\n');
        }
        s.push_str(
            "| race | `--race-seed` | candidates per stage | LP solves | vs the mean | `--plan` expected (vs the run; 80 % of its simulated runs) | its proxy race × S (vs the run) | winner | tied | of them tied in the first order |\n| --- | ---: | --- | ---: | ---: | ---: | ---: | --- | ---: | ---: |\n",
        );
        let v = read_json(&file)?;
        let orders = v
            .get("orders")
            .and_then(Value::as_array)
            .filter(|o| !o.is_empty())
            .ok_or_else(|| anyhow!("{}: no orders", file.display()))?;
        let solves = orders
            .iter()
            .map(|o| f(o, "lp_solves", &file))
            .collect::<Result<Vec<f64>>>()?;
        let mean = solves.iter().sum::<f64>() / solves.len() as f64;
        let tied_of = |o: &Value| -> Vec<u64> {
            o.get("tied_indices")
                .and_then(Value::as_array)
                .map(|a| a.iter().filter_map(Value::as_u64).collect())
                .unwrap_or_default()
        };
        let first = tied_of(&orders[0]);
        for (o, lp) in orders.iter().zip(&solves) {
            let stages: Vec<String> = o
                .get("stages")
                .and_then(Value::as_array)
                .ok_or_else(|| anyhow!("{}: an order without stages", file.display()))?
                .iter()
                .filter_map(|st| st.get(0).and_then(Value::as_u64).map(|c| c.to_string()))
                .collect();
            let names: Vec<&str> = o
                .get("winner_functions")
                .and_then(Value::as_array)
                .map(|a| a.iter().filter_map(Value::as_str).collect())
                .unwrap_or_default();
            let vs = |key: &str| match o.get(key).and_then(Value::as_f64) {
                Some(p) => format!("{:.2} M ({:+.0} %)", p / 1e6, percent(p / lp)),
                None => "–".to_string(),
            };
            let range = o
                .get("plan_range")
                .and_then(Value::as_array)
                .and_then(|r| Some((r.first()?.as_f64()?, r.get(1)?.as_f64()?)))
                .map_or(String::new(), |(a, b)| {
                    format!("; {:.2}–{:.2} M", a / 1e6, b / 1e6)
                });
            let expected = match vs("plan_lp_solves") {
                e if range.is_empty() => e,
                e => format!("{}{range})", e.trim_end_matches(')')),
            };
            let proxy = vs("plan_proxy_lp_solves");
            let _ = writeln!(
                s,
                "| m = {m} | {:.0} | {} | {:.2} M | {:+.0} % | {expected} | {proxy} | ({}) | {:.0} | {} |",
                f(o, "race_seed", &file)?,
                stages.join(", "),
                lp / 1e6,
                percent(lp / mean),
                names.join(", "),
                f(o, "tied", &file)?,
                tied_of(o).iter().filter(|i| first.contains(i)).count()
            );
        }
        let (lo, hi) = solves
            .iter()
            .fold((f64::INFINITY, 0.0f64), |(a, b), &x| (a.min(x), b.max(x)));
        let _ = writeln!(
            s,
            "\nm = {m}: {} orders, LP solves {:.2}–{:.2} M (mean {:.2} M, {:+.0} % to {:+.0} %); reports/search/race_orders_m{m}.json, written by `scripts/race-orders.sh {m} SEED…`.",
            solves.len(),
            lo / 1e6,
            hi / 1e6,
            mean / 1e6,
            percent(lo / mean),
            percent(hi / mean)
        );
    }
    Ok(s)
}

/// 100·(ratio − 1) rounded to a whole percent, without a negative zero.
fn percent(ratio: f64) -> f64 {
    (100.0 * (ratio - 1.0)).round() + 0.0
}

/// Seconds of a duration printed by `search --plan`: "45 s", "26 min 1 s", "2 h 5 min".
fn parse_duration(text: &str) -> Option<f64> {
    let words: Vec<&str> = text.split_whitespace().collect();
    if words.is_empty() || !words.len().is_multiple_of(2) {
        return None;
    }
    words.chunks(2).try_fold(0.0, |acc, w| {
        let x: f64 = w[0].parse().ok()?;
        let unit = match w[1] {
            "h" => 3600.0,
            "min" => 60.0,
            "s" => 1.0,
            _ => return None,
        };
        Some(acc + x * unit)
    })
}

/// Seconds as "42 s", "68.5 s" (a fraction, below two minutes) or "17 min 5 s".
fn minutes(secs: f64) -> String {
    let s = secs.round() as u64;
    if s < 120 && secs.fract() != 0.0 {
        format!("{secs:.1} s")
    } else if s < 120 {
        format!("{s} s")
    } else {
        format!("{} min {} s", s / 60, s % 60)
    }
}

/// The tuned setting per scene and over all scenes (`reports/default/tune/tune.json`): bits per
/// texel, error with its leak/darkening split, and the paired gain over each of the paper's
/// defaults (the references named "paper …").
fn tune(reports: &Path) -> Result<String> {
    let file = reports.join("default/tune/tune.json");
    let v = read_json(&file)?;
    let targets: Vec<Value> = v
        .get("scenes")
        .and_then(Value::as_array)
        .cloned()
        .unwrap_or_default()
        .into_iter()
        .chain(v.get("overall").cloned())
        .collect();
    let pct = |x: f64| format!("{:.2}", 100.0 * x);
    let mut s = String::from(
        "| scene | tuned setting | bits / texel | GPU ns / lookup | error % (leak + darkening + noise) | noise above 1/255 | gain over the paper's 16-bit default (its noise above 1/255) |\n| --- | --- | ---: | ---: | ---: | ---: | --- |\n",
    );
    for t in &targets {
        let chosen = t
            .get("chosen")
            .ok_or_else(|| anyhow!("{}: a target without 'chosen'", file.display()))?;
        let paper = t
            .get("references")
            .and_then(Value::as_array)
            .and_then(|r| r.first())
            .ok_or_else(|| anyhow!("{}: a target without references", file.display()))?;
        let g = &paper["gain"];
        let gain = format!(
            "{} ± {} pp ({} %)",
            pct(f(g, "mean", &file)?),
            pct(f(g, "half_width", &file)?),
            pct(f(&paper["scored"], "noise_share", &file)?)
        );
        let _ = writeln!(
            s,
            "| {} | {} | {:.0} | {:.0} | {} ({} + {} + {}) | {} % | {gain} |",
            t.get("scene").and_then(Value::as_str).unwrap_or("?"),
            chosen.get("label").and_then(Value::as_str).unwrap_or("?"),
            f(chosen, "bits_per_texel", &file)?,
            f(chosen, "ns_per_fragment", &file)?,
            pct(f(chosen, "error", &file)?),
            pct(f(chosen, "leak", &file)?),
            pct(f(chosen, "darkening", &file)?),
            pct(f(chosen, "noise", &file)?),
            pct(f(chosen, "noise_share", &file)?),
        );
    }
    let _ = writeln!(
        s,
        "\nFeasible: noise above 1/255 on at most {} % of fragments. Tolerance {} percentage points of the best, {:.0} fragments per scene, 95 % paired intervals. GPU ns from the cost model calibrated on the committed `gpu bench` artefact. The report compares with every published and engine default (MJP, Filament, HDRP) under the same model.",
        pct(f(&v, "max_noise", &file)?),
        pct(f(&v, "tolerance", &file)?),
        f(&v, "fragments_per_scene", &file)?
    );
    Ok(s)
}

/// θ transforms: `reports/theta/summary.json`.
fn theta(reports: &Path) -> Result<String> {
    let file = reports.join("theta/summary.json");
    let v = read_json(&file)?;
    let rows = v
        .get("rows")
        .and_then(Value::as_array)
        .ok_or_else(|| anyhow!("{}: no rows", file.display()))?;
    let mut s = String::from(
        "| m | ours (bits) | published (paper) | volume bound (bits) |\n| ---: | ---: | ---: | ---: |\n",
    );
    for r in rows {
        let _ = writeln!(
            s,
            "| {:.0} | {:.4} | {} | {:.3} |",
            f(r, "m", &file)?,
            f(r, "ours_gain_bits", &file)?,
            r.get("quoted").and_then(Value::as_str).unwrap_or("—"),
            f(r, "volume_bound_bits", &file)?
        );
    }
    if let Some(fig5) = v.get("fig5") {
        let _ = writeln!(
            s,
            "\nFig. 5 analogue: θ₃ multiplies the hull volume of the moment curve by {:.1} (paper: 73.9).",
            f(fig5, "ratio", &file)?
        );
    }
    Ok(s)
}

/// The (name, text) of every generated block of a README text, in order.
pub fn blocks(readme: &str) -> Result<Vec<(String, String)>> {
    let mut out = Vec::new();
    let mut rest = readme;
    while let Some(p) = rest.find(OPEN) {
        let after = &rest[p + OPEN.len()..];
        let e = after
            .find("-->")
            .ok_or_else(|| anyhow!("README: unterminated block marker"))?;
        let name = after[..e].trim().to_string();
        let body = after[e + 3..]
            .strip_prefix('\n')
            .ok_or_else(|| anyhow!("README: block '{name}': marker not on its own line"))?;
        let end = body
            .find(CLOSE)
            .ok_or_else(|| anyhow!("README: block '{name}' has no {CLOSE}"))?;
        out.push((name, body[..end].to_string()));
        rest = &body[end + CLOSE.len()..];
    }
    Ok(out)
}

/// README with every generated block replaced by `render(name)`.
pub fn splice(readme: &str, render: impl Fn(&str) -> Result<String>) -> Result<String> {
    let mut out = String::new();
    let mut rest = readme;
    while let Some(p) = rest.find(OPEN) {
        let after = &rest[p + OPEN.len()..];
        let e = after
            .find("-->")
            .ok_or_else(|| anyhow!("README: unterminated block marker"))?;
        let name = after[..e].trim();
        let body = &after[e + 3..];
        let end = body
            .find(CLOSE)
            .ok_or_else(|| anyhow!("README: block '{name}' has no {CLOSE}"))?;
        out.push_str(&rest[..p]);
        let _ = write!(out, "{OPEN}{name} -->\n{}{CLOSE}", render(name)?);
        rest = &body[end + CLOSE.len()..];
    }
    out.push_str(rest);
    Ok(out)
}

/// README text with the generated blocks removed (what must hold no unchecked numbers).
pub fn outside_blocks(readme: &str) -> String {
    let mut out = String::new();
    let mut rest = readme;
    while let Some(p) = rest.find(OPEN) {
        out.push_str(&rest[..p]);
        match rest[p..].find(CLOSE) {
            Some(e) => rest = &rest[p + e + CLOSE.len()..],
            None => return out,
        }
    }
    out.push_str(rest);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn blocks_round_trip_and_splice_replaces_only_their_text() {
        let readme =
            "a 1\n<!-- generated:x -->\nold\n<!-- end -->\nb\n<!-- generated:y -->\n<!-- end -->\n";
        let b = blocks(readme).unwrap();
        assert_eq!(
            b,
            vec![("x".into(), "old\n".into()), ("y".into(), String::new())]
        );
        let s = splice(readme, |n| Ok(format!("new {n}\n"))).unwrap();
        assert_eq!(
            s,
            "a 1\n<!-- generated:x -->\nnew x\n<!-- end -->\nb\n<!-- generated:y -->\nnew y\n<!-- end -->\n"
        );
        assert_eq!(outside_blocks(&s), "a 1\n\nb\n\n");
        assert!(blocks("<!-- generated:z -->\nno end").is_err());
    }

    #[test]
    fn plan_durations_parse() {
        assert_eq!(parse_duration("45 s"), Some(45.0));
        assert_eq!(parse_duration("26 min 1 s"), Some(1561.0));
        assert_eq!(parse_duration("2 h 5 min"), Some(7500.0));
        assert_eq!(parse_duration("?"), None);
        assert_eq!(parse_duration("5 days"), None);
        assert_eq!(parse_duration(""), None);
    }

    #[test]
    fn ns_precision() {
        assert_eq!(fmt_ns(8981.2), "8981");
        assert_eq!(fmt_ns(27.84), "27.8");
        assert_eq!(fmt_ns(6.87), "6.87");
    }

    /// A report whose race an LP budget ended: the tie column names the unresolved set and the
    /// note says so; a resolved report keeps its tie set and has no note.
    #[test]
    fn a_budget_ended_race_is_reported_unresolved() {
        let dir = std::env::temp_dir().join(format!("momentlab-readme-{}", std::process::id()));
        std::fs::create_dir_all(dir.join("search")).unwrap();
        let head = "The sweep's dataset holds 4096 of the non-trivial ones.\n\
                    The winner of 666 scored candidates is 12 = (z, z^2) with 7.5 % ± 0.05 %.\n";
        let ended =
            "**Unresolved**: the LP budget ended the race with 321 candidates left; none.\n";
        let tied = "40 candidates are statistically tied for first.\n";
        std::fs::write(dir.join("search/search_m2.md"), format!("{head}{ended}")).unwrap();
        let x = sweep_summary(&dir, 2).unwrap().unwrap();
        assert_eq!(x.tied_or_unresolved(), "321 unresolved (LP budget)");
        assert!(x
            .unresolved_note(2)
            .unwrap()
            .contains("321 candidates unresolved"));
        std::fs::write(dir.join("search/search_m2.md"), format!("{head}{tied}")).unwrap();
        let x = sweep_summary(&dir, 2).unwrap().unwrap();
        assert_eq!(x.tied_or_unresolved(), "40");
        assert!(x.unresolved_note(2).is_none());
        assert_eq!(
            (x.candidates.as_str(), x.functions.as_str()),
            ("666", "z, z^2")
        );
        std::fs::remove_dir_all(&dir).ok();
    }
}
