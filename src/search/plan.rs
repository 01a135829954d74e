//! What a sweep will cost before it runs (`momentlab search --plan`): the candidates it scores,
//! the racing stages and LP solves exactly as [`super::run_sweep`] schedules them (for racing
//! and for the exhaustive mode, per shard), and the core-hours from a short single-threaded
//! calibration of the LP solver on this machine and data.
//!
//! LP solves (as `SweepSummary::lp_solves`): the pilot block P picks the stage-0 reference
//! (pilot·|P| solves); racing stage k with |C_k| candidates on a block of B_k fragments costs
//! (|C_k| + 1)·B_k (the stage reference included); |C_{k+1}| ≤ min(max(⌈keep·|C_k|⌉, top), |C_k|)
//! (the cap; eliminations by confidence only lower it, and racing stops early when one
//! candidate is left); then the survivors on the fragments they have not seen, (|C| + 1)·|rest|.
//! The racing schedule is therefore an upper bound, reached when no candidate is eliminated by
//! confidence. Exhaustive: |C|·F, exact.

use super::config::SweepConfig;
use super::select;
use super::Scorer;
use anyhow::{bail, Result};
use std::collections::BTreeSet;
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
/// (racing unless `cfg.exhaustive`), each stage promoting the fraction `keep`.
pub fn schedule(cfg: &SweepConfig, active: u64, fragments: u64, keep: f64) -> Schedule {
    let top = cfg.top as u64;
    let (mut cur, mut lp, mut stages) = (active, 0u64, Vec::new());
    if cfg.exhaustive {
        return Schedule {
            stages,
            full: cur,
            lp_solves: cur * fragments,
        };
    }
    let (pilot, blocks) = super::race::blocks(fragments as usize, cfg.first_sample, cfg.growth);
    let mut run = 0;
    for b in &blocks {
        if cur <= 1 {
            break;
        }
        if stages.is_empty() {
            lp += (cfg.pilot as u64).clamp(1, cur) * pilot.len() as u64;
        }
        lp += (cur + 1) * b.len() as u64;
        stages.push((cur, b.len() as u64));
        cur = super::race::cap(keep, cur, top).min(cur);
        run += 1;
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

/// A timed sample of LP solves: evenly spaced candidates on the first fragments of the
/// stratified order (a racing block), one solver per candidate, on one thread.
#[derive(Clone, Debug)]
pub struct Calibration {
    pub candidates: usize,
    pub fragments: usize,
    pub lp_solves: u64,
    /// Wall time of the solves on one thread.
    pub seconds: f64,
    /// Unsettled LPs in the sample.
    pub failures: u64,
}

impl Calibration {
    /// LP solves per second on one core.
    pub fn rate(&self) -> f64 {
        self.lp_solves as f64 / self.seconds.max(1e-9)
    }
    /// Core-hours for `lp_solves` solves at the calibrated rate.
    pub fn core_hours(&self, lp_solves: u64) -> f64 {
        lp_solves as f64 / self.rate() / 3600.0
    }
}

/// The plan of a sweep over all shards of `cfg.shard[1]`.
#[derive(Clone, Debug)]
pub struct Plan {
    /// Candidates selected (before sharding), degenerate ones, duplicate spans.
    pub candidates: u64,
    pub degenerate: u64,
    pub duplicates: u64,
    /// Kept non-trivial fragments.
    pub fragments: u64,
    /// Per shard: racing (an upper bound, see the module docs), exhaustive.
    pub racing: Vec<Schedule>,
    pub exhaustive: Vec<Schedule>,
    pub calibration: Calibration,
}

/// Plan the sweep `cfg` on `scorer`'s data and catalog: flags and schedules of every shard,
/// and a calibration of `calibration[0]` candidates × `calibration[1]` fragments.
pub fn plan(cfg: &SweepConfig, scorer: &Scorer, calibration: [usize; 2]) -> Result<Plan> {
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
    let per = |keep: f64, exhaustive: bool| -> Vec<Schedule> {
        let c = SweepConfig {
            exhaustive,
            ..cfg.clone()
        };
        active_per_shard
            .iter()
            .map(|&a| schedule(&c, a, fragments, keep))
            .collect()
    };
    let order = scorer.data().stratified_order(cfg.seed);
    Ok(Plan {
        candidates: all.len() as u64,
        degenerate: flags.iter().filter(|f| f.0).count() as u64,
        duplicates: flags.iter().filter(|f| f.1.is_some()).count() as u64,
        fragments,
        racing: per(cfg.keep, false),
        exhaustive: per(cfg.keep, true),
        calibration: calibrate(scorer, &active, &order, calibration)?,
    })
}

/// Time `[candidates, fragments]` LP solves on one thread (see [`Calibration`]).
pub fn calibrate(
    scorer: &Scorer,
    active: &[&Vec<usize>],
    order: &[u32],
    [candidates, fragments]: [usize; 2],
) -> Result<Calibration> {
    let k = candidates.clamp(1, active.len().max(1));
    let mut block: Vec<u32> =
        order[..fragments.clamp(1, order.len().max(1)).min(order.len())].to_vec();
    block.sort_unstable();
    let mut out = Calibration {
        candidates: 0,
        fragments: block.len(),
        lp_solves: 0,
        seconds: 0.0,
        failures: 0,
    };
    if active.is_empty() || block.is_empty() {
        return Ok(out);
    }
    let t0 = Instant::now();
    for j in 0..k {
        let e = scorer.errors_seq(active[j * active.len() / k], &block)?;
        out.failures += e.failures;
        out.lp_solves += block.len() as u64;
        out.candidates += 1;
    }
    out.seconds = t0.elapsed().as_secs_f64();
    Ok(out)
}
