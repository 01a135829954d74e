//! `gpu check`: a setting's shadow-map pipeline run by the GPU driver against its CPU model
//! ([`crate::quantize::pipeline`]) on the same depth map and receivers, fragment by fragment.
//!
//! * The driver's binary16 conversion (nearest-even or toward zero, both allowed by Vulkan) is
//!   read off the GPU first ([`half_rounding`]) and the model uses it.
//! * The model runs in both operation orders (every operation rounded, and every a·b + c
//!   fused, [`Order`]), since a driver may contract either way.
//! * The filtered, stored map: every channel of every texel within [`MAP_TOLERANCE`] storage
//!   steps of one of the two model maps (for f32 storage a step is 4 ulp of the channel's
//!   largest value: transcendentals in an encoder are a few ulp on a GPU).
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
use serde::Serialize;

/// A filtered channel may differ from the model by this many storage steps.
pub const MAP_TOLERANCE: f64 = 1.0;
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

/// The comparison of one setting.
#[derive(Clone, Debug, Serialize)]
pub struct Verdict {
    /// Label of the setting.
    pub label: String,
    /// Receivers compared.
    pub receivers: usize,
    /// The driver's binary16 conversion the model used.
    pub half_rounding: HalfRounding,
    /// Share of texel channels whose filtered value is not bit-identical to either model map.
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
        Some(if self.map_steps > MAP_TOLERANCE {
            format!(
                "{}: the GPU's filtered map differs from the model by {:.1} storage steps at texel {}",
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
    let mut input = vec![0.0f32; m + 1];
    let mut scratch = Vec::new();
    let mut out = [0.0f32];
    let mut g = Vec::with_capacity(receivers.texel.len());
    for (&t, &zf) in receivers.texel.iter().zip(&receivers.zf) {
        let t = t as usize;
        input[..m].copy_from_slice(&map[t * m..(t + 1) * m]);
        input[m] = zf;
        f.eval_order_into(order, &input, &mut scratch, &mut out)?;
        g.push(out[0]);
    }
    Ok(g)
}

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
    let maps: Vec<Vec<f32>> = [Order::Unfused, Order::Fused]
        .iter()
        .map(|&o| stored::filtered_map(enc, o, (program.storage, half), &kernel, depth, size))
        .collect::<Result<_>>()?;
    // channel scales for the f32 tolerance
    let mut scale = vec![0.0f32; m];
    for (i, v) in maps[0].iter().enumerate() {
        scale[i % m] = scale[i % m].max(v.abs());
    }
    let (mut map_steps, mut map_worst_texel, mut inexact) = (0.0f64, 0usize, 0usize);
    for (i, &g) in out.filtered.iter().enumerate() {
        inexact += maps.iter().all(|mm| mm[i].to_bits() != g.to_bits()) as usize;
        let s = maps
            .iter()
            .map(|mm| steps(program.storage, g, mm[i], scale[i % m]))
            .fold(f64::INFINITY, f64::min);
        if s > map_steps || s.is_nan() {
            map_steps = if s.is_nan() { f64::INFINITY } else { s };
            map_worst_texel = i / m;
        }
    }
    let own: Vec<Vec<f32>> = [Order::Unfused, Order::Fused]
        .iter()
        .map(|&o| model_shadow(program.module, o, &out.filtered, m, receivers))
        .collect::<Result<_>>()?;
    let sens = sensitivity(program.module, &out.filtered, m, receivers, &own[0])?;
    let whole = model_shadow(program.module, Order::Unfused, &maps[0], m, receivers)?;
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
    let passed = map_steps <= MAP_TOLERANCE && g_outliers <= G_OUTLIER_SHARE;
    Ok(Verdict {
        label: label.to_string(),
        receivers: receivers.texel.len(),
        half_rounding: half,
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
