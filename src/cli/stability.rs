//! `momentlab stability`: stress-test every technique where it fails (the study in
//! [`momentlab::report::stability`], documented in docs/stability.md); writes a Markdown table,
//! JSON and SVG heat maps to the output directory.

use super::common::{technique_list, usize_in};
use anyhow::Result;
use momentlab::progress::Bar;
use momentlab::report::stability::{self, Options};
use std::path::PathBuf;

use momentlab::report::stability::DEFAULT_TECHNIQUES;

#[derive(clap::Args, Debug)]
pub struct Args {
    /// Output folder (the tracked reports/stability only when given explicitly).
    #[arg(long, default_value = "results/stability")]
    pub out: PathBuf,
    /// Number of inputs, cycled over the scenarios (1..=1000000).
    #[arg(long, alias = "samples", default_value_t = 3000, value_parser = usize_in(1, 1_000_000))]
    pub inputs: usize,
    /// Random seed.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Uniform grid points of the oracle (Algorithm 1) on [0,1] (2..=65536).
    #[arg(long, default_value_t = 256, value_parser = usize_in(2, 65_536))]
    pub grid: usize,
    /// Techniques (repeatable; comma lists, `lp:` specs keep their commas); an unknown name is
    /// an error before the study runs.
    #[arg(long, alias = "techniques", default_value = DEFAULT_TECHNIQUES)]
    pub technique: Vec<String>,
    /// Replace files that already exist in --out (otherwise refused before the study runs).
    #[arg(long)]
    pub force: bool,
    /// Print the summary (inputs, techniques, seconds, output folder) as JSON.
    #[arg(long)]
    pub json: bool,
}

pub fn run(args: Args) -> Result<()> {
    let opts = Options {
        out: args.out,
        samples: args.inputs,
        seed: args.seed,
        grid: args.grid,
        techniques: technique_list(&args.technique),
        force: args.force,
    };
    let pb = Bar::new("stability inputs × techniques", 0);
    let o = stability::study(&opts, &|n| pb.set_total(n as u64), &|n| pb.inc(n as u64))?;
    pb.finish();
    if args.json {
        println!(
            "{}",
            serde_json::json!({
                "inputs": o.inputs, "techniques": o.techniques,
                "seconds": o.seconds, "out": opts.out,
            })
        );
        return Ok(());
    }
    println!(
        "stability: {} inputs × {} techniques in {:.1} s → {}",
        o.inputs,
        o.techniques,
        o.seconds,
        opts.out.display()
    );
    Ok(())
}
