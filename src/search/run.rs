//! The library entry points of the whole sweep, shared by `momentlab search` and
//! `momentlab reproduce`: build the dataset from depth stacks, run (or resume) the sweep and score
//! the references (the report files: `crate::report::sweep`).

use super::config::Parameters;
use super::reference::{self, Reference, ReferenceCache, Summary};
use super::results::{read_rows, Row};
use super::{run_sweep, Dataset, FunctionTable, Hooks, Outcome, Progress, SamplePlan, Scorer};
use super::{SweepConfig, SweepSummary};
use crate::basis::candidates as bc;
use crate::metrics::Bias;
use crate::stack::DepthStack;
use crate::Grid;
use anyhow::{bail, Context, Result};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Everything a sweep on depth stacks needs (defaults: the m = 4 study as documented in
/// docs/search.md).
#[derive(Clone, Debug)]
pub struct SweepOptions {
    /// Functions per candidate.
    pub m: usize,
    /// Catalog file (None: the embedded catalog).
    pub catalog: Option<PathBuf>,
    /// LP grid size n (uniform on [0,1]).
    pub grid: usize,
    /// "fast" (default) or "reference" ([`crate::lp::make_solver`]).
    pub solver: String,
    /// Fragments per solver instance (warm-start chain).
    pub chunk: usize,
    /// Depth biases of PCF and of the techniques (as in `momentlab evaluate`).
    pub bias: Bias,
    /// Cap on the non-trivial fragments kept (None: all).
    pub max_fragments: Option<usize>,
    /// Seed of the fragment sample and of the racing order.
    pub seed: u64,
    /// Name of the data in the config (e.g. "default dataset 512").
    pub dataset: String,
    /// Racing parameters (see [`SweepConfig`]); `lp_budget` 0: none.
    pub lp_budget: u64,
    /// Every candidate on every fragment, no racing.
    pub exhaustive: bool,
    /// Only these candidate indices, or these candidates by names "f1,f2;g1,g2".
    pub candidates: Option<Vec<u64>>,
    /// Only these candidates by names "f1,f2;g1,g2" (see `candidates`).
    pub names: Option<String>,
    /// [i, N]: this run scores the candidates with index % N == i.
    pub shard: [usize; 2],
    /// Fragments in racing stage 0.
    pub first_sample: usize,
    /// Sample growth factor per stage.
    pub growth: usize,
    /// Early look (see [`SweepConfig::early_look`]).
    pub early_look: usize,
    /// Confidence of the elimination tests.
    pub confidence: f64,
    /// What the confidence covers (see [`SweepConfig::correction`]).
    pub correction: super::race::Correction,
    /// One-sided bound of the tests.
    pub bound: super::race::Bound,
    /// Seed of the racing order (None: `seed`); the fragment sample keeps `seed`.
    pub race_seed: Option<u64>,
    /// Candidates tried to pick the stage-0 reference.
    pub pilot: usize,
    /// Candidates per flushed batch.
    pub batch: usize,
    /// Mark the closed forms (metrics::evaluate on every fragment of the stacks).
    pub closed_forms: bool,
}

impl Default for SweepOptions {
    fn default() -> Self {
        SweepOptions {
            m: 4,
            catalog: None,
            grid: 1024,
            solver: "fast".into(),
            chunk: 4096,
            bias: Bias::default(),
            max_fragments: Some(super::DEFAULT_MAX_FRAGMENTS),
            seed: 1,
            dataset: "stacks".into(),
            lp_budget: 0,
            exhaustive: false,
            candidates: None,
            names: None,
            shard: [0, 1],
            first_sample: super::config::DEFAULT_FIRST_SAMPLE,
            growth: 4,
            early_look: super::config::DEFAULT_EARLY_LOOK,
            confidence: 0.99,
            correction: super::race::Correction::Best,
            bound: super::race::Bound::Normal,
            race_seed: None,
            pilot: 32,
            batch: 64,
            closed_forms: true,
        }
    }
}

/// What a finished sweep reports (the figures `momentlab reproduce` shows).
#[derive(Clone, Debug)]
pub struct SweepResult {
    /// None when the run was stopped by a hook (rows are then partial).
    pub summary: Option<SweepSummary>,
    /// All rows of the results directory.
    pub rows: Vec<Row>,
    /// Wall time of this call (dataset, sweep, references, report), seconds.
    pub seconds: f64,
    /// Wall time of the sweep itself, seconds.
    pub sweep_seconds: f64,
    /// Best candidate and ranks of the references (b_MSM, b_TMSM, …); None for a shard or an
    /// unfinished run.
    pub ranking: Option<Summary>,
    /// The reference values.
    pub references: Vec<Reference>,
}

impl SweepOptions {
    /// The parameters [`Parameters::check`] validates (before any expensive work).
    pub fn parameters(&self) -> Parameters {
        Parameters {
            shard: self.shard,
            first_sample: self.first_sample,
            growth: self.growth,
            batch: self.batch,
            confidence: self.confidence,
        }
    }
}

/// The catalog (file or embedded) tabulated on `grid`.
pub fn load_table(catalog: Option<&Path>, grid: &Grid) -> Result<FunctionTable> {
    let catalog = match catalog {
        Some(p) => {
            crate::basis::Catalog::load(p).with_context(|| format!("catalog {}", p.display()))?
        }
        None => crate::basis::Catalog::embedded(),
    };
    FunctionTable::from_functions(grid, catalog.functions()).context("tabulating the catalog")
}

/// Candidate indices from explicit indices or from names "f1,f2,…;g1,g2,…" (None: all).
pub fn resolve_candidates(
    table: &FunctionTable,
    m: usize,
    indices: Option<&[u64]>,
    names: Option<&str>,
) -> Result<Option<Vec<u64>>> {
    if indices.is_some() && names.is_some() {
        bail!("give candidates either by index or by names, not both");
    }
    if let Some(c) = indices {
        let total = bc::count(table.len(), m);
        if let Some(bad) = c.iter().find(|&&i| i >= total) {
            bail!(
                "candidate index {bad} out of range (C({},{m}) = {total})",
                table.len()
            );
        }
        return Ok(Some(c.to_vec()));
    }
    let Some(names) = names else {
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
                .with_context(|| format!("candidate names: unknown function '{n}'"))?;
            cols.push(j);
        }
        if cols.len() != m {
            bail!("candidate '{set}' has {} functions, m is {m}", cols.len());
        }
        out.push(bc::subset_to_index(&cols).with_context(|| format!("candidate '{set}'"))?);
    }
    Ok(Some(out))
}

/// The sweep's dataset on depth stacks ([`Dataset::from_stacks`]: grid, bias, capped
/// stratified sample) and the catalog tabulated on its grid.
pub fn stacks_dataset(
    stacks: &[DepthStack],
    opts: &SweepOptions,
) -> Result<(Dataset, FunctionTable)> {
    let grid = Grid::uniform(opts.grid)?;
    let plan = SamplePlan {
        max_fragments: opts.max_fragments,
        seed: opts.seed,
    };
    let data = Dataset::from_stacks(stacks, &grid, &opts.bias, &plan)?;
    let table = load_table(opts.catalog.as_deref(), &grid)?;
    Ok((data, table))
}

/// The whole sweep on a prepared dataset and table ([`stacks_dataset`], synthetic data, custom
/// catalogs): [`run_sweep`] into `results` (resumable), then for a complete unsharded run the
/// references (LP on the same fragments, closed forms via `metrics::evaluate` on the stacks of
/// `refs`, which keeps them for the next sweep on the same data) and the ranking
/// ([`references_for`]).
pub fn sweep_dataset(
    data: &Dataset,
    table: &FunctionTable,
    refs: &ReferenceCache,
    opts: &SweepOptions,
    results: &Path,
    progress: Option<&(dyn Fn(Progress) + Sync)>,
) -> Result<SweepResult> {
    let t0 = Instant::now();
    let scorer = Scorer::new(data, table, &opts.solver, opts.chunk)?;
    let cfg = sweep_config(opts, &scorer)?;
    let hooks = Hooks {
        stop_after_batches: None,
        progress,
        half_width: None,
    };
    let outcome = run_sweep(&cfg, &scorer, results, &hooks)?;
    let sweep_seconds = t0.elapsed().as_secs_f64();
    let rows = read_rows(results)?;
    let summary = match outcome {
        Outcome::Complete(s) => Some(s),
        Outcome::Stopped => None,
    };
    let mut out = SweepResult {
        summary,
        rows,
        seconds: 0.0,
        sweep_seconds,
        ranking: None,
        references: Vec::new(),
    };
    if out.summary.is_some() && opts.shard[1] == 1 {
        let (ranking, refs) =
            references_for(data, table, refs, &out.rows, opts, results, progress)?;
        out.ranking = Some(ranking);
        out.references = refs;
    }
    out.seconds = t0.elapsed().as_secs_f64();
    Ok(out)
}

/// The [`SweepConfig`] of `opts` on `scorer`'s data and catalog.
pub fn sweep_config(opts: &SweepOptions, scorer: &Scorer) -> Result<SweepConfig> {
    Ok(SweepConfig {
        seed: opts.race_seed.unwrap_or(opts.seed),
        lp_budget: opts.lp_budget,
        exhaustive: opts.exhaustive,
        candidates: resolve_candidates(
            scorer.table(),
            opts.m,
            opts.candidates.as_deref(),
            opts.names.as_deref(),
        )?,
        shard: opts.shard,
        first_sample: opts.first_sample,
        growth: opts.growth,
        early_look: opts.early_look,
        confidence: opts.confidence,
        correction: opts.correction,
        bound: opts.bound,
        pilot: opts.pilot,
        batch: opts.batch,
        ..SweepConfig::new(opts.m, scorer, &opts.dataset)
    })
}

/// The plan of the sweep `opts` on a prepared dataset and table, with a calibration of
/// `calibration` = [candidates, fragments] LP solves and, with `proxy` = Some(s), a proxy race
/// on 1/s of the fragments in a scratch folder under the system's temporary folder
/// ([`super::plan`]); `stacks` (when the dataset came from stacks) time the closed-form
/// references that follow a race.
pub fn plan_dataset(
    data: &Dataset,
    table: &FunctionTable,
    stacks: Option<&[DepthStack]>,
    opts: &SweepOptions,
    calibration: [usize; 2],
    proxy: Option<usize>,
) -> Result<super::plan::Plan> {
    crate::basis::candidates::check_m(table.len(), opts.m)?;
    let scorer = Scorer::new(data, table, &opts.solver, opts.chunk)?;
    let cfg = sweep_config(opts, &scorer)?;
    let scratch = std::env::temp_dir();
    let mut plan = super::plan::plan(
        &cfg,
        &scorer,
        calibration,
        proxy.map(|s| (s, scratch.as_path())),
    )?;
    if opts.shard[1] == 1 {
        plan.references_seconds = references_seconds(data, stacks, opts, &plan.calibration)?;
    }
    Ok(plan)
}

/// Wall seconds of the references [`references_for`] computes after a race on this machine:
/// the winner and the LP references on every kept fragment at the calibrated rate, and the
/// closed forms timed on the stack with the fewest fragments, scaled by the fragments of all.
fn references_seconds(
    data: &Dataset,
    stacks: Option<&[DepthStack]>,
    opts: &SweepOptions,
    calibration: &super::plan::Calibration,
) -> Result<f64> {
    let lps = (1 + reference::LP_REFERENCES as u64) * data.fragments().len() as u64;
    let mut secs = calibration.seconds_for(&[], lps, rayon::current_num_threads());
    if let Some(stacks) = stacks.filter(|_| opts.closed_forms) {
        let all: usize = stacks.iter().map(DepthStack::fragment_count).sum();
        if let Some(small) = stacks
            .iter()
            .filter(|s| s.fragment_count() > 0)
            .min_by_key(|s| s.fragment_count())
        {
            let t0 = Instant::now();
            reference::closed_form_references(std::slice::from_ref(small), &opts.bias)?;
            secs += t0.elapsed().as_secs_f64() * all as f64 / small.fragment_count() as f64;
        }
    }
    Ok(secs)
}

/// The references (LP, paired with the winner; closed forms with `opts.closed_forms`) and the
/// ranking of existing `rows` of the results folder `results`; `refs` holds what an earlier
/// sweep on the same data computed already. Progress: the phases "references (LP)" (fragment
/// solves) and "references (closed forms)".
pub fn references_for(
    data: &Dataset,
    table: &FunctionTable,
    refs: &ReferenceCache,
    rows: &[Row],
    opts: &SweepOptions,
    results: &Path,
    progress: Option<&(dyn Fn(Progress) + Sync)>,
) -> Result<(Summary, Vec<Reference>)> {
    if scored_rows(rows) == 0 {
        bail!("{}: no scored candidates to report", results.display());
    }
    let phase = |name: &str, units: u64| {
        if let Some(p) = progress {
            p(Progress::Phase {
                name: name.to_string(),
                units,
            });
        }
    };
    let tick = |u: u64| {
        if let Some(p) = progress {
            p(Progress::Advance(u));
        }
    };
    // The LP references paired with the winner on every fragment (their difference to it).
    let winner = super::tieset::winner_of(rows).and_then(|w| {
        w.functions
            .iter()
            .map(|n| table.names().iter().position(|x| x == n))
            .collect::<Option<Vec<usize>>>()
    });
    let fragments = data.fragments().len() as u64;
    let mut out = match &winner {
        Some(cols) => {
            phase(
                "references (LP)",
                (1 + reference::LP_REFERENCES as u64) * fragments,
            );
            let solver = (opts.solver.as_str(), opts.chunk);
            reference::lp_references_paired(data, table, cols, solver, refs, &tick)?
        }
        None => reference::lp_references(data, &opts.solver, opts.chunk)?,
    };
    if opts.closed_forms && refs.stacks().is_some() {
        phase("references (closed forms)", 1);
        out.extend(refs.closed_forms(&opts.bias)?);
        tick(1);
    }
    let summary = reference::summarize(rows, &out);
    Ok((summary, out))
}

fn scored_rows(rows: &[Row]) -> usize {
    rows.iter().filter(|r| r.error.is_some()).count()
}

/// One line about a finished sweep (candidates, stages, LP solves and their rate); None when
/// the sweep was stopped before the end.
pub fn sweep_line(r: &SweepResult) -> Option<String> {
    let s = r.summary.as_ref()?;
    let mut line = format!(
        "search: sweep done in {:.1} s: {} candidates ({} degenerate, {} duplicates), stages {:?}, {} on all fragments, {} LP solves planned ({:.1} % of exhaustive on the kept fragments, {:.0} solves/s)",
        r.sweep_seconds, s.candidates, s.degenerate, s.duplicates, s.stages, s.full, s.lp_solves,
        s.sampled_share * 100.0, s.lp_solves as f64 / r.sweep_seconds.max(1e-9)
    );
    if let Some(race) = &s.race {
        line.push_str(&format!(
            "\nsearch: race at {:.0} % confidence: {} tied for first, {} unresolved, {} eliminated by evidence (none otherwise); {} of {} fragments used, {}",
            race.confidence * 100.0,
            race.tied,
            race.unresolved,
            race.confidence_eliminated,
            race.fragments_used,
            race.fragment_budget,
            if race.resolved {
                "resolved"
            } else if race.lp_budget_bound {
                "the LP budget ended the race (unresolved)"
            } else {
                "the fragment budget bound"
            }
        ));
    }
    Some(line)
}

/// Lines naming the best candidate and the ranks of the references.
pub fn ranking_lines(s: &Summary) -> Vec<String> {
    let mut out = Vec::new();
    if let Some(b) = &s.best {
        out.push(format!(
            "search: winner of {} candidates: ({}) {:.4} % ± {:.4} %; {} tied for first",
            s.scored,
            b.functions.join(", "),
            b.error * 100.0,
            b.stderr * 100.0,
            s.tied
        ));
    }
    for r in &s.references {
        if let (Some(rank), Some((d, se))) = (r.rank, r.diff) {
            out.push(format!(
                "search: {} {:.4} % ± {:.4} %, rank {rank} of {}; {:+.4} ± {:.4} pp to the winner ({})",
                r.label,
                r.error * 100.0,
                r.stderr * 100.0,
                s.scored,
                d * 100.0,
                se * 100.0,
                if r.paired { "paired" } else { "unpaired" }
            ));
        }
    }
    out
}
