//! `momentlab theta`: optimal affine quantization transform θ for a basis (Section 4.3 of the
//! 2015 paper). JSON to stdout or --output; HLSL/GLSL snippets to --snippets DIR.

use crate::basis::Catalog;
use crate::progress::Bar;
use crate::quantize::{self, codegen, curve, optimize, theta, volume, Curve};
use anyhow::{bail, Context, Result};
use serde_json::json;
use std::path::PathBuf;
use std::time::Instant;

#[derive(clap::Args, Debug)]
pub struct Args {
    /// Instead of searching: read DIR/theta{2,3,4,6}.json, re-verify them and the published
    /// θ₂/θ₄/θ₆, write DIR/comparison.md, DIR/summary.json and the Fig. 5 analogue
    /// (DIR/fig5.svg, DIR/fig5.json).
    #[arg(long, conflicts_with_all = ["moments", "basis"])]
    pub summary: Option<PathBuf>,
    /// Power basis (z, z², …, z^m).
    #[arg(long, conflicts_with = "basis")]
    pub moments: Option<usize>,
    /// Comma-separated catalog names or formulas ("z,z^2,exp(2z)").
    #[arg(long)]
    pub basis: Option<String>,
    /// Seed of the random starts.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Number of independent random starts.
    #[arg(long, default_value_t = 16)]
    pub restarts: usize,
    /// Maximum sweeps over all rows per start.
    #[arg(long, default_value_t = 400)]
    pub max_sweeps: usize,
    /// Basin-hopping steps per start (perturb, re-ascend, keep if better).
    #[arg(long, default_value_t = 0)]
    pub hops: usize,
    /// Relative size of the basin-hopping perturbation.
    #[arg(long, default_value_t = 0.2)]
    pub hop_sigma: f64,
    /// Write the JSON here instead of stdout.
    #[arg(long)]
    pub output: Option<PathBuf>,
    /// Directory for the HLSL/GLSL snippets (default reports/theta).
    #[arg(long, default_value = "reports/theta")]
    pub snippets: PathBuf,
}

/// The curve for --moments / --basis: exact monomials when every name is "z" or "z^k",
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
            if names.is_empty() {
                bail!("--basis: empty list");
            }
            if let Some(e) = curve::parse_monomials(&names) {
                return Ok(Box::new(curve::MonomialCurve::new(e).context("--basis")?));
            }
            let cat = Catalog::embedded();
            let funcs = names
                .iter()
                .map(|n| {
                    cat.resolve(n)
                        .with_context(|| format!("--basis entry '{n}'"))
                })
                .collect::<Result<Vec<_>>>()?;
            let b = crate::basis::Basis::new(funcs);
            Ok(Box::new(curve::SampledCurve::new(
                b.names(),
                1 << 14,
                Box::new(move |z, out: &mut [f64]| b.eval(z, out)),
            )?))
        }
        _ => bail!("give exactly one of --moments m or --basis f1,f2,..."),
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

pub fn run(args: Args) -> Result<()> {
    if let Some(dir) = &args.summary {
        return summary(dir);
    }
    let command = std::env::args().collect::<Vec<_>>().join(" ");
    let curve = build_curve(args.moments, args.basis.as_deref())?;
    let m = curve.dim();
    let opts = optimize::Options {
        seed: args.seed,
        restarts: args.restarts,
        max_sweeps: args.max_sweeps,
        hops: args.hops,
        hop_sigma: args.hop_sigma,
        ..Default::default()
    };
    let pb = Bar::new(&format!("theta m={m} starts"), args.restarts as u64);
    let t0 = Instant::now();
    let best = std::sync::Mutex::new(f64::NEG_INFINITY);
    let out = optimize::optimize(curve.as_ref(), &opts, &|_k, g| {
        let mut b = best.lock().unwrap();
        *b = b.max(g);
        pb.set_label(&format!("theta m={m} starts (best {:.4} bits)", *b));
        pb.inc(1);
    })?;
    pb.finish();
    let seconds = t0.elapsed().as_secs_f64();
    let th = &out.theta;
    let ver = theta::verify(th, curve.as_ref())?;
    let gain = th.gain_bits();
    let power = matches!(curve.monomial_exponents(), Some(e) if e.iter().copied().eq(1..=m as u32));
    let mut j = json!({
        "m": m,
        "basis": th.basis,
        "matrix": th.matrix,
        "offset": th.offset,
        "inverse": th.inverse,
        "gain_bits": gain,
        "max_violation": ver.max_violation,
        "seconds": seconds,
        "exact_verification": ver.exact,
        "seed": args.seed,
        "restarts": args.restarts,
        "hops": args.hops,
        "start_gains_bits": out.start_gains,
        "lps_solved": out.lps,
        "command": command,
    });
    if power {
        let bound = volume::volume_bound_bits(m);
        j["volume_bound_bits"] = json!(bound);
        j["headroom_bits"] = json!(bound - gain);
        if let Some(p) = theta::published(m) {
            j["published_gain_bits"] = json!(p.gain_bits());
        }
    }
    let text = serde_json::to_string_pretty(&j)?;
    match &args.output {
        Some(p) => {
            if let Some(d) = p.parent().filter(|d| !d.as_os_str().is_empty()) {
                std::fs::create_dir_all(d).with_context(|| format!("creating {}", d.display()))?;
            }
            std::fs::write(p, text + "\n").with_context(|| format!("writing {}", p.display()))?
        }
        None => println!("{text}"),
    }
    std::fs::create_dir_all(&args.snippets)
        .with_context(|| format!("creating {}", args.snippets.display()))?;
    let tag = snippet_tag(curve.as_ref());
    let exps = curve.monomial_exponents();
    for (lang, ext) in [(codegen::Lang::Hlsl, "hlsl"), (codegen::Lang::Glsl, "glsl")] {
        let p = args.snippets.join(format!("theta{tag}.{ext}"));
        std::fs::write(&p, codegen::snippet(th, exps.as_deref(), &tag, gain, lang))
            .with_context(|| format!("writing {}", p.display()))?;
    }
    eprintln!(
        "theta m={m}: {gain:.6} bits, max violation {:.3e}, {seconds:.1} s, snippets in {}",
        ver.max_violation,
        args.snippets.display()
    );
    Ok(())
}

fn read_theta(path: &std::path::Path) -> Result<Option<(theta::Theta, serde_json::Value)>> {
    if !path.exists() {
        return Ok(None);
    }
    let text =
        std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
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

fn summary(dir: &std::path::Path) -> Result<()> {
    // quoted gains: 2015 paper Section 4.3 (θ2 2, θ3 6.2, θ4 12.2783), 2016 supplementary
    // Section 3 (θ6 30.511 / "30.5")
    let quoted = [(2usize, "2"), (3, "6.2"), (4, "12.2783"), (6, "30.511")];
    let mut md = String::from(
        "| m | ours: gain (bits) | ours: time (s) | ours: max violation | published: gain (our verifier) | published: max violation | quoted in paper | volume bound (bits) | headroom ours (bits) |\n|---|---|---|---|---|---|---|---|---|\n",
    );
    let mut rows = Vec::new();
    let mut commands = String::new();
    for (m, q) in quoted {
        let curve = curve::MonomialCurve::power(m)?;
        let ours = read_theta(&dir.join(format!("theta{m}.json")))?;
        let pubd = theta::published(m);
        let bound = volume::volume_bound_bits(m);
        let (og, ov, ot) = match &ours {
            Some((th, v)) => {
                let ver = theta::verify(th, &curve)?;
                if let Some(c) = v.get("command").and_then(|c| c.as_str()) {
                    commands.push_str(&format!("- m = {m}: `{c}`\n"));
                }
                (
                    Some(th.gain_bits()),
                    Some(ver.max_violation),
                    v.get("seconds").and_then(|s| s.as_f64()),
                )
            }
            None => (None, None, None),
        };
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
            "| {m} | {} | {} | {} | {} | {} | {q} | {bound:.4} | {} |\n",
            f(og, 7),
            f(ot, 1),
            e(ov),
            f(pg, 7),
            e(pv),
            f(og.map(|g| bound - g), 4)
        ));
        rows.push(json!({
            "m": m, "ours_gain_bits": og, "ours_seconds": ot, "ours_max_violation": ov,
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
        let p = dir.join("fig5.svg");
        std::fs::write(&p, svg).with_context(|| format!("writing {}", p.display()))?;
        md.push_str(&format!(
            "\nFig. 5 analogue (fig5.svg): hull of b([0,1]) {:.6} (exact 1/180 = {:.6}), hull of θ₃∘b([0,1]) {:.4}, ratio {:.1} (paper: 0.41 and 73.9×).\n",
            vols.volume_b, vols.volume_b_exact, vols.volume_theta, vols.ratio
        ));
        fig = serde_json::to_value(&vols)?;
    }
    let p = dir.join("comparison.md");
    std::fs::write(&p, &md).with_context(|| format!("writing {}", p.display()))?;
    let p = dir.join("summary.json");
    std::fs::write(
        &p,
        serde_json::to_string_pretty(&json!({"rows": rows, "fig5": fig}))? + "\n",
    )
    .with_context(|| format!("writing {}", p.display()))?;
    print!("{md}");
    Ok(())
}
