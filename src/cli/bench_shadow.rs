//! `momentlab bench shadow [--inputs N] [--json]`: nanoseconds per evaluation of every
//! closed-form technique on one core (no rayon), at f32 and f64 arithmetic. Inputs are the
//! moments (with each technique's own basis) of random mixtures of 1–4 Diracs in [0,1] with
//! z_f uniform in [0,1]; every result is accumulated and passed through `black_box`.

use crate::technique::registry::{build, Params, Precision};
use anyhow::{bail, Result};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::hint::black_box;
use std::io::Write;
use std::time::Instant;

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
    let mut rng = ChaCha8Rng::seed_from_u64(2015);
    let mut dists: Vec<[(f64, f64); 4]> = Vec::with_capacity(n);
    let mut zfs = Vec::with_capacity(n);
    for _ in 0..n {
        let k = rng.gen_range(1..=4);
        let mut d = [(0.0, 0.0); 4];
        let mut s = 0.0;
        for x in d.iter_mut().take(k) {
            *x = (rng.gen_range(0.0..1.0), rng.gen_range(0.05..1.0));
            s += x.1;
        }
        d.iter_mut().for_each(|x| x.1 /= s);
        dists.push(d);
        zfs.push(rng.gen_range(0.0..1.0));
    }
    let mut rows = Vec::new();
    for &name in TECHNIQUES {
        for precision in [Precision::F32, Precision::F64] {
            let t = build(name, &Params::with(precision, None))?;
            let m = t.moment_count();
            let mut moments = vec![0.0; n * m];
            let mut tmp = vec![0.0; m];
            for (i, d) in dists.iter().enumerate() {
                let row = &mut moments[i * m..(i + 1) * m];
                for &(z, w) in d.iter().filter(|x| x.1 > 0.0) {
                    t.basis(z, &mut tmp);
                    row.iter_mut().zip(&tmp).for_each(|(a, b)| *a += w * b);
                }
            }
            let mut ev = t.evaluator();
            let mut times = Vec::with_capacity(args.reps);
            let mut sum = 0.0;
            for _ in 0..args.reps {
                let start = Instant::now();
                let mut acc = 0.0;
                for (i, &zf) in zfs.iter().enumerate() {
                    acc += ev.shadow(black_box(&moments[i * m..(i + 1) * m]), black_box(zf));
                }
                times.push(start.elapsed().as_secs_f64());
                sum = black_box(acc);
            }
            times.sort_by(|a, b| a.partial_cmp(b).unwrap());
            let ns = times[times.len() / 2] * 1e9 / n as f64;
            rows.push(Row {
                technique: t.name(),
                precision: precision.name(),
                moments: m,
                inputs: n,
                ns_per_eval: ns,
                mean_g: sum / n as f64,
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
