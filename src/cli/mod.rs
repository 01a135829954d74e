//! The command-line layer: parses arguments, reads and writes files, shows progress bars, and
//! calls the library. No numerics here. One file per subcommand.

pub mod bench;
pub mod bench_lp;
pub mod bench_shadow;
pub mod candidates;
pub mod evaluate;
pub mod import;
pub mod lp;
pub mod merge;
pub mod plan;
pub mod quantize;
pub mod recommend;
pub mod render;
pub mod reproduce;
pub mod search;
pub mod shadow;
pub mod stability;
pub mod theta;
pub mod threads;

use anyhow::Result;
use clap::{Parser, Subcommand};

/// momentlab: moment shadow mapping research pipeline.
#[derive(Parser, Debug)]
#[command(name = "momentlab", version, about, long_about = None)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

#[derive(Subcommand, Debug)]
pub enum Command {
    /// Solve Algorithm 1 (the discretized moment problem) for a JSON batch.
    Lp(lp::Args),
    /// Count, list and index candidates (m-subsets of the basis catalog).
    Candidates(candidates::Args),
    /// Render depth stacks of the scenes with the reference ray caster.
    Render(render::Args),
    /// Validate and import depth stacks written by another renderer.
    Import(import::Args),
    /// Error of a technique against PCF over all fragments of the depth stacks.
    Evaluate(evaluate::Args),
    /// Closed-form shadow techniques for a JSON batch of (moments, z_f).
    Shadow(shadow::Args),
    /// Stress-test every technique where it fails; writes reports/stability/.
    Stability(stability::Args),
    /// Benchmarks (LP solvers, closed-form techniques).
    Bench(bench::Args),
    /// Optimal affine quantization transform θ for a basis.
    Theta(theta::Args),
    /// Quantized moment shadow maps on the depth stacks: error against bias α per bit depth.
    Quantize(quantize::Args),
    /// The candidate sweep: rank every m-subset of the catalog.
    Search(search::Args),
    /// Merge sharded search results.
    Merge(merge::Args),
    /// The cheapest technique within a tolerance of the best, per scene.
    Recommend(recommend::Args),
    /// Reproduce the whole study on the default data and write the report.
    Reproduce(reproduce::Args),
}

/// Entry point of the binary.
pub fn main() -> Result<()> {
    let cli = Cli::parse();
    threads::init_from_env()?;
    match cli.command {
        Command::Lp(a) => lp::run(a),
        Command::Candidates(a) => candidates::run(a),
        Command::Render(a) => render::run(a),
        Command::Import(a) => import::run(a),
        Command::Evaluate(a) => evaluate::run(a),
        Command::Shadow(a) => shadow::run(a),
        Command::Stability(a) => stability::run(a),
        Command::Bench(a) => bench::run(a),
        Command::Theta(a) => theta::run(a),
        Command::Quantize(a) => quantize::run(a),
        Command::Search(a) => search::run(a),
        Command::Merge(a) => merge::run(a),
        Command::Recommend(a) => recommend::run(a),
        Command::Reproduce(a) => reproduce::run(a),
    }
}
