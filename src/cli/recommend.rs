//! `momentlab recommend`: for each scene, the cheapest closed-form technique (fewest bits per
//! texel, then fewest ns per fragment) whose error against PCF is within `--tolerance` of the
//! best one on that scene.

use crate::report::recommend::{recommendations, Measured};
use crate::technique::linalg::Precision;
use crate::technique::registry::{build, Params};
use anyhow::{bail, Context, Result};
use std::path::PathBuf;

#[derive(clap::Args, Debug)]
pub struct Args {
    /// Absolute error above the best technique that is acceptable (0.002 = 0.2 points).
    #[arg(long, default_value_t = 0.002)]
    pub tolerance: f64,
    /// Depth stacks (default: render the embedded scenes).
    #[arg(long)]
    pub stacks: Option<PathBuf>,
    /// Resolution when rendering the embedded scenes.
    #[arg(long, default_value_t = 512)]
    pub resolution: usize,
    /// Comma-separated closed-form techniques to consider (each at f32 and f64 storage).
    #[arg(
        long,
        default_value = "vsm,esm,evsm,csm,hamburger4,hausdorff4,hamburger6,tmsm"
    )]
    pub techniques: String,
    /// Random inputs for the speed measurement.
    #[arg(long, default_value_t = 200_000)]
    pub speed_inputs: usize,
    /// Print JSON instead of a table.
    #[arg(long)]
    pub json: bool,
}

pub fn run(args: Args) -> Result<()> {
    if !(args.tolerance.is_finite() && args.tolerance >= 0.0) {
        bail!(
            "--tolerance must be a finite number ≥ 0, got {}",
            args.tolerance
        );
    }
    if args.speed_inputs == 0 {
        bail!("--speed-inputs must be at least 1");
    }
    let stacks = match &args.stacks {
        Some(d) => {
            crate::stack::load_dir(d).with_context(|| format!("--stacks {}", d.display()))?
        }
        None => {
            if args.resolution < 16 {
                bail!("--resolution must be at least 16, got {}", args.resolution);
            }
            crate::render::default_dataset(args.resolution)?
        }
    };
    let mut all: Vec<Measured> = Vec::new();
    for name in args
        .techniques
        .split(',')
        .map(str::trim)
        .filter(|s| !s.is_empty())
    {
        for prec in [Precision::F32, Precision::F64] {
            let t = build(name, &Params::with(prec, None))
                .with_context(|| format!("--techniques: '{name}'"))?;
            all.push(crate::pipeline::techniques::measured(
                &stacks,
                t.as_ref(),
                name,
                prec.name(),
                1,
                args.speed_inputs,
            )?);
        }
    }
    let recs = recommendations(&all, args.tolerance);
    if args.json {
        println!("{}", serde_json::to_string_pretty(&recs)?);
        return Ok(());
    }
    println!(
        "{:<10} {:<22} {:>9} {:>6} {:>9}   {:<22} {:>9}   {:<22} {:>9} {:>9}",
        "scene",
        "recommended",
        "error",
        "bits",
        "ns/frag",
        "best",
        "error",
        "runner-up",
        "error",
        "ns/frag"
    );
    for r in &recs {
        let (ru, ru_err, ru_ns) = r
            .runner_up
            .clone()
            .map_or(("–".to_string(), f64::NAN, f64::NAN), |u| u);
        println!(
            "{:<10} {:<22} {:>8.3}% {:>6} {:>9.1}   {:<22} {:>8.3}%   {:<22} {:>8.3}% {:>9.1}",
            r.scene,
            format!("{} ({})", r.name, r.precision),
            100.0 * r.error,
            r.bits_per_texel,
            r.ns_per_fragment,
            r.best_name,
            100.0 * r.best_error,
            ru,
            100.0 * ru_err,
            ru_ns
        );
    }
    println!("(tolerance {:.3} % absolute)", 100.0 * args.tolerance);
    Ok(())
}
