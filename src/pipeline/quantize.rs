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
    quantize::run(quantize::Args {
        stacks: stacks.to_path_buf(),
        theta_dir: theta_dir.to_path_buf(),
        out: out.to_path_buf(),
        stride: plan.quantize_stride,
        alphas: quantize::DEFAULT_ALPHAS.to_string(),
    })
}
