//! Benchmark of the Algorithm 1 solvers on realistic problems (`momentlab bench lp`): median
//! microseconds per LP of the reference and the fast solver (with and without warm start) on the
//! same moment vectors, and their ratio, measured in the same run.

use super::instances::{kernel_patches, mixture_moments, power_table};
use crate::lp::FastSolver;
use crate::lp::ReferenceSolver;
use crate::lp::{MomentSolver, Status};
use crate::Grid;
use anyhow::{bail, Result};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use std::time::Instant;

/// What to measure.
#[derive(Clone, Debug)]
pub struct BenchConfig {
    /// Grid sizes.
    pub ns: Vec<usize>,
    /// Number of LPs per grid size for the fast solver.
    pub problems: usize,
    /// Number of LPs per grid size for the reference solver (a prefix of the same problems).
    pub reference_problems: usize,
    /// Number of basis functions: the power basis z, …, z^m (m = 4 is MSM).
    pub m: usize,
    /// Seed of the random depth maps.
    pub seed: u64,
    /// Timed repeats of the fast solvers' sequence (per-problem minimum is kept).
    pub repeats: usize,
}

/// Results for one grid size.
#[derive(Clone, Debug, serde::Serialize)]
pub struct BenchRow {
    /// Pricing kernel of the fast solver ("avx512", "avx2", "scalar").
    pub pricing_kernel: &'static str,
    /// Grid size.
    pub n: usize,
    /// Basis size (power basis z…z^m).
    pub m: usize,
    /// LPs timed for the fast solver.
    pub problems: usize,
    /// LPs timed for the reference (a prefix).
    pub reference_problems: usize,
    /// Median µs per LP.
    pub reference_us: f64,
    /// Median µs, from the moments with the warm start.
    pub fast_warm_us: f64,
    /// Median µs, from the moments, every solve cold.
    pub fast_cold_us: f64,
    /// Mean µs per LP (fast), to show the tail.
    pub fast_warm_mean_us: f64,
    /// Mean µs, cold.
    pub fast_cold_mean_us: f64,
    /// reference median / fast median.
    pub speedup_warm: f64,
    /// Reference median / cold median.
    pub speedup_cold: f64,
    /// Mean simplex pivots per LP.
    pub pivots_warm: f64,
    /// Mean pivots per LP, cold.
    pub pivots_cold: f64,
    /// Median / mean µs per LP given the kernel's distribution (`solve_distribution`:
    /// crossover start, no phase 1), and reference median / its median.
    pub fast_dist_us: f64,
    /// Mean µs, given the distribution.
    pub fast_dist_mean_us: f64,
    /// Reference median / distribution-start median.
    pub speedup_dist: f64,
    /// Mean phase-2 pivots per LP after the crossover.
    pub pivots_dist: f64,
    /// max |G_fast − G_reference| over the reference problems (warm, cold and distribution).
    pub max_abs_diff: f64,
    /// The same per mode: warm, cold, distribution start.
    pub max_abs_diff_modes: [f64; 3],
    /// Problems where the statuses differ (must be 0).
    pub status_mismatches: usize,
    /// Fast solves answered `Failed` (no certificate for either verdict), all three modes.
    pub failed: u64,
    /// Fast solves that returned an error (should be 0).
    pub errors: usize,
}

fn median(v: &mut [f64]) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(|a, b| a.total_cmp(b));
    let k = v.len() / 2;
    if v.len() % 2 == 1 {
        v[k]
    } else {
        0.5 * (v[k - 1] + v[k])
    }
}

/// The benchmark problems for grid size n: moment vectors of 9×9 Gaussian kernels over depth
/// maps with 1–3 clusters (depths snapped to the grid), each followed by its fragment depths.
pub fn problems(grid: &Grid, m: usize, count: usize, seed: u64) -> Result<Vec<Problem>> {
    let table = power_table(grid, m)?;
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut out = Vec::with_capacity(count);
    while out.len() < count {
        for patch in kernel_patches(&mut rng, grid, 16) {
            let b = mixture_moments(&table, &patch.mixture);
            let dist: Vec<(u32, f64)> = patch.mixture.iter().map(|&(i, w)| (i as u32, w)).collect();
            for &zf in &patch.zf {
                if out.len() < count {
                    out.push(Problem {
                        moments: b.clone(),
                        zf,
                        dist: dist.clone(),
                    });
                }
            }
        }
    }
    Ok(out)
}

/// One benchmark LP: the kernel's moments, the fragment depth, and the kernel's depth
/// distribution (for [`MomentSolver::solve_distribution`]).
#[derive(Clone, Debug)]
pub struct Problem {
    /// The kernel's moments b.
    pub moments: Vec<f64>,
    /// Fragment depth z_f.
    pub zf: f64,
    /// The kernel's depth distribution [(grid index, weight)].
    pub dist: Vec<(u32, f64)>,
}

/// µs per LP and (status, G) per LP.
type Timed = (Vec<f64>, Vec<(Option<Status>, f64)>);

/// Time each solve of `solver` over `probs`; returns (µs per LP, G per LP).
fn time_solver(
    solver: &mut dyn MomentSolver,
    probs: &[Problem],
    from_distribution: bool,
    mut progress: impl FnMut(),
) -> Result<Timed> {
    let mut times = Vec::with_capacity(probs.len());
    let mut gs = Vec::with_capacity(probs.len());
    for p in probs {
        let t0 = Instant::now();
        let sol = if from_distribution {
            solver.solve_distribution(&p.dist, p.zf)
        } else {
            solver.solve(&p.moments, p.zf)
        };
        times.push(t0.elapsed().as_secs_f64() * 1e6);
        // A solver error is recorded as status "error" (NaN), not fatal.
        gs.push(match sol {
            Ok(sol) => (Some(sol.status), sol.g),
            Err(_) => (None, f64::NAN),
        });
        progress();
    }
    Ok((times, gs))
}

/// A fast solver over the whole sequence `repeats` times from the same state (the solver is
/// deterministic, so every repeat does the same pivots), keeping each problem's minimum time:
/// this filters out preemption on a loaded machine. Returns (µs per LP, G per LP, mean pivots).
fn time_fast(
    solver: &mut FastSolver,
    probs: &[Problem],
    repeats: usize,
    from_distribution: bool,
) -> Result<(Timed, f64)> {
    let mut best = vec![f64::INFINITY; probs.len()];
    let mut gs = Vec::new();
    let mut pivots = 0.0;
    for _ in 0..repeats.max(1) {
        solver.reset();
        let p0 = solver.stats().pivots;
        let (t, g) = time_solver(solver, probs, from_distribution, || {})?;
        pivots = (solver.stats().pivots - p0) as f64 / probs.len() as f64;
        best.iter_mut().zip(&t).for_each(|(a, b)| *a = a.min(*b));
        gs = g;
    }
    Ok(((best, gs), pivots))
}

/// Run the benchmark for one grid size. `progress` is called after every reference LP.
pub fn run_one(cfg: &BenchConfig, n: usize, mut progress: impl FnMut()) -> Result<BenchRow> {
    if !(1..=8).contains(&cfg.m) {
        bail!("bench lp: m must be in 1..=8, got {}", cfg.m);
    }
    if cfg.problems == 0 {
        bail!("bench lp: need at least one problem");
    }
    let grid = Grid::uniform(n)?;
    let probs = problems(&grid, cfg.m, cfg.problems, cfg.seed ^ n as u64)?;
    let table = power_table(&grid, cfg.m)?;

    // Per-problem minimum over `cfg.repeats` identical passes (see `time_fast`).
    let mut warm = FastSolver::new(table.clone());
    let ((mut tw, gw), pivots_warm) = time_fast(&mut warm, &probs, cfg.repeats, false)?;
    let mut cold = FastSolver::new(table.clone());
    cold.set_warm_start(false);
    let ((mut tc, gc), pivots_cold) = time_fast(&mut cold, &probs, cfg.repeats, false)?;
    // The pipeline's case: the kernel's distribution is known (crossover start, no phase 1).
    let mut dist = FastSolver::new(table.clone());
    let ((mut td, gd), pivots_dist) = time_fast(&mut dist, &probs, cfg.repeats, true)?;

    let nref = cfg.reference_problems.min(probs.len());
    let mut reference = ReferenceSolver::new(table);
    let (mut tr, gr) = time_solver(&mut reference, &probs[..nref], false, &mut progress)?;

    let mut max_abs_diff: f64 = 0.0;
    let mut max_abs_diff_modes = [0.0f64; 3];
    let mut status_mismatches = 0;
    for i in 0..nref {
        for (mode, g) in [gw[i], gc[i], gd[i]].into_iter().enumerate() {
            if g.0 != gr[i].0 {
                status_mismatches += 1;
            } else if g.0 == Some(Status::Optimal) {
                let d = (g.1 - gr[i].1).abs();
                max_abs_diff = max_abs_diff.max(d);
                max_abs_diff_modes[mode] = max_abs_diff_modes[mode].max(d);
            }
        }
    }
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
    let (fast_warm_mean_us, fast_cold_mean_us) = (mean(&tw), mean(&tc));
    let reference_us = median(&mut tr);
    let fast_warm_us = median(&mut tw);
    let fast_cold_us = median(&mut tc);
    let fast_dist_mean_us = mean(&td);
    let fast_dist_us = median(&mut td);
    Ok(BenchRow {
        pricing_kernel: crate::lp::pricing_kernel(),
        n,
        m: cfg.m,
        problems: probs.len(),
        reference_problems: nref,
        reference_us,
        fast_warm_us,
        fast_cold_us,
        fast_warm_mean_us,
        fast_cold_mean_us,
        speedup_warm: reference_us / fast_warm_us,
        speedup_cold: reference_us / fast_cold_us,
        fast_dist_us,
        fast_dist_mean_us,
        speedup_dist: reference_us / fast_dist_us,
        pivots_dist,
        pivots_warm,
        pivots_cold,
        max_abs_diff,
        max_abs_diff_modes,
        status_mismatches,
        failed: warm.stats().failed + cold.stats().failed + dist.stats().failed,
        errors: gw
            .iter()
            .chain(&gc)
            .chain(&gd)
            .filter(|g| g.0.is_none())
            .count(),
    })
}
