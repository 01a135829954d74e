//! Step 5: the optimal quantization transforms θ_m of the plan (`theta/theta<m>.json` and
//! shader snippets, kept when they exist) and their comparison with the published ones
//! (`theta/comparison.md`, `summary.json`, Fig. 5 analogue).
//!
//! The work is done by `momentlab theta` (src/cli/theta.rs), called with typed arguments.

use super::Plan;
use crate::artefact::read_json;
use crate::cli::theta;
use anyhow::Result;
use serde::Deserialize;
use std::path::Path;

/// One θ of the run: (m, entropy gain in bits, max violation, seconds).
pub type ThetaRow = (usize, f64, f64, f64);

fn args(m: usize, restarts: usize, dir: &Path) -> theta::Args {
    theta::Args {
        summary: None,
        m: Some(m),
        basis: None,
        seed: 1,
        restarts,
        starts: None,
        max_sweeps: 400,
        hops: 0,
        hop_sigma: 0.2,
        basin_tol: 1e-3,
        out: Some(dir.to_path_buf()),
        force: true,
        json: false,
        channel_order: theta::Order::Paper,
        snippets: None,
    }
}

/// Compute the missing θ_m into `dir`, write the summary, return one row per m.
pub fn run(plan: &Plan, dir: &Path) -> Result<Vec<ThetaRow>> {
    std::fs::create_dir_all(dir)?;
    let mut runs: Vec<(usize, theta::Args)> = Vec::new();
    for &m in &plan.theta_moments {
        let mut a = args(m, plan.theta_restarts, dir);
        if m >= 4 {
            // Basin hopping for m ≥ 4, where few single ascents end in poorer local optima.
            (a.hops, a.hop_sigma) = (10, 0.3);
        }
        runs.push((m, a));
    }
    for &(m, restarts, start) in &plan.theta_best_starts {
        let mut a = args(m, restarts, dir);
        a.starts = Some(start.to_string());
        runs.push((m, a));
    }
    let mut rows = Vec::new();
    for (m, a) in runs {
        let file = dir.join(format!("theta{m}.json"));
        if !file.exists() {
            theta::run(a)?;
        }
        #[derive(Deserialize)]
        struct T {
            gain_bits: f64,
            max_violation: f64,
            seconds: f64,
        }
        let t: T = read_json(&file)?;
        rows.push((m, t.gain_bits, t.max_violation, t.seconds));
    }
    let mut s = args(2, 1, dir);
    s.summary = Some(dir.to_path_buf());
    s.m = None;
    theta::run(s)?;
    Ok(rows)
}
