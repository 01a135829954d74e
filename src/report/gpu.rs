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

/// The bench artefacts under `reports/gpu/`, sorted, each with its file stem.
fn benches(reports: &std::path::Path) -> Result<Vec<(String, Report)>> {
    let dir = reports.join("gpu");
    let mut files: Vec<std::path::PathBuf> = std::fs::read_dir(&dir)
        .map_err(|e| anyhow::anyhow!("{}: {e}", dir.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "json"))
        .collect();
    files.sort();
    if files.is_empty() {
        anyhow::bail!("{}: no bench artefact", dir.display());
    }
    files
        .iter()
        .map(|f| {
            let stem = f.file_stem().and_then(|x| x.to_str()).unwrap_or("");
            Ok((stem.to_string(), crate::artefact::read_json(f)?))
        })
        .collect()
}

/// "name (backend, software: CPU times | hardware, timer timer; `reports/gpu/stem.json`)".
fn adapter_line(stem: &str, r: &Report) -> String {
    format!(
        "**{}** ({}, {}, {} timer; `reports/gpu/{stem}.json`)",
        r.adapter.name,
        r.adapter.backend,
        if r.adapter.software {
            "software: CPU times"
        } else {
            "hardware"
        },
        r.timer
    )
}

/// The base point is measured once on each axis: per technique × storage, the largest ratio of
/// its median total times, over all technique × storage (1 = the three agree exactly).
pub fn base_spread(r: &Report) -> f64 {
    let (size, taps, output) = r.plan.base;
    let mut worst = 1.0f64;
    let mut seen: Vec<(&str, &str)> = Vec::new();
    for p in &r.points {
        let key = (p.technique.as_str(), p.storage.as_str());
        if seen.contains(&key) {
            continue;
        }
        seen.push(key);
        let t: Vec<f64> = r
            .points
            .iter()
            .filter(|q| {
                (q.technique.as_str(), q.storage.as_str()) == key
                    && (q.size, q.filter, q.output) == (size, taps, output)
            })
            .map(|q| q.total_ms.median)
            .collect();
        let (lo, hi) = t
            .iter()
            .fold((f64::INFINITY, 0.0f64), |(a, b), &x| (a.min(x), b.max(x)));
        if t.len() > 1 && lo > 0.0 {
            worst = worst.max(hi / lo);
        }
    }
    worst
}

/// The three charts of a bench as Markdown images, `prefix` leading to `reports/`.
fn charts(stem: &str, r: &Report, prefix: &str, sep: &str) -> String {
    [
        ("size", "shadow-map size"),
        ("filter", "filter size"),
        ("output", "output resolution"),
    ]
    .iter()
    .map(|(axis, what)| {
        format!(
            "![time per frame against {what}, {}]({prefix}reports/gpu/{stem}_{axis}.svg)",
            r.adapter.name
        )
    })
    .collect::<Vec<_>>()
    .join(sep)
}

/// README's `gpu-bench` block, one paragraph per bench artefact under `reports/gpu/`: the
/// adapter, the axes, the frame time at the largest shadow map from the cheapest to the
/// dearest technique × storage (with bits per texel), and the three charts.
pub fn readme_bench(reports: &std::path::Path) -> Result<String> {
    let mut s = String::new();
    for (stem, r) in benches(reports)? {
        let list = |v: &[usize]| {
            v.iter()
                .map(|x| x.to_string())
                .collect::<Vec<_>>()
                .join(", ")
        };
        let largest = r.plan.sizes.iter().copied().max().unwrap_or(r.plan.base.0);
        let at: Vec<&crate::gpu::bench::Point> = r
            .points
            .iter()
            .filter(|p| p.axis == "size" && p.size == largest)
            .collect();
        let lo = at
            .iter()
            .min_by(|a, b| a.total_ms.median.total_cmp(&b.total_ms.median));
        let hi = at
            .iter()
            .max_by(|a, b| a.total_ms.median.total_cmp(&b.total_ms.median));
        let range = match (lo, hi) {
            (Some(a), Some(b)) => format!(
                "; at {largest}² a frame takes {:.0} ms ({} {}, {} bits per texel) to {:.0} ms \
                 ({} {}, {} bits per texel)",
                a.total_ms.median,
                a.technique,
                a.storage,
                a.bits_per_texel,
                b.total_ms.median,
                b.technique,
                b.storage,
                b.bits_per_texel
            ),
            _ => String::new(),
        };
        s += &format!(
            "**On a GPU** (`momentlab gpu check` runs every technique × storage through wgpu \
             against the CPU model, fragment by fragment; `momentlab gpu bench` times it; \
             [docs/gpu.md](docs/gpu.md)): the paper's Figure 7 analogue on {}, time per frame (encode, two filter passes, lookup) of every technique × storage against \
             shadow-map size ({}), filter taps ({}) and output resolution ({}){range}. {}\n\n",
            adapter_line(&stem, &r),
            list(&r.plan.sizes),
            list(&r.plan.filters),
            list(&r.plan.outputs),
            charts(&stem, &r, "", " ")
        );
    }
    Ok(s.trim_end().to_string() + "\n")
}

/// docs/gpu.md's `gpu` block: per bench artefact under `reports/gpu/` (one adapter each,
/// software and hardware never in one table), the lookup time at the base point per
/// technique × storage (the median of its measurements on the three axes), their spread, and
/// the three charts.
pub fn docs_block(reports: &std::path::Path) -> Result<String> {
    let mut s = String::new();
    for (stem, r) in benches(reports)? {
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
            "The paper's Figure 7 analogue on {}: ns per lookup at a {size}² shadow map, \
             {taps}×{taps} filter, {output}² lookups (median of {} runs{large}; encode and filter \
             times, mean and max in the artefact). The base point is measured once on each axis; \
             the table gives the median of its three measurements, whose frame times differ by a \
             factor of up to {:.2}: a measure of the timing noise of this run.\n\n",
            adapter_line(&stem, &r),
            r.plan.repeats_at(size),
            base_spread(&r)
        );
        let base =
            |p: &crate::gpu::bench::Point| p.size == size && p.filter == taps && p.output == output;
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
                    let mut v: Vec<f64> = r
                        .points
                        .iter()
                        .filter(|p| base(p) && p.technique == t && p.storage == *st)
                        .map(|p| p.lookup_ms.median)
                        .collect();
                    v.sort_by(f64::total_cmp);
                    v.get(v.len() / 2).map_or("".into(), |m| {
                        format!("{:.1}", m * 1e6 / (output * output) as f64)
                    })
                })
                .collect();
            s += &format!("| {t} | {} |\n", cells.join(" | "));
        }
        s += &format!("\n{}\n\n", charts(&stem, &r, "../", "\n\n"));
    }
    Ok(s.trim_end().to_string() + "\n")
}
