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

/// README's GPU block: per bench artefact under `reports/gpu/` (one adapter each, software and
/// hardware never in one table), the pass times at the base point per technique × storage, and
/// the three charts.
pub fn readme_block(reports: &std::path::Path) -> Result<String> {
    let dir = reports.join("gpu");
    let mut files: Vec<std::path::PathBuf> = std::fs::read_dir(&dir)
        .map_err(|e| anyhow::anyhow!("{}: {e}", dir.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "json"))
        .collect();
    files.sort();
    let mut s = String::new();
    for f in files {
        let r: Report = crate::artefact::read_json(&f)?;
        let stem = f
            .file_stem()
            .and_then(|x| x.to_str())
            .unwrap_or("")
            .to_string();
        let (size, taps, output) = r.plan.base;
        let large = if r.plan.sizes.iter().any(|&e| e >= r.plan.large_from) {
            format!(
                "; shadow maps from {0}² up: {1} run{2}",
                r.plan.large_from,
                r.plan.repeats_large,
                if r.plan.repeats_large == 1 { "" } else { "s" }
            )
        } else {
            String::new()
        };
        s += &format!(
            "The paper's Figure 7 analogue on **{}** ({}, {}, {} timer; `reports/gpu/{stem}.json`): \
             ns per lookup at a {size}² shadow map, {taps}×{taps} filter, {output}² lookups \
             (median of {} runs{large}; encode and filter times, mean and max in the artefact).\n\n",
            r.adapter.name,
            r.adapter.backend,
            if r.adapter.software { "software: CPU times" } else { "hardware" },
            r.timer,
            r.plan.repeats_at(size)
        );
        let base = |p: &crate::gpu::bench::Point| {
            p.axis == "size" && p.size == size && p.filter == taps && p.output == output
        };
        let storages = ["f32", "f16", "unorm16", "unorm16-theta"];
        s += "| ns per lookup | f32 | f16 | unorm16 | unorm16-theta |\n| --- | ---: | ---: | ---: | ---: |\n";
        let mut techniques: Vec<&str> = Vec::new();
        for p in &r.points {
            if !techniques.contains(&p.technique.as_str()) {
                techniques.push(&p.technique);
            }
        }
        for t in techniques {
            let cells: Vec<String> = storages
                .iter()
                .map(|st| {
                    r.points
                        .iter()
                        .find(|p| base(p) && p.technique == t && p.storage == *st)
                        .map_or("".into(), |p| {
                            format!("{:.1}", p.lookup_ms.median * 1e6 / (output * output) as f64)
                        })
                })
                .collect();
            s += &format!("| {t} | {} |\n", cells.join(" | "));
        }
        s += &format!(
            "\n![time against shadow-map size, {}](../reports/gpu/{stem}_size.svg)\n\n",
            r.adapter.name
        );
    }
    if s.is_empty() {
        anyhow::bail!("{}: no bench artefact", dir.display());
    }
    Ok(s.trim_end().to_string() + "\n")
}
