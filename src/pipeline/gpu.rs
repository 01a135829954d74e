//! The GPU step of a run: where the machine has an adapter, `gpu check` on the run's stacks
//! (every technique × storage on one view each, the views taken in turn) and a small
//! `gpu bench`; where it has none, one line saying so. Files: `gpu/check.json`,
//! `gpu/<adapter>.json` and its charts.

use crate::gpu::bench::{self, Plan};
use crate::gpu::check::Verdict;
use crate::gpu::{study, Adapter, Gpu};
use crate::report::document::Document;
use crate::stack::DepthStack;
use anyhow::{bail, Result};
use serde::Serialize;
use std::path::Path;

/// What the step found.
#[derive(Clone, Debug, Serialize)]
pub struct Outcome {
    /// The adapter the step ran on (None when there is none).
    pub adapter: Option<Adapter>,
    /// Why the step was skipped (no adapter), or empty.
    pub skipped: String,
    /// The GPU check's comparison of each setting.
    pub verdicts: Vec<Verdict>,
    /// The bench's file stem under `gpu/` (charts `<stem>_{size,filter,output}.svg`).
    pub bench: Option<String>,
}

/// Receivers per view of the check.
const RECEIVERS: usize = 4000;

/// Run the step into `dir` (the run's `gpu/` folder).
pub fn run(stacks: &[DepthStack], dir: &Path) -> Result<Outcome> {
    let gpu = match Gpu::new() {
        Ok(g) => g,
        Err(e) => {
            eprintln!("  GPU step skipped: {e}");
            return Ok(Outcome {
                adapter: None,
                skipped: e.to_string(),
                verdicts: vec![],
                bench: None,
            });
        }
    };
    eprintln!("  {}", gpu.adapter.label());
    let mut verdicts = Vec::new();
    for (i, s) in study::settings().iter().enumerate() {
        let stack = &stacks[(3 * i) % stacks.len()];
        verdicts.push(study::check_setting(&gpu, s, None, stack, RECEIVERS)?);
    }
    crate::artefact::write_json(&dir.join("check.json"), &verdicts)?;
    if let Some(f) = verdicts.iter().find_map(|v| v.failure()) {
        bail!("GPU check: {f}");
    }
    let plan = Plan {
        sizes: vec![256, 512, 1024],
        filters: vec![3, 9, 15],
        outputs: vec![128, 256],
        base: (512, 9, 256),
        repeats: 3,
        repeats_large: 3,
        large_from: usize::MAX,
    };
    let view = stacks
        .iter()
        .max_by_key(|s| s.fragment_count())
        .expect("a run has views");
    let report = bench::run(&gpu, &plan, &study::settings(), view, |_| {})?;
    let stem = gpu.adapter.file_stem();
    crate::artefact::write_json(&dir.join(format!("{stem}.json")), &report)?;
    for (axis, svg) in crate::report::gpu::gpu_charts(&report)? {
        crate::artefact::write_text(&dir.join(format!("{stem}_{axis}.svg")), &svg)?;
    }
    Ok(Outcome {
        adapter: Some(gpu.adapter),
        skipped: String::new(),
        verdicts,
        bench: Some(stem),
    })
}

/// The report's GPU section.
pub fn section(doc: &mut Document, o: &Outcome) {
    doc.heading("On a GPU");
    let Some(a) = &o.adapter else {
        doc.paragraph(format!(
            "The GPU step was skipped: {}. The CPU study above does not need a GPU; \
             `momentlab gpu check` and `momentlab gpu bench` run the same pipeline where there \
             is one.",
            o.skipped.trim_end_matches('.')
        ));
        return;
    };
    let passed = o.verdicts.iter().filter(|v| v.passed).count();
    let worst_map = o.verdicts.iter().map(|v| v.map_steps).fold(0.0, f64::max);
    let worst_encode = o
        .verdicts
        .iter()
        .filter(|v| v.encode_bound > 1.0)
        .map(|v| v.encode_steps)
        .fold(0.0, f64::max);
    doc.paragraph(format!(
        "Adapter: {} ({}). The shadow-map pipeline of every technique × storage — encode, the \
         separable 9×9 Gaussian as two passes each stored in the format, the lookup of every \
         fragment — ran on this driver from the emitted WGSL and was compared with momentlab's \
         CPU model of the same pipeline: {passed} of {} settings agree (encoded f32 maps within \
         {worst_encode:.0} ulp, the encoders' built-ins not being correctly rounded; filtered \
         maps within {worst_map:.1} storage step of the model's filtering of the GPU's encoded \
         map; G within 10⁻⁵ plus four times each fragment's rounding \
         sensitivity on all but 0.1 % of fragments).{}",
        a.label(),
        a.driver,
        o.verdicts.len(),
        if a.software {
            " This adapter is a software rasterizer: its times below are CPU times and rank \
             shader cost only roughly."
        } else {
            ""
        }
    ));
    if let Some(stem) = &o.bench {
        for (axis, what) in [
            ("size", "shadow-map size"),
            ("filter", "filter size"),
            ("output", "output resolution"),
        ] {
            doc.figure(
                format!("gpu/{stem}_{axis}.svg"),
                format!(
                    "Time of encode, filter and lookup against {what} (median of 3 runs), one line \
                     per technique × storage: the analogue of the paper's Figure 7. Read which \
                     techniques cost more as the {what} grows."
                ),
            );
        }
    }
}
