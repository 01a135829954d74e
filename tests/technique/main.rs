//! The closed-form techniques (Hamburger/Hausdorff MSM, TMSM, ESM, VSM, CSM …) against the LP
//! and their own properties, `momentlab shadow`, and the stability harness.

#[path = "../common/mod.rs"]
mod common;

mod closed_form_cli;
mod closed_form_lp;
mod closed_form_props;
mod sparse_theorem1;
mod stability_harness;
mod tmsm_equiv;
mod tmsm_lp;
mod tmsm_old;
