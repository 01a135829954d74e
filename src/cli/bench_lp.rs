//! `momentlab bench lp`: median µs per LP of the reference and fast solvers on realistic
//! moment vectors (9×9 Gaussian kernels over depth maps with 1–3 clusters), their ratio measured
//! in the same run. The timing loop lives in [`momentlab::bench::timing`].

use super::common::{resolution, usize_in};
use anyhow::{bail, Result};
use momentlab::bench::corpus::{self, Group};
use momentlab::bench::kernels::{run_one, BenchConfig, BenchRow};
use momentlab::bench::timing::{self, CorpusRow, Start};
use momentlab::progress::Bar;
use std::path::PathBuf;

/// Where the benchmark problems come from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum CorpusKind {
    /// 9×9 Gaussian kernels over random depth maps with 1–3 clusters; reference, warm, cold and
    /// distribution-start modes side by side.
    Kernels,
    /// Filter windows of fragments sampled from real depth stacks (every layer, the pipeline's
    /// bias), depths snapped to each grid.
    Stacks,
    /// The adversarial corpus (bench::corpus: flat receivers, adjacent points, tight clusters,
    /// boundary moments, steep exponentials, power bases up to m = 12).
    Adversarial,
    /// Given as moments only (the path of `momentlab lp`): mixed 1–4 Diracs on grid points and
    /// flat-receiver windows, one row each per grid size, power basis z…z^m or `--basis`.
    Moments,
}

#[derive(clap::Args, Debug)]
pub struct Args {
    /// Where the problems come from (default: windows of the rendered default dataset, the
    /// workload of evaluate and search).
    #[arg(long, value_enum, default_value_t = CorpusKind::Stacks)]
    pub corpus: CorpusKind,
    /// `--corpus stacks`: a folder of .exr depth stacks (default: render the embedded dataset).
    #[arg(long)]
    pub stacks: Option<PathBuf>,
    /// `--corpus stacks` without `--stacks`: resolution of the rendered dataset (16..=4096).
    #[arg(long, default_value_t = 512, value_parser = resolution())]
    pub resolution: usize,
    /// `--corpus adversarial`: also the n = 4096 and 8192 tables.
    #[arg(long)]
    pub large: bool,
    /// `--corpus stacks|moments`: the basis (comma-separated catalog names or formulas, e.g.
    /// "exp(40z),tanh(10(z-0.5))") instead of the power basis z…z^m.
    #[arg(long)]
    pub basis: Option<String>,
    /// Grid sizes n (comma-separated; each 2..=100000).
    #[arg(long, value_delimiter = ',', default_values_t = vec![256usize, 1024, 4096], value_parser = usize_in(2, 100_000))]
    pub n: Vec<usize>,
    /// LPs per grid size for the fast solver (1..=1000000).
    #[arg(long, alias = "problems", default_value_t = 2000, value_parser = usize_in(1, 1_000_000))]
    pub inputs: usize,
    /// LPs per grid size for the reference solver (a prefix of the same problems; it takes
    /// milliseconds per LP; with `--corpus stacks|adversarial` timed 64 problems at a time
    /// between the fast solver's passes, so that both see the same machine; 1..=100000).
    #[arg(long, alias = "reference-problems", default_value_t = 30, value_parser = usize_in(1, 100_000))]
    pub reference_inputs: usize,
    /// Number of basis functions: the power basis z, …, z^m (4 = MSM; 1..=8).
    #[arg(long, default_value_t = 4, value_parser = usize_in(1, 8))]
    pub m: usize,
    /// Seed of the random depth maps the moment vectors come from.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// `--corpus adversarial`: how many tables to list by their share of the mean (tables
    /// with a failed LP are always listed; 0..=1000).
    #[arg(long, default_value_t = 8, value_parser = usize_in(0, 1000))]
    pub top_groups: usize,
    /// Timed repeats of the fast solvers' problem sequence; each problem's minimum time is
    /// kept (filters preemption on a shared machine; 1..=1000).
    #[arg(long, default_value_t = 3, value_parser = usize_in(1, 1000))]
    pub repeats: usize,
    /// Print JSON instead of a table.
    #[arg(long)]
    pub json: bool,
}

pub fn run(args: Args) -> Result<()> {
    check_flags(&args)?;
    if args.corpus != CorpusKind::Kernels {
        return run_corpus(&args);
    }
    if args.n.is_empty() {
        bail!("bench lp: --n needs at least one grid size");
    }
    if let Some(&n) = args.n.iter().find(|&&n| !(2..=100_000).contains(&n)) {
        bail!("bench lp: grid size {n} out of range 2..=100000");
    }
    let cfg = BenchConfig {
        ns: args.n.clone(),
        problems: args.inputs,
        reference_problems: args.reference_inputs,
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
        momentlab::lp::pricing_kernel()
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
        if r.status_mismatches > 0 || r.failed > 0 || r.errors > 0 {
            println!(
                "  warning: n = {}: {} status mismatches, {} failed, {} errors",
                r.n, r.status_mismatches, r.failed, r.errors
            );
        }
    }
    println!(
        "(µs: median per LP, fast = per-problem minimum of {} repeats; warm/cold: from the moments only; dist: given the kernel's depth distribution (crossover start); × = reference median / fast median, same run)",
        cfg.repeats
    );
    Ok(())
}

/// The problem groups of `--corpus stacks` (one table per grid size, power basis z…z^m or
/// `--basis`), `--corpus moments` (two groups per grid size) or `--corpus adversarial`.
fn groups(args: &Args) -> Result<Vec<Group>> {
    if args.corpus == CorpusKind::Adversarial {
        return corpus::adversarial(6, args.large, args.seed);
    }
    let basis: Vec<String> = match &args.basis {
        Some(list) => momentlab::basis::split_list(list),
        None => (1..=args.m).map(|k| format!("z^{k}")).collect(),
    };
    let catalog = momentlab::basis::Catalog::embedded();
    let table = |n: usize| {
        let grid = momentlab::Grid::uniform(n)?;
        match &args.basis {
            Some(_) => corpus::table_for(&catalog, &grid, &basis),
            None => momentlab::bench::instances::power_table(&grid, args.m),
        }
    };
    if args.corpus == CorpusKind::Moments {
        let mut out = Vec::new();
        for &n in &args.n {
            let label = format!("[{}]", basis.join(", "));
            out.extend(corpus::moments_groups(
                &table(n)?,
                &label,
                args.inputs,
                args.seed,
            ));
        }
        return Ok(out);
    }
    let stacks = match &args.stacks {
        Some(d) => momentlab::stack::load_dir(d)?,
        None => momentlab::render::default_dataset(args.resolution)?,
    };
    let windows = momentlab::metrics::windows::stacks_corpus(&stacks, args.inputs, args.seed)?;
    args.n
        .iter()
        .map(|&n| {
            let name = format!("stacks, basis {} @ {n}", basis.join(", "));
            corpus::from_windows(&name, &basis, &table(n)?, &windows.dists, &windows.zfs)
        })
        .collect()
}

/// The `top` groups that contribute most to the corpus mean, and every group with a failure.
fn print_top_groups(r: &CorpusRow, top: usize) {
    let mut order: Vec<usize> = (0..r.groups.len()).collect();
    order.sort_by(|&a, &b| r.groups[b].total_us.total_cmp(&r.groups[a].total_us));
    let total: f64 = r.groups.iter().map(|g| g.total_us).sum();
    println!(
        "  {:<62} {:>5} {:>9} {:>10} {:>6} {:>5} {:>5}",
        "largest shares of the mean (table: kind)",
        "LPs",
        "mean µs",
        "max µs",
        "failed",
        "escal",
        "exact"
    );
    for (k, &i) in order.iter().enumerate() {
        let g = &r.groups[i];
        if k >= top && g.failed == 0 {
            continue;
        }
        println!(
            "  {:<62} {:>5} {:>9.1} {:>10.1} {:>6} {:>5} {:>5}   {:>4.1} % of the total",
            g.name,
            g.problems,
            g.total_us / g.problems.max(1) as f64,
            g.max_us,
            g.failed,
            g.escalations,
            g.exact,
            100.0 * g.total_us / total
        );
        if let Some(why) = &g.first_reason {
            println!("      first failure: {why}");
        }
    }
}

/// `--corpus stacks|moments|adversarial`: one row per group (stacks: per grid size; moments:
/// per kind and grid size) or one for the corpus (adversarial).
/// Flags the chosen corpus would ignore are errors, not silently dropped (before any work).
fn check_flags(args: &Args) -> Result<()> {
    use CorpusKind::*;
    let c = args.corpus;
    let name = format!("{c:?}").to_lowercase();
    let not_for =
        |flag: &str| anyhow::anyhow!("bench lp: {flag} does not apply to --corpus {name}");
    if args.large && c != Adversarial {
        return Err(not_for("--large"));
    }
    if (args.stacks.is_some() || args.resolution != 512) && c != Stacks {
        return Err(not_for(if args.stacks.is_some() {
            "--stacks"
        } else {
            "--resolution"
        }));
    }
    if args.basis.is_some() && !matches!(c, Stacks | Moments) {
        return Err(not_for("--basis"));
    }
    if args.basis.is_some() && args.m != 4 {
        bail!("bench lp: --basis and --m both choose the functions; give one of them");
    }
    if args.top_groups != 8 && c != Adversarial {
        return Err(not_for("--top-groups"));
    }
    if c == Adversarial {
        let given = [
            ("--n", args.n != [256, 1024, 4096]),
            ("--inputs", args.inputs != 2000),
            ("--m", args.m != 4),
        ];
        if let Some((flag, _)) = given.iter().find(|g| g.1) {
            bail!(
                "bench lp: {flag} does not apply to --corpus adversarial (its tables have fixed \
                 sizes, functions and problems; --large adds the n = 4096 and 8192 tables)"
            );
        }
    }
    Ok(())
}

fn run_corpus(args: &Args) -> Result<()> {
    let groups = groups(args)?;
    let total: u64 = groups
        .iter()
        .map(|g| g.problems.iter().map(|p| p.zf.len() as u64).sum::<u64>())
        .sum();
    let bar = Bar::new("bench lp: fast solves", total);
    let start = match args.corpus {
        CorpusKind::Moments => Start::Moments,
        _ => Start::Distribution,
    };
    let rows: Vec<CorpusRow> = if args.corpus != CorpusKind::Adversarial {
        groups
            .iter()
            .map(|g| {
                let name = match args.corpus {
                    CorpusKind::Moments => {
                        let kind = g.name.split(' ').next().unwrap_or("");
                        format!("{kind} n = {}", g.table.n())
                    }
                    _ => format!("stacks n = {}", g.table.n()),
                };
                timing::run(
                    &name,
                    std::slice::from_ref(g),
                    args.reference_inputs,
                    args.repeats,
                    start,
                    |k| bar.inc(k),
                )
            })
            .collect::<Result<_>>()?
    } else {
        // Two reference solves per table keep the reference part to seconds.
        let per = args.reference_inputs.div_ceil(groups.len()).max(2);
        vec![timing::run(
            "adversarial",
            &groups,
            per,
            args.repeats,
            start,
            |k| bar.inc(k),
        )?]
    };
    bar.finish();
    if args.json {
        println!("{}", serde_json::to_string_pretty(&rows)?);
        return Ok(());
    }
    let given = match start {
        Start::Moments => "the moments only",
        Start::Distribution => "each window's depth distribution",
    };
    println!(
        "Algorithm 1, fast solver given {given} (one solver per table, warm), µs per LP: per-problem minimum of {} passes; reference = good_lp + microlp on a prefix, same run; pricing kernel {}",
        args.repeats,
        momentlab::lp::pricing_kernel()
    );
    println!(
        "{:<18} {:>7} | {:>8} {:>8} {:>8} {:>8} {:>9} | {:>7} {:>6} {:>6} {:>5} | {:>5} {:>10} {:>10} {:>8} {:>8}",
        "corpus", "LPs", "mean", "median", "p99", "p99.9", "max", "optimal", "infeas", "failed", "escal",
        "ref n", "ref mean", "ref median", "× mean", "max |dG|"
    );
    for r in &rows {
        println!(
            "{:<18} {:>7} | {:>8.2} {:>8.2} {:>8.2} {:>8.2} {:>9.1} | {:>7} {:>6} {:>6} {:>5} | {:>5} {:>10.0} {:>10.0} {:>8.0} {:>8.1e}",
            r.corpus,
            r.problems,
            r.fast_us.mean,
            r.fast_us.median,
            r.fast_us.p99,
            r.fast_us.p999,
            r.fast_us.max,
            r.optimal,
            r.infeasible,
            r.failed,
            r.escalations,
            r.reference_problems,
            r.reference_us.mean,
            r.reference_us.median,
            r.speedup_mean,
            r.max_abs_diff
        );
        if r.reference_invalid > 0 || r.exact > 0 {
            println!(
                "  {}: {} reference answers invalid (not compared), {} handed to the exact simplex",
                r.corpus, r.reference_invalid, r.exact
            );
        }
        if r.groups.len() > 1 {
            print_top_groups(r, args.top_groups);
        }
    }
    if start == Start::Moments {
        for pair in rows.chunks(2) {
            if let [d, f] = pair {
                println!(
                    "  {} / {}: mean {:.2}× (median {:.2}×)",
                    f.corpus,
                    d.corpus,
                    f.fast_us.mean / d.fast_us.mean,
                    f.fast_us.median / d.fast_us.median
                );
            }
        }
    }
    println!("(× mean = reference mean / fast mean on the same problems; failed = no certificate for either verdict)");
    Ok(())
}
