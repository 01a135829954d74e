//! "No more model than a scene needs": per-scene errors of measured techniques and the cheapest
//! technique within a tolerance of the best ([`super::pareto::recommend`]).

use super::pareto::{self, Entry};
use crate::metrics::EvalReport;
use serde::{Deserialize, Serialize};

/// One evaluated technique configuration (as stored in `reports/<run>/evaluate/*.json`).
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Measured {
    pub name: String,
    pub precision: String,
    pub bits_per_texel: u32,
    pub ns_per_fragment: f64,
    pub error: f64,
    pub fragments: usize,
    pub trivial: usize,
    pub non_finite: usize,
    pub seconds: f64,
    /// Per scene: (scene, mean error over its fragments, fragments).
    pub scenes: Vec<(String, f64, usize)>,
}

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
    pub scene: String,
    pub name: String,
    pub precision: String,
    pub bits_per_texel: u32,
    pub ns_per_fragment: f64,
    pub error: f64,
    pub best_name: String,
    pub best_error: f64,
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
