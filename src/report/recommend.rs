//! "No more model than a scene needs": per-scene errors of measured techniques, their error
//! histograms, and the recommendation per scene, which is `tune`'s answer ([`recommendations`]).

use crate::metrics::EvalReport;
use serde::{Deserialize, Serialize};

/// One evaluated technique configuration (as stored in `reports/<run>/evaluate/*.json`).
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Measured {
    /// Technique spec name.
    pub name: String,
    /// Moment storage precision ("f64", "f32", "u16", …).
    pub precision: String,
    /// Bits stored per shadow-map texel at that precision.
    pub bits_per_texel: u32,
    /// Mean CPU time of one shading call, nanoseconds.
    pub ns_per_fragment: f64,
    /// Mean |G − PCF| over the evaluated fragments.
    pub error: f64,
    /// Evaluated fragments.
    pub fragments: usize,
    /// Evaluated fragments with F_Z(z_f − ε′) = 0.
    pub trivial: usize,
    /// Fragments with non-finite G (excluded from `error`).
    pub non_finite: usize,
    /// LP answers the solver settled neither way, scored as the trivial bound G = 0
    /// (`lp::UNSETTLED_G`); 0 for closed forms and in artefacts of older runs.
    #[serde(default)]
    pub unsettled: usize,
    /// Wall time of the evaluation, seconds.
    pub seconds: f64,
    /// Per scene: (scene, mean error over its fragments, fragments).
    pub scenes: Vec<(String, f64, usize)>,
    /// Fragments per bin of |G − PCF| ([`HIST_EDGES`]); empty in artefacts of older runs.
    #[serde(default)]
    pub histogram: Vec<u64>,
    /// The error with PCF's constant ε at ε/3 and 3ε (`metrics::EPSILON_FACTORS`): how much of
    /// `error` depends on the reference; absent in artefacts of older runs.
    #[serde(default)]
    pub error_scaled: Option<[f64; 2]>,
    /// Mean max(0, PCF − G), the light-leaking part of `error`; absent in older artefacts.
    #[serde(default)]
    pub leak: Option<f64>,
}

/// Bin edges of the error histogram: [0, 1e-4) then four bins per decade up to 1 (the last bin
/// is closed): |G − PCF| at rounding level, then log-spaced.
pub const HIST_EDGES: [f64; 18] = [
    0.0, 1e-4, 1.778e-4, 3.162e-4, 5.623e-4, 1e-3, 1.778e-3, 3.162e-3, 5.623e-3, 1e-2, 1.778e-2,
    3.162e-2, 5.623e-2, 0.1, 0.1778, 0.3162, 0.5623, 1.0,
];

/// Counts of `errors` in the bins of [`HIST_EDGES`] (values ≥ 1 go to the last bin; NaN and
/// negative values are not counted).
pub fn error_histogram(errors: impl Iterator<Item = f64>) -> Vec<u64> {
    let mut h = vec![0u64; HIST_EDGES.len() - 1];
    for k in errors.filter_map(|e| crate::metrics::histogram_bin(&HIST_EDGES, e)) {
        h[k] += 1;
    }
    h
}

/// The error histogram of an evaluation that counted it in the bins of [`HIST_EDGES`]
/// (`EvalOptions::histogram`), summed over its views (empty when no view counted one).
pub fn histogram_of(r: &EvalReport) -> Vec<u64> {
    if r.views.iter().all(|v| v.histogram.is_empty()) {
        return Vec::new();
    }
    let mut h = vec![0u64; HIST_EDGES.len() - 1];
    for v in &r.views {
        for (t, c) in h.iter_mut().zip(&v.histogram) {
            *t += c;
        }
    }
    h
}

/// Per scene of an evaluation: (scene, mean |G − PCF| over its finite fragments, finite fragments).
pub fn per_scene(r: &EvalReport) -> Vec<(String, f64, usize)> {
    let mut out: Vec<(String, f64, usize)> = Vec::new();
    for v in &r.views {
        let finite = v.fragments - v.non_finite;
        match out.iter_mut().find(|s| s.0 == v.scene) {
            Some(s) => {
                s.1 += v.sum_abs_error;
                s.2 += finite;
            }
            None => out.push((v.scene.clone(), v.sum_abs_error, finite)),
        }
    }
    for s in &mut out {
        s.1 /= s.2.max(1) as f64;
    }
    out
}

/// The recommendation for one scene: `tune`'s answer ([`crate::tune::Target::chosen`]), the
/// cheapest feasible setting within the tolerance of the best in the modelled GPU pipeline.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Recommendation {
    /// The scene.
    pub scene: String,
    /// The technique's name (`tmsm`, `hamburger4`, …).
    pub name: String,
    /// The storage format's name (`f32`, `unorm16-theta`, …).
    pub storage: String,
    /// The whole setting: technique, storage, α, depth bias, own parameters.
    pub setting: String,
    /// Bits per shadow-map texel.
    pub bits_per_texel: u32,
    /// GPU ns per lookup (`gpu::cost`).
    pub gpu_ns: f64,
    /// Mean |G − PCF| split as leak + darkening + noise ([`crate::tune::score`]).
    pub error: f64,
    /// Mean light leaking against PCF of the same technique on exact moments.
    pub leak: f64,
    /// Mean over-darkening against PCF of the same technique on exact moments.
    pub darkening: f64,
    /// Mean |G − G_exact|: noise from storage and f32 arithmetic.
    pub noise: f64,
    /// Share of fragments whose shadow is more than 1/255 from exact moments.
    pub noise_share: f64,
    /// The lowest-error feasible setting and its error.
    pub best_name: String,
    /// Its mean |G − PCF|.
    pub best_error: f64,
    /// Allowed excess error over the best: the recommendation is within it.
    pub tolerance: f64,
    /// The noise bound the setting meets: largest share of fragments above 1/255.
    pub max_noise: f64,
}

/// Per scene (and over all scenes): the tuned setting of `t` as a recommendation.
pub fn recommendations(t: &crate::tune::Tuning) -> Vec<Recommendation> {
    t.scenes
        .iter()
        .chain(std::iter::once(&t.overall))
        .map(|x| {
            let c = &x.chosen;
            Recommendation {
                scene: x.scene.clone(),
                name: c.setting.family.technique.name().to_string(),
                storage: c.setting.family.storage.name().to_string(),
                setting: c.label.clone(),
                bits_per_texel: c.bits_per_texel,
                gpu_ns: c.ns_per_fragment,
                error: c.error,
                leak: c.leak,
                darkening: c.darkening,
                noise: c.noise,
                noise_share: c.noise_share,
                best_name: x.best.label.clone(),
                best_error: x.best.error,
                tolerance: t.tolerance,
                max_noise: t.max_noise,
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn histogram_bins_by_edges() {
        let h = error_histogram([0.0, 5e-5, 1e-4, 0.5, 0.99, 1.0, 3.0, f64::NAN, -1.0].into_iter());
        assert_eq!(h.len(), 17);
        assert_eq!(h[0], 2); // 0 and 5e-5
        assert_eq!(h[1], 1); // 1e-4
        assert_eq!(h[15], 1); // 0.5 ∈ [0.3162, 0.5623)
        assert_eq!(h[16], 3); // 0.99, 1 and 3 (clamped)
        assert_eq!(h.iter().sum::<u64>(), 7);
    }
}
