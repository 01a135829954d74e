//! The fragments `tune` scores on: per scene a seeded uniform sample of fragments (all layers of
//! all its views) with their PCF reference (the evaluation's receiver-plane test, [`Bias`]
//! defaults), the unbiased depth z, the slope sum |dz/du| + |dz/dv| (for the technique depth
//! bias) and the 9×9 filter window of front depths a shadow map filters over.

use crate::kernel::{self, Gaussian};
use crate::metrics::{check_stack, fragments_subsampled, Bias, Subsample};
use crate::stack::DepthStack;
use anyhow::{bail, Result};

/// A fragment sample (struct of arrays; fragment i of every field).
#[derive(Clone, Debug, Default)]
pub struct Sample {
    /// Scene names, in order of first appearance in the stacks.
    pub scenes: Vec<String>,
    /// Scene index of each fragment.
    pub scene: Vec<usize>,
    /// Depth z of the fragment (no bias).
    pub z: Vec<f64>,
    /// |dz/du| + |dz/dv| of the fragment.
    pub slope: Vec<f64>,
    /// PCF reference.
    pub pcf: Vec<f64>,
    /// Front depths of the filter window, `taps` per fragment (tap order of `weights`).
    pub window: Vec<f32>,
    /// Kernel weights of the taps (the paper's 9×9 Gaussian, σ = 2.4).
    pub weights: Vec<f64>,
}

impl Sample {
    /// Number of fragments.
    pub fn len(&self) -> usize {
        self.z.len()
    }
    /// True when the sample has no fragments.
    pub fn is_empty(&self) -> bool {
        self.z.is_empty()
    }
    /// The window of fragment i as (depth, weight).
    pub fn window_of(&self, i: usize) -> impl Iterator<Item = (f64, f64)> + '_ {
        let n = self.weights.len();
        self.window[i * n..(i + 1) * n]
            .iter()
            .zip(&self.weights)
            .map(|(&z, &w)| (z as f64, w))
    }
    /// Fragment indices of scene `s`.
    pub fn of_scene(&self, s: usize) -> Vec<usize> {
        (0..self.len()).filter(|&i| self.scene[i] == s).collect()
    }
}

/// The scene names of `stacks`, each once, in the order of their first stack: the scenes of a
/// [`Sample`] and of a tuning's targets.
pub fn scene_names(stacks: &[DepthStack]) -> Vec<String> {
    let mut names: Vec<String> = Vec::new();
    for s in stacks {
        if !names.contains(&s.meta.scene) {
            names.push(s.meta.scene.clone());
        }
    }
    names
}

/// About `per_scene` fragments of every scene (fewer when a scene has fewer), drawn with
/// `seed` from all layers of all its views; `done(views)` is called after each view.
pub fn draw(
    stacks: &[DepthStack],
    per_scene: usize,
    seed: u64,
    done: &dyn Fn(usize),
) -> Result<Sample> {
    if per_scene == 0 {
        bail!("fragments per scene must be ≥ 1");
    }
    crate::metrics::require_fragments(stacks)?;
    for s in stacks {
        check_stack(s)?;
    }
    let mut out = Sample {
        weights: Gaussian::paper().taps().iter().map(|t| t.2).collect(),
        ..Default::default()
    };
    out.scenes = scene_names(stacks);
    let taps = Gaussian::paper().taps();
    let bias = Bias {
        technique_epsilon: 0.0,
        technique_slope_scale: 0.0,
        ..Bias::default()
    };
    let mut views = 0;
    for (si, name) in out.scenes.clone().iter().enumerate() {
        let of: Vec<(usize, &DepthStack)> = stacks
            .iter()
            .enumerate()
            .filter(|(_, s)| &s.meta.scene == name)
            .collect();
        let total: usize = of.iter().map(|(_, s)| s.fragment_count()).sum();
        if total == 0 {
            continue;
        }
        let fraction = (per_scene as f64 / total as f64 * 1.05).min(1.0);
        let mut picked: Vec<(usize, crate::metrics::Fragment)> = Vec::new();
        for &(v, s) in &of {
            let sub = Subsample::Random { fraction, seed };
            for f in fragments_subsampled(s, v, &bias, &sub) {
                picked.push((v, f));
            }
            views += 1;
            done(views);
        }
        // Spread the cut over all views: every k-th when more than asked were drawn.
        let keep: Vec<usize> = if picked.len() > per_scene {
            (0..per_scene)
                .map(|i| i * picked.len() / per_scene)
                .collect()
        } else {
            (0..picked.len()).collect()
        };
        let mut fronts: Vec<Option<Vec<f64>>> = vec![None; stacks.len()];
        for k in keep {
            let (v, f) = picked[k];
            let s = &stacks[v];
            let front = fronts[v].get_or_insert_with(|| kernel::front_map(s));
            let (w, h) = (s.meta.width, s.meta.height);
            let (x, y) = (f.texel % w, f.texel / w);
            for &(dx, dy, _) in &taps {
                let t = kernel::clamp_coord(y, dy, h) * w + kernel::clamp_coord(x, dx, w);
                out.window.push(front[t] as f32);
            }
            let slope = |v: f32| if v.is_finite() { v.abs() as f64 } else { 0.0 };
            out.scene.push(si);
            out.z.push(f.zf);
            out.slope
                .push(slope(s.dzdu[f.layer][f.texel]) + slope(s.dzdv[f.layer][f.texel]));
            out.pcf.push(f.pcf);
        }
    }
    if out.is_empty() {
        bail!("the depth stacks hold no fragment to sample");
    }
    Ok(out)
}
