//! `gpu check`: a setting's shadow-map pipeline run by the GPU driver against its CPU model
//! ([`crate::quantize::pipeline`]) on the same depth map and receivers, fragment by fragment.
//!
//! * The driver's binary16 conversion (nearest-even or toward zero, both allowed by Vulkan) is
//!   read off the GPU first ([`half_rounding`]) and the model uses it.
//! * The model runs in both operation orders (every operation rounded, and every a·b + c
//!   fused, [`Order`]), since a driver may contract either way.
//! * The encoded, stored map: every channel of every texel within one code (UNORM, binary16)
//!   or [`ENCODE_TOLERANCE_ULPS`] ulp (f32) of one of the two model encodings: the encoder's
//!   built-ins (exp, log, sin, cos) are not correctly rounded on a GPU.
//! * The filtered, stored map: every channel within [`MAP_TOLERANCE`] storage steps of the
//!   model's two filter passes over the GPU's own encoded map, in either order (for f32 a step
//!   is 4 ulp of the channel's largest value).
//! * G on the GPU's filtered values against the model's `tunedShadow` on the same values,
//!   closer order: within 10⁻⁵ plus four times the receiver's sensitivity — the larger of the
//!   change of the model's G when the stored values move by one f32 ulp each ([`PERTURBATIONS`]
//!   random sign patterns) and the difference between its two orders, which shows how much
//!   the rounding inside the reconstruction moves G — on all but [`G_OUTLIER_SHARE`] of the
//!   receivers. An
//!   ill-conditioned reconstruction (a small α on 16 bits) magnifies an ulp into a visible
//!   change; that is the setting's noise, not a fault of the driver.
//! * The whole model (its own map) beside it: max, mean and the share above 1/255.
//!
//! A changed constant in the emitted code moves G on far more receivers than that, so it fails.

use super::pipeline::{Compiled, Program, Receivers};
use super::Gpu;
use crate::kernel::Gaussian;
use crate::quantize::pipeline::{self as stored, HalfRounding};
use crate::quantize::study::Storage;
use crate::shader::{Func, Module, Order, Shape};
use anyhow::{bail, Result};
use rayon::prelude::*;
use serde::Serialize;

/// A filtered channel may differ from the model's two filter passes over the GPU's own encoded
/// map by this many storage steps.
pub const MAP_TOLERANCE: f64 = 1.0;
/// An encoded f32 channel may differ from the model's by this many ulp of its value. The
/// encode pass calls built-ins that are not correctly rounded: Vulkan allows exp and exp2
/// 3 + 2·|x| ulp and log an absolute 2⁻²¹ near 1, so moments such as EVSM's e^(c·z) with
/// c ≤ 42 are specified to about 90 ulp; this bound is tighter than the specification and
/// looser than the exact agreement of a correctly rounded library. A UNORM or binary16
/// channel may differ by one code.
pub const ENCODE_TOLERANCE_ULPS: f64 = 64.0;
/// |G_gpu − G_model| allowed on a receiver beyond its sensitivity.
pub const G_TOLERANCE: f64 = 1e-5;
/// Share of receivers allowed beyond their tolerance.
pub const G_OUTLIER_SHARE: f64 = 1e-3;
/// Sign patterns of the one-ulp perturbations that measure a receiver's sensitivity.
pub const PERTURBATIONS: usize = 4;

/// How the GPU converts f32 to binary16 when it writes an RGBA16Float target: 4 096 values
/// through a pass that stores them, compared with both roundings; an error if neither fits.
pub fn half_rounding(gpu: &Gpu) -> Result<HalfRounding> {
    let mut enc = Func::new("tunedEncode");
    let z = enc.input_scalar("depth");
    enc.output("stored", Shape::Array(1), &[z]);
    let mut sh = Func::new("tunedShadow");
    let s = sh.input("stored", Shape::Array(1));
    let _ = sh.input_scalar("fragmentDepth");
    sh.ret(Shape::Scalar, &[s[0]]);
    let module = Module {
        header: vec![],
        funcs: vec![enc, sh],
    };
    let n = 4096usize;
    let values: Vec<f32> = (0..n)
        .map(|i| (i as f32 * 0.618_034).fract() * [1.0, 3e-3, 40.0, 7e3][i % 4])
        .collect();
    let program = Program {
        module: &module,
        wgsl: None,
        storage: Storage::Half,
        weights: &[1.0],
    };
    let out =
        Compiled::new(gpu, &program)?.run(gpu, &values, (n, 1), &Receivers::default(), true)?;
    for mode in [HalfRounding::NearestEven, HalfRounding::TowardZero] {
        if values
            .iter()
            .zip(&out.filtered)
            .all(|(&v, &g)| stored::store(Storage::Half, mode, v) == g)
        {
            return Ok(mode);
        }
    }
    bail!(
        "GPU '{}': its binary16 stores are neither rounded to nearest even nor toward zero",
        gpu.adapter.name
    )
}

/// The distance of two stored values in storage steps: UNORM codes, binary16 codes (ordered
/// by value), or for f32 multiples of 4 ulp of the channel's `scale`.
fn steps(storage: Storage, a: f32, b: f32, scale: f32) -> f64 {
    match storage {
        Storage::Unorm(bits) => {
            let q = ((1u64 << bits) - 1) as f64;
            ((a as f64 * q).round() - (b as f64 * q).round()).abs()
        }
        Storage::Half => {
            // binary16 codes as an ordered integer line (negative values mirrored)
            let code = |v: f32| {
                let h = half::f16::from_f32(v).to_bits() as i32;
                if h & 0x8000 != 0 {
                    -(h & 0x7fff)
                } else {
                    h
                }
            };
            (code(a) - code(b)).abs() as f64
        }
        _ => {
            let ulp = 4.0 * f32::EPSILON as f64 * scale.max(a.abs()).max(f32::MIN_POSITIVE) as f64;
            (a as f64 - b as f64).abs() / ulp
        }
    }
}

/// The two operation orders the model evaluates: a GPU compiler may or may not fuse a·b + c.
const ORDERS: [Order; 2] = [Order::Unfused, Order::Fused];

/// The largest distance in storage steps of `gpu` from the nearer of the `models` (per value,
/// channel scales `scale` for f32), and its texel; NaN counts as infinitely far.
fn worst_steps(storage: Storage, gpu: &[f32], models: &[Vec<f32>], scale: &[f32]) -> (f64, usize) {
    let m = scale.len().max(1);
    let (mut worst, mut at) = (0.0f64, 0usize);
    for (i, &g) in gpu.iter().enumerate() {
        let s = models
            .iter()
            .map(|mm| steps(storage, g, mm[i], scale[i % m]))
            .fold(f64::INFINITY, f64::min);
        if s > worst || s.is_nan() {
            worst = if s.is_nan() { f64::INFINITY } else { s };
            at = i / m;
        }
    }
    (worst, at)
}

/// The comparison of one setting.
#[derive(Clone, Debug, Serialize)]
pub struct Verdict {
    /// Label of the setting.
    pub label: String,
    /// Receivers compared.
    pub receivers: usize,
    /// The driver's binary16 conversion the model used.
    pub half_rounding: HalfRounding,
    /// Largest difference of the GPU's encoded map from the model's: ulp of the value for f32,
    /// codes for UNORM and binary16.
    pub encode_steps: f64,
    /// The bound on [`Self::encode_steps`]: [`ENCODE_TOLERANCE_ULPS`] for f32, one code else.
    pub encode_bound: f64,
    /// Texel of the largest encode difference.
    pub encode_worst_texel: usize,
    /// Share of texel channels whose filtered value is not bit-identical to either model
    /// filtering of the GPU's encoded map.
    pub map_inexact: f64,
    /// Largest map difference in storage steps.
    pub map_steps: f64,
    /// Texel of the largest map difference.
    pub map_worst_texel: usize,
    /// Largest |G_gpu − G_model(GPU map)| beyond the receiver's tolerance (0: none), the
    /// receiver, and the largest |G_gpu − G_model(GPU map)| itself.
    pub g_excess: f64,
    /// Index of the receiver with the largest excess.
    pub g_worst: usize,
    /// Largest |G_gpu − G_model(GPU map)|.
    pub g_max: f64,
    /// Share of receivers beyond their tolerance.
    pub g_outliers: f64,
    /// The worst receiver's texel (x, y) and z_f.
    pub worst_texel: (usize, usize),
    /// z_f of the worst receiver.
    pub worst_zf: f32,
    /// Largest and mean |G_gpu − G_model| of the whole CPU model (its own map).
    pub pipeline_max: f64,
    /// Mean |G_gpu − G_model| of the whole CPU model.
    pub pipeline_mean: f64,
    /// Share of receivers where the whole model differs by more than 1/255.
    pub pipeline_above_8bit: f64,
    /// The map is within its tolerance and few enough receivers are beyond theirs.
    pub passed: bool,
}

impl Verdict {
    /// One line: what failed and where.
    pub fn failure(&self) -> Option<String> {
        if self.passed {
            return None;
        }
        Some(if self.encode_steps > self.encode_bound {
            format!(
                "{}: the GPU's encoded map differs from the model by {:.1} {} at texel {} (allowed {})",
                self.label,
                self.encode_steps,
                if self.encode_bound > 1.0 { "ulp" } else { "codes" },
                self.encode_worst_texel,
                self.encode_bound
            )
        } else if self.map_steps > MAP_TOLERANCE {
            format!(
                "{}: the GPU's filtered map differs from the model's filtering of its encoded map by {:.1} storage steps at texel {}",
                self.label, self.map_steps, self.map_worst_texel
            )
        } else {
            format!(
                "{}: G differs from the model beyond {G_TOLERANCE} + 4 × its rounding sensitivity on {:.3} % of receivers (allowed {} %), worst by {:.3e} at texel ({}, {}), z_f = {}",
                self.label,
                100.0 * self.g_outliers,
                100.0 * G_OUTLIER_SHARE,
                self.g_excess,
                self.worst_texel.0,
                self.worst_texel.1,
                self.worst_zf
            )
        })
    }
}

/// Evaluate `tunedShadow` of `module` on a map (m per texel) for the receivers, in `order`.
pub fn model_shadow(
    module: &Module,
    order: Order,
    map: &[f32],
    m: usize,
    receivers: &Receivers,
) -> Result<Vec<f32>> {
    let Some(f) = module.func("tunedShadow") else {
        bail!("shader module has no tunedShadow");
    };
    // Receivers in parallel blocks; each receiver's evaluation is the same as serially.
    let mut g = vec![0.0f32; receivers.texel.len()];
    g.par_chunks_mut(RECEIVER_BLOCK)
        .zip(receivers.texel.par_chunks(RECEIVER_BLOCK))
        .zip(receivers.zf.par_chunks(RECEIVER_BLOCK))
        .try_for_each(|((g, texels), zfs)| {
            let mut input = vec![0.0f32; m + 1];
            let mut scratch = Vec::new();
            let mut out = [0.0f32];
            for ((g, &t), &zf) in g.iter_mut().zip(texels).zip(zfs) {
                let t = t as usize;
                input[..m].copy_from_slice(&map[t * m..(t + 1) * m]);
                input[m] = zf;
                f.eval_order_into(order, &input, &mut scratch, &mut out)?;
                *g = out[0];
            }
            Ok::<(), anyhow::Error>(())
        })?;
    Ok(g)
}

/// Receivers per parallel block of [`model_shadow`].
const RECEIVER_BLOCK: usize = 512;

/// Run the pipeline of `program` on the GPU and compare it with the model; `label` names the
/// setting in the verdict.
pub fn check(
    gpu: &Gpu,
    label: &str,
    program: &Program,
    depth: &[f32],
    size: (usize, usize),
    receivers: &Receivers,
) -> Result<Verdict> {
    let compiled = Compiled::new(gpu, program)?;
    let m = compiled.channels();
    let out = compiled.run(gpu, depth, size, receivers, true)?;
    let Some(enc) = program.module.func("tunedEncode") else {
        bail!("shader module has no tunedEncode");
    };
    let half = half_rounding(gpu)?;
    let kernel = Gaussian::paper();
    let st = (program.storage, half);
    // Stage 1, encode: the GPU's stored texels against the model's, in ulp of each value.
    let encoded: Vec<Vec<f32>> = ORDERS
        .iter()
        .map(|&o| stored::encode_map(enc, o, st, depth))
        .collect::<Result<_>>()?;
    let (encode_steps, encode_worst_texel) =
        worst_steps(program.storage, &out.encoded, &encoded, &vec![0.0; m]);
    let encode_steps = match program.storage {
        Storage::Unorm(_) | Storage::Half => encode_steps,
        // in ulp: steps() counts multiples of 4 ulp
        _ => 4.0 * encode_steps,
    };
    // Stage 2, filter: the model's two passes over the GPU's own encoded map.
    let w = stored::weights_f32(&kernel);
    let dims = (size.0, size.1, m);
    // The model's whole pipeline from the depths (unfused), for the whole-model figures.
    let whole_map = stored::filter_map(&encoded[0], dims, &w, Order::Unfused, st);
    let refiltered: Vec<Vec<f32>> = ORDERS
        .iter()
        .map(|&o| stored::filter_map(&out.encoded, dims, &w, o, st))
        .collect();
    // channel scales for the f32 tolerance
    let mut scale = vec![0.0f32; m];
    for (i, v) in refiltered[0].iter().enumerate() {
        scale[i % m] = scale[i % m].max(v.abs());
    }
    let (map_steps, map_worst_texel) =
        worst_steps(program.storage, &out.filtered, &refiltered, &scale);
    let inexact = out
        .filtered
        .iter()
        .enumerate()
        .filter(|&(i, g)| refiltered.iter().all(|mm| mm[i].to_bits() != g.to_bits()))
        .count();
    let own: Vec<Vec<f32>> = ORDERS
        .iter()
        .map(|&o| model_shadow(program.module, o, &out.filtered, m, receivers))
        .collect::<Result<_>>()?;
    let sens = sensitivity(program.module, &out.filtered, m, receivers, &own[0])?;
    let whole = model_shadow(program.module, Order::Unfused, &whole_map, m, receivers)?;
    let n = receivers.texel.len().max(1);
    let (mut g_max, mut g_excess, mut g_worst, mut outliers) = (0.0f64, 0.0f64, 0usize, 0usize);
    let (mut p_max, mut p_sum, mut p_above) = (0.0f64, 0.0f64, 0usize);
    for (i, &g) in out.shadow.iter().enumerate() {
        let d = own
            .iter()
            .map(|o| diff(g, o[i]))
            .fold(f64::INFINITY, f64::min);
        g_max = g_max.max(d);
        // the receiver's sensitivity: to one-ulp inputs, and to the order of its operations
        let spread = diff(own[0][i], own[1][i]);
        let excess = d - (G_TOLERANCE + 4.0 * sens[i].max(spread));
        if excess > g_excess {
            g_excess = excess;
            g_worst = i;
        }
        outliers += (excess > 0.0) as usize;
        let p = diff(g, whole[i]);
        p_max = p_max.max(p);
        p_sum += p;
        p_above += (p > 1.0 / 255.0) as usize;
    }
    let g_outliers = outliers as f64 / n as f64;
    let encode_bound = match program.storage {
        Storage::Unorm(_) | Storage::Half => 1.0,
        _ => ENCODE_TOLERANCE_ULPS,
    };
    let passed =
        encode_steps <= encode_bound && map_steps <= MAP_TOLERANCE && g_outliers <= G_OUTLIER_SHARE;
    Ok(Verdict {
        label: label.to_string(),
        receivers: receivers.texel.len(),
        half_rounding: half,
        encode_steps,
        encode_bound,
        encode_worst_texel,
        map_inexact: inexact as f64 / out.filtered.len().max(1) as f64,
        map_steps,
        map_worst_texel,
        g_excess,
        g_worst,
        g_max,
        g_outliers,
        worst_texel: receivers
            .texel
            .get(g_worst)
            .map_or((0, 0), |&t| (t as usize % size.0, t as usize / size.0)),
        worst_zf: receivers.zf.get(g_worst).copied().unwrap_or(0.0),
        pipeline_max: p_max,
        pipeline_mean: p_sum / n as f64,
        pipeline_above_8bit: p_above as f64 / n as f64,
        passed,
    })
}

/// Per receiver, the largest |G(s′) − G(s)| of the model (unfused) when every stored value
/// moves by one f32 ulp, over [`PERTURBATIONS`] fixed sign patterns.
fn sensitivity(
    module: &Module,
    map: &[f32],
    m: usize,
    receivers: &Receivers,
    base: &[f32],
) -> Result<Vec<f64>> {
    let mut out = vec![0.0f64; receivers.texel.len()];
    let mut moved = map.to_vec();
    for k in 0..PERTURBATIONS {
        for (i, (v, &x)) in moved.iter_mut().zip(map).enumerate() {
            // a fixed pseudo-random sign per value and pattern
            let h = (i as u64 ^ (k as u64) << 40).wrapping_mul(0x9E37_79B9_7F4A_7C15) >> 63;
            *v = if h == 1 { x.next_up() } else { x.next_down() };
        }
        let g = model_shadow(module, Order::Unfused, &moved, m, receivers)?;
        for ((o, &a), &b) in out.iter_mut().zip(&g).zip(base) {
            *o = o.max(diff(a, b).min(1.0));
        }
    }
    Ok(out)
}

/// |a − b|, with NaN equal to NaN and unequal to anything else (∞).
fn diff(a: f32, b: f32) -> f64 {
    match (a.is_nan(), b.is_nan()) {
        (true, true) => 0.0,
        (false, false) => (a as f64 - b as f64).abs(),
        _ => f64::INFINITY,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn worst_steps_takes_the_nearer_model_per_value_and_counts_nan_as_far() {
        // UNORM16: one code is 1/65535.
        let code = 1.0 / 65535.0f32;
        let gpu = [0.5, 0.25 + 3.0 * code];
        let a = vec![0.5 + 2.0 * code, 0.25];
        let b = vec![0.5, 0.25 + 2.0 * code];
        let (w, at) = worst_steps(Storage::Unorm(16), &gpu, &[a, b], &[0.0]);
        assert_eq!((w, at), (1.0, 1));
        // f32 relative to the value (scale 0): 8 ulp of 1.0 are 2 steps of 4 ulp.
        let g = [1.0f32 + 8.0 * f32::EPSILON];
        let (w, _) = worst_steps(Storage::Float32, &g, &[vec![1.0]], &[0.0]);
        assert!((w - 2.0).abs() < 1e-5, "{w}");
        let (w, _) = worst_steps(Storage::Float32, &[f32::NAN], &[vec![1.0]], &[0.0]);
        assert!(w.is_infinite());
    }
}
