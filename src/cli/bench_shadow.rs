//! `momentlab bench shadow [--inputs N] [--json]`: nanoseconds per evaluation of every
//! closed-form technique on one core (no rayon), at f32 and f64 arithmetic. Inputs are the
//! moments (with each technique's own basis) of random mixtures of 1–4 Diracs in [0,1] with
//! z_f uniform in [0,1]; every result is accumulated and passed through `black_box`.

use crate::technique::registry::{build, Params, Precision};
use crate::technique::timing;
use anyhow::{bail, Result};
use std::io::Write;

#[derive(clap::Args, Debug)]
pub struct Args {
    /// Number of (moments, z_f) inputs per technique and precision.
    #[arg(long, default_value_t = 1_000_000)]
    pub inputs: usize,
    /// Timed repetitions (the median is reported).
    #[arg(long, default_value_t = 3)]
    pub reps: usize,
    /// Print JSON instead of a table.
    #[arg(long)]
    pub json: bool,
}

/// Techniques timed, with the registry name and parameters.
const TECHNIQUES: &[&str] = &[
    "vsm",
    "esm",
    "evsm",
    "csm",
    "hamburger4",
    "hausdorff4",
    "hamburger6",
    "hamburger",
    "tmsm",
];

#[derive(serde::Serialize)]
struct Row {
    technique: String,
    precision: &'static str,
    moments: usize,
    inputs: usize,
    ns_per_eval: f64,
    /// Sum of all G (keeps the work observable; also a cheap sanity figure).
    mean_g: f64,
}

pub fn run(args: Args) -> Result<()> {
    if args.inputs == 0 || args.reps == 0 {
        bail!("--inputs and --reps must be positive");
    }
    let n = args.inputs;
    // Depth distributions shared by all techniques: up to 4 Diracs each.
    let (dists, zfs) = timing::random_inputs(n, 2015);
    let mut rows = Vec::new();
    for &name in TECHNIQUES {
        for precision in [Precision::F32, Precision::F64] {
            let t = build(name, &Params::with(precision, None))?;
            let m = t.moment_count();
            let (moments, zfs) = timing::moments_of(t.as_ref(), &dists, &zfs);
            let (ns, mean_g) = timing::ns_per_eval(t.as_ref(), &moments, &zfs, args.reps);
            rows.push(Row {
                technique: t.name(),
                precision: precision.name(),
                moments: m,
                inputs: n,
                ns_per_eval: ns,
                mean_g,
            });
        }
    }
    let mut out = std::io::stdout().lock();
    if args.json {
        writeln!(out, "{}", serde_json::to_string_pretty(&rows)?)?;
    } else {
        writeln!(
            out,
            "{:<15} {:>4} {:>3} {:>10} {:>8}",
            "technique", "prec", "m", "ns/eval", "mean G"
        )?;
        for r in &rows {
            writeln!(
                out,
                "{:<15} {:>4} {:>3} {:>10.1} {:>8.4}",
                r.technique, r.precision, r.moments, r.ns_per_eval, r.mean_g
            )?;
        }
        writeln!(
            out,
            "({n} inputs per row, median of {} runs, one core)",
            args.reps
        )?;
    }
    Ok(())
}
