//! `momentlab quantize`: quantized moment shadow maps on the depth stacks. Error against PCF
//! over the bias α for canonical / optimized (θ) storage at 8 and 16 bits and 32-bit float,
//! for VSM (θ₂), Hamburger 4MSM (θ₄), 6MSM (θ₆) and 8 moments (θ₈): ours from --theta-dir,
//! the published θ₂/θ₄/θ₆ beside them. Parses the flags and calls
//! [`momentlab::pipeline::quantize`].

use super::common::resolution;
use anyhow::{bail, Context, Result};
use momentlab::artefact::{Checkpoint, OutDir};
use momentlab::pipeline::quantize::{self, Study, FILES};
use momentlab::quantize::study::{Tech, DEFAULT_ALPHAS};
use std::path::{Path, PathBuf};

#[derive(clap::Args, Debug)]
pub struct Args {
    /// Directory of depth stacks (.exr + .json); default: render the embedded default dataset.
    #[arg(long)]
    pub stacks: Option<PathBuf>,
    /// Shadow-map resolution when rendering the default dataset (16..=4096).
    #[arg(long, default_value_t = 512, value_parser = resolution())]
    pub resolution: usize,
    /// Folder with θ (theta{m}.json from `momentlab theta`) for every technique run; a missing
    /// file is an error. Default: the study's θ committed in reports/theta (read only).
    #[arg(long, default_value = "reports/theta")]
    pub theta_dir: PathBuf,
    /// Techniques (repeatable; comma lists): vsm (θ₂), hamburger4 (θ₄), hamburger6 (θ₆),
    /// hamburger8 (θ₈; the older 4msm, 6msm, 8msm are accepted).
    #[arg(
        long,
        alias = "techniques",
        default_value = "vsm,hamburger4,hamburger6,hamburger8"
    )]
    pub technique: Vec<String>,
    /// Output folder (quantize.json, quantize.md, quantize_alpha.svg).
    #[arg(long, default_value = "results/quantize")]
    pub out: PathBuf,
    /// Overwrite existing output files (otherwise a name clash is an error).
    #[arg(long)]
    pub force: bool,
    /// Evaluate every k-th fragment only, 1..=1000000.
    #[arg(long, default_value_t = 1)]
    pub stride: usize,
    /// Comma-separated bias strengths α in (0, 1) (default: 1e-8, 3e-8, …, 1e-2, the
    /// study's 13 strengths).
    #[arg(long)]
    pub alphas: Option<String>,
    /// Print the sweeps as JSON on stdout instead of the table.
    #[arg(long)]
    pub json: bool,
    /// Instead of computing: combine the sweeps of these quantize.json files (comma-separated,
    /// same stacks and stride) and write the tables and plot into --out.
    #[arg(long)]
    pub merge: Option<String>,
}

pub fn run(args: Args) -> Result<()> {
    let alphas: Vec<f64> = match &args.alphas {
        None => DEFAULT_ALPHAS.to_vec(),
        Some(list) => list
            .split(',')
            .map(|s| {
                s.trim()
                    .parse::<f64>()
                    .ok()
                    .filter(|a| a.is_finite() && *a > 0.0 && *a < 1.0)
                    .with_context(|| format!("--alphas: '{s}' is not a number in (0, 1)"))
            })
            .collect::<Result<_>>()?,
    };
    if !(1..=1_000_000).contains(&args.stride) {
        bail!("--stride must be in 1..=1000000, got {}", args.stride);
    }
    let techniques: Vec<Tech> = super::common::technique_list(&args.technique)
        .iter()
        .map(|t| {
            Tech::parse(t).with_context(|| {
                format!("--technique: '{t}' is not one of vsm, hamburger4, hamburger6, hamburger8")
            })
        })
        .collect::<Result<_>>()?;
    if techniques.is_empty() {
        bail!("--technique: empty list");
    }
    // Nothing in --out is replaced without --force, but what an interrupted study wrote there
    // (its checkpoint then resumes, or refuses other parameters, once the stacks are loaded).
    OutDir::new(&args.out, args.force).context("--out")?;
    let resumable = args.merge.is_none() && Checkpoint::exists(&args.out, quantize::CHECKPOINT);
    let od = OutDir::new(&args.out, args.force || resumable).context("--out")?;
    od.reserve(FILES).context("--out")?;
    let written = match &args.merge {
        Some(list) => {
            let files: Vec<&Path> = list.split(',').map(|f| Path::new(f.trim())).collect();
            quantize::merge(&files, &od)?
        }
        None => quantize::study(
            &Study {
                stacks: args.stacks.clone(),
                resolution: args.resolution,
                theta_dir: args.theta_dir.clone(),
                techniques,
                stride: args.stride,
                alphas,
            },
            &od,
            args.force,
        )?,
    };
    if args.json && args.merge.is_none() {
        print!("{}", written.json);
    } else {
        print!("{}", written.markdown);
    }
    Ok(())
}
