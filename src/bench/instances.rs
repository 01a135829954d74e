//! Problem generators for testing and benchmarking the Algorithm 1 solvers: a built-in list of
//! smooth basis functions (independent of the catalog), random Dirac mixtures on grid points,
//! and "realistic" moment vectors as a 9×9 Gaussian PCF kernel (σ = 2.4 texels, the paper's
//! reference filter, Section 3.2) produces them over a depth map with 1–3 depth clusters.

use crate::lp::GridTable;
use crate::Grid;
use anyhow::Result;
use rand::Rng;

/// A named smooth function of z on [0, 1].
pub type SmoothFn = (&'static str, fn(f64) -> f64);

/// About twenty smooth, elementary functions on [0, 1]: powers, exponentials, logarithms,
/// roots, trigonometric functions, rationals, tanh.
pub fn smooth_functions() -> Vec<SmoothFn> {
    use std::f64::consts::PI;
    vec![
        ("z", |z| z),
        ("z^2", |z| z * z),
        ("z^3", |z| z * z * z),
        ("z^4", |z| z.powi(4)),
        ("z^6", |z| z.powi(6)),
        ("exp(5z)", |z| (5.0 * z).exp()),
        ("exp(20z)", |z| (20.0 * z).exp()),
        ("exp(-5z)", |z| (-5.0 * z).exp()),
        ("exp(-20z)", |z| (-20.0 * z).exp()),
        ("log(1+10z)", |z| (10.0 * z).ln_1p()),
        ("log(1+z)", |z| z.ln_1p()),
        ("sqrt(z)", |z| z.sqrt()),
        ("sin(pi z)", |z| (PI * z).sin()),
        ("cos(pi z)", |z| (PI * z).cos()),
        ("sin(2pi z)", |z| (2.0 * PI * z).sin()),
        ("cos(2pi z)", |z| (2.0 * PI * z).cos()),
        ("sin(4pi z)", |z| (4.0 * PI * z).sin()),
        ("cos(4pi z)", |z| (4.0 * PI * z).cos()),
        ("1/(1+5z)", |z| 1.0 / (1.0 + 5.0 * z)),
        ("1/(1+50z)", |z| 1.0 / (1.0 + 50.0 * z)),
        ("tanh(10(z-0.5))", |z| (10.0 * (z - 0.5)).tanh()),
    ]
}

/// Tabulate the given functions on `grid`.
pub fn table_of(grid: &Grid, fns: &[SmoothFn]) -> Result<GridTable> {
    Ok(GridTable::from_fn(grid, fns.len(), |z, out| {
        for (o, (_, f)) in out.iter_mut().zip(fns) {
            *o = f(z);
        }
    })?)
}

/// The power basis (z, z², …, z^m) on `grid`, as used by MSM.
pub fn power_table(grid: &Grid, m: usize) -> Result<GridTable> {
    Ok(GridTable::from_fn(grid, m, |z, out| {
        let mut p = 1.0;
        for o in out.iter_mut() {
            p *= z;
            *o = p;
        }
    })?)
}

/// Moments Σ w_k b(z_{i_k}) of a mixture of Diracs at grid indices (weights sum to 1).
pub fn mixture_moments(table: &GridTable, mixture: &[(usize, f64)]) -> Vec<f64> {
    let mut b = vec![0.0; table.m()];
    for &(i, w) in mixture {
        for (bj, v) in b.iter_mut().zip(table.row(i)) {
            *bj += w * v;
        }
    }
    b
}

/// A random mixture of `k` Diracs on distinct grid indices < n with random positive weights
/// summing to 1.
pub fn random_mixture(rng: &mut impl Rng, n: usize, k: usize) -> Vec<(usize, f64)> {
    let k = k.min(n).max(1);
    let mut idx: Vec<usize> = Vec::with_capacity(k);
    while idx.len() < k {
        let i = rng.gen_range(0..n);
        if !idx.contains(&i) {
            idx.push(i);
        }
    }
    let mut w: Vec<f64> = (0..k).map(|_| rng.gen_range(0.05..1.0)).collect();
    let s: f64 = w.iter().sum();
    w.iter_mut().for_each(|v| *v /= s);
    idx.into_iter().zip(w).collect()
}

/// One filtered texel: the depth distribution under the kernel (Diracs at grid indices) and
/// the depths z_f of the fragments to shade with it.
#[derive(Clone, Debug)]
pub struct KernelPatch {
    /// The kernel's depth distribution [(grid index, weight)].
    pub mixture: Vec<(usize, f64)>,
    /// Fragment depths shaded with it.
    pub zf: Vec<f64>,
}

/// Realistic problems: a 9×9 Gaussian kernel (σ = 2.4 texels) over a depth map made of 1–3
/// planar depth clusters (an occluder edge through the kernel), depths snapped to the grid
/// (as the evaluation does). Each patch comes with the fragment depths to shade: the surface
/// depth at the centre texel of every cluster plus one uniform depth (snapped to the grid too),
/// so consecutive problems
/// share the moments and vary z_f.
pub fn kernel_patches(rng: &mut impl Rng, grid: &Grid, count: usize) -> Vec<KernelPatch> {
    let z = grid.points();
    let n = z.len();
    let (lo, hi) = (z[0], z[n - 1]);
    let mut weights = [[0.0f64; 9]; 9];
    let mut total = 0.0;
    for (dy, row) in weights.iter_mut().enumerate() {
        for (dx, w) in row.iter_mut().enumerate() {
            let (x, y) = (dx as f64 - 4.0, dy as f64 - 4.0);
            *w = (-(x * x + y * y) / (2.0 * 2.4 * 2.4)).exp();
            total += *w;
        }
    }
    let snap = |d: f64| -> usize {
        let d = d.clamp(lo, hi);
        let k = z.partition_point(|&v| v < d);
        if k == 0 {
            0
        } else if k >= n || (d - z[k - 1]) <= (z[k] - d) {
            (k - 1).min(n - 1)
        } else {
            k
        }
    };
    let mut out = Vec::with_capacity(count);
    for _ in 0..count {
        let clusters = rng.gen_range(1..=3usize);
        // Each cluster: a plane depth(x, y) = d + gx x + gy y over the kernel footprint.
        let planes: Vec<(f64, f64, f64)> = (0..clusters)
            .map(|_| {
                (
                    rng.gen_range(0.1..0.9),
                    rng.gen_range(-0.004..0.004),
                    rng.gen_range(-0.004..0.004),
                )
            })
            .collect();
        // Cluster c covers the texels on one side of a random line through the footprint.
        let lines: Vec<(f64, f64, f64)> = (0..clusters)
            .map(|_| {
                let a: f64 = rng.gen_range(0.0..std::f64::consts::TAU);
                (a.cos(), a.sin(), rng.gen_range(-3.0..3.0))
            })
            .collect();
        let mut mix: Vec<(usize, f64)> = Vec::new();
        for (dy, row) in weights.iter().enumerate() {
            for (dx, &w) in row.iter().enumerate() {
                let (x, y) = (dx as f64 - 4.0, dy as f64 - 4.0);
                // The nearest (smallest-depth) cluster whose half-plane contains the texel;
                // cluster 0 (the receiver) covers everything.
                let mut depth = planes[0].0 + planes[0].1 * x + planes[0].2 * y;
                for c in 1..clusters {
                    let (cx, cy, off) = lines[c];
                    if cx * x + cy * y < off {
                        let d = planes[c].0 + planes[c].1 * x + planes[c].2 * y;
                        depth = depth.min(d);
                    }
                }
                let i = snap(lo + (hi - lo) * depth);
                match mix.iter_mut().find(|(j, _)| *j == i) {
                    Some(e) => e.1 += w / total,
                    None => mix.push((i, w / total)),
                }
            }
        }
        let mut zf: Vec<f64> = planes
            .iter()
            .map(|p| z[snap(lo + (hi - lo) * p.0)])
            .collect();
        zf.push(z[snap(rng.gen_range(lo..=hi))]);
        out.push(KernelPatch { mixture: mix, zf });
    }
    out
}
