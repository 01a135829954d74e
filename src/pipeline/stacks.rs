//! Step 1: the depth stacks of the run — read back from `<results>/<run>/stacks` when they
//! exist at the planned resolution, otherwise rendered (the embedded default dataset) and
//! written there.

use crate::stack::DepthStack;
use anyhow::Result;
use std::path::Path;
use std::time::Instant;

/// The stacks in `dir` at `resolution`, rendering and writing them when missing or stale.
pub fn load_or_render(dir: &Path, resolution: usize) -> Result<Vec<DepthStack>> {
    if let Ok(s) = crate::stack::load_dir(dir) {
        if s.first().map(|s| s.meta.width) == Some(resolution) {
            return Ok(s);
        }
    }
    let t0 = Instant::now();
    let stacks = crate::render::default_dataset(resolution)?;
    // Stale stacks (another resolution) are replaced.
    let out = crate::artefact::OutDir::new(dir, true)?;
    for st in &stacks {
        crate::stack::write_to(&out, &st.file_stem(), st)?;
    }
    eprintln!(
        "  rendered {} views in {:.1} s",
        stacks.len(),
        t0.elapsed().as_secs_f64()
    );
    Ok(stacks)
}
