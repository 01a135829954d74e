//! The filtered moment shadow map as a GPU pipeline produces it, computed on the CPU:
//!
//! 1. encode: every texel stores s = encode(z0) (the setting's `tunedEncode`, f32), each
//!    channel rounded to the storage format;
//! 2. the separable Gaussian as two passes, along x then along y, each accumulating its taps in
//!    f32 in tap order (acc ← acc + w_i·s_i, i = −r..r, edges clamped) and storing its output in
//!    the storage format;
//! 3. the lookup at a texel centre, where bilinear interpolation returns the texel itself.
//!
//! The same passes run on a GPU in `crate::gpu`; with [`Order::Fused`] every tap is one fused
//! multiply-add, as a contracting driver computes it. This is the model the GPU check compares
//! against, fragment by fragment.

use crate::kernel::{clamp_coord, Gaussian};
use crate::shader::{Func, Order};
use anyhow::{bail, Result};
use rayon::prelude::*;
use serde::Serialize;

/// One step of an 8-bit display: a shadow further than this from the same technique on exact
/// moments is visible noise.
pub const DISPLAY_STEP: f64 = 1.0 / 255.0;

/// The default noise bound: a setting is usable when at most this share of fragments is further
/// than [`DISPLAY_STEP`] from exact moments (0.1 %; docs/tune.md gives the reason).
pub const MAX_NOISE: f64 = 0.001;

/// Per-texel storage format of the moment channels.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub enum Storage {
    /// n-bit UNORM: clamp to [0,1], round to the nearest of 2^n − 1 steps.
    Unorm(u32),
    /// IEEE single precision (round to nearest).
    Float32,
    /// IEEE half precision (binary16, round to nearest even; beyond ±65504 it is ±∞, as a
    /// GPU's R16F/RGBA16F target stores it).
    Half,
    /// No rounding (f64): the reference for the quantization deviation.
    Exact,
}

impl Storage {
    /// The value a texture of this format returns for `v`.
    pub fn store(self, v: f64) -> f64 {
        match self {
            Storage::Unorm(bits) => {
                let q = ((1u64 << bits) - 1) as f64;
                (v.clamp(0.0, 1.0) * q).round() / q
            }
            Storage::Float32 => v as f32 as f64,
            Storage::Half => half::f16::from_f64(v).to_f64(),
            Storage::Exact => v,
        }
    }

    /// Bits per stored channel (64 for the unrounded reference).
    pub fn bits(self) -> u32 {
        match self {
            Storage::Unorm(bits) => bits,
            Storage::Float32 => 32,
            Storage::Half => 16,
            Storage::Exact => 64,
        }
    }
}

/// How a driver converts an f32 to binary16 when it writes a half-float target: IEEE's round
/// to nearest even, or round toward zero (Vulkan allows either; lavapipe rounds toward zero).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum HalfRounding {
    /// IEEE round to nearest, ties to even.
    #[default]
    NearestEven,
    /// Round toward zero (truncate the mantissa).
    TowardZero,
}

/// One channel value as a texture of `storage` holds it: f32 unchanged; n-bit UNORM
/// k = round(clamp(v, 0, 1)·(2ⁿ − 1)) with the product in f32, read back as k/(2ⁿ − 1);
/// binary16 by `rounding`.
#[inline]
pub fn store(storage: Storage, rounding: HalfRounding, v: f32) -> f32 {
    match storage {
        Storage::Float32 | Storage::Exact => v,
        Storage::Unorm(bits) => {
            let q = ((1u64 << bits) - 1) as f32;
            let k = (v.clamp(0.0, 1.0) * q).round_ties_even();
            (k as f64 / q as f64) as f32
        }
        Storage::Half => {
            let h = half::f16::from_f32(v);
            match rounding {
                HalfRounding::NearestEven => h.to_f32(),
                HalfRounding::TowardZero => {
                    // one step back towards zero where rounding went away from it
                    if h.is_finite() && h.to_f32().abs() > v.abs() {
                        half::f16::from_bits(h.to_bits() - 1).to_f32()
                    } else if h.is_infinite() && v.is_finite() {
                        half::f16::MAX.to_f32().copysign(v)
                    } else {
                        h.to_f32()
                    }
                }
            }
        }
    }
}

/// The 1-D weights of `kernel` in f32, as the filter passes use them.
pub fn weights_f32(kernel: &Gaussian) -> Vec<f32> {
    kernel.weights_1d().iter().map(|&w| w as f32).collect()
}

/// Per-texel encode: `m` channels per texel (texel-major), each rounded to `storage`.
/// `encode` takes the depth and returns (or writes) m values; `rounding` is the driver's binary16
/// conversion.
pub fn encode_map(
    encode: &Func,
    order: Order,
    (storage, rounding): (Storage, HalfRounding),
    depth: &[f32],
) -> Result<Vec<f32>> {
    if encode.n_inputs() != 1 {
        bail!(
            "{}: an encoder takes one depth, not {}",
            encode.name,
            encode.n_inputs()
        );
    }
    let m = encode.n_outputs();
    let mut out = vec![0.0f32; depth.len() * m];
    if m == 0 {
        return Ok(out);
    }
    // Texels in parallel blocks (each texel's evaluation as serially).
    const BLOCK: usize = 1024;
    out.par_chunks_mut(BLOCK * m)
        .zip(depth.par_chunks(BLOCK))
        .try_for_each(|(out, depth)| {
            let mut scratch = Vec::new();
            for (o, &z) in out.chunks_exact_mut(m).zip(depth) {
                encode.eval_order_into(order, &[z], &mut scratch, o)?;
                for v in o.iter_mut() {
                    *v = store(storage, rounding, *v);
                }
            }
            Ok::<(), anyhow::Error>(())
        })?;
    Ok(out)
}

/// One filter tap sum in f32, in tap order: acc ← acc + w_i·v(i) for i = 0..n (unfused: the
/// product rounded, then the sum; fused: one rounding per tap).
#[inline]
pub fn tap_sum(weights: &[f32], v: impl Fn(usize) -> f32, order: Order) -> f32 {
    let mut acc = 0.0f32;
    for (i, &w) in weights.iter().enumerate() {
        acc = match order {
            Order::Unfused => acc + w * v(i),
            Order::Fused => w.mul_add(v(i), acc),
        };
    }
    acc
}

/// The stored, filtered value of the centre texel of one (2r+1)² window, as [`filter_pass`]
/// along x and then along y computes it there: `texels` holds the window's stored texels row by
/// row (dy outer, dx inner, edges already clamped), `m` channels each; row j's pass output
/// h_j = store(Σ_i w_i·s(i, j)), then out = store(Σ_j w_j·h_j). The windows that
/// `crate::tune::sample` gathers with clamped coordinates give the same values as the whole-map
/// passes at that texel (a test).
pub fn filtered_window(
    texels: &[f32],
    (m, weights): (usize, &[f32]),
    order: Order,
    storage: (Storage, HalfRounding),
    out: &mut [f32],
) {
    let n = weights.len();
    assert_eq!(texels.len(), n * n * m, "filtered_window: window size");
    let mut rows = [0.0f32; 129]; // radius ≤ 64 (`Gaussian::new`)
    for c in 0..m {
        for (j, h) in rows.iter_mut().enumerate().take(n) {
            let row = &texels[j * n * m..(j + 1) * n * m];
            *h = store(
                storage.0,
                storage.1,
                tap_sum(weights, |i| row[i * m + c], order),
            );
        }
        out[c] = store(storage.0, storage.1, tap_sum(weights, |j| rows[j], order));
    }
}

/// One filter pass over a map of `m` channels per texel: along x (`vertical` false) or y,
/// out = store(Σ_i w_i·map(p + i)) accumulated in f32 in tap order.
pub fn filter_pass(
    map: &[f32],
    (width, height, m): (usize, usize, usize),
    weights: &[f32],
    vertical: bool,
    order: Order,
    (storage, rounding): (Storage, HalfRounding),
) -> Vec<f32> {
    assert_eq!(map.len(), width * height * m, "filter_pass: map size");
    let r = (weights.len() / 2) as i64;
    let mut out = vec![0.0f32; map.len()];
    if out.is_empty() {
        return out;
    }
    // Rows in parallel; every value is the same tap sum as serially.
    out.par_chunks_mut(width * m)
        .enumerate()
        .for_each(|(y, row)| {
            for x in 0..width {
                for c in 0..m {
                    let tap = |i: usize| {
                        let d = i as i64 - r;
                        let t = if vertical {
                            clamp_coord(y, d, height) * width + x
                        } else {
                            y * width + clamp_coord(x, d, width)
                        };
                        map[t * m + c]
                    };
                    let acc = tap_sum(weights, tap, order);
                    row[x * m + c] = store(storage, rounding, acc);
                }
            }
        });
    out
}

/// The separable filter of a stored map: [`filter_pass`] along x, stored, then along y,
/// stored, as a two-pass blur writes its targets.
pub fn filter_map(
    map: &[f32],
    dims: (usize, usize, usize),
    weights: &[f32],
    order: Order,
    storage: (Storage, HalfRounding),
) -> Vec<f32> {
    let h = filter_pass(map, dims, weights, false, order, storage);
    filter_pass(&h, dims, weights, true, order, storage)
}

/// The stored, filtered map of a front-layer depth map: [`encode_map`], then [`filter_map`].
pub fn filtered_map(
    encode: &Func,
    order: Order,
    storage: (Storage, HalfRounding),
    kernel: &Gaussian,
    depth: &[f32],
    (width, height): (usize, usize),
) -> Result<Vec<f32>> {
    if depth.len() != width * height {
        bail!(
            "filtered_map: {} depths for a {width}×{height} map",
            depth.len()
        );
    }
    let m = encode.n_outputs();
    let w = weights_f32(kernel);
    let s = encode_map(encode, order, storage, depth)?;
    Ok(filter_map(&s, (width, height, m), &w, order, storage))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shader::Shape;

    fn power2() -> Func {
        let mut f = Func::new("enc");
        let z = f.input_scalar("z");
        let z2 = f.mul(z, z);
        f.output("s", Shape::Array(2), &[z, z2]);
        f
    }

    #[test]
    fn a_constant_map_filters_to_itself_up_to_the_weight_sum() {
        let k = Gaussian::paper();
        let sum: f32 = weights_f32(&k).iter().sum();
        let depth = vec![0.25f32; 7 * 5];
        for order in [Order::Unfused, Order::Fused] {
            let m = filtered_map(
                &power2(),
                order,
                (Storage::Float32, HalfRounding::NearestEven),
                &k,
                &depth,
                (7, 5),
            )
            .unwrap();
            for t in 0..35 {
                assert!(
                    (m[2 * t] - 0.25).abs() <= 4.0 * f32::EPSILON * sum,
                    "{}",
                    m[2 * t]
                );
                assert!((m[2 * t + 1] - 0.0625).abs() <= 4.0 * f32::EPSILON);
            }
        }
    }

    #[test]
    fn unorm_storage_rounds_the_texels_and_each_pass() {
        let k = Gaussian::paper();
        let depth: Vec<f32> = (0..64).map(|i| (i as f32 * 0.37).fract()).collect();
        let m = filtered_map(
            &power2(),
            Order::Unfused,
            (Storage::Unorm(16), HalfRounding::NearestEven),
            &k,
            &depth,
            (8, 8),
        )
        .unwrap();
        for v in &m {
            let q = *v as f64 * 65535.0;
            assert!(
                (q - q.round()).abs() < 1e-2,
                "{v} is not a 16-bit UNORM value"
            );
        }
        // the rounding of the intermediate pass shows: the f32 map differs
        let f = filtered_map(
            &power2(),
            Order::Unfused,
            (Storage::Float32, HalfRounding::NearestEven),
            &k,
            &depth,
            (8, 8),
        )
        .unwrap();
        let worst = m
            .iter()
            .zip(&f)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f32::max);
        assert!(worst > 0.0 && worst <= 1.0 / 65535.0, "{worst}");
    }

    #[test]
    fn half_rounding_toward_zero_never_rounds_away() {
        for i in 0..20000 {
            let v = (i as f32 * 0.618034).fract() * 3.0 - 1.5 + i as f32 * 1e-3;
            let n = store(Storage::Half, HalfRounding::NearestEven, v);
            let z = store(Storage::Half, HalfRounding::TowardZero, v);
            assert!(
                z.abs() <= v.abs() && (n - v).abs() <= (z - v).abs(),
                "{v}: {n} {z}"
            );
            assert_eq!(half::f16::from_f32(z).to_f32(), z);
        }
        assert_eq!(store(Storage::Half, HalfRounding::TowardZero, 1e6), 65504.0);
        // UNORM: the product is rounded in f32 first (32815.499… → 32815.5 → 32816)
        let v = 32815.5f32 / 65535.0 - 1e-8;
        assert_eq!(
            store(Storage::Unorm(16), HalfRounding::NearestEven, v),
            (32816.0f64 / 65535.0) as f32
        );
    }

    #[test]
    fn a_window_filters_to_the_whole_map_passes_bit_for_bit() {
        let k = Gaussian::paper();
        let w = weights_f32(&k);
        let (width, height, m) = (13usize, 11usize, 3usize);
        let mut x = 0x2545f491u64;
        let mut rnd = || {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            (x >> 40) as f32 / (1u64 << 24) as f32
        };
        for storage in [Storage::Float32, Storage::Unorm(16), Storage::Half] {
            for order in [Order::Unfused, Order::Fused] {
                let st = (storage, HalfRounding::TowardZero);
                let map: Vec<f32> = (0..width * height * m)
                    .map(|_| store(storage, st.1, rnd() * 1.3 - 0.1))
                    .collect();
                let v = filter_map(&map, (width, height, m), &w, order, st);
                let mut out = [0.0f32; 3];
                for y in 0..height {
                    for xx in 0..width {
                        let mut win = Vec::new();
                        for dy in -4i64..=4 {
                            for dx in -4i64..=4 {
                                let t =
                                    clamp_coord(y, dy, height) * width + clamp_coord(xx, dx, width);
                                win.extend_from_slice(&map[t * m..(t + 1) * m]);
                            }
                        }
                        filtered_window(&win, (m, &w), order, st, &mut out);
                        let t = y * width + xx;
                        assert_eq!(&out[..], &v[t * m..(t + 1) * m], "{storage:?} {order:?}");
                    }
                }
            }
        }
    }

    #[test]
    fn an_edge_texel_repeats_under_the_clamped_filter() {
        // one bright texel in the corner: its filtered value is the weight mass that falls on it
        let k = Gaussian::paper();
        let w = weights_f32(&k);
        let mut depth = vec![0.0f32; 9 * 9];
        depth[0] = 1.0;
        let m = filtered_map(
            &power2(),
            Order::Unfused,
            (Storage::Float32, HalfRounding::NearestEven),
            &k,
            &depth,
            (9, 9),
        )
        .unwrap();
        let edge: f32 = w[..5].iter().sum();
        assert!(
            (m[0] - edge * edge).abs() < 1e-6,
            "{} vs {}",
            m[0],
            edge * edge
        );
    }
}
