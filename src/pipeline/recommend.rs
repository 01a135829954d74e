//! Step 8: speed against accuracy (`speed_accuracy.svg`, Pareto front), the tuned setting per
//! scene (`tune/tune.json`: technique × storage × biases, [`crate::tune`]) and the
//! recommendation per scene, which is the tuned setting (`recommend.json`).

use crate::artefact::{write_json, write_text, Checkpoint, OutDir};
use crate::progress::Bar;
use crate::report::chart;
use crate::report::pareto::Entry;
use crate::report::recommend::{recommendations, Measured, Recommendation};
use crate::stack::DepthStack;
use crate::tune::{self, Options, Tuning};
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

/// Write the speed–accuracy chart and the error histograms into `out`; return the chart's
/// entries.
pub fn run(all: &[Measured], out: &Path) -> Result<Vec<Entry>> {
    let entries = entries(all);
    write_text(
        &out.join("speed_accuracy.svg"),
        &chart::speed_accuracy_svg(
            "Error against PCF vs cost per fragment (marker size: bits per texel)",
            &entries,
        )?,
    )?;
    let hists: Vec<(String, Vec<u64>)> = all
        .iter()
        .filter(|m| m.precision == "f32" || m.name.starts_with("lp:"))
        .map(|m| (format!("{} ({})", m.name, m.precision), m.histogram.clone()))
        .collect();
    write_text(
        &out.join("error_histograms.svg"),
        &chart::histograms_svg(
            "Distribution of |G − PCF| over fragments (log counts)",
            &hists,
        )?,
    )?;
    // The TMSM construction (docs/tmsm.md) on one example distribution.
    write_text(
        &out.join("tmsm_geometry.svg"),
        &crate::report::tmsm_figure::svg()?,
    )?;
    Ok(entries)
}

/// The recommendation per scene, `tune`'s answer, written to `out/recommend.json`.
pub fn recommend(t: &Tuning, out: &Path) -> Result<Vec<Recommendation>> {
    let recs = recommendations(t);
    write_json(&out.join("recommend.json"), &recs)?;
    Ok(recs)
}

/// The tuning of the run: read back from `out/tune/tune.json` when it exists (same tolerance
/// and sample sizes), otherwise searched on `stacks` and written there with the export of
/// every chosen setting (`out/tune/export/<scene>/`, [`tune::export`]) through one writer on
/// `out` (a linked `tune` or `export` folder is refused before the search). `tune.json` is
/// written last: it marks a finished tuning.
pub fn tuning(
    stacks: &[DepthStack],
    plan: &super::Plan,
    tolerance: f64,
    out: &Path,
) -> Result<Tuning> {
    let file = out.join(TUNE_FILE);
    if let Ok(t) = crate::artefact::read_json::<Tuning>(&file) {
        if t.tolerance == tolerance
            && t.fragments_per_scene == plan.tune_fragments
            && t.max_noise == Options::default().max_noise
        {
            return Ok(t);
        }
    }
    let od = OutDir::new(out, true)?;
    od.reserve(
        tune::export::file_names(EXPORT_DIR, &tune::sample::scene_names(stacks))
            .into_iter()
            .chain([TUNE_FILE.to_string()]),
    )?;
    let opts = Options {
        tolerance,
        fragments_per_scene: plan.tune_fragments,
        screen_per_scene: plan.tune_screen.min(plan.tune_fragments),
        cost: Some(crate::gpu::cost::tune_cost),
        ..Options::default()
    };
    // The search's units in a checkpoint of the report folder, so that a killed run continues
    // the search ([`tune::units`]); a checkpoint of other options is replaced.
    let cp = Checkpoint::open(
        out,
        tune::units::CHECKPOINT,
        tune::units::params(&opts, stacks),
        true,
    )?;
    cp.start()?;
    if cp.resuming() {
        eprintln!(
            "tune: resuming the interrupted search in {}: {} units done",
            cp.dir().display(),
            cp.done()
        );
    }
    let bar = Bar::new("tune", 0);
    let t = tune::tune_with(stacks, &opts, &bar, Some(&cp))?;
    tune::export::write(&od, EXPORT_DIR, &t)?;
    od.write_json(TUNE_FILE, &t)?;
    cp.finish()?;
    Ok(t)
}

/// The tuning file of a run, relative to its report folder.
pub const TUNE_FILE: &str = "tune/tune.json";

/// The export folder of a run's tuning, relative to its report folder.
pub const EXPORT_DIR: &str = "tune/export";

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pipeline::{Plan, Preset};
    use std::fs;

    #[test]
    fn tuning_refuses_a_linked_export_folder_before_the_search() {
        let root = std::env::temp_dir().join(format!("momentlab-tune-link-{}", std::process::id()));
        let _ = fs::remove_dir_all(&root);
        let (out, outside) = (root.join("run"), root.join("outside"));
        fs::create_dir_all(out.join("tune")).unwrap();
        fs::create_dir_all(&outside).unwrap();
        std::os::unix::fs::symlink(&outside, out.join("tune/export")).unwrap();
        let stacks = crate::render::default_dataset(16).unwrap();
        let plan = Plan::of(Preset::Tiny, Some(16));
        let e = format!("{:#}", tuning(&stacks, &plan, 0.002, &out).unwrap_err());
        assert!(e.contains("symbolic link") && e.contains("export"), "{e}");
        assert_eq!(
            fs::read_dir(&outside).unwrap().count(),
            0,
            "written outside"
        );
        assert!(
            !out.join("tune/tune.json").exists(),
            "tuned before the check"
        );
        fs::remove_dir_all(&root).unwrap();
    }

    /// The step keeps its units in a checkpoint while it runs and removes it when `tune.json`
    /// is written; a second call reads the tuning back.
    #[test]
    fn tuning_leaves_no_checkpoint_and_is_read_back() {
        let out = std::env::temp_dir().join(format!("momentlab-tune-cp-{}", std::process::id()));
        let _ = fs::remove_dir_all(&out);
        fs::create_dir_all(&out).unwrap();
        let stacks = crate::render::default_dataset(16).unwrap();
        let plan = Plan::of(Preset::Tiny, Some(16));
        let t = tuning(&stacks, &plan, 0.002, &out).unwrap();
        assert!(out.join(TUNE_FILE).exists());
        assert!(!Checkpoint::exists(&out, tune::units::CHECKPOINT));
        let again = tuning(&stacks, &plan, 0.002, &out).unwrap();
        assert_eq!(again.seconds, t.seconds, "read back, not searched again");
        fs::remove_dir_all(&out).unwrap();
    }
}
