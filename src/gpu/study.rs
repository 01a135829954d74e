//! The settings and receivers `gpu check` and `gpu bench` run: every technique × storage of
//! `tune`'s space with one representative α and own parameter, on a depth stack's fragments.

use super::check::{check, Verdict};
use super::pipeline::{Program, Receivers};
use super::Gpu;
use crate::kernel::Gaussian;
use crate::metrics::technique_depth;
use crate::quantize::pipeline as stored;
use crate::stack::DepthStack;
use crate::tune::export;
use crate::tune::space::{DepthBias, Family, Setting, TechniqueKind};
use anyhow::{bail, Result};

/// The evaluation default depth bias (ε = 10⁻⁴, s = 2).
pub const DEPTH_BIAS: DepthBias = DepthBias {
    constant: 1e-4,
    slope_scale: 2.0,
};

/// Every technique × storage of `tune`'s space: the first own parameter set, the middle α of
/// the technique's grid, the evaluation default depth bias.
pub fn settings() -> Vec<Setting> {
    let mut out = Vec::new();
    for t in TechniqueKind::ALL {
        let alphas = t.alphas();
        for &st in t.storages() {
            let own = t.own_params(st)[0];
            out.push(Setting {
                family: Family {
                    technique: t,
                    storage: st,
                    own,
                },
                alpha: alphas[alphas.len() / 2],
                depth_bias: DEPTH_BIAS,
            });
        }
    }
    out
}

/// The receivers of a stack under a depth bias: every fragment (layer-major, texel order), or
/// every k-th of them so that at most `max` remain; z_f = z − ε′ rounded to f32.
pub fn receivers(stack: &DepthStack, bias: DepthBias, max: usize) -> Receivers {
    let b = crate::metrics::Bias {
        technique_epsilon: bias.constant,
        technique_slope_scale: bias.slope_scale,
        ..crate::metrics::Bias::default()
    };
    let all = crate::metrics::fragment_positions(stack);
    let k = all.len().div_ceil(max.max(1)).max(1);
    let mut r = Receivers::default();
    for &(layer, texel) in all.iter().step_by(k) {
        r.texel.push(texel as u32);
        r.zf.push(technique_depth(stack, layer, texel, &b) as f32);
    }
    r
}

/// The front-layer depth map of a stack in f32 (background 1).
pub fn depth_map(stack: &DepthStack) -> Vec<f32> {
    (0..stack.texel_count()).map(|t| stack.front(t)).collect()
}

/// Check one setting on one stack (at most `max` receivers); `wgsl` is the shipped shader text
/// to run instead of the setting's own printing (an export's `shadow.wgsl`).
pub fn check_setting(
    gpu: &Gpu,
    s: &Setting,
    wgsl: Option<&str>,
    stack: &DepthStack,
    max: usize,
) -> Result<Verdict> {
    let Some(module) = export::module(s, export::header(s))? else {
        bail!("{}: no shader reconstruction to check", s.label());
    };
    let weights = stored::weights_f32(&Gaussian::paper());
    let program = Program {
        module: &module,
        wgsl,
        storage: s.family.storage.storage(),
        weights: &weights,
    };
    let size = (stack.meta.width, stack.meta.height);
    let label = format!("{} on {}", s.label(), stack.file_stem());
    check(
        gpu,
        &label,
        &program,
        &depth_map(stack),
        size,
        &receivers(stack, s.depth_bias, max),
    )
}
