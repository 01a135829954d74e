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

/// Compute the missing θ_m into `dir`, write the summary, return one row per m.
pub fn run(plan: &Plan, dir: &Path) -> Result<Vec<ThetaRow>> {
    std::fs::create_dir_all(dir)?;
    let mut rows = Vec::new();
    for &m in &plan.theta_moments {
        let file = dir.join(format!("theta{m}.json"));
        if !file.exists() {
            // Basin hopping for m ≥ 4, where single ascents end in poorer local optima.
            let (hops, hop_sigma) = if m >= 4 { (10, 0.3) } else { (0, 0.2) };
            theta::run(theta::Args {
                summary: None,
                moments: Some(m),
                basis: None,
                seed: 1,
                restarts: plan.theta_restarts,
                max_sweeps: 400,
                hops,
                hop_sigma,
                output: Some(file.clone()),
                snippets: dir.to_path_buf(),
            })?;
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
    theta::run(theta::Args {
        summary: Some(dir.to_path_buf()),
        moments: None,
        basis: None,
        seed: 1,
        restarts: 16,
        max_sweeps: 400,
        hops: 0,
        hop_sigma: 0.2,
        output: None,
        snippets: dir.to_path_buf(),
    })?;
    Ok(rows)
}
