//! `momentlab theta`: optimal affine quantization transform θ for a basis (Section 4.3 of the
//! 2015 paper). theta{m}.json and HLSL/GLSL/WGSL snippets into --out DIR
//! (default a run directory under results/; never overwrites without --force). Parses the flags
//! and calls [`momentlab::pipeline::theta`].

use anyhow::{bail, Context, Result};
use momentlab::artefact::OutDir;
use momentlab::pipeline::theta;
use momentlab::quantize::{codegen, curve, optimize, Curve};
use std::path::PathBuf;

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
    /// Output folder for theta{m}.json and the HLSL/GLSL/WGSL snippets theta{m}.hlsl|glsl|wgsl
    /// (default results/theta{m}-seed{seed}; for --basis a hash of the names replaces m); with
    /// --summary, for the comparison files.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Replace existing output files (otherwise a name clash is an error, found before the
    /// search); also for --summary's comparison.md, summary.json and fig5.svg and for the
    /// snippets --snippets re-emits.
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
    /// Instead of searching: re-emit theta*.hlsl / .glsl / .wgsl for every theta*.json in DIR (the
    /// JSON files are only read); existing snippets are replaced only with --force.
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

pub fn run(args: Args) -> Result<()> {
    if let Some(dir) = &args.summary {
        if !dir.is_dir() {
            bail!("--summary {}: no such folder", dir.display());
        }
        let out = args.out.as_deref().unwrap_or(dir);
        // Before any verification: the three outputs can be written (refused unless --force).
        let od = OutDir::new(out, args.force).context("--summary")?;
        od.reserve(theta::SUMMARY_FILES).context("--summary")?;
        print!("{}", theta::summary(dir, &od)?);
        return Ok(());
    }
    if let Some(dir) = &args.snippets {
        return theta::snippets(dir, args.channel_order.into(), args.force);
    }
    let search = theta::Search {
        options: options(&args)?,
        basin_tol: args.basin_tol,
        order: args.channel_order.into(),
    };
    let curve = build_curve(args.m, args.basis.as_deref())?;
    let tag = theta::snippet_tag(curve.as_ref());
    let dir = args
        .out
        .clone()
        .unwrap_or_else(|| PathBuf::from(format!("results/theta{tag}-seed{}", args.seed)));
    // Before the search: --out is a folder, and nothing there is replaced without --force
    // (or, resuming an interrupted run of this command, the files that run wrote).
    OutDir::new(&dir, args.force).context("--out")?;
    let cp = theta::checkpoint(curve.as_ref(), &search, &dir, args.force).context("--out")?;
    let od = OutDir::new(&dir, args.force || cp.resuming()).context("--out")?;
    od.reserve(theta::file_names(&tag)).context("--out")?;
    let text = theta::search(curve.as_ref(), &search, &od, cp)?;
    if args.json {
        print!("{text}");
    }
    Ok(())
}
