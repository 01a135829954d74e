//! The quantized moment-shadow-map study (Peters & Klein 2015, Section 4.3): store θ(b(z)) per
//! texel at a given bit depth (rounded to nearest like a GPU UNORM or float format), filter the
//! stored maps with the 9×9 Gaussian, decode with θ⁻¹, reconstruct with bias α
//! (b' = (1−α)·b + α·b*, b* = (½, …, ½)) and measure the mean |G − PCF| over all fragments.
//! Quantization happens per texel BEFORE filtering, as in a real shadow map.

use super::theta::{published, Theta};
use crate::kernel::{filter_separable, front_map, Gaussian};
use crate::metrics::{fragments_subsampled, Bias, Subsample};
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

/// One texel as a texture of `storage` holds it: s = θ(b) rounded channel by channel.
pub fn store_texel(theta: &Theta, storage: Storage, b: &[f64], out: &mut [f64]) {
    theta.encode(b, out);
    for v in out.iter_mut() {
        *v = storage.store(*v);
    }
}

/// The decoded filtered moments of one filter window Σ w_l·δ(z_l): every texel stores
/// θ(b(z_l)) in `storage` ([`store_texel`]), the filter sums the stored values with the weights,
/// θ⁻¹ decodes the sum. `basis(z, out)` is b(z) (any basis with m = θ's size).
pub fn decoded_window(
    window: impl IntoIterator<Item = (f64, f64)>,
    basis: &dyn Fn(f64, &mut [f64]),
    theta: &Theta,
    storage: Storage,
    out: &mut [f64],
) {
    let m = theta.m();
    let (mut b, mut s, mut sum) = (vec![0.0; m], vec![0.0; m], vec![0.0; m]);
    for (z, w) in window {
        basis(z, &mut b);
        store_texel(theta, storage, &b, &mut s);
        for (a, v) in sum.iter_mut().zip(&s) {
            *a += w * v;
        }
    }
    theta.decode(&sum, out);
}

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

/// Filtered, decoded moment maps of a front-depth map: per texel store θ(b(z0)) in `storage`,
/// filter each stored channel with `kernel`, decode with θ⁻¹. Result: `[t][j]`.
pub fn decoded_moments(
    front: &[f64],
    width: usize,
    height: usize,
    theta: &Theta,
    storage: Storage,
    kernel: &Gaussian,
) -> Vec<Vec<f64>> {
    let m = theta.m();
    let mut stored = vec![vec![0.0; front.len()]; m];
    let mut b = vec![0.0; m];
    let mut s = vec![0.0; m];
    for (t, &z) in front.iter().enumerate() {
        crate::technique::hamburger4::power_basis(z, &mut b);
        store_texel(theta, storage, &b, &mut s);
        for j in 0..m {
            stored[j][t] = storage.store(s[j]);
        }
    }
    let filtered: Vec<Vec<f64>> = stored
        .iter()
        .map(|c| filter_separable(c, width, height, kernel.weights_1d()))
        .collect();
    (0..front.len())
        .map(|t| {
            let sv: Vec<f64> = filtered.iter().map(|c| c[t]).collect();
            let mut out = vec![0.0; m];
            theta.decode(&sv, &mut out);
            out
        })
        .collect()
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
    crate::metrics::require_fragments(stacks)?;
    for s in stacks {
        crate::metrics::check_stack(s)?;
    }
    let kernel = Gaussian::paper();
    let frags: Vec<_> = stacks
        .par_iter()
        .enumerate()
        .map(|(v, s)| fragments_subsampled(s, v, bias, sub))
        .collect();
    let fronts: Vec<Vec<f64>> = stacks.iter().map(front_map).collect();
    let n_frag: usize = frags.iter().map(|f| f.len()).sum();
    let exact: Vec<Vec<Vec<f64>>> = stacks
        .par_iter()
        .zip(&fronts)
        .map(|(s, f)| {
            let id = identity_theta(tech.m());
            decoded_moments(f, s.meta.width, s.meta.height, &id, Storage::Exact, &kernel)
        })
        .collect();
    let mut out = Vec::new();
    for cfg in configs {
        let maps: Vec<Vec<Vec<f64>>> = stacks
            .par_iter()
            .zip(&fronts)
            .map(|(s, f)| {
                decoded_moments(
                    f,
                    s.meta.width,
                    s.meta.height,
                    &cfg.theta,
                    cfg.storage,
                    &kernel,
                )
            })
            .collect();
        let per_alpha: Vec<(f64, usize, f64)> = alphas
            .par_iter()
            .map(|&a| {
                let sh = tech.shadower(a);
                let mut sum = 0.0;
                let mut dev = 0.0;
                let mut bad = 0;
                for ((fr, mp), ex) in frags.iter().zip(&maps).zip(&exact) {
                    for f in fr {
                        let g = sh.shadow(&mp[f.texel], f.zf);
                        let ge = sh.shadow(&ex[f.texel], f.zf);
                        if g.is_finite() {
                            sum += (g - f.pcf).abs();
                            dev += if ge.is_finite() { (g - ge).abs() } else { 1.0 };
                        } else {
                            sum += 1.0;
                            dev += 1.0;
                            bad += 1;
                        }
                    }
                }
                let n = n_frag.max(1) as f64;
                (sum / n, bad, dev / n)
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

/// Mean |G − G_exact| up to which storage counts as usable (0.1 % shadow intensity on average).
pub const USABLE_DEVIATION: f64 = 1e-3;

/// For every 16-bit configuration: the smallest α at which its deviation from unquantized
/// moments is at most USABLE_DEVIATION (an absolute threshold: at tiny α even 32-bit float
/// storage deviates by 1e-2 for 6MSM, so a threshold relative to it would pass anything).
pub fn usability(all: &[Sweep]) -> Vec<serde_json::Value> {
    let mut out = Vec::new();
    for s in all.iter().filter(|s| s.config.contains("16-bit")) {
        let Some(f32s) = all
            .iter()
            .find(|f| f.technique == s.technique && f.config == "32-bit float")
        else {
            continue;
        };
        let k = (0..s.alphas.len()).find(|&i| s.deviation[i] <= USABLE_DEVIATION);
        out.push(serde_json::json!({
            "technique": s.technique, "config": s.config,
            "smallest_usable_alpha": k.map(|i| s.alphas[i]),
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
        // the same texels through decoded_moments (separable filter of the stored maps) and
        // through decoded_window (weighted sum over the 9×9 window) agree to rounding
        let (w, h) = (16, 13);
        let front: Vec<f64> = (0..w * h)
            .map(|i| ((i * 7919) % 101) as f64 / 101.0)
            .collect();
        let k = Gaussian::paper();
        let th = published_theta4();
        let maps = decoded_moments(&front, w, h, &th, Storage::Unorm(16), &k);
        let r = k.radius() as i64;
        for (x, y) in [(0usize, 0usize), (7, 6), (15, 12), (3, 11)] {
            let window = k.taps().into_iter().map(|(dx, dy, wt)| {
                let xx = crate::kernel::clamp_coord(x, dx, w);
                let yy = crate::kernel::clamp_coord(y, dy, h);
                (front[yy * w + xx], wt)
            });
            let mut out = [0.0; 4];
            let pb: &dyn Fn(f64, &mut [f64]) = &crate::technique::hamburger4::power_basis;
            decoded_window(window, pb, &th, Storage::Unorm(16), &mut out);
            for j in 0..4 {
                let d = (out[j] - maps[y * w + x][j]).abs();
                assert!(d < 1e-9, "texel ({x},{y}) moment {j}: {d} (radius {r})");
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
        // canonical 16-bit: filtering averages the rounded texels, so the error stays within
        // half a quantum
        let exact = decoded_moments(&front, w, h, &identity_theta(4), Storage::Float32, &k);
        let err = |d: &Vec<Vec<f64>>| {
            d.iter()
                .zip(&exact)
                .flat_map(|(a, b)| a.iter().zip(b).map(|(p, q)| (p - q).abs()))
                .fold(0.0f64, f64::max)
        };
        let canon = decoded_moments(&front, w, h, &identity_theta(4), Storage::Unorm(16), &k);
        assert!(err(&canon) <= 0.5 / 65535.0 + 1e-7);
    }
}
