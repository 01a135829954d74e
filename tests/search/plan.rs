//! `search --plan` schedules what the sweep then does: on a synthetic dataset, the planned
//! exhaustive work equals the `complete.json` of real runs, and the planned racing schedule
//! (no eliminations) bounds the real one (same blocks, at most as many candidates per stage and LP
//! solves), exactly when no elimination by confidence is possible (every shard, a candidate
//! subset, several sample sizes). The calibration times real solves.

use crate::common::search::{table, WITH_DEGENERATE};
use crate::common::tmp_path;
use momentlab::search::plan::{plan, proxy_race, Plan};
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
                    cfg.first_sample = first_sample;
                    cfg.growth = growth;
                    cfg.pilot = 4;
                    cfg.exhaustive = exhaustive;
                    cfg.candidates = candidates.clone();
                    cfg.shard = [0, shards];
                    let p: Plan = plan(&cfg, &s, [3, 20], None).unwrap();
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
/// planned one exactly, also when an LP budget ends it after stage 0 (nobody completed).
#[test]
fn without_confidence_eliminations_the_plan_is_exact() {
    let grid = Grid::uniform(24).unwrap();
    let table = table(&grid, &WITH_DEGENERATE);
    let data = Dataset::synthetic(11, &grid, 3, 25, 3).unwrap();
    let s = Scorer::new(&data, &table, "reference", 16).unwrap();
    let mut cfg = SweepConfig::new(3, &s, "synthetic");
    cfg.first_sample = 16;
    cfg.growth = 3;
    cfg.pilot = 4;
    cfg.bound = momentlab::search::race::Bound::Bernstein;
    cfg.confidence = 1.0 - 1e-12;
    let p = plan(&cfg, &s, [2, 10], None).unwrap();
    let a = actual(&cfg, &s, "exact");
    assert_eq!(a.race.as_ref().unwrap().confidence_eliminated, 0);
    assert_eq!(a.lp_solves, p.racing[0].lp_solves);
    assert_eq!(a.stages, p.racing[0].stages);
    assert_eq!(a.full, p.racing[0].full);
    assert!(a.stages.len() > 1, "{a:?}");
    let (c0, b0) = a.stages[0];
    cfg.lp_budget = 4 * 16 + (c0 + 1) * b0 + 1;
    let p = plan(&cfg, &s, [2, 10], None).unwrap();
    let a = actual(&cfg, &s, "exact-budget");
    let race = a.race.as_ref().unwrap();
    assert!(race.lp_budget_bound && race.unresolved == c0, "{race:?}");
    assert_eq!((a.lp_solves, a.full), (4 * 16 + (c0 + 1) * b0, 0));
    assert_eq!(a.lp_solves, p.racing[0].lp_solves);
    assert_eq!(a.stages, p.racing[0].stages);
    assert_eq!(a.full, p.racing[0].full);
}

/// A synthetic race with eliminations by evidence, resolved before its fragment budget.
fn racing_setup() -> (Grid, Dataset) {
    let grid = Grid::uniform(24).unwrap();
    let data = Dataset::synthetic(5, &grid, 4, 2000, 4).unwrap();
    (grid, data)
}

fn racing_config(s: &Scorer) -> SweepConfig {
    let mut cfg = SweepConfig::new(3, s, "synthetic");
    cfg.first_sample = 256;
    cfg.growth = 2;
    cfg.early_look = 256;
    cfg.pilot = 4;
    cfg
}

/// On 1/1 of the fragments the proxy race is the race: same stages, tie set and LP solves,
/// the LP solves split into the candidates' (per family) and the references'; the scratch
/// folder is left empty.
#[test]
fn a_proxy_race_on_every_fragment_is_the_race() {
    let (grid, data) = racing_setup();
    let table = table(&grid, &WITH_DEGENERATE);
    let s = Scorer::new(&data, &table, "fast", 64).unwrap();
    let cfg = racing_config(&s);
    let a = actual(&cfg, &s, "proxy-whole");
    let race = a.race.as_ref().unwrap();
    assert!(race.confidence_eliminated > 0, "{a:?}");
    let scratch = crate::common::tmp("proxy-scratch");
    let p = proxy_race(&cfg, &s, 1, &scratch).unwrap();
    assert_eq!(p.stages, a.stages);
    assert_eq!(p.tied, a.full);
    assert_eq!(p.lp_solves, a.lp_solves);
    assert_eq!(p.fragments, data.fragments().len() as u64);
    let candidates: u64 = p.by_family.iter().map(|f| f.1).sum();
    assert_eq!(candidates + p.other, p.lp_solves);
    assert!(p.other > 0 && candidates > p.other);
    assert_eq!(std::fs::read_dir(&scratch).unwrap().count(), 0);
    assert!(proxy_race(&cfg, &s, 0, &scratch).is_err());
}

/// On 1/4 of the fragments the proxy race runs the run's stages on blocks a quarter as large
/// (its stage sizes × 4 are the run's, up to rounding), and `plan` reports it for racing only;
/// its LP solves never exceed the fixed schedule's.
#[test]
fn a_proxy_race_on_a_quarter_scales_the_blocks() {
    let (grid, data) = racing_setup();
    let table = table(&grid, &WITH_DEGENERATE);
    let s = Scorer::new(&data, &table, "fast", 64).unwrap();
    let mut cfg = racing_config(&s);
    let scratch = crate::common::tmp("proxy-quarter-scratch");
    let planned = plan(&cfg, &s, [2, 10], Some((4, &scratch))).unwrap();
    let p = planned.proxy.expect("racing with a proxy");
    assert_eq!(p.share, 4);
    assert_eq!(p.fragments, (data.fragments().len() as u64).div_ceil(4));
    // Up to the rounding of the quarter blocks (each at most 3 fragments short × 4).
    let bound = planned.racing[0].lp_solves;
    assert!(
        p.lp_solves <= bound + bound / 100,
        "{} vs {bound}",
        p.lp_solves
    );
    for (x, y) in p.stages.iter().zip(&planned.racing[0].stages) {
        assert!(
            x.0 <= y.0 && x.1.abs_diff(y.1) < 4 * 4,
            "{:?} vs {:?}",
            p.stages,
            planned.racing
        );
    }
    cfg.exhaustive = true;
    assert!(plan(&cfg, &s, [2, 10], Some((4, &scratch)))
        .unwrap()
        .proxy
        .is_none());
}

/// `search --plan` prints racing's expected cost (runs simulated from the proxy race) as the
/// chosen row, the upper bound beside it, the proxy's stages and the simulated runs' range; `--plan-proxy 0` leaves only the bound,
/// chosen; `--plan-proxy` needs `--plan`. Nothing is left in the results folder.
#[test]
fn the_plan_prints_the_proxy_races_expected_cost() {
    let results = crate::common::tmp_path("plan-cli");
    let r = results.to_str().unwrap();
    let base = [
        "search",
        "--synthetic",
        "300",
        "--m",
        "2",
        "--plan",
        "--results",
        r,
    ];
    let (code, out, err) = crate::common::run(&[&base[..], &["--plan-proxy", "2"]].concat(), None);
    assert_eq!(code, 0, "{err}");
    let row = |label: &str| {
        out.lines()
            .find(|l| l.contains(label))
            .unwrap_or_else(|| panic!("no '{label}' in {out}"))
            .to_string()
    };
    assert!(row("racing (expected)").starts_with("plan: * racing"));
    assert!(row("racing (at most)").starts_with("plan:   racing"));
    assert!(row("proxy race on 1/2 of the fragments").contains("its LP solves × 2 = "));
    assert!(row("expected from 64 runs of the race simulated").contains("80 % of the runs between"));
    let (code, out, err) = crate::common::run(&[&base[..], &["--plan-proxy", "0"]].concat(), None);
    assert_eq!(code, 0, "{err}");
    assert!(!out.contains("expected"), "{out}");
    assert!(out.contains("plan: * racing (at most)"), "{out}");
    let (code, _, err) =
        crate::common::run(&["search", "--synthetic", "300", "--plan-proxy", "2"], None);
    assert_eq!(code, 2);
    assert!(err.contains("--plan"), "{err}");
    assert!(!results.exists());
}

/// The plan's forecast, simulated from a proxy race on a quarter of the fragments with its
/// estimates refined on the next two stage-0 blocks, follows the race's cost over fragment
/// orders: the real races of six orders (eliminations by evidence decide every stage) average
/// within 20 % of the forecast of the first, at most 20 % above its 80 % range; the forecast
/// never exceeds the fixed schedule, and its family split sums to it.
#[test]
fn the_forecast_follows_the_races_of_other_orders() {
    let (grid, data) = racing_setup();
    let table = table(&grid, &WITH_DEGENERATE);
    let s = Scorer::new(&data, &table, "fast", 64).unwrap();
    let mut cfg = racing_config(&s);
    let scratch = crate::common::tmp("proxy-forecast-scratch");
    let planned = plan(&cfg, &s, [2, 10], Some((4, &scratch))).unwrap();
    let p = planned.proxy.expect("racing with a proxy");
    let f = p.forecast.clone().expect("a forecast");
    // The fragments after the proxy's quarter hold two stage-0 blocks: the estimates were
    // refined there (refine.rs).
    let r = f.refinement.clone().expect("a refinement");
    assert_eq!(r.fragments, 2 * cfg.first_sample);
    assert!(r.closest > 0 && r.lp_solves > 0, "{r:?}");
    let bound = planned.racing[0].lp_solves;
    assert!(f.lp_solves <= bound, "{} vs {bound}", f.lp_solves);
    assert!(
        f.range.0 as f64 <= f.lp_solves as f64 && f.lp_solves <= f.range.1,
        "{f:?}"
    );
    let own: u64 = f.by_family.iter().map(|x| x.1).sum();
    assert_eq!(own + f.other, f.lp_solves);
    assert_eq!(p.expected().0, f.lp_solves);
    let runs: Vec<u64> = (1..=6)
        .map(|seed| {
            cfg.seed = seed;
            actual(&cfg, &s, &format!("forecast-order{seed}")).lp_solves
        })
        .collect();
    let mean = runs.iter().sum::<u64>() as f64 / runs.len() as f64;
    assert!(
        (f.lp_solves as f64 / mean - 1.0).abs() < 0.2,
        "forecast {} vs the races' mean {mean} ({runs:?})",
        f.lp_solves
    );
    // The 80 % range is the spread of simulated orders on the estimates, which carry errors
    // of their own: the six orders' mean lies in it or at most 20 % above its upper end.
    assert!(
        f.range.0 as f64 <= mean && mean <= 1.2 * f.range.1 as f64,
        "{runs:?} vs {:?}",
        f.range
    );
    assert!(runs.iter().any(|&r| r != runs[0]), "{runs:?}");
}
