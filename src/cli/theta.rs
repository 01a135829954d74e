//! `momentlab theta`: optimal affine quantization transform θ for a basis (Section 4.3 of the
//! 2015 paper). JSON to stdout or --output; HLSL/GLSL snippets to --snippets DIR.

use crate::basis::Catalog;
use crate::quantize::{codegen, curve, optimize, theta, volume, Curve};
use anyhow::{bail, Context, Result};
use indicatif::{ProgressBar, ProgressStyle};
use serde_json::json;
use std::path::PathBuf;
use std::time::Instant;

#[derive(clap::Args, Debug)]
pub struct Args {
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
    let pb = ProgressBar::new(args.restarts as u64);
    pb.set_style(
        ProgressStyle::with_template("theta m={msg} [{bar:30}] {pos}/{len} starts {elapsed}")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    pb.set_message(format!("{m}"));
    let t0 = Instant::now();
    let best = std::sync::Mutex::new(f64::NEG_INFINITY);
    let out = optimize::optimize(curve.as_ref(), &opts, &|_k, g| {
        let mut b = best.lock().unwrap();
        *b = b.max(g);
        pb.set_message(format!("{m} best {:.4} bits", *b));
        pb.inc(1);
    })?;
    pb.finish_and_clear();
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
