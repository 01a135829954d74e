//! Test problems of Algorithm 1 (deterministic for a seed): distributions on the grid with
//! known moments, chosen where solvers break (flat receivers, adjacent points, tight clusters,
//! boundary moment vectors, mixtures), the moments-only groups and groups from real filter
//! windows. The LP's unit tests, tests/lp and `momentlab bench lp` ([`crate::bench::corpus`],
//! which adds the adversarial set of bases) draw from here.
//!
//! Every problem is the moment vector of a known distribution on the grid, so it is feasible
//! and its own mass below z_f bounds G from above ([`mass_below`]).

use super::GridTable;
use crate::Grid;
use anyhow::Result;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// One problem: a distribution [(grid index, weight)] (weights sum to 1) and the fragment
/// depths to solve for (consecutive solves share the moments, as in the pipeline).
#[derive(Clone, Debug)]
pub struct Problem {
    /// The distribution [(grid index, weight)], weights summing to 1.
    pub dist: Vec<(u32, f64)>,
    /// Fragment depths to solve for.
    pub zf: Vec<f64>,
}

/// A table with its problems.
#[derive(Clone, Debug)]
pub struct Group {
    /// "basis @ n: kind".
    pub name: String,
    /// The basis formulas.
    pub basis: Vec<String>,
    /// The constraint table.
    pub table: GridTable,
    /// The problems on it.
    pub problems: Vec<Problem>,
}

/// Kinds of problem.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// Flat-receiver 9×9 Gaussian windows.
    Flat,
    /// 1–3 adjacent grid points.
    Adjacent,
    /// Two points 1–3 grid steps apart with most of the mass on one.
    Cluster,
    /// At most m/2 Diracs (the boundary of the moment space).
    Boundary,
    /// 1–6 random Diracs.
    Mixture,
}

/// Every kind, in order.
pub const KINDS: [Kind; 5] = [
    Kind::Flat,
    Kind::Adjacent,
    Kind::Cluster,
    Kind::Boundary,
    Kind::Mixture,
];

/// The moments-only corpus at one grid size (`momentlab bench lp --corpus moments`): two
/// groups of `count` problems each on `table`, one fragment depth per problem, to be solved
/// from the moments alone as `momentlab lp` and other programs call the solver:
/// * "diracs": 1–4 Diracs (uniformly many) at random grid points with weights in [0.05, 1),
///   z_f uniform on [0, 1];
/// * "flat": flat-receiver windows ([`Kind::Flat`]) with one of that kind's fragment depths
///   (below, at, inside, above the support or uniform) drawn at random.
pub fn moments_groups(table: &GridTable, label: &str, count: usize, seed: u64) -> Vec<Group> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let (n, m) = (table.n(), table.m());
    let diracs = (0..count)
        .map(|_| {
            let k = rng.gen_range(1..=4usize);
            let atoms: Vec<(u32, f64)> = (0..k)
                .map(|_| (rng.gen_range(0..n) as u32, rng.gen_range(0.05..1.0)))
                .collect();
            Problem {
                dist: normalised(atoms),
                zf: vec![rng.gen_range(0.0..=1.0)],
            }
        })
        .collect();
    let flat = (0..count)
        .map(|_| {
            let p = problem(&mut rng, n, m, Kind::Flat);
            let zf = p.zf[rng.gen_range(0..p.zf.len())];
            Problem {
                dist: p.dist,
                zf: vec![zf],
            }
        })
        .collect();
    let group = |kind: &str, problems| Group {
        name: format!("{kind} {label} @ {n}"),
        basis: Vec::new(),
        table: table.clone(),
        problems,
    };
    vec![group("diracs", diracs), group("flat", flat)]
}

/// Atoms sorted by grid index, duplicates merged, weights normalised to sum 1.
fn normalised(mut dist: Vec<(u32, f64)>) -> Vec<(u32, f64)> {
    dist.sort_by_key(|e| e.0);
    dist.dedup_by(|a, b| {
        if a.0 == b.0 {
            b.1 += a.1;
            true
        } else {
            false
        }
    });
    let total: f64 = dist.iter().map(|e| e.1).sum();
    dist.iter_mut().for_each(|e| e.1 /= total);
    dist
}

/// One problem of `kind` on a uniform grid of n points for m functions.
pub fn problem(rng: &mut impl Rng, n: usize, m: usize, kind: Kind) -> Problem {
    let h = 1.0 / (n - 1) as f64;
    let z = |i: usize| i as f64 * h;
    let dist: Vec<(u32, f64)> = match kind {
        Kind::Flat => flat_window(rng, n),
        Kind::Adjacent => {
            let k = rng.gen_range(1..=3usize);
            let at = match rng.gen_range(0..4) {
                0 => 0,
                1 => n - k,
                _ => rng.gen_range(0..=n - k),
            };
            (at..at + k)
                .map(|i| (i as u32, rng.gen_range(0.05..1.0)))
                .collect()
        }
        Kind::Cluster => {
            let d = rng.gen_range(1..=3usize);
            let i = rng.gen_range(0..n - d);
            let w = if rng.gen_bool(0.5) {
                0.99
            } else {
                rng.gen_range(0.5..0.999)
            };
            vec![(i as u32, w), ((i + d) as u32, 1.0 - w)]
        }
        Kind::Boundary => {
            let k = rng.gen_range(1..=(m / 2).max(1));
            (0..k)
                .map(|_| (rng.gen_range(0..n) as u32, rng.gen_range(0.05..1.0)))
                .collect()
        }
        Kind::Mixture => {
            let k = rng.gen_range(1..=6usize);
            (0..k)
                .map(|_| (rng.gen_range(0..n) as u32, rng.gen_range(0.05..1.0)))
                .collect()
        }
    };
    let dist = normalised(dist);
    // z_f: below, at, inside and above the support, and one uniform point.
    let lo = dist[0].0 as usize;
    let hi = dist[dist.len() - 1].0 as usize;
    let mut zf = vec![
        z(lo.saturating_sub(1)),
        z(lo),
        z((lo + hi).div_ceil(2)),
        z(hi),
        z((hi + 1).min(n - 1)),
        rng.gen_range(0.0..=1.0),
    ];
    if dist.len() > 1 {
        zf.push(z(lo) + 0.5 * h);
    }
    Problem { dist, zf }
}

/// A 9×9 Gaussian window (σ = 2.4) over a plane spanning 0–3 grid steps, 30 % of them with an
/// occluder edge in front; depths snapped to the grid.
fn flat_window(rng: &mut impl Rng, n: usize) -> Vec<(u32, f64)> {
    let h = 1.0 / (n - 1) as f64;
    let span = rng.gen_range(0.0..=3.0) * h;
    let a: f64 = rng.gen_range(0.0..std::f64::consts::TAU);
    let (gx, gy) = (span / 8.0 * a.cos(), span / 8.0 * a.sin());
    let d0 = rng.gen_range(4.0 * h..1.0 - 4.0 * h);
    let edge = rng.gen_bool(0.3).then(|| {
        let b: f64 = rng.gen_range(0.0..std::f64::consts::TAU);
        (
            b.cos(),
            b.sin(),
            rng.gen_range(-3.0..3.0),
            rng.gen_range(0.005..0.3),
        )
    });
    let mut dist: Vec<(u32, f64)> = Vec::with_capacity(81);
    for dy in 0..9 {
        for dx in 0..9 {
            let (x, y) = (dx as f64 - 4.0, dy as f64 - 4.0);
            let w = (-(x * x + y * y) / (2.0 * 2.4 * 2.4)).exp();
            let mut d = d0 + gx * x + gy * y;
            if let Some((cx, cy, off, depth)) = edge {
                if cx * x + cy * y < off {
                    d -= depth;
                }
            }
            let i = (d.clamp(0.0, 1.0) / h).round() as u32;
            dist.push((i.min(n as u32 - 1), w));
        }
    }
    dist
}

/// Σ_{z_i < z_f} w_i of a distribution: an upper bound on G for its moments.
pub fn mass_below(grid: &Grid, dist: &[(u32, f64)], zf: f64) -> f64 {
    let z = grid.points();
    dist.iter()
        .filter(|e| z[e.0 as usize] < zf)
        .map(|e| e.1)
        .sum()
}

/// A group from filter windows of real depth stacks (`metrics::windows::stacks_corpus`): each
/// window Σ w·δ(z) has its depths snapped to the nearest grid point of `table` (duplicates
/// merged), and its fragment depth z_f snapped likewise, as the pipeline evaluates LP
/// candidates. Windows and depths come as plain slices so this module needs no renderer.
pub fn from_windows(
    name: &str,
    basis: &[String],
    table: &GridTable,
    windows: &[Vec<(f64, f64)>],
    zfs: &[f64],
) -> Result<Group> {
    if windows.len() != zfs.len() {
        anyhow::bail!(
            "{} windows but {} fragment depths",
            windows.len(),
            zfs.len()
        );
    }
    let grid = table.grid();
    let problems = windows
        .iter()
        .zip(zfs)
        .map(|(w, &zf)| {
            let mut dist: Vec<(u32, f64)> = Vec::with_capacity(w.len());
            for &(z, wt) in w {
                let i = grid.nearest(z) as u32;
                match dist.iter_mut().find(|e| e.0 == i) {
                    Some(e) => e.1 += wt,
                    None => dist.push((i, wt)),
                }
            }
            let total: f64 = dist.iter().map(|e| e.1).sum();
            dist.iter_mut().for_each(|e| e.1 /= total);
            dist.sort_by_key(|e| e.0);
            Problem {
                dist,
                zf: vec![grid.points()[grid.nearest(zf)]],
            }
        })
        .collect();
    Ok(Group {
        name: name.to_string(),
        basis: basis.to_vec(),
        table: table.clone(),
        problems,
    })
}
