//! `momentlab bench <what>`: benchmarks reported as medians, ratios measured in one run.

use anyhow::Result;
use clap::Subcommand;

#[derive(clap::Args, Debug)]
pub struct Args {
    #[command(subcommand)]
    pub what: What,
}

#[derive(Subcommand, Debug)]
pub enum What {
    /// Microseconds per LP for the reference and fast solvers.
    Lp(super::bench_lp::Args),
    /// Nanoseconds per evaluation of every closed-form technique.
    Shadow(super::bench_shadow::Args),
}

pub fn run(args: Args) -> Result<()> {
    match args.what {
        What::Lp(a) => super::bench_lp::run(a),
        What::Shadow(a) => super::bench_shadow::run(a),
    }
}
