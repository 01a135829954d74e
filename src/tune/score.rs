//! How `tune` scores a setting: the pipeline a GPU runs, and noise counted as error.
//!
//! **The moments a lookup reads** ([`Moments`]), per fragment of the [`Sample`]: every texel of
//! its 9×9 window stores θ(b(z)) (b and θ in f64, rounded to f32 as the encoder's output, then
//! to the storage format); the separable Gaussian runs as two passes accumulated in f32 in tap
//! order, each pass's output stored in the format
//! ([`crate::quantize::pipeline::filtered_window`], the same arithmetic as the whole-map passes
//! that `momentlab gpu check` compares with a GPU driver); the lookup at the texel centre reads
//! that texel (bilinear weights 1, 0, 0, 0); θ⁻¹ decodes in f32. binary16 stores round to nearest
//! even, as IEEE and hardware GPUs do. Beside them, the **exact moments**: the same window's
//! b(z) filtered in f64 with no storage.
//!
//! **The outcome of a fragment** ([`Outcome`]): G from the stored moments with the technique's
//! f32 arithmetic, and G_exact, the same technique (same α, same depth bias) in f64 on the exact
//! moments. With e = G_exact − PCF (the technique's own error) and ν = G − G_exact (noise):
//! - leak = max(−e, 0), darkening = max(e, 0), noise = |ν|;
//! - the score of a setting is mean(leak + darkening + noise) = mean |e| + mean |ν|, with a
//!   fragment whose G or G_exact is not finite counted as 1.
//!
//! By the triangle inequality the score bounds mean |G − PCF| from above. The part mean |e| does
//! not depend on the storage at all, and the noise part is ≥ 0, so noise never lowers a score:
//! darkening a leaking lower bound by noise shows up as noise, not as a smaller leak. For
//! zero-mean noise δ added to the moments, E|ν + δ'| ≥ |ν| (Jensen), so the expected score
//! cannot fall either (a test adds such noise).
//!
//! **The noise bound**: the share of fragments with |ν| > 1/255 (one step of an 8-bit display)
//! must not exceed `max_noise` for a setting to be feasible.

use super::sample::Sample;
use super::space::{Family, Setting, StorageKind};
use crate::kernel::Gaussian;
use crate::quantize::pipeline::{filtered_window, store, weights_f32, HalfRounding};
use crate::shader::Order;
use crate::technique::registry::Precision;
use crate::technique::Technique;
use anyhow::Result;
use rayon::prelude::*;

/// One step of an 8-bit display: the noise threshold.
pub use crate::quantize::pipeline::DISPLAY_STEP;

/// Stored (pipeline) and exact moments of every sample fragment for one family
/// (row-major, fragments × m).
pub struct Moments {
    /// The family the moments belong to.
    pub family: Family,
    /// What the lookup decodes: the pipeline model's filtered texel, θ⁻¹ in f32.
    pub stored: Vec<f64>,
    /// The window's b(z) filtered in f64.
    pub exact: Vec<f64>,
}

impl Moments {
    /// Both moment sets of `family` on every fragment of `sample`.
    pub fn compute(family: &Family, sample: &Sample) -> Result<Moments> {
        let t = family.build(family.technique.alphas()[0])?;
        let m = t.moment_count();
        let theta = family.technique.theta(family.storage);
        let identity = family.storage != StorageKind::Unorm16Theta;
        let inv: Vec<f32> = theta.inverse.iter().flatten().map(|&v| v as f32).collect();
        let off: Vec<f32> = theta.offset.iter().map(|&v| v as f32).collect();
        let storage = (family.storage.storage(), HalfRounding::NearestEven);
        let w1 = weights_f32(&Gaussian::paper());
        let taps = sample.weights.len();
        let n = sample.len();
        let mut stored = vec![0.0; n * m];
        let mut exact = vec![0.0; n * m];
        stored
            .par_chunks_mut(m)
            .zip(exact.par_chunks_mut(m))
            .enumerate()
            .for_each_init(
                || {
                    (
                        vec![0.0f64; m],
                        vec![0.0f64; m],
                        vec![0.0f32; taps * m],
                        vec![0.0f32; m],
                    )
                },
                |(b, s, texels, filtered), (i, (st, ex))| {
                    ex.iter_mut().for_each(|v| *v = 0.0);
                    for (k, (z, w)) in sample.window_of(i).enumerate() {
                        t.basis(z, b);
                        for (e, v) in ex.iter_mut().zip(b.iter()) {
                            *e += w * v;
                        }
                        theta.encode(b, s);
                        for (c, v) in s.iter().enumerate() {
                            texels[k * m + c] = store(storage.0, storage.1, *v as f32);
                        }
                    }
                    filtered_window(texels, (m, &w1), Order::Unfused, storage, filtered);
                    for r in 0..m {
                        st[r] = if identity {
                            filtered[r] as f64
                        } else {
                            let mut acc = 0.0f32;
                            for c in 0..m {
                                acc += inv[r * m + c] * (filtered[c] - off[c]);
                            }
                            acc as f64
                        };
                    }
                },
            );
        Ok(Moments {
            family: *family,
            stored,
            exact,
        })
    }

    /// The moment count m.
    pub fn m(&self) -> usize {
        self.family.technique.moment_count()
    }
}

/// One fragment under one setting.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Outcome {
    /// G_exact − PCF; NaN when G or G_exact is not finite.
    pub error: f64,
    /// G − G_exact; NaN when G or G_exact is not finite.
    pub noise: f64,
}

impl Outcome {
    /// leak + darkening + noise of the fragment (1 when not finite).
    pub fn score(&self) -> f64 {
        if self.error.is_finite() && self.noise.is_finite() {
            self.error.abs() + self.noise.abs()
        } else {
            1.0
        }
    }
}

/// The setting's technique at its α in f64 arithmetic: G_exact.
fn exact_technique(s: &Setting) -> Result<Box<dyn Technique>> {
    let mut p = s.family.params(s.alpha);
    p.precision = Precision::F64;
    crate::technique::registry::build(s.family.technique.name(), &p)
}

/// Outcomes of setting `s` on fragments `idx`, from `stored` and `exact` moments (row-major
/// per fragment, as in [`Moments`]).
pub fn outcomes(
    s: &Setting,
    (stored, exact): (&[f64], &[f64]),
    sample: &Sample,
    idx: &[usize],
) -> Result<Vec<Outcome>> {
    let t = s.family.build(s.alpha)?;
    let tx = exact_technique(s)?;
    let m = t.moment_count();
    let (mut ev, mut evx) = (t.evaluator(), tx.evaluator());
    Ok(idx
        .iter()
        .map(|&i| {
            let zf =
                sample.z[i] - (s.depth_bias.constant + s.depth_bias.slope_scale * sample.slope[i]);
            let g = ev.shadow(&stored[i * m..(i + 1) * m], zf);
            let gx = evx.shadow(&exact[i * m..(i + 1) * m], zf);
            if g.is_finite() && gx.is_finite() {
                Outcome {
                    error: gx - sample.pcf[i],
                    noise: g - gx,
                }
            } else {
                Outcome {
                    error: f64::NAN,
                    noise: f64::NAN,
                }
            }
        })
        .collect())
}

/// Sums of one setting over some fragments (mergeable across scenes).
#[derive(Clone, Debug, Default)]
pub struct Acc {
    /// Fragments added.
    pub n: usize,
    /// Σ max(PCF − G_exact, 0): light leaked.
    pub leak: f64,
    /// Σ max(G_exact − PCF, 0): over-darkening.
    pub dark: f64,
    /// Σ |G − G_exact|: noise.
    pub noise: f64,
    /// Fragments with |ν| > 1/255.
    pub noisy: usize,
    /// Fragments whose G or G_exact is not finite.
    pub non_finite: usize,
    /// |ν| of every finite fragment, kept where a quantile is wanted.
    pub noise_values: Option<Vec<f32>>,
}

impl Acc {
    /// An empty accumulator; `keep` keeps |ν| of every fragment for [`Acc::noise_quantile`].
    pub fn new(keep: bool) -> Acc {
        Acc {
            noise_values: keep.then(Vec::new),
            ..Acc::default()
        }
    }
    /// Adds one fragment's outcome.
    pub fn add(&mut self, o: &Outcome) {
        self.n += 1;
        if !(o.error.is_finite() && o.noise.is_finite()) {
            self.non_finite += 1;
            return;
        }
        if o.error < 0.0 {
            self.leak -= o.error;
        } else {
            self.dark += o.error;
        }
        let a = o.noise.abs();
        self.noise += a;
        if a > DISPLAY_STEP {
            self.noisy += 1;
        }
        if let Some(v) = &mut self.noise_values {
            v.push(a as f32);
        }
    }
    /// Adds the sums of `o` (noise values are kept only when both kept them).
    pub fn merge(&mut self, o: &Acc) {
        self.n += o.n;
        self.leak += o.leak;
        self.dark += o.dark;
        self.noise += o.noise;
        self.noisy += o.noisy;
        self.non_finite += o.non_finite;
        match (&mut self.noise_values, &o.noise_values) {
            (Some(a), Some(b)) => a.extend_from_slice(b),
            (a, _) => *a = None,
        }
    }
    /// The score: mean(leak + darkening + noise), non-finite fragments counted as 1.
    pub fn score(&self) -> f64 {
        (self.leak + self.dark + self.noise + self.non_finite as f64) / self.n.max(1) as f64
    }
    /// Share of fragments above one display step of noise; a non-finite G counts as noisy.
    pub fn noise_share(&self) -> f64 {
        (self.noisy + self.non_finite) as f64 / self.n.max(1) as f64
    }
    /// The q-quantile of |ν| over the finite fragments (NaN when not kept or none).
    pub fn noise_quantile(&self, q: f64) -> f64 {
        let Some(v) = &self.noise_values else {
            return f64::NAN;
        };
        if v.is_empty() {
            return f64::NAN;
        }
        let mut v = v.clone();
        let k = ((q * v.len() as f64).ceil() as usize).clamp(1, v.len()) - 1;
        let (_, x, _) = v.select_nth_unstable_by(k, f32::total_cmp);
        *x as f64
    }
}

/// Per-scene accumulators of one setting's outcomes on fragments `idx`.
pub fn accumulate(outcomes: &[Outcome], sample: &Sample, idx: &[usize], keep: bool) -> Vec<Acc> {
    let mut acc = vec![Acc::new(keep); sample.scenes.len()];
    for (&i, o) in idx.iter().zip(outcomes) {
        acc[sample.scene[i]].add(o);
    }
    acc
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_score_splits_into_leak_darkening_and_noise() {
        let mut a = Acc::new(true);
        for o in [
            Outcome {
                error: -0.1,
                noise: 0.02,
            },
            Outcome {
                error: 0.05,
                noise: -0.001,
            },
            Outcome {
                error: f64::NAN,
                noise: f64::NAN,
            },
            Outcome {
                error: 0.0,
                noise: 0.0,
            },
        ] {
            a.add(&o);
        }
        assert_eq!(a.n, 4);
        assert!((a.leak - 0.1).abs() < 1e-15 && (a.dark - 0.05).abs() < 1e-15);
        assert!((a.noise - 0.021).abs() < 1e-15);
        assert_eq!((a.noisy, a.non_finite), (1, 1));
        assert!((a.score() - (0.1 + 0.05 + 0.021 + 1.0) / 4.0).abs() < 1e-15);
        assert!((a.noise_share() - 0.5).abs() < 1e-15);
        assert!((a.noise_quantile(1.0) - 0.02).abs() < 1e-9);
        assert_eq!(a.noise_quantile(0.0), 0.0);
        let mut b = Acc::new(true);
        b.merge(&a);
        b.merge(&a);
        assert_eq!((b.n, b.noisy), (8, 2));
        assert!((b.score() - a.score()).abs() < 1e-15);
    }
}
