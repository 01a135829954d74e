//! "No more model than a scene needs": per-scene errors of measured techniques and the cheapest
//! technique within a tolerance of the best ([`super::pareto::recommend`]).

use super::pareto::{self, Entry};
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
    for e in errors.filter(|e| *e >= 0.0) {
        let k = HIST_EDGES[1..].partition_point(|&edge| edge <= e);
        let last = h.len() - 1;
        h[k.min(last)] += 1;
    }
    h
}

/// The error histogram of an evaluation kept with per-fragment values (empty without them).
pub fn histogram_of(r: &EvalReport) -> Vec<u64> {
    let values = r.views.iter().flat_map(|v| v.values.iter().flatten());
    if r.views.iter().all(|v| v.values.is_none()) {
        return Vec::new();
    }
    error_histogram(values.map(|f| (f.g - f.pcf).abs()))
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

/// The recommendation for one scene.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Recommendation {
    /// The scene.
    pub scene: String,
    /// The recommended technique's spec name.
    pub name: String,
    /// Its storage precision.
    pub precision: String,
    /// Its bits per texel.
    pub bits_per_texel: u32,
    /// Its CPU time per shading call, nanoseconds.
    pub ns_per_fragment: f64,
    /// Its mean |G − PCF| on the scene.
    pub error: f64,
    /// The most accurate closed form on the scene, "name (precision)".
    pub best_name: String,
    /// That technique's mean |G − PCF|.
    pub best_error: f64,
    /// Allowed excess error over the best: the recommendation is within it.
    pub tolerance: f64,
    /// The alternative ([`pareto::runner_up`]): "name (precision)", its error and ns/fragment.
    #[serde(default)]
    pub runner_up: Option<(String, f64, f64)>,
}

/// Per scene: the cheapest closed-form technique within `tolerance` of the best one
/// ([`pareto::recommend`]). LP candidates are references, not shippable techniques.
pub fn recommendations(all: &[Measured], tolerance: f64) -> Vec<Recommendation> {
    let mut scenes: Vec<String> = Vec::new();
    for m in all {
        for (s, _, _) in &m.scenes {
            if !scenes.contains(s) {
                scenes.push(s.clone());
            }
        }
    }
    let mut out = Vec::new();
    for scene in scenes {
        let rows: Vec<(&Measured, Entry)> = all
            .iter()
            .filter(|m| !m.name.starts_with("lp:"))
            .filter_map(|m| {
                m.scenes.iter().find(|s| s.0 == scene).map(|s| {
                    (
                        m,
                        Entry {
                            name: m.name.clone(),
                            precision: m.precision.clone(),
                            error: s.1,
                            ns_per_fragment: m.ns_per_fragment,
                            bits_per_texel: m.bits_per_texel,
                        },
                    )
                })
            })
            .collect();
        let entries: Vec<Entry> = rows.iter().map(|r| r.1.clone()).collect();
        let Some(i) = pareto::recommend(&entries, tolerance) else {
            continue;
        };
        let best = entries
            .iter()
            .filter(|e| e.error.is_finite())
            .min_by(|a, b| a.error.total_cmp(&b.error))
            .expect("recommend found a finite entry");
        let runner_up = pareto::runner_up(&entries, i, tolerance).map(|k| {
            let r = &entries[k];
            (
                format!("{} ({})", r.name, r.precision),
                r.error,
                r.ns_per_fragment,
            )
        });
        out.push(Recommendation {
            scene,
            name: entries[i].name.clone(),
            precision: entries[i].precision.clone(),
            bits_per_texel: entries[i].bits_per_texel,
            ns_per_fragment: entries[i].ns_per_fragment,
            error: entries[i].error,
            best_name: format!("{} ({})", best.name, best.precision),
            best_error: best.error,
            tolerance,
            runner_up,
        });
    }
    out
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
