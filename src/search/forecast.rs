//! Racing's expected cost from a proxy race's estimates, by simulating the run (pure functions,
//! no IO; `search --plan`, [`super::plan::proxy_race`]).
//!
//! The proxy race decides on 1/s of every block, so its block means are √s times noisier than
//! the run's. Where many candidates lie a little below the run's threshold (m = 4) it eliminates
//! them by noise; its own LP solves then fall short of the run's. Its statistics are used instead as estimates
//! ([`estimates`]): each candidate's mean error gap g_c to the proxy's winner, paired over the
//! looks both saw, and the per-fragment spread σ_c of its paired differences to a reference.
//!
//! [`simulate`] then runs the run's own race on them: the run's blocks and looks
//! ([`race::blocks`], [`race::looks`]), δ ([`race::stage_delta`]) and decisions
//! ([`race::decide`]: evidence only) and LP budget. On a look of n fragments each candidate's mean
//! error is g_c + ι_c with independent ι_c ~ N(0, σ_c²/(2n)), so a paired difference to the
//! reference R has variance (σ_c² + σ_R²)/(2n) ≈ σ_c²/n, half of it R's own noise, shared by
//! every candidate of the look (as for exchangeable candidates). Stage references are the
//! leaders of these draws, except where the run's is known ([`known_reference`]: the proxy's
//! winner, while the blocks before the stage lie in the fragments the proxy raced on). The
//! mean LP solves over the replicates is the forecast; their spread is the race's spread over
//! fragment orders.

use super::config::SweepConfig;
use super::race::{self, Bound, Correction, Moments, Rule, StageStats};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};
use rayon::prelude::*;
use std::collections::HashMap;

/// One candidate's estimates from the proxy race.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Estimate {
    /// Candidate index.
    pub index: u64,
    /// Mean error gap to the proxy's winner over the looks both saw (fragment-weighted).
    pub gap: f64,
    /// Per-fragment standard deviation of its paired differences to a look's reference.
    pub sd: f64,
    /// Per-fragment standard deviation of its errors (for unpaired tests).
    pub esd: f64,
    /// Fragments the gap was measured on (over the looks it shared with the winner).
    pub fragments: u64,
}

/// The candidates' estimates from the statistics of every look of a race (`looks[l]`: each
/// scored candidate's errors and paired differences on look l), gaps relative to `winner`,
/// which must be scored on every look (a race's winner is). σ_c comes from the look with the
/// most fragments on which c was not the reference (whose differences are 0); a candidate that
/// was the reference on every look it saw takes the median σ of the others. Sorted by index.
pub fn estimates(looks: &[Vec<StageStats>], winner: u64) -> Vec<Estimate> {
    struct Acc {
        gap_sum: f64,
        n: u64,
        sd: Option<(u64, f64)>,
        esd: (u64, f64),
    }
    let mut acc: HashMap<u64, Acc> = HashMap::new();
    for look in looks {
        let Some(w) = look.iter().find(|s| s.index == winner) else {
            continue;
        };
        let w_mean = w.e.mean();
        for s in look {
            let a = acc.entry(s.index).or_insert(Acc {
                gap_sum: 0.0,
                n: 0,
                sd: None,
                esd: (0, 0.0),
            });
            a.gap_sum += s.e.sum - s.e.n as f64 * w_mean;
            a.n += s.e.n;
            if s.e.n >= a.esd.0 && s.e.n >= 2 {
                a.esd = (s.e.n, s.e.var().sqrt());
            }
            let is_reference = s.d.sum == 0.0 && s.d.sumsq == 0.0;
            if !is_reference && s.d.n >= 2 && a.sd.is_none_or(|(n, _)| s.d.n >= n) {
                a.sd = Some((s.d.n, s.d.var().sqrt()));
            }
        }
    }
    let mut known: Vec<f64> = acc.values().filter_map(|a| a.sd.map(|x| x.1)).collect();
    known.sort_by(f64::total_cmp);
    let median = known.get(known.len() / 2).copied().unwrap_or(0.0);
    let mut out: Vec<Estimate> = acc
        .into_iter()
        .map(|(index, a)| Estimate {
            index,
            gap: if a.n == 0 {
                0.0
            } else {
                a.gap_sum / a.n as f64
            },
            sd: a.sd.map_or(median, |x| x.1),
            esd: a.esd.1,
            fragments: a.n,
        })
        .collect();
    out.sort_by_key(|e| e.index);
    out
}

/// The run a forecast simulates: its kept fragments and racing parameters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Shape {
    /// Kept non-trivial fragments.
    pub fragments: usize,
    /// Fragments in racing stage 0.
    pub first_sample: usize,
    /// Sample growth factor per stage.
    pub growth: usize,
    /// Early look ([`SweepConfig::early_look`]).
    pub early_look: usize,
    /// Candidates tried to pick the stage-0 reference.
    pub pilot: usize,
    /// LP solves after which no look starts (0: none; [`SweepConfig::lp_budget`]).
    pub lp_budget: u64,
    /// Confidence 1 − α of the elimination tests.
    pub confidence: f64,
    /// What the confidence covers.
    pub correction: Correction,
    /// One-sided bound of the tests.
    pub bound: Bound,
    /// Paired differences (true) or independent intervals.
    pub paired: bool,
    /// Number of shards N.
    pub shards: usize,
    /// The proxy race's winner and the fragments it raced on ([`known_reference`]; None:
    /// every stage reference is the simulated leader).
    pub proxy_winner: Option<ProxyWinner>,
}

/// The proxy race's winner and the prefix of the run's fragment order the proxy raced on.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ProxyWinner {
    /// Candidate index.
    pub index: u64,
    /// The proxy's fragments: the first ones of the run's order.
    pub fragments: usize,
}

impl Shape {
    /// The race of `cfg` on `fragments` kept fragments.
    pub fn of(cfg: &SweepConfig, fragments: usize) -> Shape {
        Shape {
            fragments,
            first_sample: cfg.first_sample,
            growth: cfg.growth,
            early_look: cfg.early_look,
            pilot: cfg.pilot,
            lp_budget: cfg.lp_budget,
            confidence: cfg.confidence,
            correction: cfg.correction,
            bound: cfg.bound,
            paired: cfg.paired,
            shards: cfg.shard[1],
            proxy_winner: None,
        }
    }
}

/// Simulated runs of a race ([`simulate`]).
#[derive(Clone, Debug, PartialEq)]
pub struct Forecast {
    /// Simulated runs.
    pub replicates: usize,
    /// Mean LP solves per run (stage references and the pilot included).
    pub lp_solves: f64,
    /// 10th and 90th percentile of the runs' LP solves.
    pub range: (u64, u64),
    /// Mean LP solves of each candidate's own scoring (the fragments it was scored on), in the
    /// order of the estimates.
    pub per_candidate: Vec<f64>,
    /// Mean candidates entering each stage (0 for a run that stopped before it).
    pub stages: Vec<f64>,
}

/// `replicates` runs of the race `shape` on candidates with the true gaps and spreads `est`
/// (sorted by index, as the run orders its candidates), each seeded from `seed` and its
/// number, in parallel; the same inputs give the same forecast.
pub fn simulate(est: &[Estimate], shape: &Shape, replicates: usize, seed: u64) -> Forecast {
    let runs: Vec<Run> = (0..replicates.max(1) as u64)
        .into_par_iter()
        .map(|r| {
            let mut rng = ChaCha8Rng::seed_from_u64(seed ^ r.wrapping_mul(0x9E37_79B9_7F4A_7C15));
            one_run(est, shape, &mut rng)
        })
        .collect();
    let k = runs.len() as f64;
    let mut totals: Vec<u64> = runs.iter().map(|r| r.lp_solves).collect();
    totals.sort_unstable();
    let pick = |q: f64| totals[(q * (totals.len() - 1) as f64).round() as usize];
    let mut per_candidate = vec![0.0; est.len()];
    let mut stages: Vec<f64> = Vec::new();
    for r in &runs {
        for (p, &x) in per_candidate.iter_mut().zip(&r.per_candidate) {
            *p += x as f64 / k;
        }
        if stages.len() < r.stages.len() {
            stages.resize(r.stages.len(), 0.0);
        }
        for (s, &x) in stages.iter_mut().zip(&r.stages) {
            *s += x as f64 / k;
        }
    }
    Forecast {
        replicates: runs.len(),
        lp_solves: totals.iter().map(|&t| t as f64).sum::<f64>() / k,
        range: (pick(0.1), pick(0.9)),
        per_candidate,
        stages,
    }
}

/// One simulated run.
struct Run {
    lp_solves: u64,
    per_candidate: Vec<u64>,
    stages: Vec<u64>,
}

/// A look's sums of one candidate: fragments and Σ of its simulated per-fragment errors.
#[derive(Clone, Copy, Default)]
struct Sums {
    n: u64,
    sum: f64,
}

impl Sums {
    fn mean(&self) -> f64 {
        self.sum / self.n.max(1) as f64
    }
}

/// One run of the race of `shape` (the driver of `sweep::racing` on simulated look means).
fn one_run(est: &[Estimate], shape: &Shape, rng: &mut ChaCha8Rng) -> Run {
    let mut sim = Sim {
        est,
        shape,
        rng,
        pooled: vec![Sums::default(); est.len()],
        run: Run {
            lp_solves: 0,
            per_candidate: vec![0; est.len()],
            stages: Vec::new(),
        },
        stopped: false,
    };
    if est.is_empty() || shape.fragments == 0 {
        return sim.run;
    }
    let (pilot, plan) = race::blocks(shape.fragments, shape.first_sample, shape.growth);
    let planned_looks: usize = plan
        .iter()
        .enumerate()
        .map(|(k, r)| race::looks(k, r.len(), shape.early_look).len())
        .sum();
    let mut cur: Vec<usize> = (0..est.len()).collect();
    let mut reference = None;
    let mut stages_run = 0;
    for (k, block) in plan.iter().enumerate() {
        if cur.len() <= 1 || sim.stopped {
            break;
        }
        let first = race::looks(k, block.len(), shape.early_look)[0].len();
        if sim.over_budget(cur.len(), first) {
            sim.stopped = true;
            break;
        }
        let r = match reference {
            Some(r) => r,
            None => sim.pilot(pilot.len()),
        };
        let r = known_reference(shape, est, &cur, &plan[..k]).unwrap_or(r);
        cur = sim.stage(&cur, r, k, block.len(), planned_looks);
        stages_run += 1;
        reference = sim.leader(&cur).or(Some(r));
    }
    if sim.stopped && cur.len() > 1 {
        // The LP budget ended the race: the survivors stay unresolved, not completed.
        return sim.run;
    }
    // The survivors on every fragment they have not seen (`racing::Race::complete`).
    let rest = if stages_run > 0 {
        pilot.len() + plan[stages_run..].iter().map(|r| r.len()).sum::<usize>()
    } else {
        shape.fragments
    };
    if !cur.is_empty() && rest > 0 {
        sim.score(&cur, rest);
    }
    sim.run
}

/// The reference the run is known to pick for the stage after the blocks `before`
/// ([`Shape::proxy_winner`]): while every one of them lies in the fragments the proxy raced
/// on, the run picks its leader on fragments on which the proxy's winner proved best, so the
/// simulated run takes that winner (its position in `est`) while it is still in `cur`, in
/// place of the leader of its independent draws. None for stage 0 and otherwise.
fn known_reference(
    shape: &Shape,
    est: &[Estimate],
    cur: &[usize],
    before: &[std::ops::Range<usize>],
) -> Option<usize> {
    let w = shape.proxy_winner?;
    if before.last()?.end > w.fragments {
        return None;
    }
    cur.iter().copied().find(|&c| est[c].index == w.index)
}

/// The state of one simulated run.
struct Sim<'a, 'r> {
    est: &'a [Estimate],
    shape: &'a Shape,
    rng: &'r mut ChaCha8Rng,
    /// Each candidate's sums over every block it has seen.
    pooled: Vec<Sums>,
    run: Run,
    /// The LP budget ended the race.
    stopped: bool,
}

impl Sim<'_, '_> {
    /// Whether a look of `alive` candidates and the reference on `len` fragments would exceed
    /// the LP budget.
    fn over_budget(&self, alive: usize, len: usize) -> bool {
        let b = self.shape.lp_budget;
        b > 0 && self.run.lp_solves + ((alive + 1) * len) as u64 > b
    }

    /// Sum of candidate c's errors over m fragments: m·g_c + √(m/2)·σ_c · N(0, 1).
    fn draw(&mut self, c: usize, m: usize) -> f64 {
        let z: f64 = StandardNormal.sample(self.rng);
        m as f64 * self.est[c].gap + (m as f64 / 2.0).sqrt() * self.est[c].sd * z
    }

    /// Count the LP solves of scoring `cands` and a reference on m fragments.
    fn score(&mut self, cands: &[usize], m: usize) {
        self.run.lp_solves += ((cands.len() + 1) * m) as u64;
        for &c in cands {
            self.run.per_candidate[c] += m as u64;
        }
    }

    /// The stage-0 reference: the best of `pilot` evenly spaced candidates on the pilot block.
    fn pilot(&mut self, block: usize) -> usize {
        let n = self.est.len();
        let p = self.shape.pilot.clamp(1, n);
        self.run.lp_solves += (p * block) as u64;
        let sums: Vec<(usize, f64)> = (0..p)
            .map(|k| k * n / p)
            .map(|c| (c, self.draw(c, block)))
            .collect();
        sums.iter()
            .min_by(|a, b| a.1.total_cmp(&b.1).then(a.0.cmp(&b.0)))
            .expect("p ≥ 1")
            .0
    }

    /// Stage k of `cur` against `reference` on a block of `len` fragments: its looks, each
    /// decided by [`race::decide`]; the survivors.
    fn stage(
        &mut self,
        cur: &[usize],
        reference: usize,
        k: usize,
        len: usize,
        planned: usize,
    ) -> Vec<usize> {
        self.run.stages.push(cur.len() as u64);
        let shape = self.shape;
        let rule = Rule {
            delta: race::stage_delta(
                1.0 - shape.confidence,
                planned,
                cur.len(),
                shape.shards,
                shape.correction,
            ),
            bound: shape.bound,
            paired: shape.paired,
            width: 1.0,
        };
        let looks = race::looks(k, len, shape.early_look);
        let mut acc: HashMap<usize, Sums> = HashMap::with_capacity(cur.len() + 1);
        let mut alive = cur.to_vec();
        for (j, part) in looks.iter().enumerate() {
            let m = part.len();
            if j > 0 && self.over_budget(alive.len(), m) {
                self.stopped = true;
                break;
            }
            self.score(&alive, m);
            let mut scored = alive.clone();
            if !alive.contains(&reference) {
                scored.push(reference);
            }
            for c in scored {
                let x = self.draw(c, m);
                let a = acc.entry(c).or_default();
                a.n += m as u64;
                a.sum += x;
            }
            let r = acc[&reference];
            let stats: Vec<StageStats> = alive
                .iter()
                .map(|&c| stage_stats(&self.est[c], acc[&c], r, c == reference))
                .collect();
            let decisions = race::decide(&stats, self.est[reference].index, &rule);
            alive = alive
                .iter()
                .zip(&decisions)
                .filter(|(_, d)| d.is_none())
                .map(|(&c, _)| c)
                .collect();
        }
        for &c in cur {
            let a = acc[&c];
            self.pooled[c].n += a.n;
            self.pooled[c].sum += a.sum;
        }
        alive
    }

    /// The candidate of `cur` with the smallest pooled mean (ties: smallest index).
    fn leader(&self, cur: &[usize]) -> Option<usize> {
        cur.iter().copied().min_by(|&a, &b| {
            self.pooled[a]
                .mean()
                .total_cmp(&self.pooled[b].mean())
                .then(self.est[a].index.cmp(&self.est[b].index))
        })
    }
}

/// A candidate's statistics on a look from its simulated sums `a` and the reference's `r`:
/// means from the sums, spreads σ_c (paired) and its error spread (unpaired); the reference's
/// own differences are 0, as in a run.
fn stage_stats(e: &Estimate, a: Sums, r: Sums, is_reference: bool) -> StageStats {
    let moments = |n: u64, mean: f64, sd: f64| {
        let nf = n as f64;
        Moments::new(n, nf * mean, (nf - 1.0) * sd * sd + nf * mean * mean)
    };
    StageStats {
        index: e.index,
        e: moments(a.n, a.mean(), e.esd),
        d: if is_reference {
            Moments::new(a.n, 0.0, 0.0)
        } else {
            moments(a.n, a.mean() - r.mean(), e.sd)
        },
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn shape(fragments: usize) -> Shape {
        Shape {
            fragments,
            first_sample: 64,
            growth: 4,
            early_look: 0,
            pilot: 4,
            lp_budget: 0,
            confidence: 0.99,
            correction: Correction::Best,
            bound: Bound::Normal,
            paired: true,
            shards: 1,
            proxy_winner: None,
        }
    }

    /// Candidates `indices` with gap 0, spreads `sd` (paired) and `esd` (errors).
    fn tied(indices: std::ops::Range<u64>, sd: f64, esd: f64) -> Vec<Estimate> {
        indices
            .map(|index| Estimate {
                index,
                gap: 0.0,
                sd,
                esd,
                fragments: 0,
            })
            .collect()
    }

    /// The proxy's winner is the reference of a stage whose earlier blocks all lie in the
    /// proxy's fragments, while it races; never of stage 0.
    #[test]
    fn the_proxy_winner_is_the_reference_while_its_fragments_cover_the_blocks() {
        let est = tied(10..15, 1.0, 1.0);
        let s = Shape {
            proxy_winner: Some(ProxyWinner {
                index: 13,
                fragments: 200,
            }),
            ..shape(1000)
        };
        let blocks = [64..128, 128..384];
        let cur = [0, 1, 3, 4];
        assert_eq!(known_reference(&s, &est, &cur, &[]), None);
        assert_eq!(known_reference(&s, &est, &cur, &blocks[..1]), Some(3));
        assert_eq!(known_reference(&s, &est, &cur, &blocks), None);
        assert_eq!(known_reference(&s, &est, &[0, 1], &blocks[..1]), None);
        assert_eq!(
            known_reference(&shape(1000), &est, &cur, &blocks[..1]),
            None
        );
    }

    fn looks_of(rows: &[(u64, [f64; 5])]) -> Vec<StageStats> {
        rows.iter()
            .map(|&(index, [n, sum, sumsq, dsum, dsumsq])| StageStats {
                index,
                e: Moments::new(n as u64, sum, sumsq),
                d: Moments::new(n as u64, dsum, dsumsq),
            })
            .collect()
    }

    /// Gaps are fragment-weighted over the looks a candidate shares with the winner; σ comes
    /// from its largest look as a non-reference, else the median of the others.
    #[test]
    fn estimates_pool_gaps_over_shared_looks() {
        // Look 0 (4 fragments): winner 7 mean 1.0, candidate 3 mean 1.5, reference 9 (d = 0).
        // Look 1 (8 fragments): winner 7 mean 2.0 (the reference), candidate 3 mean 2.25.
        let l0 = looks_of(&[
            (3, [4.0, 6.0, 10.0, 2.0, 2.0]),
            (7, [4.0, 4.0, 5.0, 1.0, 1.0]),
            (9, [4.0, 3.0, 3.0, 0.0, 0.0]),
        ]);
        let l1 = looks_of(&[
            (3, [8.0, 18.0, 41.0, 2.0, 0.625]),
            (7, [8.0, 16.0, 33.0, 0.0, 0.0]),
        ]);
        let e = estimates(&[l0, l1], 7);
        assert_eq!(e.iter().map(|x| x.index).collect::<Vec<_>>(), [3, 7, 9]);
        // (4·0.5 + 8·0.25) / 12.
        assert!((e[0].gap - 4.0 / 12.0).abs() < 1e-15);
        assert_eq!(e[1].gap, 0.0);
        assert!((e[2].gap + 0.25).abs() < 1e-15);
        // Candidate 3: look 1, var = (0.625 − 4/8)/7.
        assert!((e[0].sd - (0.125f64 / 7.0).sqrt()).abs() < 1e-15);
        // Winner 7: look 0 only (it is the reference of look 1): var = (1 − 1/4)/3.
        assert!((e[1].sd - 0.5).abs() < 1e-15);
        // Reference 9 on its only look: the median of the others' σ (sorted, upper middle).
        assert_eq!(e[2].sd, e[1].sd.max(e[0].sd));
    }

    /// Candidates far worse than the best leave at the first look and only the best is left:
    /// the pilot, stage 0 with every candidate and the best on the rest of the fragments.
    #[test]
    fn clear_gaps_end_the_race_after_stage_zero() {
        let est: Vec<Estimate> = (0..40u64)
            .map(|i| Estimate {
                index: i,
                gap: if i == 0 { 0.0 } else { 1.0 },
                sd: 0.1,
                esd: 0.5,
                fragments: 0,
            })
            .collect();
        let s = Shape {
            pilot: 40,
            ..shape(4096)
        };
        let f = simulate(&est, &s, 8, 1);
        let (pilot, blocks) = (64u64, 64u64);
        let rest = 4096 - blocks;
        assert_eq!(f.lp_solves, (40 * pilot + 41 * blocks + 2 * rest) as f64);
        assert_eq!(f.range, (f.lp_solves as u64, f.lp_solves as u64));
        assert_eq!(f.stages, [40.0]);
        assert_eq!(f.per_candidate[0], (blocks + rest) as f64);
        assert_eq!(f.per_candidate[1], blocks as f64);
    }

    /// Identical candidates never leave by confidence at δ ≈ 1e-5 (`all`: a few in a million
    /// looks): every candidate runs every stage and is completed; an LP budget ends the race
    /// before the look that would exceed it, without completing anyone.
    #[test]
    fn ties_run_every_stage_until_the_budget() {
        let shape = |fragments| Shape {
            correction: Correction::All,
            ..shape(fragments)
        };
        let est = tied(0..256, 0.2, 0.3);
        let f = simulate(&est, &shape(8192), 16, 3);
        // Pilot 64, blocks 64, 256, 1024, 4096, then 2688; all 256 in every stage, then the
        // pilot block for all.
        assert_eq!(f.stages, [256.0; 5]);
        let lp = 4 * 64 + 257 * (64 + 256 + 1024 + 4096 + 2688) + 257 * 64;
        assert_eq!(f.lp_solves, lp as f64);
        // A budget that admits stages 0 and 1 only.
        let budget = (4 * 64 + 257 * (64 + 256) + 10) as u64;
        let s = Shape {
            lp_budget: budget,
            ..shape(8192)
        };
        let f = simulate(&est, &s, 16, 3);
        assert_eq!(f.stages, [256.0, 256.0]);
        assert_eq!(f.lp_solves, (4 * 64 + 257 * (64 + 256)) as f64);
    }

    /// At stage 0 a candidate whose gap to the reference is exactly the run's threshold
    /// z·σ/√n leaves by confidence with probability 1/2 (the difference of two look means is
    /// normal around it): counted over many simulated runs, the share of 200 such candidates
    /// that reach stage 1 is 1/2 within sampling error (half the noise is the reference's,
    /// shared by the run's candidates, so runs are the independent units).
    #[test]
    fn stage_zero_eliminations_match_the_normal_model() {
        let s = Shape {
            pilot: 1,
            ..shape(4 * 64)
        };
        let (pilot, blocks) = race::blocks(s.fragments, s.first_sample, s.growth);
        assert_eq!((pilot.len(), blocks[0].len(), blocks.len()), (64, 64, 2));
        let k = 200;
        let delta = race::stage_delta(0.01, 2, k + 1, 1, s.correction);
        let z = race::normal_quantile(1.0 - delta);
        let (sd, n) = (1.0, 64.0f64);
        // The reference (index 0, the pilot's only candidate) is far ahead of the others.
        let mut est = vec![Estimate {
            index: 0,
            gap: -10.0,
            sd,
            esd: 1.0,
            fragments: 0,
        }];
        est.extend((1..=k as u64).map(|index| Estimate {
            index,
            gap: -10.0 + z * sd / n.sqrt(),
            sd,
            esd: 1.0,
            fragments: 0,
        }));
        let runs = 2000;
        let f = simulate(&est, &s, runs, 11);
        let stay = (f.stages[1] - 1.0) / k as f64;
        // Per run the share that stays is Φ(Z) for the reference's shared noise Z: variance
        // 1/12, plus the binomial part.
        let se = ((1.0 / 12.0 + 0.25 / k as f64) / runs as f64).sqrt();
        assert!((stay - 0.5).abs() < 4.0 * se, "stay {stay} (se {se})");
    }
}
