//! The sweep: racing (successive halving with paired comparisons), resumable, sharded.
//!
//! **Plan.** Non-trivial fragments are put in a seeded stratified order
//! ([`Dataset::stratified_order`](super::Dataset::stratified_order)); racing stage k uses the
//! next *disjoint* block of `first_sample · growth^k` fragments of that order, so every stage
//! sees a fresh stratified sample shared by all its candidates (paired differences), and the
//! estimate that promotes a candidate is not the one that selected it earlier.
//!
//! **Elimination by evidence (stage k).** The stage reference R_k (stage 0: the best of `pilot`
//! evenly spaced candidates on a separate pilot block; later: the leader by pooled mean after
//! the previous stage) is scored on the block with every candidate c, which records the paired
//! differences d = e_c − e_R. c leaves *by confidence* when μ_c − μ_R > 0 at confidence
//! 1 − δ, δ = (1 − `confidence`) / looks with `correction` best (the default), or
//! / (looks · candidates · shards) with `all` ([`super::race::Correction`]); no candidate leaves
//! for any other reason. Stage 0's block is the *common sample*: one look, every candidate scored
//! on all of it (`common_*` of the rows, Fig. 4). Racing stops when one candidate is left
//! (resolved) or the fragments run out (the fragment budget bound); the survivors are then
//! completed on the fragments they have not seen (the pilot block, unused blocks), so they are
//! scored on every fragment, and form the set *statistically tied for first*. With probability
//! ≥ `confidence` (normal approximation of block means, or always with the Bernstein bound) the
//! best candidate is never eliminated (with `all`: no candidate is eliminated while it is at
//! least as good as its reference); so the best candidate is among the
//! tied. An `lp_budget` can end the race before a look that would exceed it: the survivors are
//! then *unresolved* (not completed, not eliminated), and the best is among them.
//!
//! Every decision uses only the stage's block, which is disjoint from the blocks that chose its
//! reference, so selection does not bias the test. Eliminated candidates keep their pooled
//! estimate (over the blocks they saw) and the evidence: the stage and look, `versus`, `diff`,
//! `diff_se` and the lower confidence bound `diff_lower` > 0 that removed them; survivors carry the paired difference to the winner pooled over all blocks (its
//! standard error is exact on blocks whose reference is the winner, else bounded by
//! se(d_c) + se(d_w), Cauchy–Schwarz).
//!
//! **Resuming.** `config.json` fixes the run; `stage{k}.jsonl` holds per-candidate sufficient
//! statistics of racing stage k, `results.jsonl` the final rows; all are appended and flushed
//! per batch in candidate-index order, torn last lines are cut, finished work is skipped, and
//! every decision is taken from the statistics as read back from the files, so an interrupted
//! and resumed run writes the same rows as an uninterrupted one (except `seconds`).
//!
//! **Shards.** `shard = [i, N]` keeps the candidates with index ≡ i (mod N); each shard races
//! its own candidates on the same fragment blocks (same seed) with δ divided by N too, so the
//! union of the shards' tied sets is a certified set of the whole sweep. Merged shards give
//! exactly the single-run rows in exhaustive mode; with racing, survivors are scored on every
//! fragment in every shard, so the global winner has the same error in both.

use super::results::{
    append_jsonl, read_json, read_jsonl, write_json, Row, COMPLETE_FILE, CONFIG_FILE, RESULTS_FILE,
};

mod racing;

/// Statistics of the survivors on the fragments they had not seen (completion block).
const FINAL_FILE: &str = "final.jsonl";
use super::config::SweepConfig;
use super::race::{Bound, Correction, Moments, StageStats};
use super::{Dataset, Scorer};
use crate::basis::candidates as bc;
use anyhow::{bail, Context, Result};
use racing::Race;
use serde::{Deserialize, Serialize};
use std::collections::{BTreeSet, HashMap};
use std::path::Path;

/// Deterministic description of a finished run (`complete.json`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SweepSummary {
    /// Candidates in this run (after sharding).
    pub candidates: u64,
    /// Degenerate candidates ([1, b] numerically rank-deficient on the grid), not scored.
    pub degenerate: u64,
    /// Duplicate candidates (same span as an earlier one), scored through their representative.
    pub duplicates: u64,
    /// Per racing stage: (candidates, fragments in its block).
    pub stages: Vec<(u64, u64)>,
    /// Candidates scored on every fragment.
    pub full: u64,
    /// Non-trivial fragments stored in the dataset (the sample) / all fragments of the
    /// population.
    pub nontrivial_fragments: u64,
    /// All fragments of the population.
    pub all_fragments: u64,
    /// Non-trivial fragments of the population the dataset was sampled from.
    #[serde(default)]
    pub nontrivial_population: u64,
    /// LP solves of the plan (pilots and stage references included).
    pub lp_solves: u64,
    /// lp_solves / (scored candidates × non-trivial fragments).
    pub sampled_share: f64,
    /// Number of merged shards (merge only).
    pub merged_shards: Option<usize>,
    /// What racing resolved (None: exhaustive or merged).
    #[serde(default)]
    pub race: Option<RaceSummary>,
}

impl SweepSummary {
    /// The counts of a run that scored `scored` candidates with `lp_solves` LP solves on
    /// `data`; the per-candidate counts, stages and race are left empty.
    fn counts(data: &Dataset, scored: u64, lp_solves: u64) -> SweepSummary {
        let nontrivial = data.fragments().len() as u64;
        SweepSummary {
            candidates: 0,
            degenerate: 0,
            duplicates: 0,
            stages: Vec::new(),
            full: 0,
            nontrivial_fragments: nontrivial,
            all_fragments: data.total_count(),
            nontrivial_population: data.nontrivial_population(),
            lp_solves,
            sampled_share: if scored * nontrivial == 0 {
                0.0
            } else {
                lp_solves as f64 / (scored * nontrivial) as f64
            },
            merged_shards: None,
            race: None,
        }
    }
}

/// What the race decided and whether its budget bound.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RaceSummary {
    /// Confidence 1 − α of the elimination tests.
    pub confidence: f64,
    /// What the confidence covers (the best's survival, or every elimination).
    #[serde(default = "Correction::legacy")]
    pub correction: Correction,
    /// One-sided bound of the tests.
    pub bound: Bound,
    /// Paired differences to the reference (true) or independent intervals.
    pub paired: bool,
    /// Fragments of the pilot block (choosing the stage-0 reference).
    pub pilot_fragments: u64,
    /// One log per stage run.
    pub stages: Vec<StageLog>,
    /// Planned looks over all stages (the Bonferroni count of [`race::stage_delta`], times the
    /// candidates and shards with [`Correction::All`]).
    #[serde(default)]
    pub looks: u64,
    /// Non-trivial fragments available (the kept sample: the fragment budget).
    pub fragment_budget: u64,
    /// Fragments the race used before completing the survivors (pilot and stage blocks).
    pub fragments_used: u64,
    /// One candidate left: the winner is certified at the stated confidence.
    pub resolved: bool,
    /// The fragments ran out with more than one candidate left.
    pub budget_bound: bool,
    /// The LP budget (`lp_budget`) ended the race before its next look: the survivors are
    /// unresolved (`unresolved` candidates, not completed).
    #[serde(default)]
    pub lp_budget_bound: bool,
    /// Candidates left at the end (statistically tied for first), the winner among them; 0 when
    /// the LP budget ended the race.
    pub tied: u64,
    /// Survivors when the LP budget ended the race (the best is among them).
    #[serde(default)]
    pub unresolved: u64,
    /// The best by pooled mean among the tied (or, when unresolved, among the survivors).
    pub winner: Option<u64>,
    /// Candidates eliminated by the tests, over all stages.
    pub confidence_eliminated: u64,
    /// Fragments of the common sample (stage 0's block): every candidate is scored on it.
    #[serde(default)]
    pub common_fragments: u64,
}

/// One racing stage.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct StageLog {
    /// Candidates entering the stage.
    pub candidates: u64,
    /// Fragments in the stage's block.
    pub fragments: u64,
    /// Index of the stage reference (the leader after the previous stage, else the pilot's best).
    pub reference: u64,
    /// Per-test error probability δ and the matching normal quantile z_{1−δ}.
    pub delta: f64,
    /// z_{1−δ}.
    pub z: f64,
    /// Candidates eliminated in this stage.
    pub confidence_eliminated: u64,
    /// Of those, eliminated at an early look (on a prefix of the block).
    #[serde(default)]
    pub early_eliminated: u64,
}

impl SweepSummary {
    pub(crate) fn merged(shards: usize, rows: u64) -> SweepSummary {
        SweepSummary {
            candidates: rows,
            degenerate: 0,
            duplicates: 0,
            stages: Vec::new(),
            full: 0,
            nontrivial_fragments: 0,
            all_fragments: 0,
            nontrivial_population: 0,
            lp_solves: 0,
            sampled_share: 0.0,
            merged_shards: Some(shards),
            race: None,
        }
    }
}

/// Progress events for the CLI's progress bar.
#[derive(Clone, Debug)]
pub enum Progress {
    /// A new phase with this many work units (fragment solves).
    Phase {
        /// Name of the phase.
        name: String,
        /// Work units of the phase.
        units: u64,
    },
    /// Units done.
    Advance(u64),
}

/// Test and CLI hooks.
#[derive(Default)]
pub struct Hooks<'h> {
    /// Stop (as if killed) after this many flushed batches.
    pub stop_after_batches: Option<usize>,
    /// Called with every progress event.
    pub progress: Option<&'h (dyn Fn(Progress) + Sync)>,
    /// Factor on the racing tests' half-widths ([`super::race::Rule::width`]; None: 1). Set
    /// only by the plan's proxy race ([`super::plan::proxy_race`]).
    pub half_width: Option<f64>,
}

/// How [`run_sweep`] ended.
#[derive(Clone, Debug, PartialEq)]
#[allow(clippy::large_enum_variant)] // one value per run
pub enum Outcome {
    /// The run finished; its summary.
    Complete(SweepSummary),
    /// Stopped by [`Hooks::stop_after_batches`].
    Stopped,
}

/// Per-candidate sufficient statistics of one racing stage (`stage{k}.jsonl`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
struct StageRow {
    index: u64,
    n: u64,
    sum: f64,
    sumsq: f64,
    /// Σ d and Σ d², d = e − e_reference.
    dsum: f64,
    dsumsq: f64,
    failures: u64,
    seconds: f64,
}

impl StageRow {
    fn empty(index: u64) -> StageRow {
        StageRow {
            index,
            n: 0,
            sum: 0.0,
            sumsq: 0.0,
            dsum: 0.0,
            dsumsq: 0.0,
            failures: 0,
            seconds: 0.0,
        }
    }
    /// Sums of the errors `e` and of the differences to the reference's errors `e_ref`.
    fn paired(index: u64, e: &[f64], e_ref: &[f64], failures: u64, seconds: f64) -> StageRow {
        let mut r = StageRow {
            failures,
            seconds,
            ..StageRow::empty(index)
        };
        for (x, xr) in e.iter().zip(e_ref) {
            let d = x - xr;
            r.n += 1;
            r.sum += x;
            r.sumsq += x * x;
            r.dsum += d;
            r.dsumsq += d * d;
        }
        r
    }
    /// Pool another block (the differences then mix references: only `e` stays meaningful).
    fn add(&mut self, o: &StageRow) {
        self.n += o.n;
        self.sum += o.sum;
        self.sumsq += o.sumsq;
        self.dsum += o.dsum;
        self.dsumsq += o.dsumsq;
        self.failures += o.failures;
        self.seconds += o.seconds;
    }
    fn stats(&self) -> StageStats {
        StageStats {
            index: self.index,
            e: Moments::new(self.n, self.sum, self.sumsq),
            d: Moments::new(self.n, self.dsum, self.dsumsq),
        }
    }
}

struct Stopped;

struct Writer<'a, 'h> {
    hooks: &'a Hooks<'h>,
    batches: usize,
}

impl Writer<'_, '_> {
    /// Append and count one batch; Err(Stopped) when the hook says stop.
    fn append<T: Serialize>(&mut self, path: &Path, rows: &[T]) -> Result<Result<(), Stopped>> {
        if rows.is_empty() {
            return Ok(Ok(()));
        }
        append_jsonl(path, rows)?;
        self.batches += 1;
        Ok(match self.hooks.stop_after_batches {
            Some(k) if self.batches >= k => Err(Stopped),
            _ => Ok(()),
        })
    }
    fn progress(&self, p: Progress) {
        if let Some(f) = self.hooks.progress {
            f(p)
        }
    }
}

macro_rules! trystv {
    ($e:expr) => {
        match $e? {
            Ok(v) => v,
            Err(Stopped) => return Ok(Outcome::Stopped),
        }
    };
}

macro_rules! tryst {
    ($e:expr) => {
        if let Err(Stopped) = $e? {
            return Ok(Outcome::Stopped);
        }
    };
}

/// Run (or resume) the sweep described by `cfg` into `dir`.
pub fn run_sweep(cfg: &SweepConfig, scorer: &Scorer, dir: &Path, hooks: &Hooks) -> Result<Outcome> {
    let _lock = open_results(cfg, scorer, dir)?;
    let [shard_i, shard_n] = cfg.shard;
    let data = scorer.data();

    // --- candidates and flags -----------------------------------------------------------------
    let all = super::select::selected(cfg)?;
    let in_run: BTreeSet<u64> = all.iter().map(|c| c.0).collect();
    let mine: Vec<(u64, Vec<usize>)> = all
        .into_iter()
        .filter(|(i, _)| *i as usize % shard_n == shard_i)
        .collect();
    let subsets: HashMap<u64, Vec<usize>> = mine.iter().cloned().collect();
    let flags = super::select::flags(scorer, &mine, &in_run, cfg.tol)?;

    let results = dir.join(RESULTS_FILE);
    let mut done: BTreeSet<u64> = read_jsonl::<Row>(&results, true)?
        .into_iter()
        .map(|r| r.index)
        .collect();
    let mut w = Writer { hooks, batches: 0 };
    let names = |i: u64| scorer.table().names_of(&subsets[&i]);

    let (active, flag_rows, n_degenerate, n_duplicate) = sort_flags(&mine, &flags, &done, &names);
    for batch in flag_rows.chunks(1000) {
        tryst!(w.append(&results, batch));
        done.extend(batch.iter().map(|r| r.index));
    }

    // --- racing / exhaustive scoring ----------------------------------------------------------
    let ctx = Ctx {
        scorer,
        subsets: &subsets,
        hooks,
        batch: cfg.batch,
    };
    let nontrivial = data.fragments().len() as u64;
    let (lp_solves, full, stages, race_summary) = if cfg.exhaustive {
        tryst!(exhaustive(
            &ctx, &mut w, &results, &mut done, &active, &names
        ));
        (
            active.len() as u64 * nontrivial,
            active.len() as u64,
            Vec::new(),
            None,
        )
    } else {
        let race = Race::new(&ctx, cfg, dir, &active, &names);
        let r = trystv!(race.run(&mut w, &mut done));
        (r.lp_solves, r.summary.tied, r.stage_sizes, Some(r.summary))
    };

    let summary = SweepSummary {
        candidates: mine.len() as u64,
        degenerate: n_degenerate,
        duplicates: n_duplicate,
        stages,
        full,
        race: race_summary,
        ..SweepSummary::counts(data, active.len() as u64, lp_solves)
    };
    write_json(&dir.join(COMPLETE_FILE), &summary)?;
    Ok(Outcome::Complete(summary))
}

/// Check `cfg` against the data, catalog and scorer given, take the results folder's lock
/// (one writer per folder: a second run into it at the same time is refused) and write its
/// configuration, or check it against the one there (a resumed run must be the same run).
fn open_results(cfg: &SweepConfig, scorer: &Scorer, dir: &Path) -> Result<crate::artefact::OutDir> {
    let expected = SweepConfig {
        functions: scorer.table().names().to_vec(),
        table_fingerprint: format!("{:016x}", scorer.table().fingerprint()),
        grid: scorer.table().grid().len(),
        dataset_fingerprint: format!("{:016x}", scorer.data().fingerprint()),
        solver: scorer.solver().to_string(),
        chunk: scorer.chunk(),
        ..cfg.clone()
    };
    if let Some(f) = expected.first_difference(cfg) {
        bail!("search config field '{f}' does not match the data/catalog/scorer given");
    }
    let nf = cfg.functions.len();
    bc::check_m(nf, cfg.m)?;
    cfg.parameters().check()?;
    if scorer.data().total_count() == 0 {
        bail!("the dataset has no fragments");
    }
    // One writer per results folder: a second run into it at the same time is refused.
    let lock = crate::artefact::OutDir::new(dir, true)?;
    lock.lock()
        .with_context(|| format!("results {}", dir.display()))?;
    let cfg_path = dir.join(CONFIG_FILE);
    if cfg_path.exists() {
        let old: SweepConfig = read_json(&cfg_path)?;
        if let Some(f) = old.first_difference(cfg) {
            bail!(
                "{} holds a run with a different configuration (field '{f}'); \
                 use another --results directory or delete it",
                dir.display()
            );
        }
    } else {
        write_json(&cfg_path, cfg)?;
    }
    Ok(lock)
}

/// The candidates to score (neither degenerate nor a duplicate), and the rows of the flagged
/// ones not yet written, with the counts of each flag.
fn sort_flags(
    mine: &[(u64, Vec<usize>)],
    flags: &[(bool, Option<u64>)],
    done: &BTreeSet<u64>,
    names: &dyn Fn(u64) -> Vec<String>,
) -> (Vec<u64>, Vec<Row>, u64, u64) {
    let mut active: Vec<u64> = Vec::new();
    let mut flag_rows = Vec::new();
    let (mut n_degenerate, mut n_duplicate) = (0, 0);
    for ((i, _), &(degenerate, duplicate_of)) in mine.iter().zip(flags) {
        if !degenerate && duplicate_of.is_none() {
            active.push(*i);
            continue;
        }
        n_degenerate += degenerate as u64;
        n_duplicate += duplicate_of.is_some() as u64;
        if !done.contains(i) {
            flag_rows.push(Row {
                degenerate,
                duplicate_of,
                ..Row::plain(*i, names(*i))
            });
        }
    }
    (active, flag_rows, n_degenerate, n_duplicate)
}

/// What the scoring helpers share.
struct Ctx<'a, 'h> {
    scorer: &'a Scorer<'a>,
    subsets: &'a HashMap<u64, Vec<usize>>,
    hooks: &'a Hooks<'h>,
    batch: usize,
}

impl Ctx<'_, '_> {
    fn tick(&self) -> impl Fn(u64) + Sync + '_ {
        move |u| {
            if let Some(f) = self.hooks.progress {
                f(Progress::Advance(u))
            }
        }
    }
    fn subs(&self, ids: &[u64]) -> Vec<Vec<usize>> {
        ids.iter().map(|i| self.subsets[i].clone()).collect()
    }
}

/// Every candidate on every fragment (`--exhaustive`).
fn exhaustive(
    ctx: &Ctx,
    w: &mut Writer,
    results: &Path,
    done: &mut BTreeSet<u64>,
    active: &[u64],
    names: &dyn Fn(u64) -> Vec<String>,
) -> Result<Result<(), Stopped>> {
    let data = ctx.scorer.data();
    let nontrivial = data.fragments().len() as u64;
    let ids: Vec<u32> = (0..nontrivial as u32).collect();
    let todo: Vec<u64> = active
        .iter()
        .copied()
        .filter(|i| !done.contains(i))
        .collect();
    w.progress(Progress::Phase {
        name: format!(
            "exhaustive: {} candidates × {} fragments",
            active.len(),
            nontrivial
        ),
        units: todo.len() as u64 * nontrivial,
    });
    let tick = ctx.tick();
    for batch in todo.chunks(ctx.batch) {
        let errs = ctx.scorer.errors_many(&ctx.subs(batch), &ids, &tick)?;
        let rows: Vec<Row> = batch
            .iter()
            .zip(errs)
            .map(|(&index, e)| {
                let m = Moments::of(&e.errors);
                let (error, se) = data.error_estimate(m.n, m.sum, m.sumsq);
                Row {
                    error: Some(error),
                    stderr: Some(if nontrivial == 0 { 0.0 } else { se }),
                    fragments: nontrivial,
                    seconds: e.seconds,
                    full: true,
                    lp_failures: e.failures,
                    ..Row::plain(index, names(index))
                }
            })
            .collect();
        if let Err(Stopped) = w.append(results, &rows)? {
            return Ok(Err(Stopped));
        }
        done.extend(batch);
    }
    Ok(Ok(()))
}

/// The statistics file of look `j` of racing stage `k`: `stage{k}.jsonl` for the first (or
/// only) look, `stage{k}.look{j}.jsonl` for the later ones (j ≥ 1).
pub fn stage_file(dir: &Path, k: usize, j: usize) -> std::path::PathBuf {
    if j == 0 {
        dir.join(format!("stage{k}.jsonl"))
    } else {
        dir.join(format!("stage{k}.look{j}.jsonl"))
    }
}

/// Every look's statistics of the race in `dir`, in order (stage 0's looks, stage 1's, …, then
/// the survivors' completion block): what the plan's forecast estimates from
/// ([`super::forecast::estimates`]).
pub fn race_looks(dir: &Path) -> Result<Vec<Vec<StageStats>>> {
    let mut paths = Vec::new();
    for k in 0.. {
        if !stage_file(dir, k, 0).exists() {
            break;
        }
        paths.extend(
            (0..=super::race::EARLY_LOOKS)
                .map(|j| stage_file(dir, k, j))
                .filter(|p| p.exists()),
        );
    }
    paths.push(dir.join(FINAL_FILE));
    paths
        .iter()
        .filter(|p| p.exists())
        .map(|p| {
            Ok(read_jsonl::<StageRow>(p, false)?
                .iter()
                .map(StageRow::stats)
                .collect())
        })
        .collect()
}

/// The best of `p` evenly spaced candidates of `cur` on the pilot block (stage-0 reference).
fn pilot_best(ctx: &Ctx, cur: &[u64], p: usize, block: &[u32]) -> Result<u64> {
    let pilots: Vec<u64> = (0..p).map(|k| cur[k * cur.len() / p]).collect();
    let errs = ctx.scorer.errors_many(&ctx.subs(&pilots), block, &|_| {})?;
    let sums: Vec<f64> = errs.iter().map(|e| e.errors.iter().sum()).collect();
    let best = (0..p)
        .min_by(|&a, &b| sums[a].total_cmp(&sums[b]).then(a.cmp(&b)))
        .expect("p ≥ 1");
    Ok(pilots[best])
}

/// Score `cands` on `block` with paired differences to `reference`, resumably into `path`
/// (one [`StageRow`] per candidate); returns the statistics as stored.
#[allow(clippy::too_many_arguments)]
fn score_block(
    ctx: &Ctx,
    w: &mut Writer,
    path: &Path,
    cands: &[u64],
    reference: u64,
    block: &[u32],
    label: String,
) -> Result<Result<HashMap<u64, StageRow>, Stopped>> {
    let have: BTreeSet<u64> = read_jsonl::<StageRow>(path, true)?
        .into_iter()
        .map(|r| r.index)
        .collect();
    let todo: Vec<u64> = cands
        .iter()
        .copied()
        .filter(|i| !have.contains(i))
        .collect();
    w.progress(Progress::Phase {
        name: label,
        units: (todo.len() * block.len()) as u64,
    });
    if !todo.is_empty() {
        // The reference's errors, scored once: where it is also a candidate of the block (the
        // stage's leader, the survivor the completion scores) its row reuses them. Every
        // (candidate, chunk) is scored by a fresh solver, so these are the same bits a second
        // scoring would give.
        let refs = ctx
            .scorer
            .errors_many(&ctx.subs(&[reference]), block, &|_| {})?;
        let e_ref = &refs[0];
        let tick = ctx.tick();
        for batch in todo.chunks(ctx.batch) {
            let others: Vec<u64> = batch.iter().copied().filter(|&i| i != reference).collect();
            let mut errs = ctx
                .scorer
                .errors_many(&ctx.subs(&others), block, &tick)?
                .into_iter();
            if others.len() < batch.len() {
                tick(block.len() as u64);
            }
            let rows: Vec<StageRow> = batch
                .iter()
                .map(|&index| {
                    let own;
                    let e = if index == reference {
                        e_ref
                    } else {
                        own = errs.next().expect("one result per candidate");
                        &own
                    };
                    StageRow::paired(index, &e.errors, &e_ref.errors, e.failures, e.seconds)
                })
                .collect();
            if let Err(Stopped) = w.append(path, &rows)? {
                return Ok(Err(Stopped));
            }
        }
    }
    Ok(Ok(read_jsonl::<StageRow>(path, false)?
        .into_iter()
        .map(|r| (r.index, r))
        .collect()))
}

/// A result row from pooled statistics (error over the fragments seen, no racing fields).
fn pooled_row(
    p: &StageRow,
    data: &super::Dataset,
    names: &dyn Fn(u64) -> Vec<String>,
    nontrivial: u64,
) -> Row {
    let (error, se) = data.error_estimate(p.n, p.sum, p.sumsq);
    Row {
        error: Some(error),
        stderr: Some(se),
        fragments: p.n,
        seconds: p.seconds,
        // The blocks may have covered every fragment.
        full: p.n == nontrivial,
        lp_failures: p.failures,
        ..Row::plain(p.index, names(p.index))
    }
}
