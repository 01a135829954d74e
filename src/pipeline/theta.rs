//! Optimal quantization transforms θ_m as artefacts (Section 4.3 of the 2015 paper): one search
//! into `theta{tag}.json` with its HLSL/GLSL/WGSL snippets, the snippets re-emitted from a JSON, and
//! the comparison with the published θ (`comparison.md`, `summary.json`, Fig. 5 analogue).
//! Step 5 of the pipeline ([`run`]) and `momentlab theta` call these with typed options.

use super::Plan;
use crate::artefact::{read_json, Checkpoint, OutDir};
use crate::progress::Bar;
use crate::quantize::codegen::{self, ChannelOrder};
use crate::quantize::{curve, fig5, optimize, theta, volume, Curve};
use crate::shader;
use anyhow::{bail, Context, Result};
use serde::Deserialize;
use serde_json::json;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// One θ of the run: (m, entropy gain in bits, max violation, seconds).
pub type ThetaRow = (usize, f64, f64, f64);

/// What one θ search runs with.
#[derive(Clone, Debug)]
pub struct Search {
    /// Options of the optimizer.
    pub options: optimize::Options,
    /// Starts within this many bits of the best count as reaching the best basin.
    pub basin_tol: f64,
    /// Channel order of the emitted θ₂/θ₄ snippets.
    pub order: ChannelOrder,
}

/// The file names of one search: `theta{tag}.json`, then the snippets ([`SNIPPET_EXTENSIONS`]).
pub fn file_names(tag: &str) -> [String; 4] {
    ["json", "hlsl", "glsl", "wgsl"].map(|e| format!("theta{tag}.{e}"))
}

/// The languages of the snippets, as file extensions.
pub const SNIPPET_EXTENSIONS: [&str; 3] = ["hlsl", "glsl", "wgsl"];

/// The tag of a basis in file names: m for the power basis (z, …, z^m), otherwise `_` and an
/// FNV-1a hash of the names.
pub fn snippet_tag(curve: &dyn Curve) -> String {
    match curve.monomial_exponents() {
        Some(e) if e.iter().copied().eq(1..=e.len() as u32) => format!("{}", e.len()),
        _ => {
            let mut h: u64 = 1469598103934665603;
            for b in curve.names().join(",").bytes() {
                h = (h ^ b as u64).wrapping_mul(1099511628211);
            }
            format!("_{:08x}", h as u32)
        }
    }
}

/// Write `theta{tag}.glsl`, `theta{tag}.hlsl` and `theta{tag}.wgsl` (the GLSL-named functions)
/// for θ into `od`; returns the channel order used.
fn write_snippets(
    od: &OutDir,
    th: &theta::Theta,
    curve: &dyn Curve,
    tag: &str,
    order: ChannelOrder,
) -> Result<&'static str> {
    let sn = codegen::snippet(th, curve, tag, order)?;
    od.write_text(&format!("theta{tag}.glsl"), &shader::glsl(&sn.glsl)?)?;
    od.write_text(&format!("theta{tag}.hlsl"), &shader::hlsl(&sn.hlsl)?)?;
    od.write_text(&format!("theta{tag}.wgsl"), &shader::wgsl(&sn.glsl)?)?;
    Ok(sn.order)
}

/// Re-emit the snippets of every theta*.json in `dir` beside their JSON (which is only read).
/// Every JSON is read and every snippet name checked before the first snippet is written: an
/// existing snippet is replaced only with `force`.
pub fn snippets(dir: &Path, order: ChannelOrder, force: bool) -> Result<()> {
    let mut paths: Vec<PathBuf> = std::fs::read_dir(dir)
        .with_context(|| format!("--snippets: reading {}", dir.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| {
            p.extension().is_some_and(|e| e == "json")
                && p.file_stem()
                    .and_then(|s| s.to_str())
                    .is_some_and(|s| s.starts_with("theta"))
        })
        .collect();
    paths.sort();
    if paths.is_empty() {
        bail!("--snippets: no theta*.json in {}", dir.display());
    }
    let od = OutDir::new(dir, force).context("--snippets")?;
    let mut todo = Vec::new();
    for p in &paths {
        let Some((th, _)) = read_theta(p)? else {
            continue;
        };
        let curve = curve::from_names(&th.basis).with_context(|| p.display().to_string())?;
        let tag = snippet_tag(curve.as_ref());
        od.reserve(SNIPPET_EXTENSIONS.map(|e| format!("theta{tag}.{e}")))
            .context("--snippets")?;
        todo.push((p, th, curve, tag));
    }
    for (p, th, curve, tag) in &todo {
        let used = write_snippets(&od, th, curve.as_ref(), tag, order)?;
        eprintln!(
            "{}: wrote theta{tag}.glsl, theta{tag}.hlsl, theta{tag}.wgsl ({used} channel order)",
            p.display()
        );
    }
    Ok(())
}

/// CPU seconds (user + system) of this process so far, from /proc/self/stat (Linux; clock
/// ticks of 1/100 s); None elsewhere.
fn process_cpu_seconds() -> Option<f64> {
    let s =
        crate::artefact::read_text(Path::new("/proc/self/stat"), crate::artefact::Limit::CONFIG)
            .ok()?;
    let rest = &s[s.rfind(')')? + 2..];
    let f: Vec<&str> = rest.split_whitespace().collect();
    // fields after the command: state is index 0, utime 11, stime 12
    let ut: f64 = f.get(11)?.parse().ok()?;
    let st: f64 = f.get(12)?.parse().ok()?;
    Some((ut + st) / 100.0)
}

/// The checkpoint of the search for `curve` with `s` in output folder `out`:
/// `checkpoint/theta{tag}`, one unit per start (`start-<k>`), valid for the same basis and
/// search options. `force`: a checkpoint of other options is discarded instead of refused.
pub fn checkpoint(curve: &dyn Curve, s: &Search, out: &Path, force: bool) -> Result<Checkpoint> {
    let o = &s.options;
    let params = json!({
        "basis": curve.names(), "seed": o.seed, "restarts": o.restarts,
        "max_sweeps": o.max_sweeps, "tol_bits": o.tol_bits, "margin": o.margin,
        "hops": o.hops, "hop_sigma": o.hop_sigma, "only_starts": o.only_starts,
    });
    Checkpoint::open(out, &format!("theta{}", snippet_tag(curve)), params, force)
}

/// The starts of a search kept in its checkpoint.
struct Starts<'a>(&'a Checkpoint);

impl optimize::StartStore for Starts<'_> {
    fn get(&self, k: usize) -> Result<Option<optimize::StartState>> {
        self.0.get(&format!("start-{k}"))
    }
    fn put(&self, k: usize, state: &optimize::StartState) -> Result<()> {
        self.0.put(&format!("start-{k}"), state)
    }
}

/// Search θ for `curve` and write the snippets, then `theta{tag}.json` (last, so the JSON
/// marks a finished search) into `od`; returns the JSON text. Every converged start is kept in
/// `cp` ([`checkpoint`]) and a start found there is not run again; `cp` is removed at the end.
pub fn search(curve: &dyn Curve, s: &Search, od: &OutDir, cp: Checkpoint) -> Result<String> {
    let command = crate::report::provenance::command_line();
    let opts = &s.options;
    let m = curve.dim();
    let tag = snippet_tag(curve);
    let names = file_names(&tag);
    let n_starts = opts.only_starts.as_ref().map_or(opts.restarts, |v| v.len());
    cp.start()?;
    if let Some(note) = cp.note("theta", n_starts, "starts") {
        eprintln!("{note}");
    }
    let pb = Bar::new(&format!("theta m={m} starts"), n_starts as u64);
    let t0 = Instant::now();
    let cpu0 = process_cpu_seconds();
    let best = std::sync::Mutex::new(f64::NEG_INFINITY);
    let progress = |_k: usize, g: f64| {
        let mut b = best.lock().unwrap_or_else(|e| e.into_inner());
        *b = b.max(g);
        pb.set_label(&format!("theta m={m} starts (best {:.4} bits)", *b));
        pb.inc(1);
    };
    let out = optimize::optimize_with(curve, opts, &progress, Some(&Starts(&cp)))?;
    pb.finish();
    let seconds = t0.elapsed().as_secs_f64();
    let cpu_seconds = process_cpu_seconds().zip(cpu0).map(|(a, b)| a - b);
    let th = &out.theta;
    let ver = theta::verify(th, curve)?;
    let gain = th.gain_bits();
    let basin = optimize::basin(&out.start_gains, &out.start_indices, s.basin_tol);
    let power = matches!(curve.monomial_exponents(), Some(e) if e.iter().copied().eq(1..=m as u32));
    let mut j = json!({
        "m": m,
        "basis": th.basis,
        "matrix": th.matrix,
        "offset": th.offset,
        "inverse": th.inverse,
        "gain_bits": gain,
        "max_violation": ver.max_violation,
        "row_ranges": ver.row_ranges,
        "seconds": seconds,
        "cpu_seconds": cpu_seconds,
        "threads": rayon::current_num_threads(),
        "exact_verification": ver.exact,
        "seed": opts.seed,
        "restarts": opts.restarts,
        "hops": opts.hops,
        "hop_sigma": opts.hop_sigma,
        "start_indices": out.start_indices,
        "start_gains_bits": out.start_gains,
        "best_start": out.best_start,
        "basin": basin,
        "lps_solved": out.lps,
        "command": command,
        "commit": crate::report::provenance::COMMIT,
    });
    // canonical storage: every basis function rescaled from its own range to [0,1]
    let canonical: f64 = (0..m)
        .map(|j| {
            let mut e = vec![0.0; m];
            e[j] = 1.0;
            let (_, lo, _, hi) = curve::row_min_max(curve, &e);
            -(hi - lo).log2()
        })
        .sum();
    j["canonical_gain_bits"] = json!(canonical);
    j["gain_over_canonical_bits"] = json!(gain - canonical);
    if power {
        let bound = volume::volume_bound_bits(m);
        j["volume_bound_bits"] = json!(bound);
        j["headroom_bits"] = json!(bound - gain);
        if let Some(p) = theta::published(m) {
            j["published_gain_bits"] = json!(p.gain_bits());
        }
    }
    let order = write_snippets(od, th, curve, &tag, s.order)?;
    j["snippet_channel_order"] = json!(order);
    let text = serde_json::to_string_pretty(&j)? + "\n";
    od.write_text(&names[0], &text)?;
    cp.finish()?;
    eprintln!(
        "theta m={m}: {gain:.6} bits, max violation {:.3e}, {seconds:.1} s wall{}, best basin \
         reached by {}/{} starts (within {} bits), wrote {}",
        ver.max_violation,
        cpu_seconds.map_or(String::new(), |c| format!(" ({c:.1} s CPU)")),
        basin.starts.len(),
        n_starts,
        s.basin_tol,
        od.root().display()
    );
    Ok(text)
}

/// θ and the whole JSON of a theta*.json; None when the file does not exist.
fn read_theta(path: &Path) -> Result<Option<(theta::Theta, serde_json::Value)>> {
    if std::fs::symlink_metadata(path).is_err() {
        return Ok(None);
    }
    let text = crate::artefact::read_text(path, crate::artefact::Limit::ARTEFACT)?;
    let v: serde_json::Value =
        serde_json::from_str(&text).with_context(|| format!("parsing {}", path.display()))?;
    let get = |k: &str| {
        v.get(k)
            .cloned()
            .with_context(|| format!("{}: missing field '{k}'", path.display()))
    };
    let th = theta::Theta::new(
        serde_json::from_value(get("basis")?)
            .with_context(|| format!("{}: basis", path.display()))?,
        serde_json::from_value(get("matrix")?)
            .with_context(|| format!("{}: matrix", path.display()))?,
        serde_json::from_value(get("offset")?)
            .with_context(|| format!("{}: offset", path.display()))?,
    )
    .with_context(|| path.display().to_string())?;
    Ok(Some((th, v)))
}

/// The files [`summary`] writes.
pub const SUMMARY_FILES: [&str; 3] = ["comparison.md", "summary.json", "fig5.svg"];

/// Read `dir/theta{2,…,8}.json` (those present), re-verify them and the published θ₂/θ₄/θ₆,
/// write [`SUMMARY_FILES`] (fig5.svg when theta3.json exists) into `od`; returns the Markdown.
pub fn summary(dir: &Path, od: &OutDir) -> Result<String> {
    let mut md = String::from(
        "| m | ours: gain (bits) | ours: wall s | ours: CPU s | starts reaching the best (±basin tol) | runner-up basin (bits) | ours: max violation | published: gain (our verifier) | published: max violation | quoted in paper | volume bound (bits) | headroom ours (bits) |\n|---|---|---|---|---|---|---|---|---|---|---|---|\n",
    );
    let mut rows = Vec::new();
    let mut commands = String::new();
    for m in 2..=8usize {
        let q = theta::quoted_gain(m).unwrap_or("—");
        let curve = curve::MonomialCurve::power(m)?;
        let ours = read_theta(&dir.join(format!("theta{m}.json")))?;
        let pubd = theta::published(m);
        if ours.is_none() && pubd.is_none() && q == "—" {
            continue;
        }
        let bound = volume::volume_bound_bits(m);
        let (og, ov, ot, oc) = match &ours {
            Some((th, v)) => {
                let ver = theta::verify(th, &curve)?;
                if let Some(c) = v.get("command").and_then(|c| c.as_str()) {
                    commands.push_str(&format!("- m = {m}: `{c}`\n"));
                }
                (
                    Some(th.gain_bits()),
                    Some(ver.max_violation),
                    v.get("seconds").and_then(|s| s.as_f64()),
                    v.get("cpu_seconds").and_then(|s| s.as_f64()),
                )
            }
            None => (None, None, None, None),
        };
        let basin = ours.as_ref().and_then(|(_, v)| v.get("basin").cloned());
        let share = basin.as_ref().map_or("—".to_string(), |b| {
            let n = b["starts"].as_array().map_or(0, |a| a.len());
            let tot = ours
                .as_ref()
                .and_then(|(_, v)| v["start_gains_bits"].as_array().map(|a| a.len()))
                .unwrap_or(0);
            format!("{n}/{tot} (±{})", b["tol_bits"])
        });
        let runner = basin
            .as_ref()
            .and_then(|b| b["runner_up_bits"].as_f64())
            .map_or("—".to_string(), |v| format!("{v:.5}"));
        let (pg, pv) = match &pubd {
            Some(th) => (
                Some(th.gain_bits()),
                Some(theta::verify(th, &curve)?.max_violation),
            ),
            None => (None, None),
        };
        let f = |x: Option<f64>, p: usize| x.map_or("—".to_string(), |v| format!("{v:.p$}"));
        let e = |x: Option<f64>| x.map_or("—".to_string(), |v| format!("{v:.2e}"));
        md.push_str(&format!(
            "| {m} | {} | {} | {} | {share} | {runner} | {} | {} | {} | {q} | {bound:.4} | {} |\n",
            f(og, 7),
            f(ot, 1),
            f(oc, 1),
            e(ov),
            f(pg, 7),
            e(pv),
            f(og.map(|g| bound - g), 4)
        ));
        rows.push(json!({
            "m": m, "ours_gain_bits": og, "ours_seconds": ot, "ours_cpu_seconds": oc,
            "ours_max_violation": ov, "basin": basin,
            "published_gain_bits": pg, "published_max_violation": pv, "quoted": q,
            "volume_bound_bits": bound, "headroom_bits": og.map(|g| bound - g),
        }));
    }
    md.push_str("\nmax violation: worst amount by which θ(b(z)) leaves [0,1] over z ∈ [0,1], from the exact verifier (roots of the derivative of each row polynomial); negative = strictly inside. Published tables are printed with ~10 significant digits, so they can leave [0,1] by up to ~1e-7 (well below a 16-bit quantum, 1.5e-5).\n");
    if !commands.is_empty() {
        md.push_str("\nCommands:\n\n");
        md.push_str(&commands);
    }
    let mut fig = serde_json::Value::Null;
    if let Some((t3, _)) = read_theta(&dir.join("theta3.json"))? {
        let vols = fig5::volumes(&t3, 2000)?;
        let svg = fig5::svg(&t3, &vols, 48)?;
        od.write_text("fig5.svg", &svg)?;
        md.push_str(&format!(
            "\nFig. 5 analogue (fig5.svg): hull of b([0,1]) {:.6} (exact 1/180 = {:.6}), hull of θ₃∘b([0,1]) {:.4}, ratio {:.1} (paper: 0.41 and 73.9×).\n",
            vols.volume_b, vols.volume_b_exact, vols.volume_theta, vols.ratio
        ));
        fig = serde_json::to_value(&vols)?;
    }
    od.write_text("comparison.md", &md)?;
    od.write_json("summary.json", &json!({"rows": rows, "fig5": fig}))?;
    Ok(md)
}

/// The search options of the pipeline: seed 1, `restarts` starts, 400 sweeps; basin hopping
/// (10 hops, σ 0.3) for m ≥ 4, where few single ascents end in the best local optimum.
fn plan_search(m: usize, restarts: usize) -> Search {
    let (hops, hop_sigma) = if m >= 4 { (10, 0.3) } else { (0, 0.2) };
    Search {
        options: optimize::Options {
            seed: 1,
            restarts,
            max_sweeps: 400,
            hops,
            hop_sigma,
            ..Default::default()
        },
        basin_tol: 1e-3,
        order: ChannelOrder::Paper,
    }
}

/// Step 5: compute the plan's missing θ_m into `dir` (a θ whose JSON exists is kept), write the
/// summary, return one row per θ.
pub fn run(plan: &Plan, dir: &Path) -> Result<Vec<ThetaRow>> {
    let od = OutDir::new(dir, true)?;
    let mut runs: Vec<(usize, Search)> = plan
        .theta_moments
        .iter()
        .map(|&m| (m, plan_search(m, plan.theta_restarts)))
        .collect();
    for &(m, restarts, start) in &plan.theta_best_starts {
        let mut s = plan_search(m, restarts);
        (s.options.hops, s.options.hop_sigma) = (0, 0.2);
        s.options.only_starts = Some(vec![start]);
        runs.push((m, s));
    }
    let mut rows = Vec::new();
    for (m, s) in runs {
        let file = dir.join(format!("theta{m}.json"));
        if !file.exists() {
            let curve = curve::MonomialCurve::power(m)?;
            let cp = checkpoint(&curve, &s, dir, true)?;
            search(&curve, &s, &od, cp)?;
        }
        #[derive(Deserialize)]
        struct T {
            gain_bits: f64,
            max_violation: f64,
            seconds: f64,
        }
        let t: T = read_json(&file)?;
        rows.push((m, t.gain_bits, t.max_violation, t.seconds));
    }
    print!("{}", summary(dir, &od)?);
    Ok(rows)
}
