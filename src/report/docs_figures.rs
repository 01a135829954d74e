//! The figures of docs/*.md, rendered from the committed artefacts under `reports/`: the
//! generated blocks `<!-- generated:NAME -->` … `<!-- end -->` that [`super::readme::render`]
//! dispatches here, and the pictures of docs/img/, each a copy of a pipeline artefact
//! ([`IMAGES`]). tests/project/docs_figures.rs asserts that every block and picture equals what
//! reports/ renders (`MOMENTLAB_UPDATE_README=1` rewrites them).

use anyhow::{anyhow, Context, Result};
use serde_json::Value;
use std::fmt::Write as _;
use std::path::Path;

/// The pictures of docs/: (path under docs/, the artefact under reports/ it is a copy of).
pub const IMAGES: [(&str, &str); 13] = [
    ("img/speed_accuracy.svg", "default/speed_accuracy.svg"),
    ("img/fig3.svg", "search/fig3.svg"),
    ("img/fig4_m3.svg", "search/fig4_m3.svg"),
    ("img/fig5.svg", "theta/fig5.svg"),
    ("img/stability_u16.svg", "stability/heatmap_u16.svg"),
    (
        "img/quantize_alpha.svg",
        "default/quantize/quantize_alpha.svg",
    ),
    ("img/grid_refinement.svg", "default/grid_refinement.svg"),
    ("img/tmsm_geometry.svg", "default/tmsm_geometry.svg"),
    ("img/error_histograms.svg", "default/error_histograms.svg"),
    ("img/distributions.svg", "search/distributions.svg"),
    (
        "img/eye_city_vsm.png",
        "default/eye/city_light0_vsm_eye.png",
    ),
    (
        "img/eye_city_hamburger4.png",
        "default/eye/city_light0_hamburger4_eye.png",
    ),
    (
        "img/eye_city_tmsm.png",
        "default/eye/city_light0_tmsm_eye.png",
    ),
];

fn read_json(path: &Path) -> Result<Value> {
    let s = crate::artefact::read_text(path, crate::artefact::Limit::ARTEFACT)?;
    serde_json::from_str(&s).with_context(|| format!("parsing {}", path.display()))
}

fn num(v: &Value, key: &str, file: &Path) -> Result<f64> {
    v.get(key)
        .and_then(Value::as_f64)
        .ok_or_else(|| anyhow!("{}: no number '{key}'", file.display()))
}

/// `[[name, {…}], …]` as pairs.
fn pairs<'a>(v: &'a Value, file: &Path) -> Result<Vec<(&'a str, &'a Value)>> {
    v.as_array()
        .ok_or_else(|| anyhow!("{}: expected a list of [name, summary]", file.display()))?
        .iter()
        .map(|p| {
            (|| Some((p.get(0)?.as_str()?, p.get(1)?)))()
                .ok_or_else(|| anyhow!("{}: a malformed [name, summary] pair", file.display()))
        })
        .collect()
}

/// docs/stability.md: per technique and moment precision the mean |G − sharp bound| and the
/// share above the bound, then per input kind the mean |G − sharp bound| over all precisions
/// (reports/stability/stability.json, `momentlab stability --out reports/stability`).
pub fn stability(reports: &Path) -> Result<String> {
    let file = reports.join("stability/stability.json");
    let v = read_json(&file)?;
    let techniques: Vec<&str> = v
        .get("techniques")
        .and_then(Value::as_array)
        .ok_or_else(|| anyhow!("{}: no techniques", file.display()))?
        .iter()
        .filter_map(Value::as_str)
        .collect();
    let by_mode = v
        .get("by_mode")
        .and_then(Value::as_array)
        .ok_or_else(|| anyhow!("{}: no by_mode", file.display()))?;
    let by_scenario = v
        .get("by_scenario")
        .and_then(Value::as_array)
        .ok_or_else(|| anyhow!("{}: no by_scenario", file.display()))?;
    let modes = ["f64", "f32", "f32_theta", "u16", "u16_theta"];
    let mut s = String::from(
        "Mean |G − sharp bound| and, in brackets, the share of inputs more than the tolerance above the bound, per moment precision (θ: stored through the published θ):\n\n| technique | f64 | f32 | f32 + θ | u16 | u16 + θ |\n| --- | ---: | ---: | ---: | ---: | ---: |\n",
    );
    for (t, row) in techniques.iter().zip(by_mode) {
        let cells = pairs(row, &file)?;
        let mut line = format!("| {t} |");
        for m in modes {
            match cells.iter().find(|c| c.0 == m) {
                Some((_, c)) => {
                    let _ = write!(
                        line,
                        " {:.3} ({:.1} %) |",
                        num(c, "mean_abs_dev", &file)?,
                        100.0 * num(c, "over_share", &file)?
                    );
                }
                None => line.push_str(" – |"),
            }
        }
        let _ = writeln!(s, "{line}");
    }
    let scenarios: Vec<&str> = match by_scenario.first() {
        Some(r) => pairs(r, &file)?.iter().map(|p| p.0).collect(),
        None => Vec::new(),
    };
    let _ = write!(
        s,
        "\nMean |G − sharp bound| per input kind, all precisions together:\n\n| technique |"
    );
    for sc in &scenarios {
        let _ = write!(s, " {} |", sc.replace('_', " "));
    }
    let _ = write!(s, "\n| --- |");
    for _ in &scenarios {
        s.push_str(" ---: |");
    }
    s.push('\n');
    for (t, row) in techniques.iter().zip(by_scenario) {
        let cells = pairs(row, &file)?;
        let _ = write!(s, "| {t} |");
        for sc in &scenarios {
            match cells.iter().find(|c| c.0 == *sc) {
                Some((_, c)) => {
                    let _ = write!(s, " {:.3} |", num(c, "mean_abs_dev", &file)?);
                }
                None => s.push_str(" – |"),
            }
        }
        s.push('\n');
    }
    let cfg = v.get("config").cloned().unwrap_or(Value::Null);
    let _ = writeln!(
        s,
        "\n{} inputs per technique, seed {}, oracle on {} grid points, tolerance {}; reports/stability/stability.json.",
        num(&cfg, "samples", &file)?,
        num(&cfg, "seed", &file)?,
        num(&cfg, "grid_points", &file)?,
        num(&cfg, "over_tolerance", &file)?
    );
    Ok(s)
}

/// docs/theta.md: the table of reports/theta/comparison.md (written by `momentlab theta
/// --summary reports/theta`) as it stands, and per seeded search with more than a handful of
/// starts the share of starts that reach the best basin and the chance that as many starts
/// again miss it, (1 − share)^starts (reports/theta/summary.json).
pub fn theta_comparison(reports: &Path) -> Result<String> {
    let file = reports.join("theta/comparison.md");
    let text = crate::artefact::read_text(&file, crate::artefact::Limit::ARTEFACT)?;
    let table: Vec<&str> = text
        .lines()
        .skip_while(|l| !l.starts_with("| m |"))
        .take_while(|l| l.starts_with('|'))
        .collect();
    if table.len() < 3 {
        return Err(anyhow!("{}: no table starting '| m |'", file.display()));
    }
    let mut s = table.join("\n");
    s.push('\n');
    let sfile = reports.join("theta/summary.json");
    let v = read_json(&sfile)?;
    let rows = v
        .get("rows")
        .and_then(Value::as_array)
        .ok_or_else(|| anyhow!("{}: no rows", sfile.display()))?;
    for r in rows {
        let Some(basin) = r.get("basin") else {
            continue;
        };
        let share = num(basin, "share", &sfile)?;
        let hits = basin
            .get("starts")
            .and_then(Value::as_array)
            .map_or(0, Vec::len);
        if share <= 0.0 || hits == 0 {
            continue;
        }
        let starts = (hits as f64 / share).round();
        if starts < 10.0 {
            continue;
        }
        let first = basin
            .get("starts")
            .and_then(|a| a.get(0))
            .and_then(Value::as_u64)
            .unwrap_or(0);
        let _ = writeln!(
            s,
            "\nm = {}: {hits} of {starts:.0} starts reach the best basin ({:.5} bits; the first is start {first}); {starts:.0} further starts would all miss it with probability {:.1e}; the runner-up basin is {:.5} bits.",
            num(r, "m", &sfile)?,
            num(basin, "best_bits", &sfile)?,
            (1.0 - share).powf(starts),
            num(basin, "runner_up_bits", &sfile)?,
        );
    }
    Ok(s)
}

/// docs/theta.md: θ for the catalog bases of reports/theta/basis/*.json (`theta --basis`): gain,
/// canonical gain, gain over canonical, starts at the best, CPU seconds.
pub fn theta_basis(reports: &Path) -> Result<String> {
    let dir = reports.join("theta/basis");
    let mut files: Vec<_> = std::fs::read_dir(&dir)
        .with_context(|| format!("reading {}", dir.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|e| e == "json"))
        .collect();
    files.sort();
    let mut s = String::from(
        "| basis | ours (bits) | canonical (bits) | over canonical (bits) | starts at the best | CPU s |\n| --- | ---: | ---: | ---: | ---: | ---: |\n",
    );
    for file in &files {
        let v = read_json(file)?;
        let basis: Vec<&str> = v
            .get("basis")
            .and_then(Value::as_array)
            .map(|a| a.iter().filter_map(Value::as_str).collect())
            .unwrap_or_default();
        let best = num(&v, "gain_bits", file)?;
        let gains = v
            .get("start_gains_bits")
            .and_then(Value::as_array)
            .cloned()
            .unwrap_or_default();
        let at_best = gains
            .iter()
            .filter_map(Value::as_f64)
            .filter(|g| (g - best).abs() <= 1e-3)
            .count();
        let _ = writeln!(
            s,
            "| ({}) | {:.5} | {:.5} | {:+.3} | {at_best}/{} | {:.1} |",
            basis.join(", "),
            best,
            num(&v, "canonical_gain_bits", file)?,
            (num(&v, "gain_over_canonical_bits", file)? * 1e3).round() / 1e3 + 0.0,
            gains.len(),
            num(&v, "cpu_seconds", file)?
        );
    }
    Ok(s)
}

/// docs/theta.md: where the bias α that minimises the error against PCF lies in the quantize
/// study (reports/default/quantize/quantize.json): how many technique × storage rows have it at
/// the smallest α swept, and the others.
pub fn quantize_alpha(reports: &Path) -> Result<String> {
    let file = reports.join("default/quantize/quantize.json");
    let v = read_json(&file)?;
    let sweeps = v
        .get("sweeps")
        .and_then(Value::as_array)
        .ok_or_else(|| anyhow!("{}: no sweeps", file.display()))?;
    let mut smallest = 0;
    let mut others = Vec::new();
    for sw in sweeps {
        let alphas: Vec<f64> = sw
            .get("alphas")
            .and_then(Value::as_array)
            .map(|a| a.iter().filter_map(Value::as_f64).collect())
            .unwrap_or_default();
        let best = num(sw, "best_alpha", &file)?;
        let min = alphas.iter().copied().fold(f64::INFINITY, f64::min);
        if best <= min {
            smallest += 1;
        } else {
            others.push(format!(
                "{} {} (α = {best:.0e})",
                sw.get("technique").and_then(Value::as_str).unwrap_or("?"),
                sw.get("config").and_then(Value::as_str).unwrap_or("?")
            ));
        }
    }
    let mut s = format!(
        "The error against PCF is least at the smallest α swept on {smallest} of {} technique × storage rows",
        sweeps.len()
    );
    if others.is_empty() {
        s.push_str(".\n");
    } else {
        let _ = writeln!(s, "; elsewhere at a larger α: {}.", others.join("; "));
    }
    Ok(s)
}

/// docs/theta.md: per 16-bit storage of the quantize study, the smallest α at which its mean
/// deviation from unquantized moments is at most 10⁻³, with the error against PCF there and
/// the 32-bit float error at the same α, in % (reports/default/quantize/quantize.json).
pub fn quantize_usable(reports: &Path) -> Result<String> {
    let file = reports.join("default/quantize/quantize.json");
    let v = read_json(&file)?;
    let rows = v
        .get("usable_16bit")
        .and_then(Value::as_array)
        .ok_or_else(|| anyhow!("{}: no usable_16bit", file.display()))?;
    let mut s = String::from(
        "| technique | 16-bit storage | smallest usable α | error there | 32-bit float error there |\n| --- | --- | ---: | ---: | ---: |\n",
    );
    for r in rows {
        let t = r.get("technique").and_then(Value::as_str).unwrap_or("?");
        let c = r.get("config").and_then(Value::as_str).unwrap_or("?");
        match r.get("smallest_usable_alpha").and_then(Value::as_f64) {
            Some(a) => {
                let _ = writeln!(
                    s,
                    "| {t} | {c} | {a:.0e} | {:.2} % | {:.2} % |",
                    100.0 * num(r, "error_there", &file)?,
                    100.0 * num(r, "f32_error_there", &file)?
                );
            }
            None => {
                let _ = writeln!(s, "| {t} | {c} | never | – | – |");
            }
        }
    }
    Ok(s)
}

/// docs/theta.md: the Fig. 5 line of reports/theta/comparison.md as it stands.
pub fn theta_fig5(reports: &Path) -> Result<String> {
    let file = reports.join("theta/comparison.md");
    let text = crate::artefact::read_text(&file, crate::artefact::Limit::ARTEFACT)?;
    let line = text
        .lines()
        .find(|l| l.starts_with("Fig. 5 analogue"))
        .ok_or_else(|| anyhow!("{}: no 'Fig. 5 analogue' line", file.display()))?;
    Ok(format!("{line}\n"))
}

/// docs/search.md: per committed race (reports/search/lp_time_m<m>.txt, printed by `search` at
/// the end of a race) and candidate family, the LP solves of all stages, the mean CPU µs per LP
/// (Σ LPs·µs / Σ LPs), that mean over the mean of the candidates without exponentials, and the
/// family's share of all LP time.
pub fn lp_families(reports: &Path) -> Result<String> {
    let mut s = String::from(
        "| race | family | LP solves | mean µs per LP | vs no exponential | share of LP time |\n| --- | --- | ---: | ---: | ---: | ---: |\n",
    );
    let mut any = false;
    for m in 2..=4 {
        let file = reports.join(format!("search/lp_time_m{m}.txt"));
        if !file.is_file() {
            continue;
        }
        let text = crate::artefact::read_text(&file, crate::artefact::Limit::ARTEFACT)?;
        // family → (LPs, Σ LPs·µs, share %), in first-seen order.
        let mut fam: Vec<(String, f64, f64, f64)> = Vec::new();
        for line in text.lines().filter(|l| l.starts_with("stage ")) {
            let w: Vec<&str> = line.split_whitespace().collect();
            // The header line ("stage family candidates …") has no stage number.
            if w.get(1).and_then(|k| k.parse::<u32>().ok()).is_none() {
                continue;
            }
            if w.len() < 8 {
                return Err(anyhow!("{}: short row '{line}'", file.display()));
            }
            let n = w.len();
            let parse = |x: &str| -> Result<f64> {
                x.trim_end_matches('%')
                    .parse::<f64>()
                    .map_err(|_| anyhow!("{}: '{x}' in '{line}' is not a number", file.display()))
            };
            let (lps, us, share) = (parse(w[n - 4])?, parse(w[n - 3])?, parse(w[n - 1])?);
            // A family name may hold '|' (|c| < 20): escaped, as a Markdown table cell needs.
            let name = w[2..n - 5].join(" ").replace('|', "\\|");
            match fam.iter_mut().find(|f| f.0 == name) {
                Some(f) => {
                    f.1 += lps;
                    f.2 += lps * us;
                    f.3 += share;
                }
                None => fam.push((name, lps, lps * us, share)),
            }
        }
        let base = fam
            .iter()
            .find(|f| f.0 == "no exponential")
            .map(|f| f.2 / f.1)
            .ok_or_else(|| anyhow!("{}: no 'no exponential' family", file.display()))?;
        fam.sort_by(|a, b| (b.2 / b.1).total_cmp(&(a.2 / a.1)));
        for (name, lps, work, share) in fam {
            let _ = writeln!(
                s,
                "| m = {m} | {name} | {:.1} M | {:.1} | {:.1}× | {share:.0} % |",
                lps / 1e6,
                work / lps,
                work / lps / base
            );
        }
        any = true;
    }
    if !any {
        return Err(anyhow!("no reports/search/lp_time_m<m>.txt"));
    }
    s.push_str("\nreports/search/lp_time_m<m>.txt, printed by `momentlab search` at the end of the committed races.\n");
    Ok(s)
}

/// docs/stacks.md: the fragments of the default dataset per scene and in all, as the committed
/// run evaluated them (reports/default/evaluate/hamburger4_f32.json: a closed form sees every
/// fragment).
pub fn dataset(reports: &Path) -> Result<String> {
    let file = reports.join("default/evaluate/hamburger4_f32.json");
    let v = read_json(&file)?;
    let scenes = v
        .get("scenes")
        .and_then(Value::as_array)
        .ok_or_else(|| anyhow!("{}: no scenes", file.display()))?;
    let mut s = String::from("| scene | fragments |\n| --- | ---: |\n");
    let mut sum = 0.0;
    for sc in scenes {
        let (Some(name), Some(n)) = (
            sc.get(0).and_then(Value::as_str),
            sc.get(2).and_then(Value::as_f64),
        ) else {
            return Err(anyhow!(
                "{}: a scene is not [name, error, fragments]",
                file.display()
            ));
        };
        sum += n;
        let _ = writeln!(s, "| {name} | {n:.0} |");
    }
    let total = num(&v, "fragments", &file)?;
    if (sum - total).abs() > 0.5 {
        return Err(anyhow!(
            "{}: the scenes' fragments ({sum}) do not add up to {total}",
            file.display()
        ));
    }
    let _ = writeln!(
        s,
        "| **all** | **{total:.0}** |\n\n{:.2} % of them are trivial (no kernel depth below the biased z_f); reports/default/evaluate/hamburger4_f32.json.",
        100.0 * num(&v, "trivial", &file)? / total
    );
    Ok(s)
}
