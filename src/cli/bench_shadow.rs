//! `momentlab bench shadow [--corpus random|stacks] [--inputs N] [--json]`: nanoseconds per
//! evaluation of every closed-form technique (MSM variants, Hamburger with m = 4, 6, 8, TMSM and
//! the baselines VSM, ESM, EVSM, CSM) on one core (no rayon), at f32 and f64 arithmetic: mean
//! over all evaluations, median, p99 and max over batches of 256 consecutive inputs. Inputs:
//! `random` — moments of random mixtures of 1–4 Diracs in [0,1], z_f uniform; `stacks` —
//! fragments sampled from real depth stacks (the rendered default dataset, or `--stacks DIR`)
//! with their biased depth and the filtered moments of their 9×9 kernel window. Every result is
//! accumulated and passed through `black_box`.

use super::common::{resolution, technique_list, usize_in, MAX_INPUTS};
use anyhow::{bail, Result};
use momentlab::metrics::windows::stacks_corpus;
use momentlab::technique::registry::{build, canonical_name, Params, Precision};
use momentlab::technique::timing::{self, Corpus, Speed};
use std::io::Write;
use std::path::PathBuf;

#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum CorpusKind {
    /// Random mixtures of 1–4 Diracs.
    Random,
    /// Fragments and filter windows sampled from depth stacks.
    Stacks,
}

#[derive(clap::Args, Debug)]
pub struct Args {
    /// Where the inputs come from.
    #[arg(long, value_enum, default_value_t = CorpusKind::Random)]
    pub corpus: CorpusKind,
    /// Number of (moments, z_f) inputs per technique and precision.
    #[arg(long, default_value_t = 200_000, value_parser = usize_in(1, MAX_INPUTS))]
    pub inputs: usize,
    /// Timed passes over the inputs (1..=1000).
    #[arg(long, alias = "reps", default_value_t = 3, value_parser = usize_in(1, 1000))]
    pub repeats: usize,
    /// `--corpus stacks`: a folder of .exr depth stacks (default: render the embedded dataset).
    #[arg(long)]
    pub stacks: Option<PathBuf>,
    /// `--corpus stacks` without `--stacks`: resolution of the rendered dataset (16..=4096).
    #[arg(long, default_value_t = 256, value_parser = resolution())]
    pub resolution: usize,
    /// Only these techniques, as listed in the table (e.g. tmsm, hamburger8,
    /// hamburger4-general: Algorithm 2 at m = 4); repeatable, comma lists.
    #[arg(long)]
    pub technique: Vec<String>,
    /// Print JSON instead of a table.
    #[arg(long)]
    pub json: bool,
}

/// Techniques timed, by registry name (`-general`: Algorithm 2 at that m).
const TECHNIQUES: &[&str] = &[
    "vsm",
    "esm",
    "evsm",
    "csm",
    "hamburger4",
    "hausdorff4",
    "hamburger6",
    "hamburger4-general",
    "hamburger6-general",
    "hamburger8",
    "tmsm",
];

#[derive(serde::Serialize)]
struct Row {
    technique: String,
    precision: &'static str,
    moments: usize,
    corpus: CorpusKind,
    inputs: usize,
    /// Nanoseconds per evaluation.
    ns_mean: f64,
    ns_median: f64,
    ns_p99: f64,
    ns_max: f64,
    mean_g: f64,
}

fn corpus(args: &Args) -> Result<Corpus> {
    Ok(match args.corpus {
        CorpusKind::Random => timing::random_corpus(args.inputs, 2015),
        CorpusKind::Stacks => {
            let stacks = match &args.stacks {
                Some(d) => momentlab::stack::load_dir(d)?,
                None => momentlab::render::default_dataset(args.resolution)?,
            };
            stacks_corpus(&stacks, args.inputs, 2015)?
        }
    })
}

pub fn run(args: Args) -> Result<()> {
    let mut todo = Vec::new();
    for &name in TECHNIQUES {
        for precision in [Precision::F32, Precision::F64] {
            todo.push((build(name, &Params::with(precision, None))?, precision));
        }
    }
    let wanted: Vec<String> = technique_list(&args.technique)
        .iter()
        .map(|n| canonical_name(n))
        .collect();
    if let Some(bad) = wanted.iter().find(|n| !TECHNIQUES.contains(&n.as_str())) {
        bail!(
            "--technique {bad}: not timed here (valid: {})",
            TECHNIQUES.join(", ")
        );
    }
    todo.retain(|t| wanted.is_empty() || wanted.contains(&t.0.name()));
    let corpus = corpus(&args)?;
    let mut rows = Vec::new();
    for (t, precision) in &todo {
        let (moments, zfs) = timing::moments_of(t.as_ref(), &corpus);
        let s: Speed = timing::speed(t.as_ref(), &moments, &zfs, args.repeats);
        rows.push(Row {
            technique: t.name(),
            precision: precision.name(),
            moments: t.moment_count(),
            corpus: args.corpus,
            inputs: zfs.len(),
            ns_mean: s.mean,
            ns_median: s.median,
            ns_p99: s.p99,
            ns_max: s.max,
            mean_g: s.mean_g,
        });
    }
    let mut out = std::io::stdout().lock();
    if args.json {
        writeln!(out, "{}", serde_json::to_string_pretty(&rows)?)?;
        return Ok(());
    }
    writeln!(
        out,
        "{:<18} {:>4} {:>3} {:>9} {:>9} {:>9} {:>9} {:>8}",
        "technique", "prec", "m", "mean ns", "median", "p99", "max", "mean G"
    )?;
    for r in &rows {
        writeln!(
            out,
            "{:<18} {:>4} {:>3} {:>9.1} {:>9.1} {:>9.1} {:>9.1} {:>8.4}",
            r.technique,
            r.precision,
            r.moments,
            r.ns_mean,
            r.ns_median,
            r.ns_p99,
            r.ns_max,
            r.mean_g
        )?;
    }
    writeln!(
        out,
        "({} {:?} inputs per row, {} passes, batches of {}; one core)",
        rows.first().map_or(0, |r| r.inputs),
        args.corpus,
        args.repeats,
        timing::BATCH
    )?;
    for prec in ["f32", "f64"] {
        let mean = |name: &str| {
            rows.iter()
                .find(|r| r.technique == name && r.precision == prec)
                .map(|r| r.ns_mean)
        };
        if let (Some(t), Some(h)) = (mean("tmsm"), mean("hamburger4")) {
            writeln!(out, "tmsm / hamburger4 ({prec}, mean): {:.2}", t / h)?;
        }
    }
    Ok(())
}
