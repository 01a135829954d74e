//! The GPU bench as pictures: the paper's Figure 7 analogue from `reports/gpu/<adapter>.json`.

use crate::gpu::bench::Report;
use anyhow::Result;

/// The three panels of the Figure 7 analogue as SVG: median total time per technique × storage
/// against each axis.
pub fn gpu_charts(r: &Report) -> Result<Vec<(String, String)>> {
    let kind = if r.adapter.software {
        "software"
    } else {
        "hardware"
    };
    let mut out = Vec::new();
    for (axis, what, log) in [
        ("size", "shadow-map size (texels per edge)", true),
        ("filter", "filter taps per axis", false),
        ("output", "output resolution (pixels per edge)", true),
    ] {
        let mut series: Vec<(String, Vec<(f64, f64)>)> = Vec::new();
        for p in r.points.iter().filter(|p| p.axis == axis) {
            let name = format!("{} {} ({} b)", p.technique, p.storage, p.bits_per_texel);
            let x = match axis {
                "size" => p.size,
                "filter" => p.filter,
                _ => p.output,
            } as f64;
            match series.iter_mut().find(|s| s.0 == name) {
                Some(s) => s.1.push((x, p.total_ms.median)),
                None => series.push((name, vec![(x, p.total_ms.median)])),
            }
        }
        let title = format!(
            "GPU time per frame against {what}, {} ({kind})",
            r.adapter.name
        );
        out.push((
            axis.to_string(),
            super::chart::lines_svg(&title, what, "ms (median)", &series, log)?,
        ));
    }
    Ok(out)
}
