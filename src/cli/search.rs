//! `momentlab search`: the candidate sweep (see `momentlab::search` and docs/search.md).

use super::common::{resolution, stacks_or_default, usize_in, MAX_GRID};
use anyhow::{bail, Context, Result};
use momentlab::artefact::OutDir;
use momentlab::basis::candidates::MAX_M;
use momentlab::metrics::Bias;
use momentlab::report::sweep::{self as sweep_report, ReportOptions};
use momentlab::search::reference::ReferenceCache;
use momentlab::search::reference::{self, Summary};
use momentlab::search::run::{load_table, ranking_lines, references_for, sweep_line};
use momentlab::search::{
    read_rows, sweep_dataset, Dataset, FunctionTable, Progress, SamplePlan, SweepOptions,
    SweepResult,
};
use momentlab::stack::DepthStack;
use momentlab::Grid;
use std::path::PathBuf;

/// Boxed so the subcommand enum stays small.
#[derive(clap::Args, Debug)]
pub struct Args {
    #[command(flatten)]
    pub opts: Box<Opts>,
}

#[derive(clap::Args, Debug)]
pub struct Opts {
    /// Functions per candidate (2, 3 or 4 in the paper's study; 1..=8, at most the catalog size).
    #[arg(long, default_value_t = 4, value_parser = usize_in(1, MAX_M as u64))]
    pub m: usize,
    /// Catalog file (default: the embedded basis_functions/catalog.json).
    #[arg(long)]
    pub catalog: Option<PathBuf>,
    /// Use the 9 paper bases (z..z^4, sin/cos 2πz, 4πz, exp(80(z-1))) as catalog (demos).
    #[arg(long, conflicts_with = "catalog")]
    pub builtin_catalog: bool,
    /// Directory of depth stacks (default: render the embedded default dataset, said so on
    /// stderr).
    #[arg(long)]
    pub stacks: Option<PathBuf>,
    /// Shadow-map resolution when rendering the default dataset (16..=4096).
    #[arg(long, default_value_t = 512, value_parser = resolution())]
    pub resolution: usize,
    /// Keep at most this many non-trivial fragments (stratified by view and layer; 0 = all).
    #[arg(long, default_value_t = momentlab::search::DEFAULT_MAX_FRAGMENTS)]
    pub max_fragments: usize,
    /// Synthetic dataset with this many texels per view (tests and demos, no stacks needed;
    /// 1..=1000000).
    #[arg(long, conflicts_with_all = ["stacks", "max_fragments", "resolution"], value_parser = usize_in(1, 1_000_000))]
    pub synthetic: Option<usize>,
    /// Seed of the stratified fragment sample (and of the synthetic data).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Folder of the sweep's rows (config.json, results.jsonl; default results/search-m<m>),
    /// kept apart from the report (--out).
    #[arg(long)]
    pub results: Option<PathBuf>,
    /// LP solves after which the race starts no further look (0 = no budget). The budget never
    /// eliminates a candidate: the race ends with its survivors reported as unresolved.
    #[arg(long, default_value_t = 0)]
    pub lp_budget: u64,
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
    /// LP grid size n (uniform on [0,1]; 2..=1048576).
    #[arg(long, default_value_t = 1024, value_parser = usize_in(2, MAX_GRID))]
    pub grid: usize,
    /// LP solver: fast (default: every answer certified; unsettled LPs count as failures,
    /// G = 0, reported per candidate) or reference (microlp, uncertified, slow). "fast-strict"
    /// is accepted as fast.
    #[arg(long, default_value = "fast")]
    pub solver: String,
    /// Fragments in racing stage 0, the common sample every candidate is scored on (Fig. 4;
    /// each next stage: × growth; ≥ 1).
    #[arg(long, default_value_t = momentlab::search::config::DEFAULT_FIRST_SAMPLE, value_parser = usize_in(1, u32::MAX as u64))]
    pub first_sample: usize,
    /// Factor by which each racing stage's fragment block grows (2..=64).
    #[arg(long, default_value_t = 4, value_parser = usize_in(2, 64))]
    pub growth: usize,
    /// Early looks: a stage block after stage 0 is first tested on its prefixes of 1/8, 1/4
    /// and 1/2 that hold at least this many fragments, by confidence only, the survivors of
    /// each going on to the next and then to the whole block (0 = never).
    #[arg(long, default_value_t = momentlab::search::config::DEFAULT_EARLY_LOOK)]
    pub early_look: usize,
    /// Confidence of the elimination tests: a candidate leaves by confidence only when it is
    /// worse than the stage reference at this level (docs/search.md).
    #[arg(long, default_value_t = 0.99)]
    pub confidence: f64,
    /// What --confidence covers: best (the best candidate survives the race; α split over the
    /// looks) or all (no candidate anywhere is eliminated while as good as its reference; α
    /// split over the looks, the candidates and the shards: wider tests, more LP solves).
    #[arg(long, default_value = "best")]
    pub correction: String,
    /// Bound of the tests: normal (paired mean ± z·s.e.) or bernstein (empirical Bernstein,
    /// distribution-free, wider).
    #[arg(long, default_value = "normal")]
    pub bound: String,
    /// Seed of the racing order only (default: --seed); the fragment sample keeps --seed.
    #[arg(long)]
    pub race_seed: Option<u64>,
    /// Only compare the finished race in --results with this exhaustive results directory of
    /// the same candidates and fragments, print the check (is the exhaustive winner tied /
    /// certified, confidence-eliminated candidates better than the race winner, false
    /// eliminations) and exit.
    #[arg(long)]
    pub validate: Option<PathBuf>,
    /// Candidates tried to pick the stage-0 reference (≥ 1).
    #[arg(long, default_value_t = 32, value_parser = usize_in(1, u32::MAX as u64))]
    pub pilot: usize,
    /// Fragments per solver (warm-start chain; ≥ 1).
    #[arg(long, default_value_t = 4096, value_parser = usize_in(1, u32::MAX as u64))]
    pub chunk: usize,
    /// Candidates per flushed batch (≥ 1).
    #[arg(long, default_value_t = 64, value_parser = usize_in(1, u32::MAX as u64))]
    pub batch: usize,
    /// Output folder of the report (default: <results>/report; the tracked reports/ folder
    /// only when given).
    #[arg(long, alias = "report")]
    pub out: Option<PathBuf>,
    /// Do not write the report.
    #[arg(long)]
    pub no_report: bool,
    /// Replace existing report files in --out. The rows in --results are never replaced: a
    /// rerun of the same sweep resumes them (docs/files.md).
    #[arg(long)]
    pub force: bool,
    /// Only write the report from existing results (e.g. after `merge`).
    #[arg(long)]
    pub report_only: bool,
    /// Dry run: candidates, fragments, LP solves and core-hours (from a short calibration on
    /// this machine) for racing and --exhaustive, per task with --shard, and racing's expected
    /// cost from a proxy race on 1/S of the fragments (--plan-proxy); nothing is written
    /// outside a scratch folder in the system's temporary folder, removed after.
    #[arg(long, conflicts_with = "report_only")]
    pub plan: bool,
    /// With --plan: the proxy race runs on 1/S of the fragments (0: no proxy race, only the
    /// upper bound of the racing schedule).
    #[arg(long, default_value_t = momentlab::search::plan::PROXY_SHARE, requires = "plan", value_parser = usize_in(0, 1024))]
    pub plan_proxy: usize,
    /// Other results directories (e.g. the m = 2 and m = 3 sweeps) for the side-by-side plot.
    #[arg(long, value_delimiter = ',')]
    pub compare: Vec<PathBuf>,
    /// Depths at which the Fig. 3 curves are solved (2..=10000).
    #[arg(long, default_value_t = 96, value_parser = usize_in(2, 10_000))]
    pub fig3_points: usize,
    /// Do not evaluate the closed forms (hamburger4, tmsm, vsm, esm) for the report.
    #[arg(long)]
    pub no_closed_forms: bool,
    /// Print the ranking (best candidate, references and their ranks) as JSON on stdout.
    #[arg(long, conflicts_with = "plan")]
    pub json: bool,
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

fn table_of(args: &Opts, grid: &Grid) -> Result<FunctionTable> {
    if args.builtin_catalog {
        return reference::paper_bases(grid);
    }
    load_table(args.catalog.as_deref(), grid)
}

/// The dataset, its name for the config, and the stacks it came from (None: synthetic).
fn load_data(
    args: &Opts,
    grid: &Grid,
    bias: &Bias,
) -> Result<(Dataset, String, Option<Vec<DepthStack>>)> {
    if let Some(t) = args.synthetic {
        if t == 0 {
            bail!("--synthetic: need at least one texel");
        }
        return Ok((
            Dataset::synthetic(args.seed, grid, 4, t, 4)?,
            format!("synthetic:{t}:{}", args.seed),
            None,
        ));
    }
    let stacks = stacks_or_default(args.stacks.as_deref(), args.resolution, "search")?;
    let name = match &args.stacks {
        Some(d) => format!("stacks:{}", d.display()),
        None => format!("default dataset {}", args.resolution),
    };
    let plan = SamplePlan {
        max_fragments: (args.max_fragments > 0).then_some(args.max_fragments),
        seed: args.seed,
    };
    let data = Dataset::from_stacks(&stacks, grid, bias, &plan)?;
    Ok((data, name, Some(stacks)))
}

/// Check the flags that the sweep's parameters do not cover before any expensive work.
fn check_flags(args: &Opts) -> Result<()> {
    momentlab::search::race::Bound::parse(&args.bound).context("--bound")?;
    momentlab::search::race::Correction::parse(&args.correction).context("--correction")?;
    if args.report_only && args.no_report {
        bail!("--report-only and --no-report contradict each other");
    }
    if let Some(v) = &args.validate {
        if !v.join("results.jsonl").exists() {
            bail!("--validate {}: no results.jsonl there", v.display());
        }
    }
    args.solver
        .parse::<momentlab::lp::SolverKind>()
        .context("--solver")?;
    for c in &args.compare {
        momentlab::search::merge::verify_results(c, false)
            .with_context(|| format!("--compare {}", c.display()))?;
    }
    Ok(())
}

/// `--validate DIR`: the finished race in `results` against the exhaustive run in DIR.
fn validate(args: &Opts, exhaustive: &std::path::Path) -> Result<()> {
    let results = args
        .results
        .clone()
        .unwrap_or_else(|| PathBuf::from(format!("results/search-m{}", args.m)));
    let rows = read_rows(&results)
        .with_context(|| format!("--validate: reading the race in {}", results.display()))?;
    let v = momentlab::search::tieset::validate(&rows, &read_rows(exhaustive)?)?;
    for l in v.lines() {
        println!("validate: {l}");
    }
    Ok(())
}

pub fn run(args: Args) -> Result<()> {
    let args = *args.opts;
    check_flags(&args)?;
    if let Some(ex) = &args.validate {
        return validate(&args, ex);
    }
    let grid = Grid::uniform(args.grid)?;
    let table = table_of(&args, &grid)?;
    // Before any rendering or sampling: m, the candidate selection, the sweep's parameters, the
    // results folder (a folder, not in use by another run), for --report-only results that are
    // whole, and the report's files (refused if they exist, unless --force).
    momentlab::basis::candidates::check_m(table.len(), args.m)?;
    momentlab::search::run::resolve_candidates(
        &table,
        args.m,
        args.candidates.as_deref(),
        args.names.as_deref(),
    )?;
    let mut opts = sweep_options(&args)?;
    let results = args
        .results
        .clone()
        .unwrap_or_else(|| PathBuf::from(format!("results/search-m{}", args.m)));
    let report_dir = args.out.clone().unwrap_or_else(|| results.join("report"));
    let report = OutDir::new(&report_dir, args.force).context("--out")?;
    let writes_report = !args.no_report && !args.plan && opts.shard[1] == 1;
    if writes_report {
        report
            .reserve(sweep_report::files(args.m))
            .context("--out")?;
    }
    let results_dir = OutDir::new(&results, true).context("--results")?;
    let verified = if args.report_only {
        Some(verified_rows(&results)?)
    } else {
        if !args.plan {
            // Refuse a folder another run is writing before building the dataset; held until
            // the sweep (which takes it again, re-entrantly) is done.
            results_dir.lock().context("--results")?;
        }
        None
    };
    let t_data = std::time::Instant::now();
    let (data, data_name, stacks) = load_data(&args, &grid, &opts.bias)?;
    opts.dataset = data_name;
    // Read when the report is written: a sweep's `complete.json` exists only at its end.
    let report_opts = || ReportOptions {
        compare: args.compare.clone(),
        fig3_points: args.fig3_points,
        ..ReportOptions::of(&opts, &results)
    };
    eprintln!(
        "search: m = {}, {} functions, {} fragments ({} non-trivial, {} kept = {:.2} %; dataset built in {:.1} s), results in {}",
        args.m,
        table.len(),
        data.total_count(),
        data.nontrivial_population(),
        data.fragments().len(),
        data.sampled_fraction() * 100.0,
        t_data.elapsed().as_secs_f64(),
        results.display()
    );
    if args.plan {
        let setup = t_data.elapsed().as_secs_f64();
        let plan = momentlab::search::run::plan_dataset(
            &data,
            &table,
            stacks.as_deref(),
            &opts,
            super::plan::calibration(&opts),
            (args.plan_proxy > 0).then_some(args.plan_proxy),
        )?;
        super::plan::print(&plan, &opts, setup);
        return Ok(());
    }
    if let Some(rows) = verified {
        let cache = ReferenceCache::new(stacks.as_deref());
        let (summary, refs) = references_for(&data, &table, &cache, &rows, &opts, &results, None)?;
        let ro = report_opts();
        sweep_report::write(&report, &rows, &data, &refs, &ro)?;
        print_ranking(&summary, args.json, ro.partial.as_ref())?;
        eprintln!("report: written to {}", report_dir.display());
        return Ok(());
    }
    let r = sweep(&data, &table, stacks.as_deref(), &opts, &results)?;
    if opts.shard[1] > 1 {
        eprintln!("search: shard {}/{} done; merge the shards with `momentlab merge`, then `momentlab search --report-only --results <merged>` for the report", opts.shard[0], opts.shard[1]);
        return Ok(());
    }
    if let Some(summary) = &r.ranking {
        if writes_report {
            sweep_report::write(&report, &r.rows, &data, &r.references, &report_opts())?;
        }
        print_ranking(summary, args.json, None)?;
        if writes_report {
            eprintln!("report: written to {}", report_dir.display());
        }
    }
    Ok(())
}

/// The sweep's options from the command line (the dataset's name is set once it is built),
/// checked.
fn sweep_options(args: &Opts) -> Result<SweepOptions> {
    let shard = match &args.shard {
        Some(s) => parse_shard(s)?,
        None => [0, 1],
    };
    let opts = SweepOptions {
        m: args.m,
        catalog: args.catalog.clone(),
        grid: args.grid,
        solver: args.solver.clone(),
        chunk: args.chunk,
        bias: Bias::default(),
        max_fragments: (args.max_fragments > 0).then_some(args.max_fragments),
        seed: args.seed,
        dataset: String::new(),
        lp_budget: args.lp_budget,
        exhaustive: args.exhaustive,
        candidates: args.candidates.clone(),
        names: args.names.clone(),
        shard,
        first_sample: args.first_sample,
        growth: args.growth,
        early_look: args.early_look,
        confidence: args.confidence,
        bound: momentlab::search::race::Bound::parse(&args.bound).context("--bound")?,
        correction: momentlab::search::race::Correction::parse(&args.correction)
            .context("--correction")?,
        race_seed: args.race_seed,
        pilot: args.pilot,
        batch: args.batch,
        closed_forms: !args.no_closed_forms,
    };
    opts.parameters().check()?;
    Ok(opts)
}

/// `--report-only`: the rows of the finished (or partially merged) whole sweep in `results`.
fn verified_rows(results: &std::path::Path) -> Result<Vec<momentlab::search::Row>> {
    // A partial merge (`partial.json`, no completion marker) is reported as partial.
    let partial =
        std::fs::symlink_metadata(results.join(momentlab::search::results::PARTIAL_FILE)).is_ok();
    let v = momentlab::search::merge::verify_results(results, partial).context("--report-only")?;
    let [i, n] = v.config.shard;
    if n > 1 {
        bail!(
            "--report-only: {} holds shard {i}/{n} of a sharded run, not the whole sweep; \
             merge the shards first (momentlab merge)",
            results.display()
        );
    }
    Ok(v.rows)
}

/// The sweep with a progress bar, its closing line and, for a race, where the LP time went
/// (stderr).
fn sweep(
    data: &Dataset,
    table: &FunctionTable,
    stacks: Option<&[DepthStack]>,
    opts: &SweepOptions,
    results: &std::path::Path,
) -> Result<SweepResult> {
    let bar = momentlab::progress::Bar::new("search", 0);
    let progress = |p: Progress| match p {
        Progress::Phase { name, units } => bar.phase(&format!("search {name}"), units),
        Progress::Advance(u) => bar.inc(u),
    };
    let refs = ReferenceCache::new(stacks);
    let r = sweep_dataset(data, table, &refs, opts, results, Some(&progress))?;
    bar.finish();
    if let Some(line) = sweep_line(&r) {
        eprintln!("{line}");
    }
    if r.summary.is_some() {
        // Where the time went (stage files of a racing run; none for --exhaustive).
        let times = momentlab::search::timing::stage_family_times(results, table, opts.m)?;
        if !times.is_empty() {
            eprintln!("search: LP time per stage and candidate family (CPU seconds in the LPs)");
            eprint!("{}", momentlab::search::timing::render(&times));
        }
    }
    Ok(r)
}

/// The ranking lines (stderr) and, with `json`, the summary (stdout); results of a partial
/// merge say so first, and the JSON gains "partial" (what is missing).
fn print_ranking(
    s: &Summary,
    json: bool,
    partial: Option<&momentlab::search::merge::Partial>,
) -> Result<()> {
    if let Some(p) = partial {
        eprintln!("search: {}", p.line());
    }
    for line in ranking_lines(s) {
        eprintln!("{line}");
    }
    if json {
        let mut v = serde_json::to_value(s)?;
        if let (Some(p), Some(o)) = (partial, v.as_object_mut()) {
            o.insert("partial".into(), serde_json::to_value(p)?);
        }
        println!("{}", serde_json::to_string_pretty(&v)?);
    }
    Ok(())
}
