//! `momentlab bench lp`: median µs per LP of the reference and fast solvers on realistic
//! moment vectors (9×9 Gaussian kernels over depth maps with 1–3 clusters), their ratio measured
//! in the same run. The timing loop lives in [`crate::lp::bench`].

use super::common::usize_in;
use crate::lp::bench::{run_one, BenchConfig, BenchRow};
use crate::progress::Bar;
use anyhow::{bail, Result};

#[derive(clap::Args, Debug)]
pub struct Args {
    /// Grid sizes n (comma-separated; each 2..=100000).
    #[arg(long, value_delimiter = ',', default_values_t = vec![256usize, 1024, 4096], value_parser = usize_in(2, 100_000))]
    pub n: Vec<usize>,
    /// LPs per grid size for the fast solver (1..=1000000).
    #[arg(long, default_value_t = 2000, value_parser = usize_in(1, 1_000_000))]
    pub problems: usize,
    /// LPs per grid size for the reference solver (a prefix of the same problems; it takes
    /// milliseconds per LP; 1..=100000).
    #[arg(long, default_value_t = 30, value_parser = usize_in(1, 100_000))]
    pub reference_problems: usize,
    /// Number of basis functions: the power basis z, …, z^m (4 = MSM; 1..=8).
    #[arg(long, default_value_t = 4, value_parser = usize_in(1, 8))]
    pub m: usize,
    /// Seed of the random depth maps the moment vectors come from.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Timed repeats of the fast solvers' problem sequence; each problem's minimum time is
    /// kept (filters preemption on a shared machine; 1..=1000).
    #[arg(long, default_value_t = 3, value_parser = usize_in(1, 1000))]
    pub repeats: usize,
    /// Print JSON instead of a table.
    #[arg(long)]
    pub json: bool,
}

pub fn run(args: Args) -> Result<()> {
    if args.n.is_empty() {
        bail!("bench lp: --n needs at least one grid size");
    }
    if let Some(&n) = args.n.iter().find(|&&n| !(2..=100_000).contains(&n)) {
        bail!("bench lp: grid size {n} out of range 2..=100000");
    }
    let cfg = BenchConfig {
        ns: args.n.clone(),
        problems: args.problems,
        reference_problems: args.reference_problems,
        m: args.m,
        seed: args.seed,
        repeats: args.repeats,
    };
    let mut rows: Vec<BenchRow> = Vec::new();
    for &n in &cfg.ns {
        let bar = Bar::new(
            &format!("bench lp n = {n}: reference solves"),
            cfg.reference_problems.min(cfg.problems) as u64,
        );
        let row = run_one(&cfg, n, || bar.inc(1))?;
        bar.finish();
        rows.push(row);
    }
    if args.json {
        println!("{}", serde_json::to_string_pretty(&rows)?);
        return Ok(());
    }
    println!(
        "Algorithm 1, power basis m = {}, realistic kernel moments ({} LPs fast, {} reference per n; pricing kernel {}, MOMENTLAB_PRICING=scalar|avx2|avx512 to choose)",
        cfg.m,
        cfg.problems,
        cfg.reference_problems,
        crate::lp::pricing_kernel()
    );
    println!(
        "{:>6} | {:>12} | {:>9} {:>9} {:>9} | {:>8} {:>8} {:>8} | {:>9} {:>9} {:>9} | {:>8} {:>8} {:>8} | {:>9}",
        "n",
        "reference µs",
        "warm µs",
        "cold µs",
        "dist µs",
        "warm ×",
        "cold ×",
        "dist ×",
        "warm mean",
        "cold mean",
        "dist mean",
        "piv warm",
        "piv cold",
        "piv dist",
        "max |dG|"
    );
    for r in &rows {
        println!(
            "{:>6} | {:>12.1} | {:>9.2} {:>9.2} {:>9.2} | {:>8.0} {:>8.0} {:>8.0} | {:>9.2} {:>9.2} {:>9.2} | {:>8.2} {:>8.2} {:>8.2} | {:>9.1e}",
            r.n,
            r.reference_us,
            r.fast_warm_us,
            r.fast_cold_us,
            r.fast_dist_us,
            r.speedup_warm,
            r.speedup_cold,
            r.speedup_dist,
            r.fast_warm_mean_us,
            r.fast_cold_mean_us,
            r.fast_dist_mean_us,
            r.pivots_warm,
            r.pivots_cold,
            r.pivots_dist,
            r.max_abs_diff
        );
        println!(
            "  n = {}: max |dG| against the reference: warm {:.1e}, cold {:.1e}, dist {:.1e}",
            r.n, r.max_abs_diff_modes[0], r.max_abs_diff_modes[1], r.max_abs_diff_modes[2]
        );
        if r.status_mismatches > 0 || r.fallbacks > 0 || r.errors > 0 {
            println!(
                "  warning: n = {}: {} status mismatches, {} fallbacks to the reference, {} errors",
                r.n, r.status_mismatches, r.fallbacks, r.errors
            );
        }
    }
    println!(
        "(µs: median per LP, fast = per-problem minimum of {} repeats; warm/cold: from the moments only; dist: given the kernel's depth distribution (crossover start); × = reference median / fast median, same run)",
        cfg.repeats
    );
    Ok(())
}
