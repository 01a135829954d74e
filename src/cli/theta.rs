//! `momentlab theta`: optimal affine quantization transform θ for a basis (Section 4.3 of the
//! 2015 paper). theta{m}.json and HLSL/GLSL snippets into --out DIR
//! (default a run directory under results/; never overwrites without --force).

use crate::artefact::OutDir;
use crate::progress::Bar;
use crate::quantize::{self, codegen, curve, optimize, theta, volume, Curve};
use crate::shader;
use anyhow::{bail, Context, Result};
use serde_json::json;
use std::path::PathBuf;
use std::time::Instant;

#[derive(clap::Args, Debug)]
pub struct Args {
    /// Instead of searching: read DIR/theta{2,…,8}.json (those present), re-verify them and the
    /// published θ₂/θ₄/θ₆, write comparison.md, summary.json and the Fig. 5 analogue (fig5.svg)
    /// into --out (default: DIR itself).
    #[arg(long, conflicts_with_all = ["m", "basis"])]
    pub summary: Option<PathBuf>,
    /// Power basis (z, z², …, z^m) with m moments, m in 1..=12.
    #[arg(long, alias = "moments", conflicts_with = "basis")]
    pub m: Option<usize>,
    /// Comma-separated catalog names or formulas ("z,z^2,exp(2z)").
    #[arg(long)]
    pub basis: Option<String>,
    /// Seed of the random starts (start k uses its own stream derived from seed and k).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Number of independent random starts, 1..=100000.
    #[arg(long, default_value_t = 16)]
    pub restarts: usize,
    /// Run only these start indices of the seeded search (comma-separated, each below
    /// --restarts): re-runs e.g. the starts that reached the best basin.
    #[arg(long)]
    pub starts: Option<String>,
    /// Maximum sweeps over all rows per start, 1..=100000.
    #[arg(long, default_value_t = 400)]
    pub max_sweeps: usize,
    /// Basin-hopping steps per start (perturb, re-ascend, keep if better), 0..=10000.
    #[arg(long, default_value_t = 0)]
    pub hops: usize,
    /// Relative size of the basin-hopping perturbation, in (0, 10].
    #[arg(long, default_value_t = 0.2)]
    pub hop_sigma: f64,
    /// Starts within this many bits of the best count as reaching the best basin.
    #[arg(long, default_value_t = 1e-3)]
    pub basin_tol: f64,
    /// Output folder for theta{m}.json and the HLSL/GLSL snippets theta{m}.hlsl|glsl
    /// (default results/theta{m}-seed{seed}; for --basis a hash of the names replaces m); with
    /// --summary, for the comparison files.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Replace existing output files (otherwise a name clash is an error, found before the
    /// search); also for --summary's comparison.md, summary.json and fig5.svg.
    #[arg(long)]
    pub force: bool,
    /// Also print the JSON on stdout.
    #[arg(long)]
    pub json: bool,
    /// Channel order of the emitted θ₂/θ₄ snippets: `paper` (the 2015 paper's rows and signs, as
    /// MJP's Shadows sample and Unity HDRP ship them) or `search` (as the search found them).
    /// Other transforms always use the search's order.
    #[arg(long, value_enum, default_value_t = Order::Paper)]
    pub channel_order: Order,
    /// Instead of searching: re-emit theta*.hlsl / theta*.glsl for every theta*.json in DIR (the
    /// JSON files are only read).
    #[arg(long, conflicts_with_all = ["m", "basis", "summary"])]
    pub snippets: Option<PathBuf>,
}

/// Channel order of emitted θ₂/θ₄ snippets.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Order {
    Paper,
    Search,
}

impl From<Order> for codegen::ChannelOrder {
    fn from(o: Order) -> Self {
        match o {
            Order::Paper => codegen::ChannelOrder::Paper,
            Order::Search => codegen::ChannelOrder::Search,
        }
    }
}

/// Write `theta{tag}.glsl` and `theta{tag}.hlsl` for θ into `od` (the one output writer);
/// returns the channel order used.
fn write_snippets(
    od: &OutDir,
    th: &theta::Theta,
    curve: &dyn Curve,
    tag: &str,
    order: Order,
) -> Result<&'static str> {
    let sn = codegen::snippet(th, curve, tag, order.into())?;
    od.write_text(&format!("theta{tag}.glsl"), &shader::glsl(&sn.glsl)?)?;
    od.write_text(&format!("theta{tag}.hlsl"), &shader::hlsl(&sn.hlsl)?)?;
    Ok(sn.order)
}

/// `--snippets DIR`: re-emit the snippets of every theta*.json in DIR.
fn snippets(dir: &std::path::Path, order: Order) -> Result<()> {
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
    // Re-emitting replaces the snippets beside their JSON by design.
    let od = OutDir::new(dir, true).context("--snippets")?;
    for p in &paths {
        let Some((th, _)) = read_theta(p)? else {
            continue;
        };
        let curve = curve::from_names(&th.basis).with_context(|| p.display().to_string())?;
        let tag = snippet_tag(curve.as_ref());
        let used = write_snippets(&od, &th, curve.as_ref(), &tag, order)?;
        eprintln!(
            "{}: wrote theta{tag}.glsl, theta{tag}.hlsl ({used} channel order)",
            p.display()
        );
    }
    Ok(())
}

/// The curve for --m / --basis: exact monomials when every name is "z" or "z^k",
/// otherwise catalog functions verified by dense sampling.
pub fn build_curve(moments: Option<usize>, basis: Option<&str>) -> Result<Box<dyn Curve>> {
    match (moments, basis) {
        (Some(m), None) => Ok(Box::new(curve::MonomialCurve::power(m)?)),
        (None, Some(list)) => {
            let names: Vec<String> = list
                .split(',')
                .map(|s| s.trim().to_string())
                .filter(|s| !s.is_empty())
                .collect();
            curve::from_names(&names).context("--basis")
        }
        _ => bail!("give exactly one of --m M or --basis f1,f2,..."),
    }
}

fn snippet_tag(curve: &dyn Curve) -> String {
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

/// Parse and range-check the search options (before any work).
fn options(args: &Args) -> Result<optimize::Options> {
    if !(1..=100_000).contains(&args.restarts) {
        bail!("--restarts must be in 1..=100000, got {}", args.restarts);
    }
    if !(1..=100_000).contains(&args.max_sweeps) {
        bail!(
            "--max-sweeps must be in 1..=100000, got {}",
            args.max_sweeps
        );
    }
    if args.hops > 10_000 {
        bail!("--hops must be in 0..=10000, got {}", args.hops);
    }
    if !(args.hop_sigma > 0.0 && args.hop_sigma <= 10.0) {
        bail!("--hop-sigma must be in (0, 10], got {}", args.hop_sigma);
    }
    if !(args.basin_tol >= 0.0 && args.basin_tol <= 1.0) {
        bail!("--basin-tol must be in [0, 1] bits, got {}", args.basin_tol);
    }
    let only_starts = match &args.starts {
        None => None,
        Some(list) => {
            let v = list
                .split(',')
                .map(|s| {
                    s.trim()
                        .parse::<usize>()
                        .ok()
                        .filter(|&k| k < args.restarts)
                        .with_context(|| {
                            format!(
                                "--starts: '{s}' is not a start index below --restarts {}",
                                args.restarts
                            )
                        })
                })
                .collect::<Result<Vec<_>>>()?;
            Some(v)
        }
    };
    Ok(optimize::Options {
        seed: args.seed,
        restarts: args.restarts,
        max_sweeps: args.max_sweeps,
        hops: args.hops,
        hop_sigma: args.hop_sigma,
        only_starts,
        ..Default::default()
    })
}

/// CPU seconds (user + system) of this process so far, from /proc/self/stat (Linux; clock
/// ticks of 1/100 s); None elsewhere.
pub fn process_cpu_seconds() -> Option<f64> {
    let s = std::fs::read_to_string("/proc/self/stat").ok()?;
    let rest = &s[s.rfind(')')? + 2..];
    let f: Vec<&str> = rest.split_whitespace().collect();
    // fields after the command: state is index 0, utime 11, stime 12
    let ut: f64 = f.get(11)?.parse().ok()?;
    let st: f64 = f.get(12)?.parse().ok()?;
    Some((ut + st) / 100.0)
}

pub fn run(args: Args) -> Result<()> {
    if let Some(dir) = &args.summary {
        return summary(dir, args.out.as_deref().unwrap_or(dir), args.force);
    }
    if let Some(dir) = &args.snippets {
        return snippets(dir, args.channel_order);
    }
    let command = crate::report::provenance::command_line();
    let opts = options(&args)?;
    let curve = build_curve(args.m, args.basis.as_deref())?;
    let m = curve.dim();
    let tag = snippet_tag(curve.as_ref());
    let dir = args
        .out
        .clone()
        .unwrap_or_else(|| PathBuf::from(format!("results/theta{tag}-seed{}", args.seed)));
    let names: Vec<String> = ["json", "hlsl", "glsl"]
        .iter()
        .map(|e| format!("theta{tag}.{e}"))
        .collect();
    // Before the search: --out is a folder, and nothing there is replaced without --force.
    let od = OutDir::new(&dir, args.force).context("--out")?;
    od.reserve(&names).context("--out")?;
    let n_starts = opts.only_starts.as_ref().map_or(opts.restarts, |v| v.len());
    let pb = Bar::new(&format!("theta m={m} starts"), n_starts as u64);
    let t0 = Instant::now();
    let cpu0 = process_cpu_seconds();
    let best = std::sync::Mutex::new(f64::NEG_INFINITY);
    let out = optimize::optimize(curve.as_ref(), &opts, &|_k, g| {
        let mut b = best.lock().unwrap_or_else(|e| e.into_inner());
        *b = b.max(g);
        pb.set_label(&format!("theta m={m} starts (best {:.4} bits)", *b));
        pb.inc(1);
    })?;
    pb.finish();
    let seconds = t0.elapsed().as_secs_f64();
    let cpu_seconds = process_cpu_seconds().zip(cpu0).map(|(a, b)| a - b);
    let th = &out.theta;
    let ver = theta::verify(th, curve.as_ref())?;
    let gain = th.gain_bits();
    let basin = optimize::basin(&out.start_gains, &out.start_indices, args.basin_tol);
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
        "seed": args.seed,
        "restarts": args.restarts,
        "hops": args.hops,
        "hop_sigma": args.hop_sigma,
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
            let (_, lo, _, hi) = curve::row_min_max(curve.as_ref(), &e);
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
    let order = write_snippets(&od, th, curve.as_ref(), &tag, args.channel_order)?;
    j["snippet_channel_order"] = json!(order);
    let text = serde_json::to_string_pretty(&j)? + "\n";
    od.write_text(&names[0], &text)?;
    if args.json {
        print!("{text}");
    }
    eprintln!(
        "theta m={m}: {gain:.6} bits, max violation {:.3e}, {seconds:.1} s wall{}, best basin \
         reached by {}/{} starts (within {} bits), wrote {}",
        ver.max_violation,
        cpu_seconds.map_or(String::new(), |c| format!(" ({c:.1} s CPU)")),
        basin.starts.len(),
        n_starts,
        args.basin_tol,
        dir.display()
    );
    Ok(())
}

fn read_theta(path: &std::path::Path) -> Result<Option<(theta::Theta, serde_json::Value)>> {
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

fn summary(dir: &std::path::Path, out: &std::path::Path, force: bool) -> Result<()> {
    // Before any verification: the three outputs can be written (refused unless --force).
    let od = OutDir::new(out, force).context("--summary")?;
    od.reserve(["comparison.md", "summary.json", "fig5.svg"])
        .context("--summary")?;
    // quoted gains: 2015 paper Section 4.3 (θ2 2, θ3 6.2, θ4 12.2783), 2016 supplementary
    // Section 3 (θ6 30.511 / "30.5")
    let quoted = [
        (2usize, "2"),
        (3, "6.2"),
        (4, "12.2783"),
        (5, "—"),
        (6, "30.511"),
        (7, "—"),
        (8, "—"),
    ];
    let mut md = String::from(
        "| m | ours: gain (bits) | ours: wall s | ours: CPU s | starts reaching the best (±basin tol) | runner-up basin (bits) | ours: max violation | published: gain (our verifier) | published: max violation | quoted in paper | volume bound (bits) | headroom ours (bits) |\n|---|---|---|---|---|---|---|---|---|---|---|---|\n",
    );
    let mut rows = Vec::new();
    let mut commands = String::new();
    for (m, q) in quoted {
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
        let vols = quantize::fig5::volumes(&t3, 2000)?;
        let svg = quantize::fig5::svg(&t3, &vols, 48)?;
        od.write_text("fig5.svg", &svg)?;
        md.push_str(&format!(
            "\nFig. 5 analogue (fig5.svg): hull of b([0,1]) {:.6} (exact 1/180 = {:.6}), hull of θ₃∘b([0,1]) {:.4}, ratio {:.1} (paper: 0.41 and 73.9×).\n",
            vols.volume_b, vols.volume_b_exact, vols.volume_theta, vols.ratio
        ));
        fig = serde_json::to_value(&vols)?;
    }
    od.write_text("comparison.md", &md)?;
    od.write_json("summary.json", &json!({"rows": rows, "fig5": fig}))?;
    print!("{md}");
    Ok(())
}
