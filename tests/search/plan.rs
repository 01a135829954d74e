//! `search --plan` schedules what the sweep then does: on a synthetic dataset, the planned
//! exhaustive work equals the `complete.json` of real runs, and the planned racing schedule
//! (the cap only) bounds the real one (same blocks, at most as many candidates per stage and LP
//! solves), exactly when no elimination by confidence is possible (every shard, a candidate
//! subset, several sample sizes). The calibration times real solves.

use crate::common::search::{table, WITH_DEGENERATE};
use crate::common::tmp_path;
use momentlab::search::plan::{plan, Plan};
use momentlab::search::{run_sweep, Dataset, Hooks, Outcome, Scorer, SweepConfig};
use momentlab::Grid;

fn actual(cfg: &SweepConfig, s: &Scorer, name: &str) -> momentlab::search::SweepSummary {
    let dir = tmp_path(name);
    let out = run_sweep(cfg, s, &dir, &Hooks::default()).unwrap();
    std::fs::remove_dir_all(&dir).unwrap();
    match out {
        Outcome::Complete(s) => s,
        Outcome::Stopped => panic!("stopped"),
    }
}

#[test]
fn plan_equals_the_sweeps_own_schedule() {
    let grid = Grid::uniform(24).unwrap();
    let table = table(&grid, &WITH_DEGENERATE);
    let mut checked = 0;
    for (texels, first_sample, growth) in [(60, 40, 2), (25, 16, 3)] {
        let data = Dataset::synthetic(11, &grid, 3, texels, 3).unwrap();
        let s = Scorer::new(&data, &table, "reference", 16).unwrap();
        for (m, candidates) in [
            (2, None),
            (3, None),
            (3, Some(vec![0, 5, 9, 13, 20, 21, 30, 55])),
        ] {
            for exhaustive in [false, true] {
                for shards in [1, 3] {
                    let mut cfg = SweepConfig::new(m, &s, "synthetic");
                    cfg.top = 4;
                    cfg.first_sample = first_sample;
                    cfg.growth = growth;
                    cfg.pilot = 4;
                    cfg.exhaustive = exhaustive;
                    cfg.candidates = candidates.clone();
                    cfg.shard = [0, shards];
                    let p: Plan = plan(&cfg, &s, [3, 20]).unwrap();
                    assert!(p.calibration.lp_solves > 0 && p.calibration.seconds > 0.0);
                    let per = if exhaustive { &p.exhaustive } else { &p.racing };
                    assert_eq!(per.len(), shards);
                    let (mut deg, mut dup) = (0, 0);
                    for (i, planned) in per.iter().enumerate() {
                        cfg.shard = [i, shards];
                        let a = actual(&cfg, &s, &format!("{m}{exhaustive}{shards}{i}"));
                        if exhaustive {
                            assert_eq!(planned.lp_solves, a.lp_solves, "{cfg:?}");
                            assert_eq!(planned.stages, a.stages, "{cfg:?}");
                            assert_eq!(planned.full, a.full, "{cfg:?}");
                        } else {
                            assert!(a.lp_solves <= planned.lp_solves, "{cfg:?}");
                            assert!(a.stages.len() <= planned.stages.len(), "{cfg:?}");
                            for (x, y) in a.stages.iter().zip(&planned.stages) {
                                assert!(x.0 <= y.0 && x.1 == y.1, "{cfg:?}");
                            }
                            assert_eq!(
                                a.stages.first().map(|x| x.0),
                                planned.stages.first().map(|x| x.0)
                            );
                        }
                        deg += a.degenerate;
                        dup += a.duplicates;
                        checked += 1;
                    }
                    assert_eq!((p.degenerate, p.duplicates), (deg, dup));
                    assert!(p.degenerate + p.duplicates > 0 || candidates.is_some());
                }
            }
        }
    }
    assert_eq!(checked, 2 * 3 * 2 * 4);
}

/// With the Bernstein bound at a confidence so high that its range term exceeds any possible
/// gap (errors lie in [0, 1]), no candidate can leave by confidence: the real schedule is the
/// planned one exactly.
#[test]
fn without_confidence_eliminations_the_plan_is_exact() {
    let grid = Grid::uniform(24).unwrap();
    let table = table(&grid, &WITH_DEGENERATE);
    let data = Dataset::synthetic(11, &grid, 3, 25, 3).unwrap();
    let s = Scorer::new(&data, &table, "reference", 16).unwrap();
    let mut cfg = SweepConfig::new(3, &s, "synthetic");
    cfg.top = 4;
    cfg.first_sample = 16;
    cfg.growth = 3;
    cfg.pilot = 4;
    cfg.bound = momentlab::search::race::Bound::Bernstein;
    cfg.confidence = 1.0 - 1e-12;
    let p = plan(&cfg, &s, [2, 10]).unwrap();
    let a = actual(&cfg, &s, "exact");
    assert_eq!(a.race.as_ref().unwrap().confidence_eliminated, 0);
    assert_eq!(a.lp_solves, p.racing[0].lp_solves);
    assert_eq!(a.stages, p.racing[0].stages);
    assert_eq!(a.full, p.racing[0].full);
}
