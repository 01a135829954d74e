//! Step 7: the stability study ([`crate::report::stability`]) into `stability/`, kept when
//! `stability.json` exists.

use super::progress::bar;
use super::Plan;
use crate::report::stability::{study, Options, DEFAULT_TECHNIQUES};
use anyhow::Result;
use std::path::Path;

/// Run the study with the plan's sample count unless its artefacts exist.
pub fn run(plan: &Plan, out: &Path) -> Result<()> {
    if out.join("stability.json").exists() {
        return Ok(());
    }
    let opts = Options {
        out: out.to_path_buf(),
        samples: plan.stability_samples,
        seed: 1,
        grid: 256,
        techniques: DEFAULT_TECHNIQUES.split(',').map(str::to_string).collect(),
        // The step reruns only when its summary is missing: replace its leftovers.
        force: true,
    };
    let b = bar(0, "stability");
    let o = study(&opts, &|n| b.set_total(n as u64), &|n| b.inc(n as u64))?;
    b.finish();
    println!(
        "stability: {} inputs × {} techniques in {:.1} s → {}",
        o.inputs,
        o.techniques,
        o.seconds,
        out.display()
    );
    Ok(())
}
