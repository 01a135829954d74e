//! What a sweep will cost before it runs (`momentlab search --plan`): the candidates it scores,
//! the racing stages and LP solves exactly as [`super::run_sweep`] schedules them (for racing
//! and for the exhaustive mode, per shard), the core-hours from a short calibration of the
//! LP solver on this machine and data (a sample stratified by candidate family, all threads),
//! and racing's expected cost from a proxy race ([`proxy_race`]).
//!
//! LP solves (as `SweepSummary::lp_solves`): the pilot block P picks the stage-0 reference
//! (pilot·|P| solves); racing stage k with |C_k| candidates on a block of B_k fragments costs
//! (|C_k| + 1)·B_k (the stage reference included); |C_{k+1}| ≤ |C_k| (eliminations by
//! confidence lower it, and racing stops early when one candidate is left); then the survivors
//! on the fragments they have not seen, (|C| + 1)·|rest|. The racing schedule is therefore an
//! upper bound, reached when no candidate is eliminated; with an LP budget it stops before the
//! look that would exceed it, as the run does, and completes no one. Exhaustive: |C|·F, exact. How many leave by confidence, and when, depends on
//! the gaps between the leaders and the field, which only racing itself finds: the proxy race
//! runs it on a stratified 1/s of the fragments and scales its LP solves by s.

use super::config::SweepConfig;
use super::forecast;
use super::refine;
use super::results::{read_rows, Row};
use super::select;
use super::sweep::{race_looks, run_sweep, Hooks, Outcome};
use super::Scorer;
use crate::artefact::OutDir;
use anyhow::{bail, Result};
use std::collections::{BTreeSet, HashMap};
use std::path::Path;
use std::time::Instant;

/// The work of one run (one shard).
#[derive(Clone, Debug, PartialEq)]
pub struct Schedule {
    /// Racing stages: (candidates, fragments in the block).
    pub stages: Vec<(u64, u64)>,
    /// Candidates scored on every kept non-trivial fragment.
    pub full: u64,
    /// LP solves, pilots and stage references included.
    pub lp_solves: u64,
}

/// The schedule of a run scoring `active` candidates on `fragments` kept non-trivial fragments
/// (racing unless `cfg.exhaustive`) when no candidate is eliminated: racing's upper bound.
pub fn schedule(cfg: &SweepConfig, active: u64, fragments: u64) -> Schedule {
    let (cur, mut lp, mut stages) = (active, 0u64, Vec::new());
    if cfg.exhaustive {
        return Schedule {
            stages,
            full: cur,
            lp_solves: cur * fragments,
        };
    }
    let (pilot, blocks) = super::race::blocks(fragments as usize, cfg.first_sample, cfg.growth);
    let over =
        |lp: u64, len: usize| cfg.lp_budget > 0 && lp + (cur + 1) * len as u64 > cfg.lp_budget;
    let mut run = 0;
    let mut stopped = false;
    'stages: for (k, b) in blocks.iter().enumerate() {
        if cur <= 1 {
            break;
        }
        let looks = super::race::looks(k, b.len(), cfg.early_look);
        if over(lp, looks[0].len()) {
            stopped = true;
            break;
        }
        if stages.is_empty() {
            lp += (cfg.pilot as u64).clamp(1, cur) * pilot.len() as u64;
        }
        stages.push((cur, b.len() as u64));
        run += 1;
        for (j, part) in looks.iter().enumerate() {
            if j > 0 && over(lp, part.len()) {
                stopped = true;
                break 'stages;
            }
            lp += (cur + 1) * part.len() as u64;
        }
    }
    if stopped && cur > 1 {
        return Schedule {
            stages,
            full: 0,
            lp_solves: lp,
        };
    }
    let rest: u64 = if run > 0 {
        pilot.len() as u64 + blocks[run..].iter().map(|b| b.len() as u64).sum::<u64>()
    } else {
        fragments
    };
    if cur > 0 && rest > 0 {
        lp += (cur + 1) * rest;
    }
    Schedule {
        stages,
        full: cur,
        lp_solves: lp,
    }
}

/// A timed sample of LP solves: candidates stratified by family (steepest exponential,
/// [`super::timing::family_of`]) in proportion to the family's share of the run, on the first
/// fragments of the stratified order (a racing block), scored the way the race scores a stage
/// (all threads, one solver per candidate and chunk). The families' LP costs differ by up to 8×
/// (docs/search.md), so an unstratified sample misjudges the mix.
#[derive(Clone, Debug)]
pub struct Calibration {
    /// Candidates sampled.
    pub candidates: usize,
    /// Fragments each sampled candidate was scored on.
    pub fragments: usize,
    /// LP solves of the sample.
    pub lp_solves: u64,
    /// Wall time of the sample on `threads` threads.
    pub seconds: f64,
    /// Threads the sample ran on (those of the sweep).
    pub threads: usize,
    /// Unsettled LPs in the sample.
    pub failures: u64,
    /// Per family: (family, candidates sampled, candidates in the run).
    pub strata: Vec<(&'static str, usize, usize)>,
    /// Per family sampled: (family, CPU µs per LP).
    pub family_us: Vec<(&'static str, f64)>,
    /// CPU seconds in the sample's LPs (their sum over the threads).
    pub cpu_seconds: f64,
}

impl Calibration {
    /// LP solves per second on one core (the sample's wall-time throughput per thread).
    pub fn rate(&self) -> f64 {
        self.lp_solves as f64 / (self.seconds.max(1e-9) * self.threads.max(1) as f64)
    }
    /// Core-hours for `lp_solves` solves at the calibrated rate.
    pub fn core_hours(&self, lp_solves: u64) -> f64 {
        lp_solves as f64 / self.rate() / 3600.0
    }
    /// Wall seconds on `threads` threads for LP solves counted per family (`other`: solves of
    /// no known family, at the sample's mean): Σ_f LP_f · µs_f of the sample's CPU time per LP,
    /// divided by the threads and by the sample's parallel efficiency (CPU seconds in its LPs /
    /// (wall · threads)), so that a stage rich in costly families costs more. 0 when nothing
    /// was timed.
    pub fn seconds_for(
        &self,
        by_family: &[(&'static str, u64)],
        other: u64,
        threads: usize,
    ) -> f64 {
        if self.lp_solves == 0 {
            return 0.0;
        }
        if self.cpu_seconds <= 0.0 {
            let all = by_family.iter().map(|f| f.1).sum::<u64>() + other;
            return self.core_hours(all) * 3600.0 / threads.max(1) as f64;
        }
        let mean_us = self.cpu_seconds * 1e6 / self.lp_solves as f64;
        let us = |f: &str| {
            self.family_us
                .iter()
                .find(|x| x.0 == f)
                .map_or(mean_us, |x| x.1)
        };
        let cpu_us: f64 = by_family
            .iter()
            .map(|&(f, n)| n as f64 * us(f))
            .sum::<f64>()
            + other as f64 * mean_us;
        let efficiency =
            (self.cpu_seconds / (self.seconds.max(1e-9) * self.threads.max(1) as f64)).min(1.0);
        cpu_us * 1e-6 / (threads.max(1) as f64 * efficiency)
    }
}

/// The plan of a sweep over all shards of `cfg.shard[1]`.
#[derive(Clone, Debug)]
pub struct Plan {
    /// Candidates selected (before sharding), degenerate ones, duplicate spans.
    pub candidates: u64,
    /// Degenerate candidates.
    pub degenerate: u64,
    /// Duplicate candidates.
    pub duplicates: u64,
    /// Kept non-trivial fragments.
    pub fragments: u64,
    /// Per shard: racing (an upper bound, see the module docs), exhaustive.
    pub racing: Vec<Schedule>,
    /// Per shard: exhaustive.
    pub exhaustive: Vec<Schedule>,
    /// The measured LP cost of a stratified candidate sample.
    pub calibration: Calibration,
    /// Racing's expected cost from a proxy race of shard `cfg.shard` (None: not asked for, or
    /// exhaustive).
    pub proxy: Option<Proxy>,
    /// Wall seconds of the references after the race (0 when not estimated; set by
    /// [`super::run::plan_dataset`]).
    pub references_seconds: f64,
}

/// Plan the sweep `cfg` on `scorer`'s data and catalog: flags and schedules of every shard,
/// a calibration of `calibration[0]` candidates × `calibration[1]` fragments and, for racing
/// with `proxy` = Some((s, scratch)), a proxy race on 1/s of the fragments ([`proxy_race`]).
pub fn plan(
    cfg: &SweepConfig,
    scorer: &Scorer,
    calibration: [usize; 2],
    proxy: Option<(usize, &Path)>,
) -> Result<Plan> {
    let all = select::selected(cfg)?;
    if all.is_empty() {
        bail!("plan: no candidates selected");
    }
    let in_run: BTreeSet<u64> = all.iter().map(|c| c.0).collect();
    let flags = select::flags(scorer, &all, &in_run, cfg.tol)?;
    let n = cfg.shard[1].max(1);
    let mut active_per_shard = vec![0u64; n];
    let mut active = Vec::new();
    for ((i, c), &(degenerate, duplicate)) in all.iter().zip(&flags) {
        if !degenerate && duplicate.is_none() {
            active_per_shard[*i as usize % n] += 1;
            active.push(c);
        }
    }
    let fragments = scorer.data().fragments().len() as u64;
    let per = |exhaustive: bool| -> Vec<Schedule> {
        let c = SweepConfig {
            exhaustive,
            ..cfg.clone()
        };
        active_per_shard
            .iter()
            .map(|&a| schedule(&c, a, fragments))
            .collect()
    };
    let order = scorer.data().stratified_order(cfg.seed);
    Ok(Plan {
        candidates: all.len() as u64,
        degenerate: flags.iter().filter(|f| f.0).count() as u64,
        duplicates: flags.iter().filter(|f| f.1.is_some()).count() as u64,
        fragments,
        racing: per(false),
        exhaustive: per(true),
        calibration: calibrate(scorer, &active, &order, calibration)?,
        proxy: match proxy {
            Some((share, scratch)) if !cfg.exhaustive => {
                Some(proxy_race(cfg, scorer, share, scratch)?)
            }
            _ => None,
        },
        references_seconds: 0.0,
    })
}

/// Default share of the fragments the proxy race runs on: 1/8 (at 1/16 its noisier tests
/// eliminated fewer candidates than the run: docs/search.md).
pub const PROXY_SHARE: usize = 8;

/// What a racing run will cost, from a proxy race ([`proxy_race`]): the race itself on 1/s of
/// the fragments, its costs scaled by s.
#[derive(Clone, Debug, PartialEq)]
pub struct Proxy {
    /// s: the proxy raced on a stratified 1/s of the kept fragments.
    pub share: usize,
    /// Fragments it raced on.
    pub fragments: u64,
    /// Per stage: (candidates, fragments × s).
    pub stages: Vec<(u64, u64)>,
    /// Candidates tied at its end.
    pub tied: u64,
    /// Its LP solves × s: the expected LP solves of the run.
    pub lp_solves: u64,
    /// Of those, the candidates' per family ([`super::timing::family_of`]), and the rest
    /// (stage references and the pilot).
    pub by_family: Vec<(&'static str, u64)>,
    /// LP solves of the stage references and the pilot.
    pub other: u64,
    /// Its wall time on this machine (all threads).
    pub seconds: f64,
    /// The run simulated from the proxy's estimates ([`super::forecast`]; None when the proxy
    /// raced no more than one candidate): racing's expected cost.
    pub forecast: Option<Expected>,
}

/// Racing's expected cost from [`FORECAST_RUNS`] simulated runs of the race.
#[derive(Clone, Debug, PartialEq)]
pub struct Expected {
    /// Simulated runs.
    pub runs: usize,
    /// Mean LP solves, and the 10th and 90th percentile of the runs'.
    pub lp_solves: u64,
    /// 10th and 90th percentile of the runs' LP solves.
    pub range: (u64, u64),
    /// Of the mean, the candidates' per family and the rest (stage references and the pilot).
    pub by_family: Vec<(&'static str, u64)>,
    /// LP solves of the stage references and the pilot (mean).
    pub other: u64,
    /// The candidates' per family, each weighted by its cost per LP relative to its family's in
    /// the proxy race ([`relative_cost`]): what the calibration's µs per family are applied to.
    pub cost_by_family: Vec<(&'static str, u64)>,
    /// Mean candidates entering each stage.
    pub stages: Vec<f64>,
    /// The estimates' refinement on fresh fragments ([`refine`]; None when too few were left).
    pub refinement: Option<refine::Refinement>,
}

impl Proxy {
    /// Racing's expected LP solves, those of the candidates per family as they are costed (see
    /// [`Expected::cost_by_family`]), and the rest: the simulated runs' when there are any,
    /// else the proxy's own × s.
    pub fn expected(&self) -> (u64, &[(&'static str, u64)], u64) {
        match &self.forecast {
            Some(f) => (f.lp_solves, &f.cost_by_family, f.other),
            None => (self.lp_solves, &self.by_family, self.other),
        }
    }
}

/// The fresh block of the refinement ([`refine`]), in stage-0 blocks (`first_sample`).
pub const REFINE_BLOCKS: usize = 2;

/// Simulated runs of the race behind the plan's expected cost ([`super::forecast::simulate`]).
pub const FORECAST_RUNS: usize = 64;

/// The race `cfg` (one shard: `cfg.shard`) run on a stratified 1/`share` of the kept
/// fragments — the first F/s of the race's own fragment order — with every block 1/s as
/// large (first sample, early look) and every half-width × 1/√s, so that each test compares the
/// block mean with the threshold the full block would have: a candidate whose gap to the
/// reference exceeds the full-size half-width leaves in the proxy as in the run, in
/// expectation. Eliminations and the stopping rule are the run's own code
/// ([`super::run_sweep`], in the scratch folder `scratch`, which it removes). Racing's cost
/// depends on when candidates leave by confidence, which the fixed schedule ([`schedule`])
/// cannot know; the proxy's LP solves × s, per candidate family, estimate it (costed by
/// [`Calibration::seconds_for`]).
pub fn proxy_race(
    cfg: &SweepConfig,
    scorer: &Scorer,
    share: usize,
    scratch: &Path,
) -> Result<Proxy> {
    if share == 0 {
        bail!("plan: proxy share 0: must be at least 1");
    }
    let data = scorer.data();
    let order = data.stratified_order(cfg.seed);
    let keep = order.len().div_ceil(share);
    let sub = data.subset(&order[..keep]);
    let sub_scorer = Scorer::new(&sub, scorer.table(), scorer.solver(), scorer.chunk())?;
    let proxy_cfg = SweepConfig {
        exhaustive: false,
        dataset_fingerprint: format!("{:016x}", sub.fingerprint()),
        first_sample: cfg.first_sample.div_ceil(share).max(2),
        early_look: cfg.early_look.div_ceil(share),
        ..cfg.clone()
    };
    let hooks = Hooks {
        stop_after_batches: None,
        progress: None,
        half_width: Some(1.0 / (share as f64).sqrt()),
    };
    let parent = OutDir::new(scratch, true)?;
    static RUNS: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
    let run = RUNS.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let name = format!("{SCRATCH_PREFIX}{}-{run}", std::process::id());
    remove_stale_scratch(&parent, scratch)?;
    parent.remove_all(&name)?;
    let dir = parent.create_dir(&name)?;
    let t0 = Instant::now();
    let outcome = run_sweep(&proxy_cfg, &sub_scorer, &dir, &hooks)
        .and_then(|o| Ok((o, read_rows(&dir)?, race_looks(&dir)?)));
    let seconds = t0.elapsed().as_secs_f64();
    parent.remove_all(&name)?;
    let (summary, rows, looks) = match outcome? {
        (Outcome::Complete(s), rows, looks) => (s, rows, looks),
        (Outcome::Stopped, ..) => bail!("plan: the proxy race stopped"),
    };
    let s = share as u64;
    let family: HashMap<u64, &'static str> = rows
        .iter()
        .map(|r| (r.index, super::timing::family_of(&r.functions)))
        .collect();
    let by_family = per_family(rows.iter().map(|r| (family[&r.index], r.fragments * s)));
    let lp_solves = summary.lp_solves * s;
    let candidates: u64 = by_family.iter().map(|x| x.1).sum();
    let winner = summary.race.as_ref().and_then(|r| r.winner);
    let mut expected = None;
    if let Some(w) = winner.filter(|_| !looks.is_empty()) {
        let est = forecast::estimates(&looks, w);
        // The next fragments of the race's order, which the proxy never saw.
        let end = (keep + REFINE_BLOCKS * cfg.first_sample).min(order.len());
        let mut fresh = order[keep..end].to_vec();
        fresh.sort_unstable();
        let n = scorer.table().len();
        let cols = |i: u64| crate::basis::candidates::index_to_subset(n, cfg.m, i);
        let (est, refinement) =
            match refine::refine(scorer, &est, w, &fresh, cfg.first_sample, &cols)? {
                Some((e, r)) => (e, Some(r)),
                None => (est, None),
            };
        let shape = forecast::Shape {
            proxy_winner: Some(forecast::ProxyWinner {
                index: w,
                fragments: keep,
            }),
            ..forecast::Shape::of(cfg, order.len())
        };
        let f = forecast::simulate(&est, &shape, FORECAST_RUNS, cfg.seed);
        let lps = || est.iter().zip(&f.per_candidate).map(|(e, &n)| (e.index, n));
        let by_family = per_family(lps().map(|(i, n)| (family[&i], n.round() as u64)));
        let cost = relative_cost(&rows, &family);
        let cost_by_family = per_family(lps().map(|(i, n)| {
            (
                family[&i],
                (n * cost.get(&i).unwrap_or(&1.0)).round() as u64,
            )
        }));
        let lp_solves = f.lp_solves.round() as u64;
        let own: u64 = by_family.iter().map(|x| x.1).sum();
        expected = Some(Expected {
            runs: f.replicates,
            lp_solves,
            range: f.range,
            by_family,
            cost_by_family,
            other: lp_solves.saturating_sub(own),
            stages: f.stages,
            refinement,
        });
    }
    Ok(Proxy {
        share,
        fragments: keep as u64,
        stages: summary.stages.iter().map(|&(c, f)| (c, f * s)).collect(),
        tied: summary.full,
        lp_solves,
        by_family,
        other: lp_solves.saturating_sub(candidates),
        seconds,
        forecast: expected,
    })
}

/// Each candidate's CPU time per LP in the proxy race relative to its family's (Σ seconds /
/// Σ fragments over the family's rows): the candidates that survive to the later stages cost
/// more than their family's average (m = 4: exp(±20z) 19–20 µs per LP in stages 2–4 against
/// 15.5 µs in stage 0), while the proxy's small blocks, slower per LP than the run's, set no
/// level (the calibration on the run's own first block does).
fn relative_cost(rows: &[Row], family: &HashMap<u64, &'static str>) -> HashMap<u64, f64> {
    let mut per: HashMap<&str, (f64, u64)> = HashMap::new();
    for r in rows.iter().filter(|r| r.fragments > 0) {
        let e = per.entry(family[&r.index]).or_default();
        e.0 += r.seconds;
        e.1 += r.fragments;
    }
    rows.iter()
        .filter(|r| r.fragments > 0 && r.seconds > 0.0)
        .filter_map(|r| {
            let (secs, n) = per[family[&r.index]];
            let mean = secs / n as f64;
            (mean > 0.0).then(|| (r.index, r.seconds / r.fragments as f64 / mean))
        })
        .collect()
}

/// LP solves summed per family, sorted by family.
fn per_family(rows: impl Iterator<Item = (&'static str, u64)>) -> Vec<(&'static str, u64)> {
    let mut out: Vec<(&'static str, u64)> = Vec::new();
    for (f, n) in rows {
        match out.iter_mut().find(|x| x.0 == f) {
            Some(x) => x.1 += n,
            None => out.push((f, n)),
        }
    }
    out.sort();
    out
}

/// The proxy races' scratch folders are `{SCRATCH_PREFIX}{pid}-{n}` under the scratch parent.
const SCRATCH_PREFIX: &str = "momentlab-plan-";

/// Remove the scratch folders under `root` left by plans that were killed: those whose pid
/// names no live process (other processes' live plans and this one's are kept).
fn remove_stale_scratch(parent: &OutDir, root: &Path) -> Result<()> {
    let Ok(entries) = std::fs::read_dir(root) else {
        return Ok(());
    };
    let own = std::process::id();
    for entry in entries.flatten() {
        let name = entry.file_name();
        let Some(pid) = name
            .to_str()
            .and_then(|n| n.strip_prefix(SCRATCH_PREFIX))
            .and_then(|rest| rest.split_once('-'))
            .filter(|(_, n)| n.parse::<u64>().is_ok())
            .and_then(|(pid, _)| pid.parse::<u32>().ok())
        else {
            continue;
        };
        if pid != own && !process_alive(pid) {
            parent.remove_all(name.to_str().expect("checked above"))?;
        }
    }
    Ok(())
}

/// Whether a process `pid` exists (kill(pid, 0) does not fail with ESRCH).
fn process_alive(pid: u32) -> bool {
    let Ok(pid) = libc::pid_t::try_from(pid) else {
        return false;
    };
    // SAFETY: signal 0 only checks that the process exists and may be signalled.
    let r = unsafe { libc::kill(pid, 0) };
    r == 0 || std::io::Error::last_os_error().raw_os_error() != Some(libc::ESRCH)
}

/// Proportional allocation of `k` samples to strata of the given sizes (largest remainder, at
/// least one per non-empty stratum when k allows), then evenly spaced members of each stratum.
pub fn stratified_sample(strata: &[Vec<usize>], k: usize) -> Vec<Vec<usize>> {
    let total: usize = strata.iter().map(Vec::len).sum();
    if total == 0 || k == 0 {
        return vec![Vec::new(); strata.len()];
    }
    let k = k.min(total);
    let quota: Vec<f64> = strata
        .iter()
        .map(|s| k as f64 * s.len() as f64 / total as f64)
        .collect();
    let mut take: Vec<usize> = strata
        .iter()
        .zip(&quota)
        .map(|(s, q)| {
            (q.floor() as usize)
                .max(usize::from(!s.is_empty()))
                .min(s.len())
        })
        .collect();
    let mut by_remainder: Vec<usize> = (0..strata.len()).collect();
    by_remainder
        .sort_by(|&a, &b| (quota[b] - quota[b].floor()).total_cmp(&(quota[a] - quota[a].floor())));
    for &i in by_remainder.iter().cycle().take(4 * strata.len() * k) {
        if take.iter().sum::<usize>() >= k {
            break;
        }
        if take[i] < strata[i].len() {
            take[i] += 1;
        }
    }
    strata
        .iter()
        .zip(&take)
        .map(|(s, &t)| (0..t).map(|j| s[j * s.len() / t]).collect())
        .collect()
}

/// Time a stratified sample of `candidates` candidates of `active` × `fragments` fragments
/// (see [`Calibration`]).
pub fn calibrate(
    scorer: &Scorer,
    active: &[&Vec<usize>],
    order: &[u32],
    [candidates, fragments]: [usize; 2],
) -> Result<Calibration> {
    let mut block: Vec<u32> =
        order[..fragments.clamp(1, order.len().max(1)).min(order.len())].to_vec();
    block.sort_unstable();
    let names = scorer.table().names();
    let family = |c: &[usize]| {
        super::timing::family_of(&c.iter().map(|&j| names[j].clone()).collect::<Vec<_>>())
    };
    let mut labels: Vec<&'static str> = Vec::new();
    let mut strata: Vec<Vec<usize>> = Vec::new();
    for (i, c) in active.iter().enumerate() {
        let f = family(c);
        match labels.iter().position(|l| *l == f) {
            Some(p) => strata[p].push(i),
            None => {
                labels.push(f);
                strata.push(vec![i]);
            }
        }
    }
    let sample = stratified_sample(&strata, candidates);
    let mut out = Calibration {
        candidates: 0,
        fragments: block.len(),
        lp_solves: 0,
        seconds: 0.0,
        threads: rayon::current_num_threads(),
        failures: 0,
        strata: labels
            .iter()
            .zip(&sample)
            .zip(&strata)
            .map(|((l, s), all)| (*l, s.len(), all.len()))
            .collect(),
        family_us: Vec::new(),
        cpu_seconds: 0.0,
    };
    let cands: Vec<Vec<usize>> = sample
        .iter()
        .flatten()
        .map(|&i| active[i].clone())
        .collect();
    if cands.is_empty() || block.is_empty() {
        return Ok(out);
    }
    let t0 = Instant::now();
    let errs = scorer.errors_many(&cands, &block, &|_| {})?;
    out.seconds = t0.elapsed().as_secs_f64();
    out.failures = errs.iter().map(|e| e.failures).sum();
    out.cpu_seconds = errs.iter().map(|e| e.seconds).sum();
    let mut at = 0;
    for (label, members) in labels.iter().zip(&sample) {
        let part = &errs[at..at + members.len()];
        at += members.len();
        if !part.is_empty() {
            let secs: f64 = part.iter().map(|e| e.seconds).sum();
            out.family_us
                .push((*label, secs * 1e6 / (part.len() * block.len()) as f64));
        }
    }
    out.candidates = cands.len();
    out.lp_solves = (cands.len() * block.len()) as u64;
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stale_scratch_of_killed_plans_is_removed() {
        let root =
            std::env::temp_dir().join(format!("momentlab-stale-test-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&root);
        std::fs::create_dir_all(&root).unwrap();
        // A pid that has exited: a child we waited for.
        let dead = std::process::Command::new("true").spawn().unwrap();
        let dead_pid = dead.id();
        let mut dead = dead;
        dead.wait().unwrap();
        let stale = format!("{SCRATCH_PREFIX}{dead_pid}-0");
        let mine = format!("{SCRATCH_PREFIX}{}-7", std::process::id());
        let live = format!("{SCRATCH_PREFIX}1-0"); // init: always alive
        for d in [&stale, &mine, &live, &"unrelated-3-4".to_string()] {
            std::fs::create_dir_all(root.join(d).join("inner")).unwrap();
        }
        let parent = OutDir::new(&root, true).unwrap();
        remove_stale_scratch(&parent, &root).unwrap();
        assert!(!root.join(&stale).exists());
        for d in [&mine, &live, &"unrelated-3-4".to_string()] {
            assert!(root.join(d).join("inner").exists(), "{d}");
        }
        std::fs::remove_dir_all(&root).unwrap();
    }

    /// A candidate's cost is its seconds per LP over its family's (Σ seconds / Σ fragments);
    /// rows without fragments or time get none (costed at 1).
    #[test]
    fn relative_cost_is_per_lp_over_the_familys() {
        let row = |index, seconds, fragments| Row {
            seconds,
            fragments,
            ..Row::plain(index, vec![])
        };
        let rows = [
            row(1, 1.0, 100),
            row(2, 3.0, 100),
            row(3, 2.0, 400),
            row(4, 0.0, 0),
        ];
        let family: HashMap<u64, &'static str> = [(1, "a"), (2, "a"), (3, "b"), (4, "b")]
            .into_iter()
            .collect();
        let cost = relative_cost(&rows, &family);
        // Family a: 4 s / 200 LPs = 0.02 s per LP; family b: 2 s / 400.
        assert_eq!(cost[&1], 0.01 / 0.02);
        assert_eq!(cost[&2], 0.03 / 0.02);
        assert_eq!(cost[&3], 1.0);
        assert!(!cost.contains_key(&4));
    }

    /// Family-weighted wall time: Σ_f LP_f · µs_f (unknown families and `other` at the
    /// sample's mean µs) / (threads · efficiency).
    #[test]
    fn seconds_for_weights_each_family_by_its_cost() {
        let c = Calibration {
            candidates: 4,
            fragments: 100,
            lp_solves: 400,
            seconds: 0.001,
            threads: 2,
            failures: 0,
            strata: Vec::new(),
            family_us: vec![("a", 2.0), ("b", 8.0)],
            cpu_seconds: 0.0016,
        };
        // Mean 0.0016 s / 400 = 4 µs; efficiency 0.0016 / (0.001 · 2) = 0.8.
        // 1000 · 2 + 500 · 8 + 250 · 4 = 7000 µs on 2 threads at 0.8: 4375 µs.
        let t = c.seconds_for(&[("a", 1000), ("b", 500)], 250, 2);
        assert!((t - 4.375e-3).abs() < 1e-15, "{t}");
        // An unknown family costs the mean; one thread takes twice as long.
        let t = c.seconds_for(&[("z", 1000)], 0, 1);
        assert!((t - 4000e-6 / 0.8).abs() < 1e-15, "{t}");
        // Without a timed sample: the plain rate (no solves: nothing known, 0 s).
        let empty = Calibration {
            lp_solves: 0,
            cpu_seconds: 0.0,
            ..c
        };
        assert_eq!(empty.seconds_for(&[("a", 10)], 0, 2), 0.0);
    }

    /// Proportional allocation: 64 of the m = 4 catalog's family sizes (20 445, 11 440, 13 685,
    /// 20 475) gives 20, 11, 13, 20 by the floors and the largest remainders; small strata get
    /// one; members are evenly spaced.
    #[test]
    fn stratified_sample_allocates_in_proportion() {
        let sizes = [20_445usize, 11_440, 13_685, 20_475];
        let strata: Vec<Vec<usize>> = sizes.iter().map(|&n| (0..n).collect()).collect();
        let s = stratified_sample(&strata, 64);
        let got: Vec<usize> = s.iter().map(Vec::len).collect();
        assert_eq!(got, vec![20, 11, 13, 20]);
        assert_eq!(s[1][..3], [0, 1040, 2080]);
        let tiny = vec![(0..1000).collect(), vec![7], Vec::new()];
        let s = stratified_sample(&tiny, 10);
        assert_eq!(s.iter().map(Vec::len).collect::<Vec<_>>(), vec![9, 1, 0]);
        assert_eq!(s[1], vec![7]);
        let all = stratified_sample(&tiny, 5000);
        assert_eq!(all.iter().map(Vec::len).sum::<usize>(), 1001);
        assert!(stratified_sample(&tiny, 0).iter().all(Vec::is_empty));
    }
}
