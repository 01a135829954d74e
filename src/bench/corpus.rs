//! The adversarial corpus of Algorithm 1 problems (deterministic for a seed), used by the tests
//! (tests/lp/contract.rs) and by `momentlab bench lp --corpus adversarial`.
//!
//! Every problem is the moment vector of a known distribution on the grid (so it is feasible
//! and its own mass below z_f bounds G from above), chosen where solvers break:
//! * flat receivers: 9×9 Gaussian windows (σ = 2.4) over a plane spanning 0–3 grid steps,
//!   30 % with an occluder edge, depths snapped to the grid;
//! * 1–3 adjacent grid points (also at the ends of the grid);
//! * tight clusters (0.99 / 0.01 at 1–3 grid steps) with z_f below, inside and above;
//! * boundary moment vectors (≤ m/2 Diracs) and random mixtures;
//!
//! on the power bases m = 1…12, every catalog function alone, exp(c·z) for |c| ≤ 80 (and 400)
//! alone, exp(80(z−1)) (ESM's c = 80), the paper's bases (MSM z…z⁴, TMSM's trigonometric
//! basis, EVSM's exponentials) and mixed bases with exp(±40z), at n = 256…8192.

use crate::basis::Catalog;
use crate::lp::GridTable;
use crate::Grid;
use anyhow::{Context, Result};
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

const ALL: [Kind; 5] = [
    Kind::Flat,
    Kind::Adjacent,
    Kind::Cluster,
    Kind::Boundary,
    Kind::Mixture,
];

/// The adversarial corpus with `per_kind` problems of every kind for every table. `large`
/// adds the n = 4096 and 8192 tables.
pub fn adversarial(per_kind: usize, large: bool, seed: u64) -> Result<Vec<Group>> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let catalog = Catalog::embedded();
    let mut specs: Vec<(Vec<String>, usize)> = Vec::new();
    let power = |m: usize| -> Vec<String> {
        (1..=m)
            .map(|k| if k == 1 { "z".into() } else { format!("z^{k}") })
            .collect()
    };
    let ns: &[usize] = if large {
        &[256, 1024, 4096, 8192]
    } else {
        &[256, 1024]
    };
    for &n in ns {
        specs.push((power(4), n));
    }
    for m in (1..=12).filter(|&m| m != 4) {
        specs.push((power(m), 1024));
    }
    for c in [-80.0, -40.0, -20.0, -5.0, 5.0, 20.0, 40.0, 80.0, 400.0] {
        specs.push((vec![format!("exp({c}*z)")], 1024));
    }
    specs.push((vec!["exp(80*(z-1))".into()], 1024));
    specs.push((vec!["exp(80*(z-1))".into()], 4096));
    for f in catalog.functions() {
        specs.push((vec![f.formula().to_string()], 1024));
    }
    let paper: [&[&str]; 5] = [
        &["sin(2*pi*z)", "cos(2*pi*z)", "sin(4*pi*z)", "cos(4*pi*z)"],
        &["exp(40*z)", "exp(80*z)", "-exp(-40*z)", "exp(-80*z)"],
        &["exp(40*z)", "-exp(-40*z)"],
        &["z", "z^2", "z^3", "exp(-40*z)"],
        &["z", "z^2", "exp(40*z)", "exp(-40*z)"],
    ];
    for b in paper {
        specs.push((b.iter().map(|s| s.to_string()).collect(), 1024));
    }
    let mut out = Vec::new();
    for (basis, n) in specs {
        let grid = Grid::uniform(n)?;
        let table = table_for(&catalog, &grid, &basis)?;
        let m = basis.len();
        for kind in ALL {
            let problems = (0..per_kind)
                .map(|_| problem(&mut rng, n, m, kind))
                .collect();
            out.push(Group {
                name: format!("{} @ {n}: {kind:?}", basis.join(", ")),
                basis: basis.clone(),
                table: table.clone(),
                problems,
            });
        }
    }
    Ok(out)
}

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

/// Tabulate formulas (catalog names or formulas) on `grid`.
pub fn table_for(catalog: &Catalog, grid: &Grid, basis: &[String]) -> Result<GridTable> {
    let fns = basis
        .iter()
        .map(|s| catalog.resolve(s))
        .collect::<Result<Vec<_>>>()
        .context("corpus basis")?;
    Ok(GridTable::from_fn(grid, fns.len(), |z, out| {
        for (o, f) in out.iter_mut().zip(&fns) {
            *o = f.eval(z);
        }
    })?)
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
