//! Techniques by name, as used on the command line and in reports.
//!
//! Closed-form names: vsm, esm, evsm, csm, hamburger, hamburger4, hausdorff4, hamburger6, tmsm
//! (OWNERS: closed-form helpers). LP candidates: "lp:f1,f2,…" with catalog names or formulas
//! (OWNER: basis helper).

use super::Technique;
use anyhow::{bail, Result};

/// The technique named by `spec`; a one-line error for unknown names.
pub fn by_name(spec: &str) -> Result<Box<dyn Technique>> {
    if let Some(list) = spec.strip_prefix("lp:") {
        return Ok(Box::new(super::lp_candidate::LpCandidate::from_spec(list)?));
    }
    bail!("unknown technique '{spec}'")
}
