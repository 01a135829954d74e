//! Filter kernels over the front-layer depth map: the 9×9 Gaussian (σ = 2.4 texels) of the
//! paper's PCF reference (Peters & Klein 2015, Section 3.2), depth distributions Z_t and
//! filtered moment maps.
//!
//! Conventions used throughout:
//! * maps are row-major `width × height` slices, texel `t = y * width + x`;
//! * the front map holds the front-layer depth z0 per texel, background (no surface) = 1
//!   ([`front_map`]);
//! * edges are clamped: a neighbour outside the map reads the nearest edge texel;
//! * the depth distribution of texel t is Z_t = Σ_l w_l δ_{z0(t+l)} over the 9×9 neighbourhood
//!   with the 2-D Gaussian weights w_l = g(dx)·g(dy) (1-D weights g, normalised to sum 1).

use crate::stack::DepthStack;
use anyhow::{bail, Result};
use rayon::prelude::*;

/// A normalised, separable, odd-sized Gaussian filter kernel.
///
/// 1-D weights g(i) ∝ exp(−i² / (2σ²)) for i = −r..=r, normalised so Σ g = 1; the 2-D weight of
/// offset (dx, dy) is g(dx)·g(dy), hence the (2r+1)² weights also sum to 1.
#[derive(Clone, Debug, PartialEq)]
pub struct Gaussian {
    radius: usize,
    sigma: f64,
    weights: Vec<f64>,
}

impl Gaussian {
    /// The paper's PCF kernel: 9×9 taps (radius 4), σ = 2.4 texels (Section 3.2).
    pub fn paper() -> Gaussian {
        Gaussian::new(4, 2.4).expect("valid constant kernel")
    }

    /// A (2·radius+1)² Gaussian with standard deviation `sigma` texels.
    pub fn new(radius: usize, sigma: f64) -> Result<Gaussian> {
        if !(sigma.is_finite() && sigma > 0.0) {
            bail!("gaussian kernel: sigma must be positive and finite, got {sigma}");
        }
        if radius > 64 {
            bail!("gaussian kernel: radius {radius} is too large (max 64)");
        }
        let r = radius as i64;
        let mut weights: Vec<f64> = (-r..=r)
            .map(|i| (-((i * i) as f64) / (2.0 * sigma * sigma)).exp())
            .collect();
        let sum: f64 = weights.iter().sum();
        for w in &mut weights {
            *w /= sum;
        }
        // Enforce exact symmetry (the sum above is symmetric, but make it bit-exact).
        for i in 0..radius {
            let j = weights.len() - 1 - i;
            let avg = 0.5 * (weights[i] + weights[j]);
            weights[i] = avg;
            weights[j] = avg;
        }
        Ok(Gaussian {
            radius,
            sigma,
            weights,
        })
    }

    /// Kernel radius r (the kernel is (2r+1)×(2r+1)).
    pub fn radius(&self) -> usize {
        self.radius
    }

    /// Standard deviation σ in texels.
    pub fn sigma(&self) -> f64 {
        self.sigma
    }

    /// The 1-D weights g(−r..=r), summing to 1.
    pub fn weights_1d(&self) -> &[f64] {
        &self.weights
    }

    /// The 2-D weight g(dx)·g(dy) of offset (dx, dy); 0 outside the kernel.
    pub fn weight(&self, dx: i64, dy: i64) -> f64 {
        let r = self.radius as i64;
        if dx.abs() > r || dy.abs() > r {
            return 0.0;
        }
        self.weights[(dx + r) as usize] * self.weights[(dy + r) as usize]
    }

    /// All (2r+1)² taps as (dx, dy, weight), row by row.
    pub fn taps(&self) -> Vec<(i64, i64, f64)> {
        let r = self.radius as i64;
        let mut out = Vec::with_capacity(self.weights.len() * self.weights.len());
        for dy in -r..=r {
            for dx in -r..=r {
                out.push((dx, dy, self.weight(dx, dy)));
            }
        }
        out
    }
}

impl Default for Gaussian {
    fn default() -> Self {
        Gaussian::paper()
    }
}

/// Clamp coordinate `c + d` into `0..len`.
#[inline]
pub fn clamp_coord(c: usize, d: i64, len: usize) -> usize {
    (c as i64 + d).clamp(0, len as i64 - 1) as usize
}

fn check_map(len: usize, width: usize, height: usize, what: &str) {
    assert_eq!(
        len,
        width * height,
        "{what}: map has {len} values, expected {width}×{height}"
    );
}

/// Separable filtering with clamped edges: out(x, y) = Σ_i Σ_j g_i g_j map(x+i, y+j) for the
/// odd-length 1-D weights g centred on 0 (first pass along x, second along y).
///
/// Panics if `map.len() != width * height` or the weights have even length (programming errors,
/// not user input).
pub fn filter_separable(map: &[f64], width: usize, height: usize, weights_1d: &[f64]) -> Vec<f64> {
    separable(map, width, height, weights_1d.len(), 0.0, |acc, v, i| {
        *acc += weights_1d[i] * v
    })
}

/// Separable min filter over the (2r+1)² neighbourhood with clamped edges:
/// out(t) = min_l map(t+l). Used for trivial fragments (F_Z(z) = 0 ⇔ z ≤ min_l z0(t+l)).
pub fn min_filter(map: &[f64], width: usize, height: usize, radius: usize) -> Vec<f64> {
    check_map(map.len(), width, height, "min_filter");
    separable(
        map,
        width,
        height,
        2 * radius + 1,
        f64::INFINITY,
        |m, v, _| *m = m.min(v),
    )
}

/// The two passes of a separable filter over rows, then columns (clamped edges): each output
/// folds its taps in order with `acc`, starting from `init`. Rows run in parallel; every value
/// is folded in tap order.
fn separable(
    map: &[f64],
    width: usize,
    height: usize,
    taps: usize,
    init: f64,
    acc: impl Fn(&mut f64, f64, usize) + Sync,
) -> Vec<f64> {
    check_map(map.len(), width, height, "filter_separable");
    assert!(
        taps % 2 == 1,
        "filter_separable: need an odd number of weights"
    );
    if map.is_empty() {
        return Vec::new();
    }
    let r = (taps / 2) as i64;
    let mut tmp = vec![0.0; map.len()];
    tmp.par_chunks_mut(width).enumerate().for_each(|(y, out)| {
        let row = &map[y * width..(y + 1) * width];
        for (x, o) in out.iter_mut().enumerate() {
            let mut s = init;
            for i in 0..taps {
                acc(&mut s, row[clamp_coord(x, i as i64 - r, width)], i);
            }
            *o = s;
        }
    });
    let mut out = vec![0.0; map.len()];
    out.par_chunks_mut(width).enumerate().for_each(|(y, row)| {
        for (x, o) in row.iter_mut().enumerate() {
            let mut s = init;
            for i in 0..taps {
                acc(
                    &mut s,
                    tmp[clamp_coord(y, i as i64 - r, height) * width + x],
                    i,
                );
            }
            *o = s;
        }
    });
    out
}

/// The front-layer depth map z0 of a stack (background = 1), as f64.
pub fn front_map(stack: &DepthStack) -> Vec<f64> {
    (0..stack.texel_count())
        .map(|t| stack.front(t) as f64)
        .collect()
}

/// Depth distribution Z_t of texel (x, y): the (2r+1)² pairs (z0(t+l), w_l), clamped edges,
/// in tap order (row by row). Depths are not merged (equal depths appear repeatedly).
pub fn depth_distribution(
    front: &[f64],
    width: usize,
    height: usize,
    x: usize,
    y: usize,
    kernel: &Gaussian,
) -> Vec<(f64, f64)> {
    check_map(front.len(), width, height, "depth_distribution");
    kernel
        .taps()
        .into_iter()
        .map(|(dx, dy, w)| {
            let xx = clamp_coord(x, dx, width);
            let yy = clamp_coord(y, dy, height);
            (front[yy * width + xx], w)
        })
        .collect()
}

/// Filtered moment maps of a front-depth map: map j holds b_j,t = Σ_l w_l b_j(z0(t+l)) with the
/// paper's 9×9 Gaussian, computed separably. `f(z, out)` writes the m values b(z).
pub fn moment_maps_of(
    front: &[f64],
    width: usize,
    height: usize,
    m: usize,
    kernel: &Gaussian,
    f: impl Fn(f64, &mut [f64]) + Sync,
) -> Vec<Vec<f64>> {
    check_map(front.len(), width, height, "moment_maps");
    if m == 0 {
        return Vec::new();
    }
    // b(z) of every texel (row-major, texels in parallel), then map by map, filtered in
    // parallel.
    let mut values = vec![0.0; front.len() * m];
    values
        .par_chunks_mut(m)
        .zip(front.par_iter())
        .for_each(|(o, &z)| f(z, o));
    (0..m)
        .into_par_iter()
        .map(|j| {
            let raw: Vec<f64> = values.iter().skip(j).step_by(m).copied().collect();
            filter_separable(&raw, width, height, kernel.weights_1d())
        })
        .collect()
}

/// The m filtered moment maps b_t = Σ_l w_l b(z0(t+l)) of a stack's front layer (background
/// depth 1, clamped edges, the paper's 9×9 Gaussian σ = 2.4), computed separably.
/// `result[j][t]` = b_j at texel t.
pub fn moment_maps(
    stack: &DepthStack,
    m: usize,
    f: impl Fn(f64, &mut [f64]) + Sync,
) -> Vec<Vec<f64>> {
    let front = front_map(stack);
    moment_maps_of(
        &front,
        stack.meta.width,
        stack.meta.height,
        m,
        &Gaussian::paper(),
        f,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn paper_kernel_shape() {
        let g = Gaussian::paper();
        assert_eq!(g.weights_1d().len(), 9);
        let s: f64 = g.weights_1d().iter().sum();
        assert!((s - 1.0).abs() < 1e-15);
        // centre / edge ratio = exp(16 / (2·2.4²))
        let ratio = g.weights_1d()[4] / g.weights_1d()[0];
        assert!((ratio - (16.0f64 / 11.52).exp()).abs() < 1e-12);
    }

    #[test]
    fn rejects_bad_sigma() {
        assert!(Gaussian::new(4, 0.0).is_err());
        assert!(Gaussian::new(4, f64::NAN).is_err());
    }

    #[test]
    fn min_filter_matches_brute_force() {
        let (w, h) = (7, 5);
        let map: Vec<f64> = (0..w * h).map(|i| ((i * 37) % 11) as f64).collect();
        let out = min_filter(&map, w, h, 2);
        for y in 0..h {
            for x in 0..w {
                let mut m = f64::INFINITY;
                for dy in -2..=2 {
                    for dx in -2..=2 {
                        m = m.min(map[clamp_coord(y, dy, h) * w + clamp_coord(x, dx, w)]);
                    }
                }
                assert_eq!(out[y * w + x], m);
            }
        }
    }
}
