//! Step 8: speed against accuracy (`speed_accuracy.svg`, Pareto front) and the per-scene
//! recommendations (`recommend.json`).

use crate::artefact::write_json;
use crate::report::chart;
use crate::report::pareto::Entry;
use crate::report::recommend::{recommendations, Measured, Recommendation};
use anyhow::Result;
use std::path::Path;

/// The chart entries of the measured techniques.
pub fn entries(all: &[Measured]) -> Vec<Entry> {
    all.iter()
        .map(|m| Entry {
            name: m.name.clone(),
            precision: m.precision.clone(),
            error: m.error,
            ns_per_fragment: m.ns_per_fragment,
            bits_per_texel: m.bits_per_texel,
        })
        .collect()
}

/// Write the chart and the recommendations into `out`; return both.
pub fn run(
    all: &[Measured],
    tolerance: f64,
    out: &Path,
) -> Result<(Vec<Entry>, Vec<Recommendation>)> {
    let entries = entries(all);
    chart::speed_accuracy_svg(
        &out.join("speed_accuracy.svg"),
        "Error against PCF vs cost per fragment (marker size: bits per texel)",
        &entries,
    )?;
    let hists: Vec<(String, Vec<u64>)> = all
        .iter()
        .filter(|m| m.precision == "f32" || m.name.starts_with("lp:"))
        .map(|m| (format!("{} ({})", m.name, m.precision), m.histogram.clone()))
        .collect();
    chart::histograms_svg(
        &out.join("error_histograms.svg"),
        "Distribution of |G − PCF| over fragments (log counts)",
        &hists,
    )?;
    let recs = recommendations(all, tolerance);
    write_json(&out.join("recommend.json"), &recs)?;
    Ok((entries, recs))
}
