//! `momentlab search`: the candidate sweep (see `momentlab::search` and docs/search.md).

use crate::search::report::{self, Reference};
use crate::search::{
    combo, read_rows, run_sweep, Dataset, FunctionTable, Hooks, Outcome, Progress, Scorer,
    SweepConfig,
};
use crate::Grid;
use anyhow::{bail, Context, Result};
use indicatif::{ProgressBar, ProgressStyle};
use std::path::{Path, PathBuf};

/// Boxed so the subcommand enum stays small.
#[derive(clap::Args, Debug)]
pub struct Args {
    #[command(flatten)]
    pub opts: Box<Opts>,
}

#[derive(clap::Args, Debug)]
pub struct Opts {
    /// Functions per candidate (2, 3 or 4 in the paper's study).
    #[arg(long, default_value_t = 4)]
    pub m: usize,
    /// Catalog file (default: the embedded basis_functions/catalog.json).
    #[arg(long)]
    pub catalog: Option<PathBuf>,
    /// Use the 9 paper bases (z..z^4, sin/cos 2πz, 4πz, exp(80(z-1))) as catalog (demos).
    #[arg(long, conflicts_with = "catalog")]
    pub builtin_catalog: bool,
    /// Directory of depth stacks (default: the default dataset).
    #[arg(long)]
    pub stacks: Option<PathBuf>,
    /// Synthetic dataset with this many texels per view (tests and demos, no stacks needed).
    #[arg(long, conflicts_with = "stacks")]
    pub synthetic: Option<usize>,
    /// Seed of the stratified fragment sample (and of the synthetic data).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Results directory (default results/search-m<m>).
    #[arg(long)]
    pub results: Option<PathBuf>,
    /// Candidates scored on every fragment at the end of racing.
    #[arg(long, default_value_t = 50)]
    pub top: usize,
    /// Every selected candidate on every fragment, no racing.
    #[arg(long)]
    pub exhaustive: bool,
    /// Only these candidate indices (comma separated).
    #[arg(long, value_delimiter = ',')]
    pub candidates: Option<Vec<u64>>,
    /// Only these candidates by function names: "f1,f2,f3,f4;g1,g2,g3,g4".
    #[arg(long, conflicts_with = "candidates")]
    pub names: Option<String>,
    /// Score the shard i of N (candidates with index % N == i), e.g. 3/16.
    #[arg(long)]
    pub shard: Option<String>,
    /// LP grid size n (uniform on [0,1]).
    #[arg(long, default_value_t = 1024)]
    pub grid: usize,
    /// LP solver: fast or reference.
    #[arg(long, default_value = "fast")]
    pub solver: String,
    /// Fragments in racing stage 0 (each next stage: × growth).
    #[arg(long, default_value_t = 1024)]
    pub first_sample: usize,
    #[arg(long, default_value_t = 4)]
    pub growth: usize,
    /// Fraction always promoted per stage.
    #[arg(long, default_value_t = 0.25)]
    pub keep: f64,
    /// Largest promoted fraction (candidates within z standard errors of the leader).
    #[arg(long, default_value_t = 0.5)]
    pub max_keep: f64,
    #[arg(long, default_value_t = 2.5)]
    pub z: f64,
    /// Fragments per solver (warm-start chain).
    #[arg(long, default_value_t = 4096)]
    pub chunk: usize,
    /// Candidates per flushed batch.
    #[arg(long, default_value_t = 64)]
    pub batch: usize,
    /// Report directory.
    #[arg(long, default_value = "reports/search")]
    pub report: PathBuf,
    /// Do not write the report.
    #[arg(long)]
    pub no_report: bool,
    /// Only write the report from existing results (e.g. after `merge`).
    #[arg(long)]
    pub report_only: bool,
    /// Other results directories (e.g. the m = 2 and m = 3 sweeps) for the side-by-side plot.
    #[arg(long, value_delimiter = ',')]
    pub compare: Vec<PathBuf>,
    /// Depths at which the Fig. 3 curves are solved.
    #[arg(long, default_value_t = 96)]
    pub fig3_points: usize,
}

fn parse_shard(s: &str) -> Result<[usize; 2]> {
    let (a, b) = s
        .split_once('/')
        .with_context(|| format!("--shard '{s}': expected i/N"))?;
    let i: usize = a
        .trim()
        .parse()
        .with_context(|| format!("--shard '{s}': bad i"))?;
    let n: usize = b
        .trim()
        .parse()
        .with_context(|| format!("--shard '{s}': bad N"))?;
    if n == 0 || i >= n {
        bail!("--shard '{s}': need 0 ≤ i < N");
    }
    Ok([i, n])
}

fn load_table(args: &Opts, grid: &Grid) -> Result<FunctionTable> {
    if args.builtin_catalog {
        return report::paper_bases(grid);
    }
    let catalog = match &args.catalog {
        Some(p) => {
            crate::basis::Catalog::load(p).with_context(|| format!("catalog {}", p.display()))?
        }
        None => crate::basis::Catalog::embedded(),
    };
    FunctionTable::from_functions(grid, catalog.functions()).context("tabulating the catalog")
}

fn load_data(args: &Opts, grid: &Grid) -> Result<(Dataset, String)> {
    if let Some(t) = args.synthetic {
        if t == 0 {
            bail!("--synthetic: need at least one texel");
        }
        return Ok((
            Dataset::synthetic(args.seed, grid, 4, t, 4)?,
            format!("synthetic:{t}:{}", args.seed),
        ));
    }
    let what = match &args.stacks {
        Some(d) => format!("stacks:{}", d.display()),
        None => "default dataset".to_string(),
    };
    bail!("{what}: building the sweep dataset from depth stacks needs kernel/metrics (not merged yet); use --synthetic N")
}

fn candidates(args: &Opts, table: &FunctionTable) -> Result<Option<Vec<u64>>> {
    if let Some(c) = &args.candidates {
        let total = combo::binomial(table.len(), args.m);
        if let Some(bad) = c.iter().find(|&&i| i >= total) {
            bail!(
                "--candidates: index {bad} out of range (C({},{}) = {total})",
                table.len(),
                args.m
            );
        }
        return Ok(Some(c.clone()));
    }
    let Some(names) = &args.names else {
        return Ok(None);
    };
    let mut out = Vec::new();
    for set in names.split(';').filter(|s| !s.trim().is_empty()) {
        let mut cols = Vec::new();
        for n in set.split(',') {
            let n = n.trim();
            let j = table
                .names()
                .iter()
                .position(|x| x == n)
                .with_context(|| format!("--names: unknown function '{n}'"))?;
            cols.push(j);
        }
        cols.sort();
        if cols.len() != args.m {
            bail!(
                "--names: '{set}' has {} functions, --m is {}",
                cols.len(),
                args.m
            );
        }
        out.push(
            combo::combination_index(&cols, table.len())
                .with_context(|| format!("--names '{set}'"))?,
        );
    }
    Ok(Some(out))
}

pub fn run(args: Args) -> Result<()> {
    let args = *args.opts;
    let grid = Grid::uniform(args.grid)?;
    let table = load_table(&args, &grid)?;
    let (data, data_name) = load_data(&args, &grid)?;
    let results = args
        .results
        .clone()
        .unwrap_or_else(|| PathBuf::from(format!("results/search-m{}", args.m)));
    let scorer = Scorer::new(&data, &table, &args.solver, args.chunk)?;
    let shard = match &args.shard {
        Some(s) => parse_shard(s)?,
        None => [0, 1],
    };
    if !args.report_only {
        let cfg = SweepConfig {
            seed: args.seed,
            top: args.top,
            exhaustive: args.exhaustive,
            candidates: candidates(&args, &table)?,
            shard,
            first_sample: args.first_sample,
            growth: args.growth,
            keep: args.keep,
            max_keep: args.max_keep,
            z: args.z,
            batch: args.batch,
            ..SweepConfig::new(args.m, &scorer, &data_name)
        };
        eprintln!(
            "search: m = {}, {} functions, {} fragments ({} non-trivial), results in {}",
            args.m,
            table.len(),
            data.total_count(),
            data.fragments().len(),
            results.display()
        );
        let bar = ProgressBar::new(0);
        bar.set_style(
            ProgressStyle::with_template(
                "{msg} [{elapsed_precise}] {wide_bar} {percent}% (ETA {eta})",
            )
            .map_err(|e| anyhow::anyhow!("progress style: {e}"))?,
        );
        let progress = |p: Progress| match p {
            Progress::Phase { name, units } => {
                bar.set_message(name);
                bar.set_length(units);
                bar.set_position(0);
                bar.reset_eta();
            }
            Progress::Advance(u) => bar.inc(u),
        };
        let t0 = std::time::Instant::now();
        let hooks = Hooks {
            stop_after_batches: None,
            progress: Some(&progress),
        };
        let outcome = run_sweep(&cfg, &scorer, &results, &hooks)?;
        bar.finish_and_clear();
        let secs = t0.elapsed().as_secs_f64();
        if let Outcome::Complete(s) = &outcome {
            eprintln!(
                "search: done in {secs:.1} s: {} candidates ({} degenerate, {} duplicates), stages {:?}, {} on all fragments, {} LP solves planned ({:.1} % of exhaustive)",
                s.candidates, s.degenerate, s.duplicates, s.stages, s.full, s.lp_solves, s.sampled_share * 100.0
            );
        }
        if shard[1] > 1 {
            eprintln!("search: shard {}/{} done; merge the shards with `momentlab merge`, then `momentlab search --report-only --results <merged>` for the report", shard[0], shard[1]);
            return Ok(());
        }
    }
    if args.no_report {
        return Ok(());
    }
    write_report(&args, &data, &results)
}

fn write_report(args: &Opts, data: &Dataset, results: &Path) -> Result<()> {
    let rows = read_rows(results)?;
    if rows.is_empty() {
        bail!("{}: no results to report", results.display());
    }
    std::fs::create_dir_all(&args.report)
        .with_context(|| format!("creating {}", args.report.display()))?;
    let m = args.m;
    eprintln!("report: reference values (LP on every fragment) …");
    let mut refs: Vec<Reference> = report::lp_references(data, &args.solver, args.chunk)?;
    refs.extend(closed_form_references());
    let errs = report::errors_of(&rows);
    let dir = &args.report;
    report::plot_histogram(
        &dir.join(format!("fig4_m{m}.svg")),
        &format!("Candidate errors, m = {m} ({} candidates)", errs.len()),
        &errs,
        &refs,
    )?;
    let mut sets = vec![(format!("m = {m}"), errs.clone())];
    for d in &args.compare {
        let r = read_rows(d)?;
        let cfg: SweepConfig = crate::search::results::read_json(&d.join("config.json"))?;
        sets.push((format!("m = {}", cfg.m), report::errors_of(&r)));
    }
    sets.sort_by(|a, b| a.0.cmp(&b.0));
    report::plot_side_by_side(&dir.join("distributions.svg"), &sets)?;
    eprintln!("report: Fig. 3 curves …");
    let kernels = report::pick_kernels(data, 3);
    let panels = report::fig3_panels(data, &kernels, args.fig3_points, &args.solver)?;
    report::plot_fig3(&dir.join("fig3.svg"), &panels)?;
    let mut md = format!(
        "# Candidate sweep, m = {m}\n\nResults: `{}`; {} fragments ({} non-trivial).\n\n![Fig. 4 analogue](fig4_m{m}.svg)\n\n## Ranking\n\n{}\n## Top 20\n\n{}\n![error distributions](distributions.svg)\n\n![Fig. 3 analogue](fig3.svg)\n",
        results.display(),
        data.total_count(),
        data.fragments().len(),
        report::ranking_text(&rows, &refs),
        report::top_table(&rows, 20)
    );
    md.push_str("\nReference values: LP candidates scored on every fragment with the same grid and solver.\n");
    std::fs::write(dir.join(format!("search_m{m}.md")), md)
        .with_context(|| format!("writing {}", dir.display()))?;
    eprintln!("report: written to {}", dir.display());
    Ok(())
}

/// Closed-form 4MSM / TMSM values (via technique::by_name + metrics) once those land.
fn closed_form_references() -> Vec<Reference> {
    Vec::new()
}
