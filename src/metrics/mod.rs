//! Error of a technique against the PCF reference: mean |G − PCF| over all fragments of all
//! layers (Peters & Klein 2015, Section 3.2).
//!
//! A *fragment* is one surface seen from the light: texel t, layer k, depth z_f = depth[k][t].
//! Its reference is PCF with the paper's 9×9 Gaussian (σ = 2.4) over the front-layer depths z0
//! and a receiver-plane bias (see [`Bias`], [`pcf`]):
//!
//! PCF(t, k) = Σ_l w_l [ z0(t+l) < z_f + s·Δ_l − ε ],  Δ_l = dz/du·dx_l + dz/dv·dy_l,
//!
//! and every technique is evaluated from the filtered moments b_t at the biased depth
//! z_f − ε′ (ε′ = technique_epsilon + technique_slope_scale·(|dz/du| + |dz/dv|)).
//! The error of a technique is mean_{fragments} |G − PCF| (for a directional light this is the
//! L¹ error of the irradiance field divided by the total radiant power, Section 3.2).

pub mod windows;

use crate::kernel::{self, Gaussian};
use crate::stack::DepthStack;
use crate::technique::{Evaluator, Technique};
use crate::Grid;
use anyhow::{bail, Result};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Arc;
use std::time::Instant;

/// Depth biases of the PCF reference and of the techniques (all in normalised depth [0,1]).
///
/// Defaults (see docs/evaluation.md): the PCF test uses the exact receiver plane (s = 1) plus
/// ε = 1e-4, so every front-layer fragment of a planar lit surface is lit (its neighbours lie
/// on its own plane) up to rounding of the f32 depths; techniques see z_f − ε′ with
/// ε′ = 1e-4 + 2·(|dz/du| + |dz/dv|): on a tilted plane the sharp bound of the four power
/// moments is 0 from 1.5·(|dz/du| + |dz/dv|) below z_f on (measured with the reference LP), so
/// front layers of lit planes come out lit; a larger slope scale (4 = kernel radius makes every
/// plane fragment trivial for every basis) doubles the light leaked on thin occluders' back
/// faces and contact shadows.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Bias {
    /// ε: constant bias of the PCF depth test.
    pub pcf_epsilon: f64,
    /// s: scale of the receiver-plane offset Δ_l in the PCF depth test.
    pub slope_scale: f64,
    /// Constant part of ε′, the bias subtracted from z_f before a technique is evaluated.
    pub technique_epsilon: f64,
    /// Slope part of ε′: ε′ += technique_slope_scale · (|dz/du| + |dz/dv|) (texels).
    pub technique_slope_scale: f64,
    /// Which receiver plane the PCF test extends to each tap (see [`Receiver`]).
    #[serde(default)]
    pub receiver: Receiver,
}

/// The receiver plane of the PCF test at tap l (offset o_l = (dx_l, dy_l) texels).
///
/// * `Fragment`: Δ_l = ∇z_f·o_l, the fragment's own tangent plane.
/// * `Lower` (default): Δ_l = min(∇z_f·o_l, min_j ∇z0(p_j)·o_l) over the front texels p_j the
///   straight path to the tap passes (at each step of the longer axis the floor and ceiling
///   texel of the path point, the tap included): the lowest tangent plane met on the way. The surface's own rise along the path is
///   z(t+l) − z_f = ∫₀¹ ∇z(t + τ·o_l)·o_l dτ ≥ min_τ ∇z·o_l, so a surface whose facets the path
///   samples never shadows itself (convex, concave or saddle); on a plane every slope agrees
///   and the test is the `Fragment` test (docs/evaluation.md).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Receiver {
    Fragment,
    #[default]
    Lower,
}

impl Receiver {
    /// Parses "fragment" or "lower".
    pub fn parse(s: &str) -> Result<Receiver> {
        match s {
            "fragment" => Ok(Receiver::Fragment),
            "lower" => Ok(Receiver::Lower),
            _ => bail!("receiver plane '{s}': expected 'fragment' or 'lower'"),
        }
    }
}

/// Factors of the PCF constant ε at which every error is also reported (reference
/// sensitivity): ε/3 and 3ε.
pub const EPSILON_FACTORS: [f64; 2] = [1.0 / 3.0, 3.0];

/// Largest slope scale of a bias, in texels (times |dz/du| + |dz/dv|).
pub const MAX_SLOPE_SCALE: f64 = 1e3;

impl Default for Bias {
    fn default() -> Self {
        Bias {
            pcf_epsilon: 1e-4,
            slope_scale: 1.0,
            technique_epsilon: 1e-4,
            technique_slope_scale: 2.0,
            receiver: Receiver::Lower,
        }
    }
}

impl Bias {
    /// Rejects values outside their range with a one-line error: the constants in [0, 1]
    /// (depths lie in [0, 1], so a larger offset moves every test past the depth range), the
    /// slope scales in [0, [`MAX_SLOPE_SCALE`]] texels.
    pub fn validate(&self) -> Result<()> {
        for (name, v, max) in [
            ("pcf_epsilon", self.pcf_epsilon, 1.0),
            ("slope_scale", self.slope_scale, MAX_SLOPE_SCALE),
            ("technique_epsilon", self.technique_epsilon, 1.0),
            (
                "technique_slope_scale",
                self.technique_slope_scale,
                MAX_SLOPE_SCALE,
            ),
        ] {
            if !(v.is_finite() && (0.0..=max).contains(&v)) {
                bail!("bias: {name} must be in [0, {max}], got {v:?}");
            }
        }
        Ok(())
    }

    /// ε′ for a fragment with receiver-plane slopes (dz/du, dz/dv).
    pub fn technique_offset(&self, dzdu: f64, dzdv: f64) -> f64 {
        self.technique_epsilon + self.technique_slope_scale * (dzdu.abs() + dzdv.abs())
    }
}

/// One fragment of a depth stack with its PCF reference.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Fragment {
    /// Index of the view (stack) in the evaluated list.
    pub view: usize,
    /// Texel index t = y·width + x.
    pub texel: usize,
    /// Layer k (0 = front).
    pub layer: usize,
    /// The depth a technique sees: z_f − ε′.
    pub zf: f64,
    /// The PCF reference shadow intensity ∈ [0,1].
    pub pcf: f64,
    /// PCF with the constant ε scaled by [`EPSILON_FACTORS`] (reference sensitivity).
    #[serde(default)]
    pub pcf_scaled: [f64; 2],
    /// F_Z(zf) = 0 (no kernel depth below zf): G = 0 for every sharp lower bound.
    pub trivial: bool,
}

/// A finite slope, or 0 (defensive: stacks are validated on load).
#[inline]
fn slope(v: f32) -> f64 {
    if v.is_finite() {
        v as f64
    } else {
        0.0
    }
}

/// The front layer of a stack as the PCF test reads it: depth z0 (background = 1) and the
/// receiver-plane slopes of the front surface (0 where there is none).
#[derive(Clone, Debug, PartialEq)]
pub struct FrontMap {
    pub width: usize,
    pub height: usize,
    pub depth: Vec<f64>,
    pub dzdu: Vec<f64>,
    pub dzdv: Vec<f64>,
}

impl FrontMap {
    /// The front layer of `stack`.
    pub fn of(stack: &DepthStack) -> FrontMap {
        let n = stack.texel_count();
        let slopes = |s: &[Vec<f32>]| -> Vec<f64> {
            match (stack.depth.first(), s.first()) {
                (Some(d), Some(l)) => (0..n)
                    .map(|t| if d[t].is_finite() { slope(l[t]) } else { 0.0 })
                    .collect(),
                _ => vec![0.0; n],
            }
        };
        FrontMap {
            width: stack.meta.width,
            height: stack.meta.height,
            depth: kernel::front_map(stack),
            dzdu: slopes(&stack.dzdu),
            dzdv: slopes(&stack.dzdv),
        }
    }
}

/// PCF of a fragment at texel (x, y) with depth `zf` and receiver-plane slopes (dzdu, dzdv):
/// Σ_l w_l [z0(t+l) < zf + s·Δ_l − ε], Δ_l per [`Receiver`] with (dx, dy) the offset to the
/// (edge-clamped) neighbour texel actually read.
#[allow(clippy::too_many_arguments)]
pub fn pcf(
    front: &FrontMap,
    kernel: &Gaussian,
    x: usize,
    y: usize,
    zf: f64,
    dzdu: f64,
    dzdv: f64,
    bias: &Bias,
) -> f64 {
    pcf_at(
        front,
        kernel,
        x,
        y,
        zf,
        dzdu,
        dzdv,
        bias,
        [bias.pcf_epsilon],
    )[0]
}

/// [`pcf`] for N constants ε at once (one pass over the taps).
#[allow(clippy::too_many_arguments)]
pub fn pcf_at<const N: usize>(
    front: &FrontMap,
    kernel: &Gaussian,
    x: usize,
    y: usize,
    zf: f64,
    dzdu: f64,
    dzdv: f64,
    bias: &Bias,
    eps: [f64; N],
) -> [f64; N] {
    let (width, height) = (front.width, front.height);
    let r = kernel.radius() as i64;
    let g = kernel.weights_1d();
    let lower = bias.receiver == Receiver::Lower;
    let mut total = [0.0; N];
    for (iy, &wy) in g.iter().enumerate() {
        let yy = kernel::clamp_coord(y, iy as i64 - r, height);
        let dy = yy as f64 - y as f64;
        let row = yy * width;
        let mut s = [0.0; N];
        for (ix, &wx) in g.iter().enumerate() {
            let xx = kernel::clamp_coord(x, ix as i64 - r, width);
            let dx = xx as f64 - x as f64;
            let mut delta = dzdu * dx + dzdv * dy;
            if lower {
                // the lowest tangent plane met on the straight path to the tap: at each step
                // of the longer axis the (one or two) texels the path passes between
                let n = (xx as i64 - x as i64)
                    .abs()
                    .max((yy as i64 - y as i64).abs());
                for j in 1..=n {
                    let f = j as f64 / n as f64;
                    let (px, py) = (x as f64 + dx * f, y as f64 + dy * f);
                    for (qx, qy) in [(px.floor(), py.floor()), (px.ceil(), py.ceil())] {
                        let k = qy as usize * width + qx as usize;
                        delta = delta.min(front.dzdu[k] * dx + front.dzdv[k] * dy);
                    }
                }
            }
            let plane = zf + bias.slope_scale * delta;
            let z0 = front.depth[row + xx];
            for k in 0..N {
                if z0 < plane - eps[k] {
                    s[k] += wx;
                }
            }
        }
        for k in 0..N {
            total[k] += wy * s[k];
        }
    }
    total
}

/// PCF of fragment (texel, layer) of a stack with the paper's kernel (see [`pcf`]).
pub fn pcf_of(
    stack: &DepthStack,
    front: &FrontMap,
    texel: usize,
    layer: usize,
    bias: &Bias,
) -> f64 {
    let w = stack.meta.width;
    let zf = stack.depth[layer][texel] as f64;
    pcf(
        front,
        &Gaussian::paper(),
        texel % w,
        texel / w,
        zf,
        slope(stack.dzdu[layer][texel]),
        slope(stack.dzdv[layer][texel]),
        bias,
    )
}

/// Checks the shape of a stack (so that indexing cannot panic) with a one-line error.
pub fn check_stack(stack: &DepthStack) -> Result<()> {
    let m = &stack.meta;
    let n = m.width * m.height;
    let name = format!("{}/{}", m.scene, m.view);
    if n == 0 {
        bail!("stack {name}: empty ({}×{})", m.width, m.height);
    }
    if stack.depth.len() != stack.dzdu.len() || stack.depth.len() != stack.dzdv.len() {
        bail!(
            "stack {name}: {} depth layers but {}/{} slope layers",
            stack.depth.len(),
            stack.dzdu.len(),
            stack.dzdv.len()
        );
    }
    for (l, ((d, u), v)) in stack
        .depth
        .iter()
        .zip(&stack.dzdu)
        .zip(&stack.dzdv)
        .enumerate()
    {
        if d.len() != n || u.len() != n || v.len() != n {
            bail!(
                "stack {name}: layer {l} has {}/{}/{} values, expected {n}",
                d.len(),
                u.len(),
                v.len()
            );
        }
        if let Some(t) = d
            .iter()
            .position(|z| z.is_nan() || *z < 0.0 || (*z > 1.0 && z.is_finite()))
        {
            bail!(
                "stack {name}: layer {l} texel ({}, {}) has depth {} outside [0,1]",
                t % m.width,
                t / m.width,
                d[t]
            );
        }
    }
    Ok(())
}

/// Which fragments of a view to evaluate.
#[derive(Clone, Copy, Debug, PartialEq, Default, Serialize, Deserialize)]
pub enum Subsample {
    /// Every fragment.
    #[default]
    All,
    /// Every k-th fragment in layer-major, texel order (k ≥ 1).
    Stride(usize),
    /// Each fragment independently with probability `fraction`, decided by a hash of
    /// (seed, view, layer, texel): deterministic and independent of thread timing.
    Random { fraction: f64, seed: u64 },
}

impl Subsample {
    fn validate(&self) -> Result<()> {
        match *self {
            Subsample::All => Ok(()),
            Subsample::Stride(0) => bail!("subsample: stride must be >= 1"),
            Subsample::Stride(_) => Ok(()),
            Subsample::Random { fraction, .. } => {
                if !(fraction > 0.0 && fraction <= 1.0) {
                    bail!("subsample: fraction must be in (0, 1], got {fraction}");
                }
                Ok(())
            }
        }
    }
}

fn splitmix64(mut x: u64) -> u64 {
    x = x.wrapping_add(0x9E37_79B9_7F4A_7C15);
    x = (x ^ (x >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    x = (x ^ (x >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    x ^ (x >> 31)
}

/// (layer, texel) of the selected fragments of a view, layer-major.
fn select(stack: &DepthStack, view: usize, sub: &Subsample) -> Vec<(usize, usize)> {
    let mut out = Vec::new();
    let mut i = 0usize;
    for (l, layer) in stack.depth.iter().enumerate() {
        for (t, z) in layer.iter().enumerate() {
            if !z.is_finite() {
                continue;
            }
            let keep = match *sub {
                Subsample::All => true,
                Subsample::Stride(k) => i.is_multiple_of(k),
                Subsample::Random { fraction, seed } => {
                    let h = splitmix64(
                        seed ^ splitmix64((view as u64) << 40 ^ (l as u64) << 32 ^ t as u64),
                    );
                    ((h >> 11) as f64) * (1.0 / (1u64 << 53) as f64) < fraction
                }
            };
            if keep {
                out.push((l, t));
            }
            i += 1;
        }
    }
    out
}

/// The fragments (layer, texel) of `picked` (as [`fragments`] returns them, in that order),
/// their PCF computed for these alone: a caller that needs the reference of a few fragments
/// of a stack does not pay for all of them.
pub fn fragments_at(
    stack: &DepthStack,
    view: usize,
    bias: &Bias,
    picked: &[(usize, usize)],
) -> Vec<Fragment> {
    let w = stack.meta.width;
    let h = stack.meta.height;
    let front = FrontMap::of(stack);
    let kern = Gaussian::paper();
    let min_map = kernel::min_filter(&front.depth, w, h, kern.radius());
    let e = bias.pcf_epsilon;
    let eps = [e, e * EPSILON_FACTORS[0], e * EPSILON_FACTORS[1]];
    picked
        .par_iter()
        .with_min_len(1024)
        .map(|&(layer, texel)| {
            let z = stack.depth[layer][texel] as f64;
            let (du, dv) = (
                slope(stack.dzdu[layer][texel]),
                slope(stack.dzdv[layer][texel]),
            );
            let p = pcf_at(&front, &kern, texel % w, texel / w, z, du, dv, bias, eps);
            let zf = technique_depth(stack, layer, texel, bias);
            Fragment {
                view,
                texel,
                layer,
                zf,
                pcf: p[0],
                pcf_scaled: [p[1], p[2]],
                trivial: min_map[texel] >= zf,
            }
        })
        .collect()
}

/// All fragments of a stack (every finite depth of every layer, layer-major, texel order) with
/// their PCF reference, biased technique depth and trivial flag. `view_index` is stored in each
/// fragment. Panics on a malformed stack; call [`check_stack`] first for user data.
pub fn fragments(stack: &DepthStack, view_index: usize, bias: &Bias) -> Vec<Fragment> {
    let picked = select(stack, view_index, &Subsample::All);
    fragments_at(stack, view_index, bias, &picked)
}

/// Every fragment of a stack as (layer, texel), in the order of [`fragments`].
pub fn fragment_positions(stack: &DepthStack) -> Vec<(usize, usize)> {
    select(stack, 0, &Subsample::All)
}

/// The depth a technique sees at fragment (layer, texel): z_f − ε′ ([`Bias::technique_offset`]).
pub fn technique_depth(stack: &DepthStack, layer: usize, texel: usize, bias: &Bias) -> f64 {
    let z = stack.depth[layer][texel] as f64;
    let (du, dv) = (
        slope(stack.dzdu[layer][texel]),
        slope(stack.dzdv[layer][texel]),
    );
    z - bias.technique_offset(du, dv)
}

/// Like [`fragments`] but only a subsample.
pub fn fragments_subsampled(
    stack: &DepthStack,
    view_index: usize,
    bias: &Bias,
    sub: &Subsample,
) -> Vec<Fragment> {
    let picked = select(stack, view_index, sub);
    fragments_at(stack, view_index, bias, &picked)
}

/// Index of the grid point nearest to z (ties to the lower point; outside the grid: an end).
pub fn snap_index(grid: &Grid, z: f64) -> usize {
    grid.nearest(z)
}

/// The grid point nearest to z ([`Grid::snap`]).
pub fn snap(grid: &Grid, z: f64) -> f64 {
    grid.snap(z)
}

/// What is evaluated against PCF.
#[derive(Clone, Copy)]
pub enum Subject<'a> {
    /// A moment technique (closed form or LP candidate).
    Technique(&'a dyn Technique),
    /// PCF itself, recomputed per fragment through the same loop (its error is 0).
    Pcf,
    /// The exact F_Z(z_f − ε′) of the unsnapped depth distribution: what an ideal technique
    /// that knew Z_t would return. Its error is the floor set by the technique bias ε′ (it
    /// differs from PCF only through the biases), not a technique.
    Cdf,
}

impl<'a> Subject<'a> {
    pub fn name(&self) -> String {
        match self {
            Subject::Technique(t) => t.name(),
            Subject::Pcf => "pcf".to_string(),
            Subject::Cdf => "cdf".to_string(),
        }
    }

    /// One thread's state for the chunk loops: the technique's evaluator (None for PCF and
    /// the CDF) and a buffer of m moments.
    fn chunk_state(self, m: usize) -> (Option<Box<dyn Evaluator + 'a>>, Vec<f64>) {
        let ev = match self {
            Subject::Technique(t) => Some(t.evaluator()),
            Subject::Pcf | Subject::Cdf => None,
        };
        (ev, vec![0.0; m])
    }
}

/// Start a chunk from a cold evaluator, so that its bits do not depend on which chunks its
/// thread ran before.
fn cold(ev: &mut Option<Box<dyn Evaluator + '_>>) {
    if let Some(e) = ev.as_mut() {
        e.reset();
    }
}

/// Progress callback: (fragments done, fragments planned), over all views.
pub type Progress = Arc<dyn Fn(usize, usize) + Send + Sync>;

/// Options of [`evaluate`].
#[derive(Clone, Default)]
pub struct EvalOptions {
    pub bias: Bias,
    pub subsample: Subsample,
    /// Skip the evaluation of trivial fragments (G := 0). `None` = automatic: skip for grid
    /// techniques (LP candidates, sharp lower bounds by construction), evaluate closed forms
    /// everywhere (they are cheap and not all of them are lower bounds, e.g. CSM).
    pub skip_trivial: Option<bool>,
    /// Keep per-fragment values (G, PCF) in the report ([`ViewReport::values`]).
    pub keep_values: bool,
    pub progress: Option<Progress>,
}

/// One evaluated fragment (kept with [`EvalOptions::keep_values`]).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct FragmentValue {
    pub texel: usize,
    pub layer: usize,
    pub pcf: f64,
    pub g: f64,
    pub trivial: bool,
}

/// Result for one view.
#[derive(Clone, Debug, Serialize)]
pub struct ViewReport {
    pub scene: String,
    pub view: String,
    pub width: usize,
    pub height: usize,
    pub layers: usize,
    /// All fragments of the view.
    pub fragments_total: usize,
    /// Evaluated fragments (after subsampling).
    pub fragments: usize,
    /// Evaluated fragments with F_Z(z_f − ε′) = 0 (after grid snapping for LP candidates).
    pub trivial: usize,
    /// Fragments for which the technique was called (not skipped as trivial).
    pub solved: usize,
    /// Fragments with non-finite G (excluded from the mean, reported here).
    pub non_finite: usize,
    /// Fragments whose LP was unsettled: scored as the trivial bound G = 0 (included in the
    /// mean; `lp::UNSETTLED_G`).
    pub unsettled: usize,
    /// Fragments with finite G outside [0,1] (more than 1e-9; included in the mean as is).
    pub out_of_range: usize,
    /// Σ |G − PCF| over the finite fragments.
    pub sum_abs_error: f64,
    /// Mean |G − PCF| over the finite fragments (0 without fragments, NaN when every output
    /// was non-finite).
    pub error: f64,
    /// Σ |G − PCF| with PCF's ε scaled by [`EPSILON_FACTORS`].
    pub sum_abs_error_scaled: [f64; 2],
    /// Mean |G − PCF| with PCF's ε scaled by [`EPSILON_FACTORS`] (reference sensitivity).
    pub error_scaled: [f64; 2],
    /// Σ max(0, PCF − G): light leaked (G below the reference).
    pub sum_leak: f64,
    /// Mean max(0, PCF − G) over the finite fragments: the light-leaking part of `error`.
    pub leak: f64,
    /// Wall time of the view (fragments, moment maps, shading), seconds.
    pub seconds: f64,
    /// Wall time of the shading loop alone, seconds.
    pub shade_seconds: f64,
    #[serde(skip)]
    pub values: Option<Vec<FragmentValue>>,
}

/// Result over all views.
#[derive(Clone, Debug, Serialize)]
pub struct EvalReport {
    pub technique: String,
    pub bias: Bias,
    pub subsample: Subsample,
    pub fragments_total: usize,
    pub fragments: usize,
    pub trivial: usize,
    pub solved: usize,
    pub non_finite: usize,
    /// LP answers scored as the trivial bound because the solver settled neither verdict.
    pub unsettled: usize,
    pub out_of_range: usize,
    /// Mean |G − PCF| over all finite evaluated fragments of all views.
    pub error: f64,
    /// `error` with PCF's constant ε scaled by [`EPSILON_FACTORS`] (ε/3, 3ε): how much of the
    /// error depends on the reference's constant.
    pub error_scaled: [f64; 2],
    /// Mean max(0, PCF − G): the light-leaking part of `error` (the rest, mean
    /// max(0, G − PCF), is over-darkening).
    pub leak: f64,
    pub seconds: f64,
    /// Technique calls per second of shading time (throughput over real, non-trivial fragments
    /// when trivial ones are skipped).
    pub solves_per_second: f64,
    /// Evaluated fragments per second of total wall time.
    pub fragments_per_second: f64,
    pub views: Vec<ViewReport>,
}

/// Error of a technique against PCF over all fragments of all layers of `stacks`.
pub fn evaluate(
    stacks: &[DepthStack],
    technique: &dyn Technique,
    opts: &EvalOptions,
) -> Result<EvalReport> {
    evaluate_subject(stacks, Subject::Technique(technique), opts)
}

/// Per-view state of the shading loop.
struct ViewShader<'a> {
    subject: Subject<'a>,
    stack: &'a DepthStack,
    front: FrontMap,
    /// Moment maps (of the snapped front map for grid techniques).
    maps: Vec<Vec<f64>>,
    /// 9×9 min of the (snapped) front map.
    min_map: Vec<f64>,
    grid: Option<&'a Grid>,
    skip_trivial: bool,
    bias: Bias,
}

impl<'a> ViewShader<'a> {
    fn new(subject: Subject<'a>, stack: &'a DepthStack, opts: &EvalOptions) -> ViewShader<'a> {
        let (w, h) = (stack.meta.width, stack.meta.height);
        let kern = Gaussian::paper();
        let front = FrontMap::of(stack);
        let (grid, maps, min_map, skip) = match subject {
            Subject::Pcf | Subject::Cdf => (None, Vec::new(), Vec::new(), false),
            Subject::Technique(t) => {
                let grid = t.depth_grid();
                let snapped: Vec<f64> = match grid {
                    Some(g) => front.depth.iter().map(|&z| snap(g, z)).collect(),
                    None => front.depth.clone(),
                };
                let maps =
                    kernel::moment_maps_of(&snapped, w, h, t.moment_count(), &kern, |z, o| {
                        t.basis(z, o)
                    });
                let min_map = kernel::min_filter(&snapped, w, h, kern.radius());
                (
                    grid,
                    maps,
                    min_map,
                    opts.skip_trivial.unwrap_or(grid.is_some()),
                )
            }
        };
        ViewShader {
            subject,
            stack,
            front,
            maps,
            min_map,
            grid,
            skip_trivial: skip,
            bias: opts.bias,
        }
    }

    /// (G, trivial, solved) of one fragment.
    fn shade(
        &self,
        ev: &mut Option<Box<dyn Evaluator + 'a>>,
        buf: &mut [f64],
        f: &Fragment,
    ) -> (f64, bool, bool) {
        match self.subject {
            Subject::Pcf => {
                let g = pcf_of(self.stack, &self.front, f.texel, f.layer, &self.bias);
                (g, f.trivial, true)
            }
            Subject::Cdf => {
                let (w, h) = (self.stack.meta.width, self.stack.meta.height);
                let g = kernel::depth_distribution(
                    &self.front.depth,
                    w,
                    h,
                    f.texel % w,
                    f.texel / w,
                    &Gaussian::paper(),
                )
                .iter()
                .filter(|(z, _)| *z < f.zf)
                .map(|(_, wt)| wt)
                .sum();
                (g, f.trivial, true)
            }
            Subject::Technique(_) => {
                let zf = match self.grid {
                    Some(g) => snap(g, f.zf),
                    None => f.zf,
                };
                let trivial = self.min_map[f.texel] >= zf;
                if trivial && self.skip_trivial {
                    return (0.0, true, false);
                }
                for (j, map) in self.maps.iter().enumerate() {
                    buf[j] = map[f.texel];
                }
                let ev = ev.as_mut().expect("technique evaluator");
                (ev.shadow(buf, zf), trivial, true)
            }
        }
    }
}

#[derive(Default)]
struct Partial {
    sum: f64,
    sum_scaled: [f64; 2],
    leak: f64,
    trivial: usize,
    solved: usize,
    non_finite: usize,
    unsettled: usize,
    out_of_range: usize,
    values: Vec<FragmentValue>,
}

/// Error unless the stacks hold at least one fragment: an empty input has no error to
/// report (never a 0 % result).
pub fn require_fragments(stacks: &[DepthStack]) -> Result<()> {
    if stacks.iter().all(|s| s.fragment_count() == 0) {
        bail!(
            "the depth stacks hold 0 fragments ({} views, every texel empty); nothing to evaluate",
            stacks.len()
        );
    }
    Ok(())
}

/// [`evaluate`] for a technique or PCF itself.
pub fn evaluate_subject(
    stacks: &[DepthStack],
    subject: Subject<'_>,
    opts: &EvalOptions,
) -> Result<EvalReport> {
    let mut reports = evaluate_subjects(stacks, &[subject], opts)?;
    Ok(reports.remove(0))
}

/// [`evaluate_subject`] for several subjects on the same fragments: each view's fragments and
/// their PCF reference (most of the work for a closed form) are built once and shaded by every
/// subject in turn. One report per subject, in order; each report's `seconds` counts the
/// shared fragment building once.
pub fn evaluate_subjects(
    stacks: &[DepthStack],
    subjects: &[Subject<'_>],
    opts: &EvalOptions,
) -> Result<Vec<EvalReport>> {
    require_fragments(stacks)?;
    opts.bias.validate()?;
    opts.subsample.validate()?;
    for subject in subjects {
        if let Subject::Technique(t) = subject {
            if t.moment_count() == 0 {
                bail!("technique {}: no moments", t.name());
            }
        }
    }
    for s in stacks {
        check_stack(s)?;
    }
    let start = Instant::now();
    let picks: Vec<Vec<(usize, usize)>> = stacks
        .iter()
        .enumerate()
        .map(|(v, s)| select(s, v, &opts.subsample))
        .collect();
    let picked = start.elapsed().as_secs_f64();
    let planned: usize = picks.iter().map(|p| p.len()).sum::<usize>() * subjects.len();
    let done = AtomicUsize::new(0);
    let mut views: Vec<Vec<ViewReport>> = subjects.iter().map(|_| Vec::new()).collect();
    for (v, (stack, picked)) in stacks.iter().zip(&picks).enumerate() {
        let t0 = Instant::now();
        let frags = fragments_at(stack, v, &opts.bias, picked);
        let build = t0.elapsed().as_secs_f64();
        for (k, &subject) in subjects.iter().enumerate() {
            let progress = (&done, planned);
            views[k].push(shade_view(stack, &frags, subject, opts, progress, build));
        }
    }
    Ok(subjects
        .iter()
        .zip(views)
        .map(|(subject, views)| report_of(subject.name(), views, opts, picked))
        .collect())
}

/// One view's report for `subject` on its fragments `frags` (built in `build` seconds, counted
/// in the view's `seconds`); `progress` = (fragments shaded so far, planned in all).
fn shade_view(
    stack: &DepthStack,
    frags: &[Fragment],
    subject: Subject<'_>,
    opts: &EvalOptions,
    (done, planned): (&AtomicUsize, usize),
    build: f64,
) -> ViewReport {
    let t0 = Instant::now();
    let m = match subject {
        Subject::Technique(t) => t.moment_count(),
        Subject::Pcf | Subject::Cdf => 0,
    };
    let shader = ViewShader::new(subject, stack, opts);
    let t1 = Instant::now();
    let keep = opts.keep_values;
    let partials: Vec<Partial> = frags
        .par_chunks(512)
        .map_init(
            || subject.chunk_state(m),
            |(ev, buf), chunk| {
                cold(ev);
                let mut p = Partial::default();
                let unsettled0 = ev.as_ref().map_or(0, |e| e.unsettled());
                for f in chunk {
                    let (g, trivial, solved) = shader.shade(ev, buf, f);
                    p.trivial += trivial as usize;
                    p.solved += solved as usize;
                    if g.is_finite() {
                        p.sum += (g - f.pcf).abs();
                        p.sum_scaled[0] += (g - f.pcf_scaled[0]).abs();
                        p.sum_scaled[1] += (g - f.pcf_scaled[1]).abs();
                        p.leak += (f.pcf - g).max(0.0);
                        if !(-1e-9..=1.0 + 1e-9).contains(&g) {
                            p.out_of_range += 1;
                        }
                    } else {
                        p.non_finite += 1;
                    }
                    if keep {
                        p.values.push(FragmentValue {
                            texel: f.texel,
                            layer: f.layer,
                            pcf: f.pcf,
                            g,
                            trivial,
                        });
                    }
                }
                p.unsettled = ev.as_ref().map_or(0, |e| e.unsettled()) - unsettled0;
                let d = done.fetch_add(chunk.len(), Ordering::Relaxed) + chunk.len();
                if let Some(cb) = &opts.progress {
                    cb(d, planned);
                }
                p
            },
        )
        .collect();
    let shade_seconds = t1.elapsed().as_secs_f64();
    let mut total = Partial::default();
    let mut values = Vec::new();
    for p in partials {
        total.sum += p.sum;
        total.sum_scaled[0] += p.sum_scaled[0];
        total.sum_scaled[1] += p.sum_scaled[1];
        total.leak += p.leak;
        total.trivial += p.trivial;
        total.solved += p.solved;
        total.non_finite += p.non_finite;
        total.unsettled += p.unsettled;
        total.out_of_range += p.out_of_range;
        values.extend(p.values);
    }
    let finite = frags.len() - total.non_finite;
    let mean = |x: f64| finite_mean(x, finite, frags.len());
    ViewReport {
        sum_abs_error_scaled: total.sum_scaled,
        error_scaled: total.sum_scaled.map(mean),
        sum_leak: total.leak,
        leak: mean(total.leak),
        scene: stack.meta.scene.clone(),
        view: stack.meta.view.clone(),
        width: stack.meta.width,
        height: stack.meta.height,
        layers: stack.depth.len(),
        fragments_total: stack.fragment_count(),
        fragments: frags.len(),
        trivial: total.trivial,
        solved: total.solved,
        non_finite: total.non_finite,
        unsettled: total.unsettled,
        out_of_range: total.out_of_range,
        sum_abs_error: total.sum,
        error: mean(total.sum),
        seconds: build + t0.elapsed().as_secs_f64(),
        shade_seconds,
        values: keep.then_some(values),
    }
}

/// Mean of a sum over the `finite` of `fragments` fragments: 0 for no fragments, NaN when
/// every output was non-finite (no error is known, and none is reported as perfect).
fn finite_mean(sum: f64, finite: usize, fragments: usize) -> f64 {
    match (finite, fragments) {
        (_, 0) => 0.0,
        (0, _) => f64::NAN,
        _ => sum / finite as f64,
    }
}

/// The report over all `views` of one subject (`picked`: seconds spent choosing fragments).
fn report_of(
    technique: String,
    views: Vec<ViewReport>,
    opts: &EvalOptions,
    picked: f64,
) -> EvalReport {
    let seconds = picked + views.iter().map(|v| v.seconds).sum::<f64>();
    let sum = |f: fn(&ViewReport) -> usize| views.iter().map(f).sum::<usize>();
    let fragments = sum(|v| v.fragments);
    let non_finite = sum(|v| v.non_finite);
    let solved = sum(|v| v.solved);
    let sum_abs: f64 = views.iter().map(|v| v.sum_abs_error).sum();
    let sum_scaled: [f64; 2] =
        std::array::from_fn(|k| views.iter().map(|v| v.sum_abs_error_scaled[k]).sum());
    let sum_leak: f64 = views.iter().map(|v| v.sum_leak).sum();
    let finite = fragments - non_finite;
    let mean = |x: f64| finite_mean(x, finite, fragments);
    let shade: f64 = views.iter().map(|v| v.shade_seconds).sum();
    EvalReport {
        technique,
        bias: opts.bias,
        subsample: opts.subsample,
        fragments_total: sum(|v| v.fragments_total),
        fragments,
        trivial: sum(|v| v.trivial),
        solved,
        non_finite,
        unsettled: sum(|v| v.unsettled),
        out_of_range: sum(|v| v.out_of_range),
        error: mean(sum_abs),
        error_scaled: sum_scaled.map(mean),
        leak: mean(sum_leak),
        seconds,
        solves_per_second: if shade > 0.0 {
            solved as f64 / shade
        } else {
            0.0
        },
        fragments_per_second: if seconds > 0.0 {
            fragments as f64 / seconds
        } else {
            0.0
        },
        views,
    }
}

/// Front-layer shadow maps of one view for pictures: per texel the PCF and the subject's G of
/// the front-layer fragment (NaN where the texel has no surface).
pub struct FrontShadows {
    pub pcf: Vec<f64>,
    pub g: Vec<f64>,
}

/// PCF and G of every front-layer fragment of `stack` (full resolution, no subsampling).
pub fn front_shadows(
    stack: &DepthStack,
    subject: Subject<'_>,
    bias: &Bias,
) -> Result<FrontShadows> {
    layer_shadows(stack, 0, subject, bias)
}

/// PCF and G of every fragment of layer `layer` (the layer+1-th surface along each texel's
/// ray; NaN where a texel has fewer surfaces): where the shadows cast onto that layer fall.
pub fn layer_shadows(
    stack: &DepthStack,
    layer: usize,
    subject: Subject<'_>,
    bias: &Bias,
) -> Result<FrontShadows> {
    check_stack(stack)?;
    bias.validate()?;
    let n = stack.texel_count();
    let picked: Vec<(usize, usize)> = match stack.depth.get(layer) {
        Some(l) => (0..n)
            .filter(|&t| l[t].is_finite())
            .map(|t| (layer, t))
            .collect(),
        None => Vec::new(),
    };
    let opts = EvalOptions {
        bias: *bias,
        ..Default::default()
    };
    let frags = fragments_at(stack, 0, bias, &picked);
    let shader = ViewShader::new(subject, stack, &opts);
    let m = shader.maps.len();
    let gs: Vec<f64> = frags
        .par_chunks(512)
        .map_init(
            || subject.chunk_state(m),
            |(ev, buf), chunk| {
                cold(ev);
                chunk
                    .iter()
                    .map(|f| shader.shade(ev, buf, f).0)
                    .collect::<Vec<f64>>()
            },
        )
        .flatten()
        .collect();
    let mut out = FrontShadows {
        pcf: vec![f64::NAN; n],
        g: vec![f64::NAN; n],
    };
    for (f, g) in frags.iter().zip(gs) {
        out.pcf[f.texel] = f.pcf;
        out.g[f.texel] = g;
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// No fragments: 0; every output non-finite: NaN (never a perfect score); else the mean
    /// over the finite ones.
    #[test]
    fn means_over_finite_outputs() {
        assert_eq!(finite_mean(0.0, 0, 0), 0.0);
        assert!(finite_mean(0.0, 0, 5).is_nan());
        assert_eq!(finite_mean(3.0, 4, 6), 0.75);
    }

    #[test]
    fn biases_beyond_the_depth_range_are_refused() {
        let ok = Bias::default();
        assert!(ok.validate().is_ok());
        for bad in [
            Bias {
                technique_epsilon: 1e300,
                ..ok
            },
            Bias {
                pcf_epsilon: 1.5,
                ..ok
            },
            Bias {
                slope_scale: f64::INFINITY,
                ..ok
            },
            Bias {
                technique_slope_scale: 1e4,
                ..ok
            },
            Bias {
                pcf_epsilon: -1e-9,
                ..ok
            },
        ] {
            let e = bad.validate().unwrap_err().to_string();
            assert!(
                e.starts_with("bias: ") && e.contains("must be in [0, "),
                "{e}"
            );
        }
    }
}
