//! Timing of the fast solver on a corpus of problems (`momentlab bench lp --corpus stacks` or
//! `--corpus adversarial`): µs per LP as mean, median, p99, p99.9 and max, per-problem status
//! counts, and the microlp reference timed on a prefix of the same problems in the same run.
//!
//! Every problem is solved the way the pipeline solves it — given its depth distribution
//! ([`MomentSolver::solve_distribution`]) — or, with [`Start::Moments`], from its moments alone
//! ([`MomentSolver::solve`], the path of `momentlab lp`); one solver per table, warm state
//! carried from one problem to the next.

use super::corpus::{Group, Problem};
use crate::lp::FastSolver;
use crate::lp::ReferenceSolver;
use crate::lp::{distribution_moments, support_reproduces, MomentSolver, Solution, Status};
use anyhow::Result;
use std::time::Instant;

/// Summary of a set of per-LP times (µs).
#[derive(Clone, Copy, Debug, Default, serde::Serialize)]
pub struct Spread {
    /// Mean.
    pub mean: f64,
    /// Median (nearest rank).
    pub median: f64,
    /// 99th percentile.
    pub p99: f64,
    /// 99.9th percentile.
    pub p999: f64,
    /// Largest.
    pub max: f64,
}

impl Spread {
    /// Mean and order statistics (nearest rank) of `v`; all NaN when empty.
    pub fn of(v: &[f64]) -> Spread {
        if v.is_empty() {
            let nan = f64::NAN;
            return Spread {
                mean: nan,
                median: nan,
                p99: nan,
                p999: nan,
                max: nan,
            };
        }
        let mut s = v.to_vec();
        s.sort_by(|a, b| a.total_cmp(b));
        let rank = |q: f64| s[((q * s.len() as f64).ceil() as usize).clamp(1, s.len()) - 1];
        Spread {
            mean: s.iter().sum::<f64>() / s.len() as f64,
            median: rank(0.5),
            p99: rank(0.99),
            p999: rank(0.999),
            max: s[s.len() - 1],
        }
    }
}

/// One corpus's figures.
#[derive(Clone, Debug, serde::Serialize)]
pub struct CorpusRow {
    /// Row label.
    pub corpus: String,
    /// Grid sizes of the corpus's tables.
    pub ns: Vec<usize>,
    /// Number of tables (groups).
    pub tables: usize,
    /// LPs solved by the fast solver.
    pub problems: usize,
    /// Fast solver, µs per LP (per-problem minimum over the repeats).
    pub fast_us: Spread,
    /// Answers certified optimal.
    pub optimal: usize,
    /// Answers certified infeasible.
    pub infeasible: usize,
    /// `Failed` answers (no certificate for either verdict).
    pub failed: usize,
    /// Solves escalated to the scaled simplex (in the last pass).
    pub escalations: u64,
    /// Of which settled only by the exact simplex (`lp::exact`).
    pub exact: u64,
    /// The reference (good_lp + microlp) on a prefix of the problems, µs per LP.
    pub reference_problems: usize,
    /// The reference, µs per LP.
    pub reference_us: Spread,
    /// The fast solver's mean µs on the same prefix.
    pub fast_prefix_mean_us: f64,
    /// reference mean / fast mean on the same problems.
    pub speedup_mean: f64,
    /// Reference answers that are errors, not optimal, or miss a moment by more than the
    /// contract's 1e-9 of its own scale (max(|b_j|, 1e-10·max|f_j|)): counted, not compared.
    /// On flat receivers G moves by up to 1e-2 within a 1e-6 moment tolerance (docs/lp.md).
    pub reference_invalid: usize,
    /// max |G_fast − G_reference| where both are optimal and the reference answer valid.
    pub max_abs_diff: f64,
    /// Per table (group): where the mean and the failures come from.
    pub groups: Vec<GroupRow>,
}

/// One group's share of a corpus row.
#[derive(Clone, Debug, serde::Serialize)]
pub struct GroupRow {
    /// "basis @ n: kind".
    pub name: String,
    /// LPs in the group.
    pub problems: usize,
    /// Sum of the fast solver's µs over the group's problems.
    pub total_us: f64,
    /// Slowest LP, µs.
    pub max_us: f64,
    /// `Failed` answers.
    pub failed: usize,
    /// Solves escalated to the scaled simplex.
    pub escalations: u64,
    /// Solves handed to the exact simplex.
    pub exact: u64,
    /// The reason given by the group's first `Failed` answer.
    pub first_reason: Option<String>,
}

/// What the fast solver is given.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Start {
    /// The problem's depth distribution (the pipeline's path: crossover start).
    Distribution,
    /// Only its moments b = Σ w_i b(z_i), formed before the clock starts.
    Moments,
}

/// Time the fast solver on every problem of `groups` (`repeats` passes, minimum per problem)
/// and the reference on the first `reference_per_group` problems of each group, interleaved
/// (see [`time_group`]);
/// `progress(k)` after each group with k LPs done.
pub fn run(
    corpus: &str,
    groups: &[Group],
    reference_per_group: usize,
    repeats: usize,
    start: Start,
    mut progress: impl FnMut(u64),
) -> Result<CorpusRow> {
    let mut fast_us = Vec::new();
    let (mut ref_us, mut prefix_us) = (Vec::new(), Vec::new());
    let mut row = CorpusRow {
        corpus: corpus.to_string(),
        ns: Vec::new(),
        tables: groups.len(),
        problems: 0,
        fast_us: Spread::default(),
        optimal: 0,
        infeasible: 0,
        failed: 0,
        escalations: 0,
        exact: 0,
        reference_problems: 0,
        reference_us: Spread::default(),
        fast_prefix_mean_us: f64::NAN,
        speedup_mean: f64::NAN,
        reference_invalid: 0,
        max_abs_diff: 0.0,
        groups: Vec::new(),
    };
    for g in groups {
        if !row.ns.contains(&g.table.n()) {
            row.ns.push(g.table.n());
        }
        let Timed {
            fast_us: times,
            sols,
            stats,
            reference,
        } = time_group(g, repeats, reference_per_group, start)?;
        row.escalations += stats.escalations;
        row.exact += stats.exact;
        row.groups.push(GroupRow {
            name: g.name.clone(),
            problems: times.len(),
            total_us: times.iter().sum(),
            max_us: times.iter().fold(0.0, |a: f64, &t| a.max(t)),
            failed: sols.iter().filter(|s| s.status == Status::Failed).count(),
            escalations: stats.escalations,
            exact: stats.exact,
            first_reason: sols.iter().find_map(|s| s.reason.clone()),
        });
        for s in &sols {
            match s.status {
                Status::Optimal => row.optimal += 1,
                Status::Infeasible => row.infeasible += 1,
                Status::Failed => row.failed += 1,
            }
        }
        for (k, b, us, r) in reference {
            ref_us.push(us);
            prefix_us.push(times[k]);
            match r {
                Ok(r)
                    if r.status == Status::Optimal
                        && support_reproduces(&g.table, &b, &r, 1e-9) =>
                {
                    if sols[k].status == Status::Optimal {
                        row.max_abs_diff = row.max_abs_diff.max((sols[k].g - r.g).abs());
                    }
                }
                _ => row.reference_invalid += 1,
            }
        }
        row.problems += times.len();
        fast_us.extend(times);
        progress(sols.len() as u64);
    }
    row.fast_us = Spread::of(&fast_us);
    row.reference_problems = ref_us.len();
    row.reference_us = Spread::of(&ref_us);
    row.fast_prefix_mean_us = Spread::of(&prefix_us).mean;
    row.speedup_mean = row.reference_us.mean / row.fast_prefix_mean_us;
    Ok(row)
}

/// The Markdown table of corpus rows as docs/lp.md shows it: label, mean, median and p99 µs,
/// the speed-up over microlp on the mean, escalations, exact solves and failed answers. Reads
/// the JSON of `bench lp --json`.
pub fn markdown_rows(rows: &serde_json::Value) -> Option<String> {
    let mut out = String::from(
        "| row | mean µs | median | p99 | × microlp (mean) | escalated | exact | failed |\n\
         |---|---|---|---|---|---|---|---|",
    );
    for r in rows.as_array()? {
        let f = &r["fast_us"];
        out += &format!(
            "\n| {} | {:.1} | {:.1} | {:.1} | {:.0} | {} | {} | {} |",
            r["corpus"].as_str()?,
            f["mean"].as_f64()?,
            f["median"].as_f64()?,
            f["p99"].as_f64()?,
            r["speedup_mean"].as_f64()?,
            r["escalations"].as_u64()?,
            r["exact"].as_u64()?,
            r["failed"].as_u64()?
        );
    }
    Some(out)
}

/// Problems per stretch of [`time_group`]: the fast passes over a stretch and the reference on
/// its problems run within about a millisecond of each other.
const STRETCH: usize = 64;

/// What [`time_group`] measured.
struct Timed {
    /// µs per LP of the fast solver (minimum over the passes), in solve order.
    fast_us: Vec<f64>,
    /// Its answers (of the last pass).
    sols: Vec<Solution>,
    /// Its counters over one pass (escalations, exact, same_moments, pivots).
    stats: crate::lp::FastStats,
    /// (solve index, moments, µs, answer) of the reference on the first fragment depth of each
    /// of the first problems.
    reference: Vec<(usize, Vec<f64>, f64, crate::lp::Result<Solution>)>,
}

/// The fast solver on every problem of `g`, `repeats` passes (minimum per problem), with the
/// warm state carried from problem to problem as in one sequential pass; the reference on the
/// first `reference_per_group` problems. Both run stretch by stretch ([`STRETCH`] problems:
/// the fast passes, then the reference on the same problems), so that the speed-up is a ratio
/// of times taken in the same phase of a machine whose speed drifts by 10–40 % over seconds.
fn time_group(
    g: &Group,
    repeats: usize,
    reference_per_group: usize,
    start: Start,
) -> Result<Timed> {
    let mut solver = FastSolver::new(g.table.clone());
    let mut reference = ReferenceSolver::new(g.table.clone());
    let mut out = Timed {
        fast_us: Vec::new(),
        sols: Vec::new(),
        stats: Default::default(),
        reference: Vec::new(),
    };
    for (s, stretch) in g.problems.chunks(STRETCH).enumerate() {
        let k0 = out.fast_us.len();
        let moments = match start {
            Start::Distribution => Vec::new(),
            Start::Moments => stretch
                .iter()
                .map(|p| distribution_moments(&g.table, &p.dist))
                .collect::<crate::lp::Result<_>>()?,
        };
        time_stretch(&mut solver, stretch, &moments, repeats, &mut out)?;
        // The reference on the first fragment depth of the stretch's problems in the prefix.
        let mut k = k0;
        for (i, p) in stretch.iter().enumerate() {
            if s * STRETCH + i < reference_per_group {
                let b = distribution_moments(&g.table, &p.dist)?;
                let t0 = Instant::now();
                let r = reference.solve(&b, p.zf[0]);
                let us = t0.elapsed().as_secs_f64() * 1e6;
                out.reference.push((k, b, us, r));
            }
            k += p.zf.len();
        }
    }
    Ok(out)
}

/// `repeats` passes of the fast solver over one stretch, each from the warm state the stretch
/// started with: appends the minimum µs and the last pass's answers and counters to `out`.
/// Given `moments` (one vector per problem) the solver gets those instead of the
/// distributions.
fn time_stretch(
    solver: &mut FastSolver,
    stretch: &[Problem],
    moments: &[Vec<f64>],
    repeats: usize,
    out: &mut Timed,
) -> Result<()> {
    let start = solver.warm_state();
    let k0 = out.fast_us.len();
    for rep in 0..repeats.max(1) {
        solver.restore_warm_state(&start);
        out.sols.truncate(k0);
        let before = solver.stats();
        let mut k = k0;
        for (j, p) in stretch.iter().enumerate() {
            for &zf in &p.zf {
                let t0 = Instant::now();
                let s = match moments.get(j) {
                    Some(b) => solver.solve(b, zf)?,
                    None => solver.solve_distribution(&p.dist, zf)?,
                };
                let us = t0.elapsed().as_secs_f64() * 1e6;
                if rep == 0 {
                    out.fast_us.push(us);
                } else {
                    out.fast_us[k] = out.fast_us[k].min(us);
                }
                out.sols.push(s);
                k += 1;
            }
        }
        if rep + 1 == repeats.max(1) {
            // Counters of the last pass only (the statuses are the last pass's too).
            let after = solver.stats();
            out.stats.escalations += after.escalations - before.escalations;
            out.stats.exact += after.exact - before.exact;
            out.stats.same_moments += after.same_moments - before.same_moments;
            out.stats.pivots += after.pivots - before.pivots;
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::{time_group, Spread, Start, STRETCH};
    use crate::bench::corpus::{problem, Group, Kind};
    use crate::bench::instances::power_table;
    use crate::lp::FastSolver;
    use crate::lp::MomentSolver;
    use crate::Grid;
    use rand::SeedableRng;

    /// Stretch-wise timing with repeats gives the answers of one sequential pass (the warm
    /// state restored before every repeat of a stretch), and times the reference on exactly
    /// the requested prefix, at the solve index of each problem's first fragment depth.
    #[test]
    fn stretches_answer_as_one_sequential_pass() {
        let grid = Grid::uniform(256).unwrap();
        let table = power_table(&grid, 4).unwrap();
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        let kinds = [Kind::Flat, Kind::Cluster, Kind::Mixture, Kind::Adjacent];
        // Some problems with two fragment depths (the same moments twice: a warm start).
        let mut problems: Vec<_> = (0..2 * STRETCH + 9)
            .map(|k| {
                let mut p = problem(&mut rng, 256, 4, kinds[k % kinds.len()]);
                if k % 3 == 0 {
                    let z = p.zf[0];
                    p.zf.push((z + 0.1).min(1.0));
                }
                p
            })
            .collect();
        // The first problem of the second stretch has the moments of the last of the first:
        // solved from the warm basis only if each repeat starts from the state the first
        // stretch left.
        problems[STRETCH] = problems[STRETCH - 1].clone();
        let g = Group {
            name: "test".into(),
            basis: vec![],
            table: table.clone(),
            problems,
        };
        let timed = time_group(&g, 3, STRETCH + 5, Start::Distribution).unwrap();
        let mut fast = FastSolver::new(table);
        let mut k = 0;
        let mut firsts = Vec::new();
        for p in &g.problems {
            firsts.push(k);
            for &zf in &p.zf {
                let s = fast.solve_distribution(&p.dist, zf).unwrap();
                assert_eq!(s, timed.sols[k], "solve {k}");
                k += 1;
            }
        }
        assert_eq!(timed.fast_us.len(), k);
        assert_eq!(timed.stats.same_moments, fast.stats().same_moments);
        assert_eq!(timed.stats.pivots, fast.stats().pivots);
        assert!(timed.fast_us.iter().all(|t| t.is_finite() && *t >= 0.0));
        let at: Vec<usize> = timed.reference.iter().map(|r| r.0).collect();
        assert_eq!(at, firsts[..STRETCH + 5].to_vec());
    }

    /// Given [`Start::Moments`] the timed passes answer as `solve` on the moments, one problem
    /// after the other on one solver.
    #[test]
    fn moments_start_answers_as_sequential_solves() {
        let grid = Grid::uniform(512).unwrap();
        let table = power_table(&grid, 4).unwrap();
        let mut groups = crate::bench::corpus::moments_groups(&table, "z..z^4", STRETCH + 7, 3);
        assert_eq!(groups.len(), 2);
        for g in &mut groups {
            let timed = time_group(g, 2, 3, Start::Moments).unwrap();
            let mut fast = FastSolver::new(table.clone());
            for (k, p) in g.problems.iter().enumerate() {
                assert_eq!(p.zf.len(), 1);
                let b = crate::lp::distribution_moments(&table, &p.dist).unwrap();
                let s = fast.solve(&b, p.zf[0]).unwrap();
                assert_eq!(s, timed.sols[k], "{} problem {k}", g.name);
            }
            assert_eq!(timed.reference.len(), 3);
        }
    }

    /// docs/lp.md's moments-only and stacks tables are the renderings of
    /// reports/bench/lp_moments.json and lp_stacks.json.
    #[test]
    fn docs_table_renders_the_artefact() {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
        let doc = std::fs::read_to_string(root.join("docs/lp.md")).unwrap();
        for name in ["lp_moments.json", "lp_stacks.json"] {
            let path = root.join("reports/bench").join(name);
            let json = std::fs::read_to_string(&path).unwrap();
            let rows: serde_json::Value = serde_json::from_str(&json).unwrap();
            let table = super::markdown_rows(&rows).expect("bench lp --json rows");
            assert!(
                doc.contains(&table),
                "docs/lp.md does not show {name}:\n{table}"
            );
            // A changed figure fails the check.
            let mut changed = rows.clone();
            changed[0]["fast_us"]["mean"] = serde_json::json!(1234.5);
            assert!(!doc.contains(&super::markdown_rows(&changed).unwrap()));
        }
        // The flat windows' cost against the stacks corpus's, per grid size.
        let mean = |name: &str, row: &str| -> f64 {
            let path = root.join("reports/bench").join(name);
            let rows: serde_json::Value =
                serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
            let r = rows.as_array().unwrap().iter().find(|r| r["corpus"] == row);
            r.unwrap_or_else(|| panic!("{name}: no row {row}"))["fast_us"]["mean"]
                .as_f64()
                .unwrap()
        };
        let ratio = |n: usize| {
            let flat = mean("lp_moments.json", &format!("flat n = {n}"));
            flat / mean("lp_stacks.json", &format!("stacks n = {n}"))
        };
        let sentence = format!(
            "{:.1}× (n = 1024) and {:.1}× (n = 4096) the stacks corpus's mean",
            ratio(1024),
            ratio(4096)
        );
        assert!(
            doc.contains(&sentence),
            "docs/lp.md does not say {sentence}"
        );
    }

    #[test]
    fn spread_order_statistics() {
        let v: Vec<f64> = (1..=1000).map(|k| k as f64).collect();
        let s = Spread::of(&v);
        assert_eq!(s.mean, 500.5);
        assert_eq!(s.median, 500.0);
        assert_eq!(s.p99, 990.0);
        assert_eq!(s.p999, 999.0);
        assert_eq!(s.max, 1000.0);
        assert!(Spread::of(&[]).mean.is_nan());
    }
}
