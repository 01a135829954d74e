//! The racing driver of [`super::run_sweep`] (module docs of [`super`]): stage k scores its
//! candidates on block k of the stratified order in one look or, after stage 0, on its
//! geometric prefixes and then the whole block ([`race::looks`]), eliminates by the
//! stage's [`race::Rule`] (evidence only), records the eliminated candidates' rows with their
//! evidence and the [`StageLog`]; the survivors are then completed on every fragment they have
//! not seen and form the tie set. Stage 0's block is the common sample (one look, every
//! candidate). An LP budget ends the race before a look that would exceed it, leaving the
//! survivors unresolved.

use super::{
    pilot_best, pooled_row, score_block, stage_file, Ctx, RaceSummary, StageLog, StageRow, Stopped,
    Writer, FINAL_FILE,
};
use crate::search::config::SweepConfig;
use crate::search::race::{self, Elimination, StageStats};
use crate::search::results::{Row, RESULTS_FILE};
use crate::search::Dataset;
use anyhow::{Context, Result};
use std::collections::{BTreeSet, HashMap};
use std::ops::Range;
use std::path::{Path, PathBuf};

/// The outcome of [`Race::run`].
pub(super) struct Raced {
    pub(super) lp_solves: u64,
    pub(super) stage_sizes: Vec<(u64, u64)>,
    pub(super) summary: RaceSummary,
}

/// One elimination: the candidate's statistics on the looks of its stage so far, the look that
/// removed it and the lower confidence bound of μ_c − μ_R (> 0) that did.
struct Left {
    stats: StageStats,
    look: usize,
    lower: f64,
}

/// What the looks of one stage left: the survivors, every candidate's statistics on the
/// block, the eliminated with their evidence, and how many left at an early look (any look
/// before the whole block).
struct StageOutcome {
    alive: Vec<u64>,
    acc: HashMap<u64, StageRow>,
    left: Vec<Left>,
    early: u64,
    /// LP solves of the looks (the reference included).
    solves: u64,
    /// Looks run (fewer than planned when the LP budget stopped the stage).
    looks: usize,
    /// The LP budget stopped the race before a look of this stage.
    budget: bool,
}

/// A race between stages: the fixed plan (fragment order, pilot block, stage blocks) and the
/// state carried from stage to stage.
pub(super) struct Race<'r, 'a, 'h> {
    ctx: &'r Ctx<'a, 'h>,
    cfg: &'r SweepConfig,
    dir: &'r Path,
    names: &'r dyn Fn(u64) -> Vec<String>,
    results: PathBuf,
    /// Non-trivial fragments of the sample.
    nontrivial: u64,
    /// Non-trivial share of the population (error differences are reported per fragment of
    /// the population).
    scale: f64,
    order: Vec<u32>,
    pilot: Range<usize>,
    plan: Vec<Range<usize>>,
    /// Looks over all planned stages (the Bonferroni count).
    planned_looks: usize,
    /// Candidates still in the race.
    cur: Vec<u64>,
    lp_solves: u64,
    stage_sizes: Vec<(u64, u64)>,
    logs: Vec<StageLog>,
    /// Every candidate's statistics pooled over the blocks it has seen.
    pooled: HashMap<u64, StageRow>,
    /// Per block seen by the survivors: its reference and every candidate's statistics.
    history: Vec<(u64, HashMap<u64, StageRow>)>,
    /// The best survivor by pooled mean (the next stage's reference).
    leader: Option<u64>,
    /// Fragments used by the pilot and the stage blocks.
    used: u64,
    /// Stages run.
    run: usize,
    /// Every stage-0 candidate's statistics on stage 0's block (the common sample).
    common: HashMap<u64, StageRow>,
    /// The LP budget ended the race.
    budget_stop: bool,
}

impl<'r, 'a, 'h> Race<'r, 'a, 'h> {
    /// The race of `active` planned by `cfg` on the scorer's dataset, its files in `dir`.
    pub(super) fn new(
        ctx: &'r Ctx<'a, 'h>,
        cfg: &'r SweepConfig,
        dir: &'r Path,
        active: &[u64],
        names: &'r dyn Fn(u64) -> Vec<String>,
    ) -> Self {
        let data = ctx.scorer.data();
        let scale = if data.total_count() == 0 {
            0.0
        } else {
            data.nontrivial_population() as f64 / data.total_count() as f64
        };
        let order = data.stratified_order(cfg.seed);
        let (pilot, plan) = race::blocks(order.len(), cfg.first_sample, cfg.growth);
        let planned_looks = plan
            .iter()
            .enumerate()
            .map(|(k, r)| race::looks(k, r.len(), cfg.early_look).len())
            .sum();
        Race {
            ctx,
            cfg,
            dir,
            names,
            results: dir.join(RESULTS_FILE),
            nontrivial: data.fragments().len() as u64,
            scale,
            order,
            pilot,
            plan,
            planned_looks,
            cur: active.to_vec(),
            lp_solves: 0,
            stage_sizes: Vec::new(),
            logs: Vec::new(),
            pooled: HashMap::new(),
            history: Vec::new(),
            leader: None,
            used: 0,
            run: 0,
            common: HashMap::new(),
            budget_stop: false,
        }
    }

    fn data(&self) -> &Dataset {
        self.ctx.scorer.data()
    }

    /// Every stage until one candidate is left or the blocks run out, then the survivors on
    /// every fragment; `done` collects the candidates whose final rows are written.
    pub(super) fn run(
        mut self,
        w: &mut Writer,
        done: &mut BTreeSet<u64>,
    ) -> Result<Result<Raced, Stopped>> {
        for k in 0..self.plan.len() {
            if self.cur.len() <= 1 || self.budget_stop {
                break;
            }
            if let Err(Stopped) = self.stage(w, done, k)? {
                return Ok(Err(Stopped));
            }
        }
        if !self.unresolved() {
            if let Err(Stopped) = self.complete(w)? {
                return Ok(Err(Stopped));
            }
        }
        let rows = self.tied_rows(done);
        if let Err(Stopped) = self.append(w, done, &rows)? {
            return Ok(Err(Stopped));
        }
        Ok(Ok(self.finish()))
    }

    /// The stage reference: the leader after the previous stage, else the pilot's best.
    fn reference(&mut self) -> Result<u64> {
        if let Some(l) = self.leader {
            return Ok(l);
        }
        let pilot_block = sorted(&self.order[self.pilot.clone()]);
        self.used += pilot_block.len() as u64;
        let p = self.cfg.pilot.clamp(1, self.cur.len());
        self.lp_solves += (p * pilot_block.len()) as u64;
        pilot_best(self.ctx, &self.cur, p, &pilot_block)
    }

    /// Stage k: its looks, the eliminated candidates' rows, its log; the survivors go on.
    fn stage(
        &mut self,
        w: &mut Writer,
        done: &mut BTreeSet<u64>,
        k: usize,
    ) -> Result<Result<(), Stopped>> {
        let block = self.order[self.plan[k].clone()].to_vec();
        let looks = race::looks(k, block.len(), self.cfg.early_look);
        if self.over_budget(0, self.cur.len(), looks[0].len()) {
            self.budget_stop = true;
            return Ok(Ok(()));
        }
        let reference = self.reference()?;
        self.stage_sizes
            .push((self.cur.len() as u64, block.len() as u64));
        self.used += block.len() as u64;
        let cfg = self.cfg;
        let delta = race::stage_delta(
            1.0 - cfg.confidence,
            self.planned_looks,
            self.cur.len(),
            cfg.shard[1],
            cfg.correction,
        );
        let rule = race::Rule {
            delta,
            bound: cfg.bound,
            paired: cfg.paired,
            width: self.ctx.hooks.half_width.unwrap_or(1.0),
        };
        let out = match self.looks(w, k, &block, &looks, reference, &rule)? {
            Ok(out) => out,
            Err(Stopped) => return Ok(Err(Stopped)),
        };
        self.lp_solves += out.solves;
        self.budget_stop = out.budget;
        if k == 0 && out.looks == looks.len() {
            self.common = out.acc.clone();
        }
        for i in &self.cur {
            self.pooled
                .entry(*i)
                .or_insert_with(|| StageRow::empty(*i))
                .add(&out.acc[i]);
        }
        let rows = self.eliminated_rows(k, reference, &out.left, done);
        if let Err(Stopped) = self.append(w, done, &rows)? {
            return Ok(Err(Stopped));
        }
        self.logs.push(StageLog {
            candidates: self.cur.len() as u64,
            fragments: block.len() as u64,
            reference,
            delta,
            z: race::normal_quantile(1.0 - delta),
            confidence_eliminated: out.left.len() as u64,
            early_eliminated: out.early,
        });
        self.history.push((reference, out.acc));
        self.cur = out.alive;
        self.leader = best_of(&self.cur, &self.pooled);
        self.run = k + 1;
        Ok(Ok(()))
    }

    /// The LP budget ended the race with more than one candidate left.
    fn unresolved(&self) -> bool {
        self.budget_stop && self.cur.len() > 1
    }

    /// Whether a look of `alive` candidates (and the reference) on `len` fragments, after
    /// `pending` solves of the stage so far, would exceed the LP budget.
    fn over_budget(&self, pending: u64, alive: usize, len: usize) -> bool {
        let budget = self.cfg.lp_budget;
        budget > 0 && self.lp_solves + pending + ((alive + 1) * len) as u64 > budget
    }

    /// The looks of stage k on `block` ([`race::looks`]): candidates are tested by `rule` on
    /// each look's fragments so far (the prefixes of 1/8, 1/4 and 1/2 that are large enough,
    /// then the whole block); the LP budget can stop the stage before a look.
    fn looks(
        &self,
        w: &mut Writer,
        k: usize,
        block: &[u32],
        looks: &[Range<usize>],
        reference: u64,
        rule: &race::Rule,
    ) -> Result<Result<StageOutcome, Stopped>> {
        let mut out = StageOutcome {
            alive: self.cur.clone(),
            acc: HashMap::new(),
            left: Vec::new(),
            early: 0,
            solves: 0,
            looks: 0,
            budget: false,
        };
        for (j, part) in looks.iter().enumerate() {
            let last = j + 1 == looks.len();
            if j > 0 && self.over_budget(out.solves, out.alive.len(), part.len()) {
                out.budget = true;
                break;
            }
            let ids = sorted(&block[part.clone()]);
            let path = stage_file(self.dir, k, j);
            let look = if looks.len() > 1 {
                format!(", look {}/{}", j + 1, looks.len())
            } else {
                String::new()
            };
            let label = format!(
                "stage {k}{look}: {} candidates × {} fragments",
                out.alive.len(),
                ids.len()
            );
            let stored = match score_block(self.ctx, w, &path, &out.alive, reference, &ids, label)?
            {
                Ok(s) => s,
                Err(Stopped) => return Ok(Err(Stopped)),
            };
            out.solves += ((out.alive.len() + 1) * ids.len()) as u64;
            out.looks += 1;
            let stats = accumulate(&mut out.acc, &out.alive, &stored, &path)?;
            let decisions = race::decide(&stats, reference, rule);
            out.alive.clear();
            for (s, d) in stats.iter().zip(&decisions) {
                match d {
                    None => out.alive.push(s.index),
                    Some(lower) => {
                        out.early += !last as u64;
                        out.left.push(Left {
                            stats: *s,
                            look: j,
                            lower: *lower,
                        });
                    }
                }
            }
        }
        Ok(Ok(out))
    }

    /// Rows of the candidates stage k eliminated (not yet written), with the evidence: the
    /// look, the paired difference to the reference on the stage's fragments so far, its
    /// standard error and the lower confidence bound that was above 0.
    fn eliminated_rows(
        &self,
        k: usize,
        reference: u64,
        left: &[Left],
        done: &BTreeSet<u64>,
    ) -> Vec<Row> {
        let mut out: Vec<Row> = left
            .iter()
            .filter(|l| !done.contains(&l.stats.index))
            .map(|l| {
                let mut row = self.pooled_row(l.stats.index);
                row.stage = k;
                row.look = Some(l.look);
                row.eliminated = Some(Elimination::Confidence);
                row.versus = Some(reference);
                row.diff = Some(l.stats.d.mean() * self.scale);
                row.diff_se = Some(l.stats.d.se() * self.scale);
                row.diff_lower = Some(l.lower * self.scale);
                row
            })
            .collect();
        out.sort_by_key(|r| r.index);
        out
    }

    /// The survivors on every fragment they have not seen: the pilot block and the unused
    /// stage blocks (every fragment when no stage ran).
    fn complete(&mut self, w: &mut Writer) -> Result<Result<(), Stopped>> {
        let mut rest: Vec<u32> = Vec::new();
        if self.run > 0 {
            rest.extend_from_slice(&self.order[self.pilot.clone()]);
            for r in &self.plan[self.run..] {
                rest.extend_from_slice(&self.order[r.clone()]);
            }
        } else {
            rest.extend_from_slice(&self.order);
        }
        let rest = sorted(&rest);
        let Some(reference) = self.leader.or(self.cur.first().copied()) else {
            return Ok(Ok(()));
        };
        if rest.is_empty() {
            return Ok(Ok(()));
        }
        let path = self.dir.join(FINAL_FILE);
        let label = format!(
            "final: {} candidates × {} fragments",
            self.cur.len(),
            rest.len()
        );
        let stored = match score_block(self.ctx, w, &path, &self.cur, reference, &rest, label)? {
            Ok(s) => s,
            Err(Stopped) => return Ok(Err(Stopped)),
        };
        self.lp_solves += ((self.cur.len() + 1) * rest.len()) as u64;
        for i in &self.cur {
            let r = stored
                .get(i)
                .with_context(|| format!("{}: candidate {i} missing", path.display()))?;
            self.pooled
                .entry(*i)
                .or_insert_with(|| StageRow::empty(*i))
                .add(r);
        }
        self.history.push((reference, stored));
        Ok(Ok(()))
    }

    /// Rows of the survivors (not yet written): tied for first (or unresolved, when the LP
    /// budget ended the race), with the paired difference to the winner pooled over every
    /// block ([`race::pooled`]).
    fn tied_rows(&self, done: &BTreeSet<u64>) -> Vec<Row> {
        let Some(winner) = best_of(&self.cur, &self.pooled) else {
            return Vec::new();
        };
        let mut rows = Vec::new();
        for &i in self.cur.iter().filter(|i| !done.contains(i)) {
            let mut row = self.pooled_row(i);
            let parts: Vec<(u64, f64, f64)> = self
                .history
                .iter()
                .map(|(_, m)| {
                    let (c, b) = (m[&i].stats().d, m[&winner].stats().d);
                    (c.n, c.mean() - b.mean(), c.se() + b.se())
                })
                .collect();
            let (d, se) = race::pooled(&parts);
            row.stage = self.run;
            row.tied = !self.unresolved();
            row.unresolved = self.unresolved();
            row.versus = Some(winner);
            row.diff = Some(d * self.scale);
            row.diff_se = Some(if i == winner { 0.0 } else { se * self.scale });
            rows.push(row);
        }
        rows
    }

    /// A result row from candidate i's pooled statistics.
    fn pooled_row(&self, i: u64) -> Row {
        let mut row = pooled_row(&self.pooled[&i], self.data(), self.names, self.nontrivial);
        if let Some(c) = self.common.get(&i) {
            let (error, se) = self.data().error_estimate(c.n, c.sum, c.sumsq);
            row.common_error = Some(error);
            row.common_stderr = Some(se);
            row.common_fragments = c.n;
        }
        row
    }

    /// Append `rows` to the results in batches of 1 000, marking them done.
    fn append(
        &self,
        w: &mut Writer,
        done: &mut BTreeSet<u64>,
        rows: &[Row],
    ) -> Result<Result<(), Stopped>> {
        for batch in rows.chunks(1000) {
            if let Err(Stopped) = w.append(&self.results, batch)? {
                return Ok(Err(Stopped));
            }
            done.extend(batch.iter().map(|r| r.index));
        }
        Ok(Ok(()))
    }

    /// The race's summary once the survivors' rows are written.
    fn finish(self) -> Raced {
        let run = self.run > 0;
        let left = self.cur.len() as u64;
        let stopped = self.unresolved();
        let tied = if stopped { 0 } else { left };
        let sum = |f: fn(&StageLog) -> u64| self.logs.iter().map(f).sum::<u64>();
        let summary = RaceSummary {
            confidence: self.cfg.confidence,
            correction: self.cfg.correction,
            bound: self.cfg.bound,
            paired: self.cfg.paired,
            pilot_fragments: if run { self.pilot.len() as u64 } else { 0 },
            looks: self.planned_looks as u64,
            fragment_budget: self.nontrivial,
            fragments_used: if run { self.used } else { self.nontrivial },
            resolved: left == 1,
            budget_bound: !stopped && left > 1,
            lp_budget_bound: stopped,
            tied,
            unresolved: if stopped { left } else { 0 },
            winner: best_of(&self.cur, &self.pooled),
            confidence_eliminated: sum(|l| l.confidence_eliminated),
            common_fragments: self.common.values().next().map_or(0, |c| c.n),
            stages: self.logs,
        };
        Raced {
            lp_solves: self.lp_solves,
            stage_sizes: self.stage_sizes,
            summary,
        }
    }
}

/// Add look statistics `stored` to `acc` for each of `alive`; each candidate's statistics
/// over the stage's looks so far.
fn accumulate(
    acc: &mut HashMap<u64, StageRow>,
    alive: &[u64],
    stored: &HashMap<u64, StageRow>,
    path: &Path,
) -> Result<Vec<StageStats>> {
    alive
        .iter()
        .map(|i| {
            let r = stored
                .get(i)
                .with_context(|| format!("{}: candidate {i} missing", path.display()))?;
            let a = acc.entry(*i).or_insert_with(|| StageRow::empty(*i));
            a.add(r);
            Ok(a.stats())
        })
        .collect()
}

/// The candidate of `cur` with the smallest pooled mean (ties: smallest index).
fn best_of(cur: &[u64], pooled: &HashMap<u64, StageRow>) -> Option<u64> {
    cur.iter().copied().min_by(|a, b| {
        let (ma, mb) = (pooled[a].stats().e.mean(), pooled[b].stats().e.mean());
        ma.total_cmp(&mb).then(a.cmp(b))
    })
}

/// Fragment ids in increasing order (the scorer's batches and the stage files are sorted).
fn sorted(ids: &[u32]) -> Vec<u32> {
    let mut b = ids.to_vec();
    b.sort_unstable();
    b
}
