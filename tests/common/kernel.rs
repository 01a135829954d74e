//! Shared helpers of the kernel/evaluate tests: in-memory depth stacks and an independent
//! brute-force implementation of the 9×9 Gaussian, PCF and the evaluation loop.
#![allow(dead_code)]

use momentlab::stack::{DepthStack, StackMeta};
use rand::Rng;
use rand_chacha::rand_core::SeedableRng;
use rand_chacha::ChaCha8Rng;

pub fn rng(seed: u64) -> ChaCha8Rng {
    ChaCha8Rng::seed_from_u64(seed)
}

pub fn meta(name: &str, w: usize, h: usize, layers: usize) -> StackMeta {
    StackMeta {
        scene: "test".into(),
        view: name.into(),
        light_dir: [0.0, 0.0, -1.0],
        near: 0.0,
        far: 1.0,
        width: w,
        height: h,
        layers,
        ..Default::default()
    }
}

/// A stack from per-layer closures (x, y) -> Option<(z, dzdu, dzdv)>; layers must be increasing.
pub fn stack_from(
    name: &str,
    w: usize,
    h: usize,
    layers: usize,
    f: impl Fn(usize, usize, usize) -> Option<(f32, f32, f32)>,
) -> DepthStack {
    let mut depth = vec![vec![f32::INFINITY; w * h]; layers];
    let mut dzdu = vec![vec![0.0; w * h]; layers];
    let mut dzdv = vec![vec![0.0; w * h]; layers];
    for l in 0..layers {
        for y in 0..h {
            for x in 0..w {
                if let Some((z, a, b)) = f(l, x, y) {
                    depth[l][y * w + x] = z;
                    dzdu[l][y * w + x] = a;
                    dzdv[l][y * w + x] = b;
                }
            }
        }
    }
    DepthStack {
        meta: meta(name, w, h, layers),
        depth,
        dzdu,
        dzdv,
    }
}

/// A plane z = z0 + a·x + b·y (one layer), with its exact slopes.
pub fn plane(w: usize, h: usize, z0: f64, a: f64, b: f64) -> DepthStack {
    stack_from("plane", w, h, 1, |_, x, y| {
        Some((
            (z0 + a * x as f64 + b * y as f64) as f32,
            a as f32,
            b as f32,
        ))
    })
}

/// A random stack: 1..=4 layers, sorted random depths, holes, random small slopes; a random
/// number of surfaces per texel (0 = background).
pub fn random_stack(rng: &mut ChaCha8Rng, name: &str, w: usize, h: usize) -> DepthStack {
    let layers = rng.gen_range(1..=4);
    let mut depth = vec![vec![f32::INFINITY; w * h]; layers];
    let mut dzdu = vec![vec![0.0f32; w * h]; layers];
    let mut dzdv = vec![vec![0.0f32; w * h]; layers];
    // Smooth-ish base so that neighbourhoods have structure, plus clustered values.
    let levels: Vec<f32> = (0..5).map(|_| rng.gen_range(0.05..0.95)).collect();
    for t in 0..w * h {
        let k = if rng.gen_bool(0.1) {
            0
        } else {
            rng.gen_range(1..=layers)
        };
        let mut zs: Vec<f32> = (0..k)
            .map(|_| {
                if rng.gen_bool(0.5) {
                    levels[rng.gen_range(0..levels.len())] + rng.gen_range(-0.002..0.002)
                } else {
                    rng.gen_range(0.0..1.0)
                }
            })
            .collect();
        zs.sort_by(|a, b| a.partial_cmp(b).unwrap());
        zs.dedup();
        for (l, z) in zs.into_iter().enumerate() {
            depth[l][t] = z.clamp(0.0, 1.0);
            if rng.gen_bool(0.7) {
                dzdu[l][t] = rng.gen_range(-0.01..0.01);
                dzdv[l][t] = rng.gen_range(-0.01..0.01);
            }
        }
    }
    // enforce strict increase after clamping
    for t in 0..w * h {
        for l in 1..layers {
            if depth[l][t].is_finite() && depth[l][t] <= depth[l - 1][t] {
                for d in depth.iter_mut().skip(l) {
                    d[t] = f32::INFINITY;
                }
                break;
            }
        }
    }
    DepthStack {
        meta: meta(name, w, h, layers),
        depth,
        dzdu,
        dzdv,
    }
}

/// Independent 2-D Gaussian weights: exp(−(dx²+dy²)/(2σ²)) over the 9×9 taps, normalised.
pub fn brute_weights() -> Vec<(i64, i64, f64)> {
    let s = 2.4f64;
    let mut v = Vec::new();
    for dy in -4i64..=4 {
        for dx in -4i64..=4 {
            v.push((
                dx,
                dy,
                (-((dx * dx + dy * dy) as f64) / (2.0 * s * s)).exp(),
            ));
        }
    }
    let sum: f64 = v.iter().map(|t| t.2).sum();
    v.into_iter().map(|(a, b, w)| (a, b, w / sum)).collect()
}

pub fn clampi(c: usize, d: i64, n: usize) -> usize {
    (c as i64 + d).max(0).min(n as i64 - 1) as usize
}

/// Brute-force depth distribution of texel (x, y): (z, w, dx_clamped, dy_clamped).
pub fn brute_distribution(s: &DepthStack, x: usize, y: usize) -> Vec<(f64, f64, f64, f64)> {
    let (w, h) = (s.meta.width, s.meta.height);
    brute_weights()
        .into_iter()
        .map(|(dx, dy, wt)| {
            let xx = clampi(x, dx, w);
            let yy = clampi(y, dy, h);
            let z = s.depth[0][yy * w + xx];
            let z = if z.is_finite() { z as f64 } else { 1.0 };
            (z, wt, xx as f64 - x as f64, yy as f64 - y as f64)
        })
        .collect()
}

/// One brute-force fragment: (texel, layer, z_f (unbiased), pcf, z_tech = z_f − ε′).
pub struct BruteFragment {
    pub x: usize,
    pub y: usize,
    pub texel: usize,
    pub layer: usize,
    pub pcf: f64,
    pub ztech: f64,
}

pub fn brute_fragments(s: &DepthStack, bias: &momentlab::metrics::Bias) -> Vec<BruteFragment> {
    let (w, h) = (s.meta.width, s.meta.height);
    let mut out = Vec::new();
    for l in 0..s.depth.len() {
        for y in 0..h {
            for x in 0..w {
                let t = y * w + x;
                let z = s.depth[l][t];
                if !z.is_finite() {
                    continue;
                }
                let z = z as f64;
                let (a, b) = (s.dzdu[l][t] as f64, s.dzdv[l][t] as f64);
                let mut p = 0.0;
                for (zz, wt, dx, dy) in brute_distribution(s, x, y) {
                    let own = a * dx + b * dy;
                    let delta = match bias.receiver {
                        momentlab::metrics::Receiver::Fragment => own,
                        momentlab::metrics::Receiver::Lower => {
                            // lowest front tangent plane on the path (texels at steps 1..=n)
                            let n = dx.abs().max(dy.abs()) as i64;
                            let mut d = own;
                            for j in 1..=n {
                                let px = x as f64 + dx * j as f64 / n as f64;
                                let py = y as f64 + dy * j as f64 / n as f64;
                                for (qx, qy) in [(px.floor(), py.floor()), (px.ceil(), py.ceil())] {
                                    let k = qy as usize * w + qx as usize;
                                    d = d.min(if s.depth[0][k].is_finite() {
                                        s.dzdu[0][k] as f64 * dx + s.dzdv[0][k] as f64 * dy
                                    } else {
                                        0.0
                                    });
                                }
                            }
                            d
                        }
                    };
                    if zz < z + bias.slope_scale * delta - bias.pcf_epsilon {
                        p += wt;
                    }
                }
                let ztech =
                    z - bias.technique_epsilon - bias.technique_slope_scale * (a.abs() + b.abs());
                out.push(BruteFragment {
                    x,
                    y,
                    texel: t,
                    layer: l,
                    pcf: p,
                    ztech,
                });
            }
        }
    }
    out
}

/// VSM (Cantelli) from b = (E z, E z²): the one-sided Chebyshev lower bound of P(z < z_f).
pub fn vsm(b: &[f64], zf: f64) -> f64 {
    let mu = b[0];
    let var = (b[1] - mu * mu).max(1e-12);
    if zf <= mu {
        0.0
    } else {
        let d = zf - mu;
        d * d / (var + d * d)
    }
}

/// The grid point nearest to z, independent of `metrics::snap`: a linear scan, ties to the
/// lower point.
pub fn nearest(grid: &momentlab::Grid, z: f64) -> f64 {
    let mut best = grid.points()[0];
    for &p in grid.points() {
        if (p - z).abs() < (best - z).abs() {
            best = p;
        }
    }
    best
}
