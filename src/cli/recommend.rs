//! `momentlab recommend`: for each scene, the cheapest closed-form technique (fewest bits per
//! texel, then fewest ns per fragment) whose error against PCF is within `--tolerance` of the
//! best one on that scene.

use super::common::{
    non_negative, resolution, stacks_or_default, technique_list, usize_in, MAX_INPUTS,
};
use anyhow::{bail, Context, Result};
use momentlab::report::recommend::{recommendations, Measured};
use momentlab::technique::linalg::Precision;
use momentlab::technique::registry::{build, Params};
use std::path::PathBuf;

#[derive(clap::Args, Debug)]
pub struct Args {
    /// Absolute error above the best technique that is acceptable (0.002 = 0.2 points;
    /// finite, ≥ 0).
    #[arg(long, default_value_t = 0.002, value_parser = non_negative, allow_negative_numbers = true)]
    pub tolerance: f64,
    /// Depth stacks (default: render the embedded scenes, said so on stderr).
    #[arg(long)]
    pub stacks: Option<PathBuf>,
    /// Resolution when rendering the embedded scenes (16..=4096).
    #[arg(long, default_value_t = 512, value_parser = resolution())]
    pub resolution: usize,
    /// Closed-form techniques to consider, each at f32 and f64 storage (repeatable; comma
    /// lists).
    #[arg(
        long,
        alias = "techniques",
        default_value = "vsm,esm,evsm,csm,hamburger4,hausdorff4,hamburger6,tmsm"
    )]
    pub technique: Vec<String>,
    /// Inputs of the speed measurement: filter windows of real fragments sampled from the same
    /// depth stacks (moments and z_f as the error sees them; 1..=10000000).
    #[arg(long, alias = "speed-inputs", default_value_t = 200_000, value_parser = usize_in(1, MAX_INPUTS))]
    pub inputs: usize,
    /// Print JSON instead of a table.
    #[arg(long)]
    pub json: bool,
}

pub fn run(args: Args) -> Result<()> {
    let names = technique_list(&args.technique);
    if names.is_empty() {
        bail!("--technique: empty list");
    }
    // Build every technique before any work, so that a bad name fails at once.
    let mut jobs = Vec::new();
    for name in &names {
        if name.starts_with("lp:") {
            bail!(
                "--technique: '{name}': recommend compares closed-form techniques only; \
                 evaluate an LP candidate with `momentlab evaluate --technique '{name}'`"
            );
        }
        for prec in [Precision::F32, Precision::F64] {
            let t = build(name, &Params::with(prec, None))
                .with_context(|| format!("--technique: '{name}'"))?;
            jobs.push((name.clone(), prec.name(), t));
        }
    }
    let stacks = stacks_or_default(args.stacks.as_deref(), args.resolution, "recommend")?;
    let mut all: Vec<Measured> = Vec::new();
    for (name, prec, t) in &jobs {
        all.push(momentlab::pipeline::techniques::measured(
            &stacks,
            t.as_ref(),
            name,
            prec,
            1,
            args.inputs,
        )?);
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
