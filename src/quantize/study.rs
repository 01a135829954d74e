//! The quantized moment-shadow-map study (Peters & Klein 2015, Section 4.3): store θ(b(z)) per
//! texel at a given bit depth (rounded to nearest like a GPU UNORM or float format), filter the
//! stored maps with the 9×9 Gaussian, decode with θ⁻¹, reconstruct with bias α
//! (b' = (1−α)·b + α·b*, b* = (½, …, ½)) and measure the mean |G − PCF| over all fragments.
//! The stored maps go through the pipeline a GPU runs ([`super::pipeline`]): each texel's
//! θ(b(z)) (computed in f64, rounded to f32) is stored in the format, the two separable filter
//! passes accumulate in f32 and store their outputs in the format, and θ⁻¹ decodes the filtered
//! texel. The reconstruction runs in f64, so the deviation from exact moments is what storage and
//! f32 filtering add. Noise is measured as in `tune`: the share of fragments whose shadow is more
//! than [`DISPLAY_STEP`] from the same technique on exact moments.

use super::pipeline::{self, HalfRounding, DISPLAY_STEP, MAX_NOISE};
use super::theta::{published, Theta};
use crate::kernel::{filter_separable, front_map, Gaussian};
use crate::metrics::{fragments_subsampled, Bias, Fragment, Subsample};
use crate::shader::Order;
use crate::stack::DepthStack;
use crate::technique::hamburger::Hamburger;
use crate::technique::hamburger4::Hamburger4;
use crate::technique::hamburger6::Hamburger6;
use crate::technique::linalg::Precision;
use crate::technique::vsm::Vsm;
use crate::technique::ClosedForm;
use anyhow::Result;
use rayon::prelude::*;
use serde::Serialize;

pub use super::pipeline::Storage;

/// A reconstruction technique of the study with its m (power basis z, …, z^m).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub enum Tech {
    /// VSM (m = 2, Cantelli), θ₂.
    Vsm,
    /// Hamburger 4MSM (Algorithm 3), θ₄.
    Msm4,
    /// Hamburger 6MSM, θ₆.
    Msm6,
    /// Hamburger MSM with 8 power moments (Algorithm 2, general even m), θ₈.
    Msm8,
}

impl Tech {
    /// Every technique of the study.
    pub const ALL: [Tech; 4] = [Tech::Vsm, Tech::Msm4, Tech::Msm6, Tech::Msm8];

    /// Parse a technique name ("vsm", "hamburger4", "hamburger6", "hamburger8"; the older
    /// "4msm", "6msm", "8msm" too).
    pub fn parse(name: &str) -> Option<Tech> {
        let name = crate::technique::registry::canonical_name(name);
        Tech::ALL.into_iter().find(|t| t.name() == name)
    }

    /// Moment count m.
    pub fn m(self) -> usize {
        match self {
            Tech::Vsm => 2,
            Tech::Msm4 => 4,
            Tech::Msm6 => 6,
            Tech::Msm8 => 8,
        }
    }
    /// The registry name ("vsm", "hamburger4", …).
    pub fn name(self) -> &'static str {
        match self {
            Tech::Vsm => "vsm",
            Tech::Msm4 => "hamburger4",
            Tech::Msm6 => "hamburger6",
            Tech::Msm8 => "hamburger8",
        }
    }
    /// G(b, z_f) with bias α towards b* = (½, …, ½), double precision arithmetic.
    pub fn shadower(self, alpha: f64) -> Box<dyn ClosedForm + Send + Sync> {
        match self {
            Tech::Vsm => Box::new(Vsm {
                alpha,
                b_star: [0.5; 2],
                min_variance: 0.0,
                precision: Precision::F64,
            }),
            Tech::Msm4 => Box::new(Hamburger4::new(alpha, [0.5; 4], Precision::F64)),
            Tech::Msm6 => Box::new(Hamburger6::new(alpha, [0.5; 6], Precision::F64)),
            Tech::Msm8 => Box::new(Hamburger::new(alpha, vec![0.5; 8], Precision::F64)),
        }
    }
}

/// Filtered, decoded moment maps of a front-depth map: per texel θ(b(z0)) (f64, rounded to
/// f32) stored in `storage`, the two separable passes of `kernel` in f32 each stored in
/// `storage` ([`pipeline::filter_map`], taps unfused), θ⁻¹ of the filtered texel in f64.
/// `Storage::Exact` is the reference: the same filter in f64 without any rounding.
/// Result: texel t's m moments at `[t]`.
pub fn decoded_moments(
    front: &[f64],
    width: usize,
    height: usize,
    theta: &Theta,
    storage: Storage,
    kernel: &Gaussian,
) -> Decoded {
    let m = theta.m();
    let mut b = vec![0.0; m];
    let mut s = vec![0.0; m];
    let mut values = vec![0.0; front.len() * m];
    if storage == Storage::Exact {
        let mut stored = vec![vec![0.0; front.len()]; m];
        for (t, &z) in front.iter().enumerate() {
            crate::technique::hamburger4::power_basis(z, &mut b);
            theta.encode(&b, &mut s);
            for j in 0..m {
                stored[j][t] = s[j];
            }
        }
        let filtered: Vec<Vec<f64>> = stored
            .iter()
            .map(|c| filter_separable(c, width, height, kernel.weights_1d()))
            .collect();
        for (t, out) in values.chunks_mut(m).enumerate() {
            for (sj, c) in s.iter_mut().zip(&filtered) {
                *sj = c[t];
            }
            theta.decode(&s, out);
        }
        return Decoded { m, values };
    }
    let st = (storage, HalfRounding::NearestEven);
    let mut texels = vec![0.0f32; front.len() * m];
    for (t, &z) in front.iter().enumerate() {
        crate::technique::hamburger4::power_basis(z, &mut b);
        theta.encode(&b, &mut s);
        for j in 0..m {
            texels[t * m + j] = pipeline::store(st.0, st.1, s[j] as f32);
        }
    }
    let w = pipeline::weights_f32(kernel);
    let dims = (width, height, m);
    let v = pipeline::filter_map(&texels, dims, &w, Order::Unfused, st);
    for (c, out) in v.chunks(m).zip(values.chunks_mut(m)) {
        for (sj, &x) in s.iter_mut().zip(c) {
            *sj = x as f64;
        }
        theta.decode(&s, out);
    }
    Decoded { m, values }
}

/// Decoded moment maps ([`decoded_moments`]): m values per texel, texel-major.
#[derive(Clone, Debug, PartialEq)]
pub struct Decoded {
    m: usize,
    values: Vec<f64>,
}

impl Decoded {
    /// Texels.
    pub fn len(&self) -> usize {
        self.values.len() / self.m.max(1)
    }
    /// Whether there is no texel.
    pub fn is_empty(&self) -> bool {
        self.values.is_empty()
    }
    /// Every texel's moments, in texel order.
    pub fn iter(&self) -> std::slice::Chunks<'_, f64> {
        self.values.chunks(self.m.max(1))
    }
}

impl<'a> IntoIterator for &'a Decoded {
    type Item = &'a [f64];
    type IntoIter = std::slice::Chunks<'a, f64>;
    fn into_iter(self) -> Self::IntoIter {
        self.iter()
    }
}

impl std::ops::Index<usize> for Decoded {
    type Output = [f64];
    /// Texel t's moments.
    fn index(&self, t: usize) -> &[f64] {
        &self.values[t * self.m..(t + 1) * self.m]
    }
}

/// θ = identity (canonical storage of b itself).
pub fn identity_theta(m: usize) -> Theta {
    let names = (1..=m).map(|e| format!("z^{e}")).collect();
    let id = (0..m)
        .map(|i| (0..m).map(|j| if i == j { 1.0 } else { 0.0 }).collect())
        .collect();
    Theta::new(names, id, vec![0.0; m]).expect("identity is regular")
}

/// One storage configuration of the study.
#[derive(Clone, Debug)]
pub struct Config {
    /// Label in tables and plots.
    pub name: String,
    /// The transform θ applied before storage.
    pub theta: Theta,
    /// The per-channel storage format.
    pub storage: Storage,
}

/// Error against α for one technique and configuration.
#[derive(Clone, Debug, Serialize, serde::Deserialize)]
pub struct Sweep {
    /// Technique name.
    pub technique: String,
    /// Configuration label.
    pub config: String,
    /// The α values swept.
    pub alphas: Vec<f64>,
    /// Mean |G − PCF| over all evaluated fragments, per α.
    pub errors: Vec<f64>,
    /// Mean |G − G_exact| per α: deviation from the same technique and α on unquantized
    /// (f64) moments, i.e. the error caused by storage alone (non-finite counted as 1).
    pub deviation: Vec<f64>,
    /// Fragments with non-finite G per α (counted as error 1).
    pub non_finite: Vec<usize>,
    /// Share of fragments per α with |G − G_exact| > [`DISPLAY_STEP`] (non-finite included):
    /// the noise measure of `tune`.
    #[serde(default)]
    pub noise_share: Vec<f64>,
    /// The α with the smallest mean error.
    pub best_alpha: f64,
    /// The mean error at `best_alpha`.
    pub best_error: f64,
    /// Evaluated fragments.
    pub fragments: usize,
}

/// Run the sweep over all stacks: for every config, the error of `tech` for every α.
pub fn sweep(
    stacks: &[DepthStack],
    tech: Tech,
    configs: &[Config],
    alphas: &[f64],
    bias: &Bias,
    sub: &Subsample,
) -> Result<Vec<Sweep>> {
    let frags = sweep_fragments(stacks, bias, sub)?;
    sweep_on(stacks, &frags, tech, configs, alphas)
}

/// The fragments (with their PCF reference) a sweep of `stacks` evaluates, one list per view:
/// every technique's sweep of the same stacks reads the same ones ([`sweep_on`]).
pub fn sweep_fragments(
    stacks: &[DepthStack],
    bias: &Bias,
    sub: &Subsample,
) -> Result<Vec<Vec<Fragment>>> {
    crate::metrics::require_fragments(stacks)?;
    for s in stacks {
        crate::metrics::check_stack(s)?;
    }
    Ok(stacks
        .par_iter()
        .enumerate()
        .map(|(v, s)| fragments_subsampled(s, v, bias, sub))
        .collect())
}

/// [`sweep`] on the fragments `frags` of `stacks` ([`sweep_fragments`]).
pub fn sweep_on(
    stacks: &[DepthStack],
    frags: &[Vec<Fragment>],
    tech: Tech,
    configs: &[Config],
    alphas: &[f64],
) -> Result<Vec<Sweep>> {
    if frags.len() != stacks.len() {
        anyhow::bail!(
            "quantize: fragment lists for {} views, but {} stacks",
            frags.len(),
            stacks.len()
        );
    }
    let kernel = Gaussian::paper();
    let n_frag: usize = frags.iter().map(|f| f.len()).sum();
    // acc[a][c]: (Σ |G − PCF|, non-finite, Σ |G − G_exact|, noisy) of config c at alpha a,
    // summed view by view, fragment by fragment.
    let mut acc = vec![vec![(0.0, 0usize, 0.0, 0usize); configs.len()]; alphas.len()];
    for (stack, fr) in stacks.iter().zip(frags) {
        // One view at a time: its unquantized moments and every config's decoded ones.
        let (w, h) = (stack.meta.width, stack.meta.height);
        let front = front_map(stack);
        let id = identity_theta(tech.m());
        let exact = decoded_moments(&front, w, h, &id, Storage::Exact, &kernel);
        let maps: Vec<Decoded> = configs
            .par_iter()
            .map(|cfg| decoded_moments(&front, w, h, &cfg.theta, cfg.storage, &kernel))
            .collect();
        alphas
            .par_iter()
            .zip(acc.par_iter_mut())
            .for_each(|(&a, acc)| {
                let sh = tech.shadower(a);
                for f in fr {
                    // G on unquantized moments: the same for every config.
                    let ge = sh.shadow(&exact[f.texel], f.zf);
                    for (mp, (sum, bad, dev, noisy)) in maps.iter().zip(acc.iter_mut()) {
                        let g = sh.shadow(&mp[f.texel], f.zf);
                        let d = if g.is_finite() && ge.is_finite() {
                            (g - ge).abs()
                        } else {
                            1.0
                        };
                        *noisy += (d > DISPLAY_STEP) as usize;
                        if g.is_finite() {
                            *sum += (g - f.pcf).abs();
                            *dev += d;
                        } else {
                            *sum += 1.0;
                            *dev += 1.0;
                            *bad += 1;
                        }
                    }
                }
            });
    }
    let n = n_frag.max(1) as f64;
    let mut out = Vec::new();
    for (c, cfg) in configs.iter().enumerate() {
        let per_alpha: Vec<(f64, usize, f64, f64)> = acc
            .iter()
            .map(|a| {
                let (sum, bad, dev, noisy) = a[c];
                (sum / n, bad, dev / n, noisy as f64 / n)
            })
            .collect();
        let errors: Vec<f64> = per_alpha.iter().map(|p| p.0).collect();
        let k = (0..errors.len())
            .min_by(|&i, &j| errors[i].total_cmp(&errors[j]))
            .unwrap_or(0);
        out.push(Sweep {
            technique: tech.name().into(),
            config: cfg.name.clone(),
            alphas: alphas.to_vec(),
            best_alpha: alphas.get(k).copied().unwrap_or(f64::NAN),
            best_error: errors.get(k).copied().unwrap_or(f64::NAN),
            errors,
            non_finite: per_alpha.iter().map(|p| p.1).collect(),
            deviation: per_alpha.iter().map(|p| p.2).collect(),
            noise_share: per_alpha.iter().map(|p| p.3).collect(),
            fragments: n_frag,
        });
    }
    Ok(out)
}

/// The bias strengths α of the study.
pub const DEFAULT_ALPHAS: [f64; 13] = [
    1e-8, 3e-8, 1e-7, 3e-7, 1e-6, 3e-6, 1e-5, 3e-5, 1e-4, 3e-4, 1e-3, 3e-3, 1e-2,
];

/// The storage configurations of the study for `tech`: canonical 8/16-bit, 32-bit float, and
/// 8/16-bit with our θ and with the published θ (where one exists).
pub fn configs(tech: Tech, ours: &Theta) -> Vec<Config> {
    let m = tech.m();
    let mut configs = vec![
        Config {
            name: "canonical 8-bit".into(),
            theta: identity_theta(m),
            storage: Storage::Unorm(8),
        },
        Config {
            name: "canonical 16-bit".into(),
            theta: identity_theta(m),
            storage: Storage::Unorm(16),
        },
        Config {
            name: "32-bit float".into(),
            theta: identity_theta(m),
            storage: Storage::Float32,
        },
    ];
    for (label, th) in [("ours", Some(ours.clone())), ("published", published(m))] {
        if let Some(th) = th {
            for bits in [8, 16] {
                configs.push(Config {
                    name: format!("optimized {bits}-bit ({label} θ{m})"),
                    theta: th.clone(),
                    storage: Storage::Unorm(bits),
                });
            }
        }
    }
    configs
}

/// For every 16-bit configuration: the smallest α at which it meets `tune`'s noise bound: the
/// shadow is more than 1/255 from unquantized moments on at most [`MAX_NOISE`] of fragments.
pub fn usability(all: &[Sweep]) -> Vec<serde_json::Value> {
    let mut out = Vec::new();
    for s in all.iter().filter(|s| s.config.contains("16-bit")) {
        let Some(f32s) = all
            .iter()
            .find(|f| f.technique == s.technique && f.config == "32-bit float")
        else {
            continue;
        };
        let k =
            (0..s.alphas.len()).find(|&i| s.noise_share.get(i).is_some_and(|&x| x <= MAX_NOISE));
        out.push(serde_json::json!({
            "technique": s.technique, "config": s.config,
            "smallest_usable_alpha": k.map(|i| s.alphas[i]),
            "noise_share_there": k.map(|i| s.noise_share[i]),
            "deviation_there": k.map(|i| s.deviation[i]),
            "error_there": k.map(|i| s.errors[i]),
            "f32_error_there": k.map(|i| f32s.errors[i]),
        }));
    }
    out
}

/// A one-α sweep of `technique` with storage `config` (test fixture).
#[cfg(test)]
pub(crate) fn sample_sweep(technique: &str, config: &str) -> Sweep {
    Sweep {
        technique: technique.into(),
        config: config.into(),
        alphas: vec![1e-3],
        errors: vec![0.02],
        deviation: vec![0.0],
        noise_share: vec![0.0],
        non_finite: vec![0],
        best_alpha: 1e-3,
        best_error: 0.02,
        fragments: 10,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::quantize::theta::published_theta4;

    #[test]
    fn storage_rounds_like_a_texture() {
        assert_eq!(Storage::Unorm(8).store(0.5), 128.0 / 255.0);
        assert_eq!(Storage::Unorm(16).store(-0.1), 0.0);
        assert_eq!(Storage::Unorm(16).store(1.3), 1.0);
        let v = 0.123456789123;
        assert!((Storage::Float32.store(v) - v).abs() < 1e-8);
        assert!((Storage::Unorm(16).store(v) - v).abs() <= 0.5 / 65535.0 + 1e-15);
        // binary16: 11 significant bits, largest finite 65504, then infinity
        assert_eq!(Storage::Half.store(1.0 + 2f64.powi(-11)), 1.0); // tie to even
        assert_eq!(
            Storage::Half.store(1.0 + 3.0 * 2f64.powi(-11)),
            1.0 + 2f64.powi(-9)
        );
        assert_eq!(Storage::Half.store(65504.0), 65504.0);
        assert_eq!(Storage::Half.store(70000.0), f64::INFINITY);
        assert!((Storage::Half.store(v) - v).abs() <= v * 2f64.powi(-11));
    }

    #[test]
    fn a_window_decodes_like_the_filtered_maps() {
        // decoded_moments (whole-map passes) and tune's per-window model
        // (pipeline::filtered_window over the clamped 9×9 window of stored texels) agree bit
        // for bit, for every storage of the study
        let (w, h) = (16, 13);
        let front: Vec<f64> = (0..w * h)
            .map(|i| ((i * 7919) % 101) as f64 / 101.0)
            .collect();
        let k = Gaussian::paper();
        let th = published_theta4();
        let wf = pipeline::weights_f32(&k);
        let r = k.radius() as i64;
        for storage in [Storage::Unorm(8), Storage::Unorm(16), Storage::Float32] {
            let maps = decoded_moments(&front, w, h, &th, storage, &k);
            let texel = |t: usize| {
                let (mut b, mut s) = ([0.0; 4], [0.0; 4]);
                crate::technique::hamburger4::power_basis(front[t], &mut b);
                th.encode(&b, &mut s);
                s.map(|v| pipeline::store(storage, HalfRounding::NearestEven, v as f32))
            };
            for (x, y) in [(0usize, 0usize), (7, 6), (15, 12), (3, 11)] {
                let mut window = Vec::new();
                for dy in -r..=r {
                    for dx in -r..=r {
                        let xx = crate::kernel::clamp_coord(x, dx, w);
                        let yy = crate::kernel::clamp_coord(y, dy, h);
                        window.extend(texel(yy * w + xx));
                    }
                }
                let mut f = [0.0f32; 4];
                pipeline::filtered_window(
                    &window,
                    (4, &wf),
                    Order::Unfused,
                    (storage, HalfRounding::NearestEven),
                    &mut f,
                );
                let mut out = [0.0; 4];
                th.decode(&f.map(|v| v as f64), &mut out);
                assert_eq!(out.to_vec(), maps[y * w + x], "{storage:?} texel ({x},{y})");
            }
        }
    }

    #[test]
    fn decoded_maps_match_filtered_moments_at_f32() {
        // constant-free check: filter(θ(b)) decoded = filter(b) by linearity, up to f32 storage
        let (w, h) = (12, 9);
        let front: Vec<f64> = (0..w * h)
            .map(|i| ((i * 7919) % 97) as f64 / 97.0)
            .collect();
        let k = Gaussian::paper();
        let th = published_theta4();
        let dec = decoded_moments(&front, w, h, &th, Storage::Float32, &k);
        let raw = decoded_moments(&front, w, h, &identity_theta(4), Storage::Float32, &k);
        for (a, b) in dec.iter().zip(&raw) {
            for (p, q) in a.iter().zip(b) {
                assert!((p - q).abs() < 1e-6, "{p} {q}");
            }
        }
        // canonical 16-bit: the texels, the first pass and the second pass are each rounded to
        // the nearest step (filtering averages the earlier roundings), so the error stays within
        // three half quanta and exceeds one half quantum (the passes' stores are modelled)
        let exact = decoded_moments(&front, w, h, &identity_theta(4), Storage::Float32, &k);
        let err = |d: &Decoded| {
            d.iter()
                .zip(&exact)
                .flat_map(|(a, b)| a.iter().zip(b).map(|(p, q)| (p - q).abs()))
                .fold(0.0f64, f64::max)
        };
        let canon = decoded_moments(&front, w, h, &identity_theta(4), Storage::Unorm(16), &k);
        let e = err(&canon);
        assert!(e <= 1.5 / 65535.0 + 1e-7, "{e}");
        assert!(e > 0.5 / 65535.0, "{e}");
    }
}
