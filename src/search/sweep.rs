//! The sweep: racing (successive halving with paired comparisons), resumable, sharded.
//!
//! **Plan.** Non-trivial fragments are put in a seeded stratified order
//! ([`Dataset::stratified_order`](super::Dataset::stratified_order)); racing stage k uses the
//! next *disjoint* block of `first_sample · growth^k` fragments of that order, so every stage
//! sees a fresh stratified sample shared by all its candidates (paired differences), and the
//! estimate that promotes a candidate is not the one that selected it earlier.
//!
//! **Promotion rule (stage k).** Every candidate c of the stage is scored on the block; the
//! stage reference R (stage 0: the best of `pilot` evenly spaced candidates; later: the leader
//! of the previous stage) is scored too and each c records the paired differences
//! d = e_c − e_R. Let b be the stage leader (smallest mean). The gap ē_c − ē_b has standard
//! error at most se(d_c) + se(d_b) (Cauchy–Schwarz), exactly se(d_c) when R = b. Candidates are
//! sorted by mean; the first max(⌈keep·|C|⌉, top) are promoted, and further candidates whose gap
//! is within `z` such standard errors of the leader ("not significantly worse") are promoted
//! too, up to ⌈max_keep·|C|⌉ in all. Racing stops when at most `top` candidates remain or the
//! fragments run out; the `top` best by pooled mean are then scored on every fragment.
//!
//! **Risk.** A candidate that belongs to the true top K is lost when it is outside the kept
//! fraction *and* looks significantly worse than the leader on a block — a z-standard-error
//! event per candidate per stage (with 66045 candidates a few such events are expected at
//! z = 2.5), or when errors are so heavy-tailed that a block of thousands of fragments
//! misjudges the mean (rare geometry concentrated in few texels). The kept fraction (default
//! 1/4) is a safety margin on top of the test. Eliminated candidates keep their sampled
//! estimate, its standard error and sample size in the results.
//!
//! **Resuming.** `config.json` fixes the run; `stage{k}.jsonl` holds per-candidate sufficient
//! statistics of racing stage k, `results.jsonl` the final rows; all are appended and flushed
//! per batch in candidate-index order, torn last lines are cut, finished work is skipped, and
//! every decision is taken from the statistics as read back from the files, so an interrupted
//! and resumed run writes the same rows as an uninterrupted one (except `seconds`).
//!
//! **Shards.** `shard = [i, N]` keeps the candidates with index ≡ i (mod N); each shard races
//! its own candidates on the same fragment blocks (same seed) and scores its own top K on
//! every fragment. Merged shards give exactly the single-run rows in exhaustive mode; with
//! racing, the global top K (each of which is in its shard's top K when racing does not drop
//! it) is scored identically, while eliminated candidates may leave at different stages.

use super::results::{
    append_jsonl, read_json, read_jsonl, write_json, Row, COMPLETE_FILE, CONFIG_FILE, RESULTS_FILE,
};
use super::Scorer;
use crate::basis::candidates as bc;
use anyhow::{bail, Context, Result};
use serde::{Deserialize, Serialize};
use std::collections::{BTreeMap, BTreeSet, HashMap};
use std::path::Path;

/// Everything that determines the rows of a run (stored as `config.json`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SweepConfig {
    /// Functions per candidate.
    pub m: usize,
    /// Catalog function names, in catalog order.
    pub functions: Vec<String>,
    /// Fingerprint of the catalog tabulated on the grid.
    pub table_fingerprint: String,
    /// Grid size n.
    pub grid: usize,
    /// Description of the dataset (e.g. "stacks:data/stacks").
    pub dataset: String,
    /// Fingerprint of the dataset's fragments.
    pub dataset_fingerprint: String,
    pub seed: u64,
    /// Candidates scored on every fragment at the end of racing.
    pub top: usize,
    /// Every candidate on every fragment, no racing.
    pub exhaustive: bool,
    /// Restrict to these candidate indices (None: all C(N, m)).
    pub candidates: Option<Vec<u64>>,
    /// [i, N]: this run scores the candidates with index % N == i.
    pub shard: [usize; 2],
    /// LP solver ("fast" or "reference").
    pub solver: String,
    /// Fragments in racing stage 0.
    pub first_sample: usize,
    /// Sample growth factor per stage.
    pub growth: usize,
    /// Fraction always promoted.
    pub keep: f64,
    /// Upper bound of the promoted fraction.
    pub max_keep: f64,
    /// Standard errors within which a candidate counts as not worse than the leader.
    pub z: f64,
    /// Candidates tried to pick the stage-0 reference.
    pub pilot: usize,
    /// Relative tolerance of the rank / span decisions.
    pub tol: f64,
    /// Fragments per solver instance (warm-start chain).
    pub chunk: usize,
    /// Candidates per flushed batch.
    pub batch: usize,
}

impl SweepConfig {
    /// Defaults for a sweep of m-subsets of `scorer`'s table on its dataset.
    pub fn new(m: usize, scorer: &Scorer, dataset: &str) -> SweepConfig {
        SweepConfig {
            m,
            functions: scorer.table().names().to_vec(),
            table_fingerprint: format!("{:016x}", scorer.table().fingerprint()),
            grid: scorer.table().grid().len(),
            dataset: dataset.to_string(),
            dataset_fingerprint: format!("{:016x}", scorer.data().fingerprint()),
            seed: 1,
            top: 50,
            exhaustive: false,
            candidates: None,
            shard: [0, 1],
            solver: scorer.solver().to_string(),
            first_sample: 1024,
            growth: 4,
            keep: 0.25,
            max_keep: 0.25,
            z: 2.5,
            pilot: 32,
            tol: 1e-9,
            chunk: scorer.chunk(),
            batch: 64,
        }
    }

    /// Name of the first field that differs, if any.
    pub fn first_difference(&self, other: &SweepConfig) -> Option<String> {
        let a = serde_json::to_value(self).ok()?;
        let b = serde_json::to_value(other).ok()?;
        let (a, b) = (a.as_object()?, b.as_object()?);
        a.keys().find(|k| a.get(*k) != b.get(*k)).cloned()
    }
}

/// Deterministic description of a finished run (`complete.json`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SweepSummary {
    /// Candidates in this run (after sharding).
    pub candidates: u64,
    pub degenerate: u64,
    pub duplicates: u64,
    /// Per racing stage: (candidates, fragments in its block).
    pub stages: Vec<(u64, u64)>,
    /// Candidates scored on every fragment.
    pub full: u64,
    /// Non-trivial fragments stored in the dataset (the sample) / all fragments of the
    /// population.
    pub nontrivial_fragments: u64,
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
        }
    }
}

/// Progress events for the CLI's progress bar.
#[derive(Clone, Debug)]
pub enum Progress {
    /// A new phase with this many work units (fragment solves).
    Phase { name: String, units: u64 },
    /// Units done.
    Advance(u64),
}

/// Test and CLI hooks.
#[derive(Default)]
pub struct Hooks<'h> {
    /// Stop (as if killed) after this many flushed batches.
    pub stop_after_batches: Option<usize>,
    pub progress: Option<&'h (dyn Fn(Progress) + Sync)>,
}

/// How [`run_sweep`] ended.
#[derive(Clone, Debug, PartialEq)]
pub enum Outcome {
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

macro_rules! tryst {
    ($e:expr) => {
        if let Err(Stopped) = $e? {
            return Ok(Outcome::Stopped);
        }
    };
}

fn mean_se(n: u64, sum: f64, sumsq: f64) -> (f64, f64) {
    if n == 0 {
        return (0.0, f64::INFINITY);
    }
    let nf = n as f64;
    let mean = sum / nf;
    if n < 2 {
        return (mean, f64::INFINITY);
    }
    let var = ((sumsq - sum * sum / nf) / (nf - 1.0)).max(0.0);
    (mean, (var / nf).sqrt())
}

/// Run (or resume) the sweep described by `cfg` into `dir`.
pub fn run_sweep(cfg: &SweepConfig, scorer: &Scorer, dir: &Path, hooks: &Hooks) -> Result<Outcome> {
    // --- configuration -------------------------------------------------------------------------
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
    let [shard_i, shard_n] = cfg.shard;
    if shard_n == 0 || shard_i >= shard_n {
        bail!("invalid shard {shard_i}/{shard_n}");
    }
    if cfg.first_sample == 0 || cfg.growth == 0 || cfg.batch == 0 || cfg.top == 0 {
        bail!("first_sample, growth, batch and top must be positive");
    }
    if !(cfg.keep > 0.0 && cfg.keep <= cfg.max_keep && cfg.max_keep <= 1.0) {
        bail!("need 0 < keep ≤ max_keep ≤ 1");
    }
    let data = scorer.data();
    if data.total_count() == 0 {
        bail!("the dataset has no fragments");
    }
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
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

    let mut active: Vec<u64> = Vec::new();
    let mut flag_rows = Vec::new();
    let (mut n_degenerate, mut n_duplicate) = (0, 0);
    for ((i, _), &(degenerate, duplicate_of)) in mine.iter().zip(&flags) {
        if !degenerate && duplicate_of.is_none() {
            active.push(*i);
            continue;
        }
        n_degenerate += degenerate as u64;
        n_duplicate += duplicate_of.is_some() as u64;
        if !done.contains(i) {
            flag_rows.push(Row {
                index: *i,
                functions: names(*i),
                error: None,
                stderr: None,
                fragments: 0,
                degenerate,
                duplicate_of,
                seconds: 0.0,
                stage: 0,
                full: false,
                lp_failures: 0,
            });
        }
    }
    for batch in flag_rows.chunks(1000) {
        tryst!(w.append(&results, batch));
        done.extend(batch.iter().map(|r| r.index));
    }

    // --- racing ---------------------------------------------------------------------------------
    let nontrivial = data.fragments().len() as u64;
    let to_error = |n: u64, sum: f64, sumsq: f64| data.error_estimate(n, sum, sumsq);
    let mut lp_solves = 0u64;
    let mut stages = Vec::new();
    let mut pooled: BTreeMap<u64, StageRow> = BTreeMap::new();
    let mut cur = active.clone();
    let mut stage = 0usize;
    if !cfg.exhaustive {
        let order = data.stratified_order(cfg.seed);
        let mut offset = 0usize;
        let mut size = cfg.first_sample;
        let mut leader: Option<u64> = None;
        while cur.len() > cfg.top && offset < order.len() {
            let end = (offset + size).min(order.len());
            let mut block: Vec<u32> = order[offset..end].to_vec();
            block.sort_unstable();
            // Stage reference.
            let reference = match leader {
                Some(l) => l,
                None => {
                    let p = cfg.pilot.clamp(1, cur.len());
                    let pilots: Vec<u64> = (0..p).map(|k| cur[k * cur.len() / p]).collect();
                    let subs: Vec<Vec<usize>> = pilots.iter().map(|i| subsets[i].clone()).collect();
                    let errs = scorer.errors_many(&subs, &block, &|_| {})?;
                    lp_solves += (p * block.len()) as u64;
                    let means: Vec<f64> = errs.iter().map(|e| e.errors.iter().sum()).collect();
                    let best = (0..p)
                        .min_by(|&a, &b| means[a].total_cmp(&means[b]).then(a.cmp(&b)))
                        .unwrap();
                    pilots[best]
                }
            };
            let e_ref = scorer.errors_many(&[subsets[&reference].clone()], &block, &|_| {})?;
            let e_ref = &e_ref[0].errors;
            lp_solves += ((cur.len() + 1) * block.len()) as u64;
            stages.push((cur.len() as u64, block.len() as u64));

            let path = dir.join(format!("stage{stage}.jsonl"));
            let have: BTreeSet<u64> = read_jsonl::<StageRow>(&path, true)?
                .into_iter()
                .map(|r| r.index)
                .collect();
            let todo: Vec<u64> = cur.iter().copied().filter(|i| !have.contains(i)).collect();
            w.progress(Progress::Phase {
                name: format!(
                    "stage {stage}: {} candidates × {} fragments",
                    cur.len(),
                    block.len()
                ),
                units: (todo.len() * block.len()) as u64,
            });
            let tick = |u: u64| {
                if let Some(f) = hooks.progress {
                    f(Progress::Advance(u))
                }
            };
            for batch in todo.chunks(cfg.batch) {
                let subs: Vec<Vec<usize>> = batch.iter().map(|i| subsets[i].clone()).collect();
                let errs = scorer.errors_many(&subs, &block, &tick)?;
                let rows: Vec<StageRow> = batch
                    .iter()
                    .zip(errs)
                    .map(|(&index, e)| {
                        let mut r = StageRow {
                            index,
                            n: e.errors.len() as u64,
                            sum: 0.0,
                            sumsq: 0.0,
                            dsum: 0.0,
                            dsumsq: 0.0,
                            failures: e.failures,
                            seconds: e.seconds,
                        };
                        for (x, xr) in e.errors.iter().zip(e_ref) {
                            let d = x - xr;
                            r.sum += x;
                            r.sumsq += x * x;
                            r.dsum += d;
                            r.dsumsq += d * d;
                        }
                        r
                    })
                    .collect();
                tryst!(w.append(&path, &rows));
            }
            // Decide from the statistics as stored.
            let stored: HashMap<u64, StageRow> = read_jsonl::<StageRow>(&path, false)?
                .into_iter()
                .map(|r| (r.index, r))
                .collect();
            let mut ranked: Vec<(f64, f64, u64)> = Vec::with_capacity(cur.len());
            for i in &cur {
                let r = stored
                    .get(i)
                    .with_context(|| format!("{}: candidate {i} missing", path.display()))?;
                let (mean, _) = mean_se(r.n, r.sum, r.sumsq);
                let (_, dse) = mean_se(r.n, r.dsum, r.dsumsq);
                ranked.push((mean, dse, *i));
                let p = pooled.entry(*i).or_insert(StageRow {
                    index: *i,
                    n: 0,
                    sum: 0.0,
                    sumsq: 0.0,
                    dsum: 0.0,
                    dsumsq: 0.0,
                    failures: 0,
                    seconds: 0.0,
                });
                p.n += r.n;
                p.sum += r.sum;
                p.sumsq += r.sumsq;
                p.failures += r.failures;
                p.seconds += r.seconds;
            }
            ranked.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.2.cmp(&b.2)));
            let (best_mean, best_dse, best) = ranked[0];
            let len = ranked.len();
            let q_min = ((cfg.keep * len as f64).ceil() as usize)
                .max(cfg.top)
                .min(len);
            let q_max = ((cfg.max_keep * len as f64).ceil() as usize).max(q_min);
            let mut promoted: Vec<u64> = ranked[..q_min].iter().map(|r| r.2).collect();
            for &(mean, dse, i) in &ranked[q_min..] {
                if promoted.len() >= q_max {
                    break;
                }
                if mean - best_mean <= cfg.z * (dse + best_dse) {
                    promoted.push(i);
                }
            }
            let keep: BTreeSet<u64> = promoted.iter().copied().collect();
            let out: Vec<u64> = cur.iter().copied().filter(|i| !keep.contains(i)).collect();
            tryst!(write_eliminated(
                &mut w, &results, &mut done, &out, &pooled, stage, &names, &to_error, nontrivial
            ));
            cur = keep.into_iter().collect();
            leader = Some(best);
            offset = end;
            size = size.saturating_mul(cfg.growth);
            stage += 1;
        }
        // Final selection by pooled mean.
        if cur.len() > cfg.top {
            let mut r: Vec<(f64, u64)> = cur
                .iter()
                .map(|i| {
                    let p = &pooled[i];
                    (p.sum / p.n.max(1) as f64, *i)
                })
                .collect();
            r.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
            let keep: BTreeSet<u64> = r[..cfg.top].iter().map(|x| x.1).collect();
            let out: Vec<u64> = cur.iter().copied().filter(|i| !keep.contains(i)).collect();
            tryst!(write_eliminated(
                &mut w, &results, &mut done, &out, &pooled, stage, &names, &to_error, nontrivial
            ));
            cur = keep.into_iter().collect();
        }
    }

    // --- final: every fragment ------------------------------------------------------------------
    let ids: Vec<u32> = (0..nontrivial as u32).collect();
    lp_solves += cur.len() as u64 * nontrivial;
    let todo: Vec<u64> = cur.iter().copied().filter(|i| !done.contains(i)).collect();
    w.progress(Progress::Phase {
        name: format!("final: {} candidates × {} fragments", cur.len(), nontrivial),
        units: todo.len() as u64 * nontrivial,
    });
    let tick = |u: u64| {
        if let Some(f) = hooks.progress {
            f(Progress::Advance(u))
        }
    };
    for batch in todo.chunks(cfg.batch) {
        let subs: Vec<Vec<usize>> = batch.iter().map(|i| subsets[i].clone()).collect();
        let errs = scorer.errors_many(&subs, &ids, &tick)?;
        let rows: Vec<Row> = batch
            .iter()
            .zip(errs)
            .map(|(&index, e)| {
                let sum: f64 = e.errors.iter().sum();
                let sumsq: f64 = e.errors.iter().map(|x| x * x).sum();
                let (error, se) = to_error(nontrivial, sum, sumsq);
                let se = if nontrivial == 0 { 0.0 } else { se };
                Row {
                    index,
                    functions: names(index),
                    error: Some(error),
                    stderr: Some(se),
                    fragments: nontrivial,
                    degenerate: false,
                    duplicate_of: None,
                    seconds: e.seconds,
                    stage,
                    full: true,
                    lp_failures: e.failures,
                }
            })
            .collect();
        tryst!(w.append(&results, &rows));
        done.extend(batch);
    }

    let scored = active.len() as u64;
    let summary = SweepSummary {
        candidates: mine.len() as u64,
        degenerate: n_degenerate,
        duplicates: n_duplicate,
        stages,
        full: cur.len() as u64,
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
    };
    write_json(&dir.join(COMPLETE_FILE), &summary)?;
    Ok(Outcome::Complete(summary))
}

/// All `(index, subset)` pairs of m-subsets of 0..n in the catalog's colex order
/// ([`bc::next_subset`]: the index is the position in this enumeration).
pub fn all_subsets(n: usize, m: usize) -> Vec<(u64, Vec<usize>)> {
    let mut out = Vec::with_capacity(bc::count(n, m).min(1 << 24) as usize);
    if m == 0 || m > n {
        return out;
    }
    let mut c: Vec<usize> = (0..m).collect();
    let mut idx = 0u64;
    loop {
        out.push((idx, c.clone()));
        idx += 1;
        if !bc::next_subset(&mut c, n) {
            return out;
        }
    }
}

#[allow(clippy::too_many_arguments)]
fn write_eliminated(
    w: &mut Writer,
    results: &Path,
    done: &mut BTreeSet<u64>,
    out: &[u64],
    pooled: &BTreeMap<u64, StageRow>,
    stage: usize,
    names: &dyn Fn(u64) -> Vec<String>,
    to_error: &dyn Fn(u64, f64, f64) -> (f64, f64),
    nontrivial: u64,
) -> Result<Result<(), Stopped>> {
    let rows: Vec<Row> = out
        .iter()
        .filter(|i| !done.contains(i))
        .map(|&i| {
            let p = &pooled[&i];
            let (error, se) = to_error(p.n, p.sum, p.sumsq);
            Row {
                index: i,
                functions: names(i),
                error: Some(error),
                stderr: Some(se),
                fragments: p.n,
                degenerate: false,
                duplicate_of: None,
                seconds: p.seconds,
                stage,
                // The disjoint stage blocks may have covered every fragment.
                full: p.n == nontrivial,
                lp_failures: p.failures,
            }
        })
        .collect();
    for batch in rows.chunks(1000) {
        if let Err(Stopped) = w.append(results, batch)? {
            return Ok(Err(Stopped));
        }
        done.extend(batch.iter().map(|r| r.index));
    }
    Ok(Ok(()))
}
