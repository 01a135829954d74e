//! Step 6: the quantization study (8/16/32-bit moment shadow maps, canonical and θ storage)
//! on the run's stacks with the run's θ; artefacts in `quantize/`, kept when they exist.
//!
//! The work is done by `momentlab quantize` (src/cli/quantize.rs), called with typed arguments.

use super::Plan;
use crate::cli::quantize;
use anyhow::Result;
use std::path::Path;

/// Run the study into `out` unless `out/quantize.json` exists.
pub fn run(plan: &Plan, stacks: &Path, theta_dir: &Path, out: &Path) -> Result<()> {
    if out.join("quantize.json").exists() {
        return Ok(());
    }
    // every technique whose θ the run computed
    let techniques: Vec<String> = crate::quantize::study::Tech::ALL
        .into_iter()
        .map(|t| (t.m(), t.name().to_string()))
        .filter(|(m, _)| theta_dir.join(format!("theta{m}.json")).is_file())
        .map(|(_, t)| t)
        .collect();
    if techniques.is_empty() {
        return Ok(());
    }
    quantize::run(quantize::Args {
        stacks: Some(stacks.to_path_buf()),
        resolution: plan.resolution,
        theta_dir: theta_dir.to_path_buf(),
        technique: techniques,
        out: out.to_path_buf(),
        force: true,
        stride: plan.quantize_stride,
        alphas: quantize::DEFAULT_ALPHAS.to_string(),
        json: false,
        merge: None,
    })
}
