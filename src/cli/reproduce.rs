//! `momentlab reproduce`: the whole study on the embedded default data, from a fresh clone —
//! a thin caller of [`momentlab::pipeline::run`] (steps, artefacts and resuming are described
//! there).

use super::common::{non_negative, resolution};
use anyhow::Result;
use momentlab::pipeline::{self, Config, Preset};
use std::path::PathBuf;

#[derive(clap::Args, Debug)]
pub struct Args {
    /// Name of the run: the report goes to <out>/<run>/, bulky data to <results>/<run>/.
    #[arg(long, default_value = "default")]
    pub run: String,
    /// The larger configuration (every fragment for the LP candidates, θ₆, larger stability,
    /// speed and sweep samples). Takes hours rather than minutes.
    #[arg(long)]
    pub full: bool,
    /// A tiny configuration for tests and smoke runs (64² stacks, small samples).
    #[arg(long, conflicts_with = "full")]
    pub tiny: bool,
    /// Shadow-map resolution of the rendered views (default 512, --tiny 64; 16..=4096).
    #[arg(long, value_parser = resolution())]
    pub resolution: Option<usize>,
    /// Recommendation tolerance: absolute error above the best technique that is acceptable
    /// (finite, ≥ 0).
    #[arg(long, default_value_t = 0.002, value_parser = non_negative, allow_negative_numbers = true)]
    pub tolerance: f64,
    /// Output folder of the report (the committed report is `--out reports`; by default
    /// nothing tracked is written).
    #[arg(long, alias = "reports", default_value = "results/reports")]
    pub out: PathBuf,
    /// Folder of bulky results (stacks, sweep rows), kept apart from the report.
    #[arg(long, default_value = "results")]
    pub results: PathBuf,
    /// Skip the candidate sweep (the slowest step).
    #[arg(long)]
    pub skip_search: bool,
    /// Replace the run's outputs: delete its previous artefacts (the entries a run writes in the
    /// report folder; stacks/ and search-m<m>/ in the data folder; other files stay, links are
    /// not followed, docs/files.md) and compute every step again. Without it a folder holding
    /// outputs is refused, except the run's own unfinished run, which resumes (steps whose
    /// artefacts exist are read back).
    #[arg(long, alias = "fresh")]
    pub force: bool,
    /// Print {"report", "seconds", "recommendations"} as JSON on stdout at the end.
    #[arg(long)]
    pub json: bool,
}

impl Args {
    /// The typed configuration of the run.
    pub fn config(&self) -> Config {
        Config {
            run: self.run.clone(),
            preset: if self.tiny {
                Preset::Tiny
            } else if self.full {
                Preset::Full
            } else {
                Preset::Default
            },
            resolution: self.resolution,
            tolerance: self.tolerance,
            reports: self.out.clone(),
            results: self.results.clone(),
            skip_search: self.skip_search,
            fresh: self.force,
        }
    }
}

pub fn run(args: Args) -> Result<()> {
    let outcome = pipeline::run(&args.config())?;
    eprintln!("report: {}", outcome.report.display());
    if args.json {
        println!(
            "{}",
            serde_json::to_string_pretty(&serde_json::json!({
                "report": outcome.report, "seconds": outcome.seconds,
                "recommendations": outcome.recommendations,
            }))?
        );
    }
    Ok(())
}
