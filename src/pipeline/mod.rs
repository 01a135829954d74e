//! The study as library code: a typed [`Config`] and the steps of a run, each resumable by its
//! artefacts (a step whose files exist is read back instead of recomputed; `fresh` starts over).
//! A run marks its report folder as its own ([`IN_PROGRESS`]) until it finishes: a run that
//! finds its own mark resumes; a folder holding anything else (a finished run, other files) is
//! refused unless `fresh` (`--force`), which first removes the run's own artefacts
//! ([`remove_artefacts`]).
//!
//! ```text
//! 1 stacks      render (or read back) the depth stacks          results/<run>/stacks/
//! 2 techniques  every technique against PCF on the same fragments, speed, light-view and
//!               eye-view pictures                   <reports>/<run>/evaluate/, pictures/, eye/
//! 3 grid        LP grid refinement per scene                    grid_refinement.{json,svg}
//! 4 sweep       candidate sweeps (racing)                       results/<run>/search-m<m>/, search/
//! 5 theta       optimal quantization transforms θ               theta/
//! 6 quantize    8/16/32-bit moment shadow maps                  quantize/
//! 7 stability   where each technique fails                      stability/
//! 8 recommend   speed against accuracy, per-scene recommendation speed_accuracy.svg, recommend.json,
//!               tuned technique × storage × biases per scene       tune/tune.json
//! 9 report      index.html + report.md
//! ```
//!
//! `<reports>` is `results/reports` by default (untracked); the committed report is the run
//! with `reports`. `momentlab reproduce` is a thin caller of [`run`].

pub mod config;
pub mod gpu;
pub mod grid;
pub mod progress;
pub mod quantize;
pub mod recommend;
pub mod report;
pub mod stability;
pub mod stacks;
pub mod sweep;
pub mod techniques;
pub mod theta;

pub use config::{Config, Plan, Preset};

use crate::artefact::OutDir;
use crate::report::recommend::Recommendation;
use anyhow::{bail, Context, Result};
use progress::{pct, Steps};
use std::path::PathBuf;

/// The folders of a run.
#[derive(Clone, Debug)]
pub struct Paths {
    /// `<reports>/<run>`: the report and the small artefacts.
    pub out: PathBuf,
    /// `<results>/<run>`: stacks and sweep rows.
    pub data: PathBuf,
    /// `<results>/<run>/stacks`: the rendered depth stacks.
    pub stacks: PathBuf,
}

impl Paths {
    /// The folders of the run `cfg`.
    pub fn of(cfg: &Config) -> Paths {
        let data = cfg.data_dir();
        Paths {
            out: cfg.report_dir(),
            stacks: data.join("stacks"),
            data,
        }
    }
}

/// What a finished run returns.
#[derive(Clone, Debug)]
pub struct Outcome {
    /// `<reports>/<run>/index.html`.
    pub report: PathBuf,
    /// The recommendation per scene.
    pub recommendations: Vec<Recommendation>,
    /// Wall time of the run, seconds.
    pub seconds: f64,
}

/// The mark of an unfinished run in its report folder (removed when the run finishes).
pub const IN_PROGRESS: &str = ".momentlab-run.json";

/// What [`IN_PROGRESS`] records: a run resumes only a run of the same configuration.
fn mark(cfg: &Config, plan: &Plan) -> serde_json::Value {
    serde_json::json!({
        "run": cfg.run,
        "configuration": cfg.preset.name(),
        "resolution": plan.resolution,
        "tolerance": cfg.tolerance,
        "skip_search": cfg.skip_search,
    })
}

/// The entries of a report folder that a run writes (the top level of `<reports>/<run>`).
pub const REPORT_ENTRIES: [&str; 19] = [
    IN_PROGRESS,
    "gpu",
    "grid_refinement.json",
    "grid_refinement.svg",
    "evaluate",
    "pictures",
    "eye",
    "search",
    "theta",
    "quantize",
    "stability",
    "speed_accuracy.svg",
    "error_histograms.svg",
    "tmsm_geometry.svg",
    "recommend.json",
    "tune",
    "index.html",
    "report.md",
    "run.json",
];

/// Whether `name` is an entry of a data folder that a run writes (the top level of
/// `<results>/<run>`): `stacks` and the sweeps' `search-m<m>`.
pub fn is_data_entry(name: &str) -> bool {
    name == "stacks"
        || name
            .strip_prefix("search-m")
            .is_some_and(|m| !m.is_empty() && m.bytes().all(|b| b.is_ascii_digit()))
}

/// What `fresh` (`--force`) removes before a run, each through its folder's writer (a link is
/// removed, never followed): the [`REPORT_ENTRIES`] of the report folder `out` and the
/// [`is_data_entry`] entries of the data folder `data`. Other files and the folders
/// themselves (with their locks) stay.
pub fn remove_artefacts(out: &OutDir, data: &OutDir) -> Result<()> {
    for name in REPORT_ENTRIES {
        out.remove_all(name)?;
    }
    let entries = match std::fs::read_dir(data.root()) {
        Ok(rd) => rd
            .collect::<std::io::Result<Vec<_>>>()
            .with_context(|| format!("reading {}", data.root().display()))?,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Vec::new(),
        Err(e) => return Err(e).with_context(|| format!("reading {}", data.root().display())),
    };
    for e in entries {
        if let Some(name) = e.file_name().to_str().filter(|n| is_data_entry(n)) {
            data.remove_all(name)?;
        }
    }
    Ok(())
}

/// The steps write into the entries of the run's folders ([`REPORT_ENTRIES`],
/// [`is_data_entry`]): a symbolic link among them (planted in a resumed run) is an error, so
/// that no step follows it out of the folder.
fn refuse_linked_entries(out: &OutDir, data: &OutDir) -> Result<()> {
    let data_entries: Vec<String> = match std::fs::read_dir(data.root()) {
        Ok(rd) => rd
            .filter_map(|e| e.ok()?.file_name().into_string().ok())
            .filter(|n| is_data_entry(n))
            .chain(["stacks".to_string()])
            .collect(),
        Err(_) => vec!["stacks".to_string()],
    };
    let report = REPORT_ENTRIES.iter().map(|n| (out.root(), n.to_string()));
    let data_paths = data_entries.into_iter().map(|n| (data.root(), n));
    for (root, name) in report.chain(data_paths) {
        let p = root.join(&name);
        if std::fs::symlink_metadata(&p).is_ok_and(|m| m.file_type().is_symlink()) {
            bail!(
                "{}: is a symbolic link; refusing to follow it out of {} (remove it, or pass \
                 --force to replace the run's outputs)",
                p.display(),
                root.display()
            );
        }
    }
    Ok(())
}

/// The first setting of `new` that `old` holds otherwise, as "key = old (this run: new)".
fn first_difference(old: &serde_json::Value, new: &serde_json::Value) -> String {
    let null = serde_json::Value::Null;
    new.as_object()
        .and_then(|o| o.iter().find(|(k, v)| old.get(k.as_str()) != Some(*v)))
        .map_or("unknown".to_string(), |(k, v)| {
            format!(
                "{k} = {} (this run: {v})",
                old.get(k.as_str()).unwrap_or(&null)
            )
        })
}

/// The LP grid step: the refinement of every scene's grid (`grid_refinement.json` and `.svg`
/// in `out`) and the smallest n per scene within `tolerance` of the finest grid.
fn lp_grids(
    stacks: &[crate::stack::DepthStack],
    plan: &Plan,
    tolerance: f64,
    out: &std::path::Path,
) -> Result<(grid::Refinement, Vec<(String, usize)>)> {
    let refinement = grid::refine(stacks, plan, &out.join("grid_refinement.json"), tolerance)?;
    let chosen = grid::choose(&refinement, tolerance);
    grid::chart(&refinement, &chosen, &out.join("grid_refinement.svg"))?;
    Ok((refinement, chosen))
}

/// The candidate sweeps (racing) of the run, or a note that they were skipped.
fn search_step(
    cfg: &Config,
    stacks: &[crate::stack::DepthStack],
    plan: &Plan,
    p: &Paths,
    report: &std::path::Path,
) -> Result<Vec<String>> {
    if cfg.skip_search {
        return Ok(vec!["skipped (--skip-search)".to_string()]);
    }
    sweep::run_all(
        stacks,
        plan,
        &sweep::Folders {
            stacks: &p.stacks,
            data: &p.data,
            report,
        },
    )
}

/// The run's report and data folders (`p.out`, `p.data`), locked for this run and ready:
/// refused unless empty, this run's own unfinished run, or `cfg.fresh` (which removes the
/// run's artefacts); marked in progress.
fn open_run(cfg: &Config, plan: &Plan, p: &Paths) -> Result<[OutDir; 2]> {
    // The run's folders are real folders inside --out and --results: a link there is refused,
    // never followed out of them.
    for root in [&cfg.reports, &cfg.results] {
        OutDir::new(root, true)?
            .create_dir(&cfg.run)
            .with_context(|| format!("run folder '{}'", cfg.run))?;
    }
    // One run per folder pair: a second `reproduce` of the same run waits for no one, it is
    // refused (both folders are locked until this run ends).
    let out = OutDir::new(&p.out, true)?;
    let locks = [out, OutDir::new(&p.data, true)?];
    for l in &locks {
        l.lock()?;
    }
    // Before any work: the report folder is empty, or holds this run's own unfinished run, or
    // `fresh` removes the run's artefacts ([`remove_artefacts`]). (Otherwise the data folder
    // only grows: a complete set of stacks is read back, the sweeps resume their own rows and
    // refuse rows of another configuration.)
    let out = &locks[0];
    let marker = crate::artefact::read_json::<serde_json::Value>(&p.out.join(IN_PROGRESS)).ok();
    let own = marker.as_ref() == Some(&mark(cfg, plan));
    if let (false, false, Some(m)) = (cfg.fresh, own, &marker) {
        bail!(
            "{} holds an unfinished run with other settings: {}; rerun it with its settings \
             to resume, or pass --force to replace its outputs",
            p.out.display(),
            first_difference(m, &mark(cfg, plan))
        );
    }
    if !cfg.fresh && !own {
        if let Some(f) = out.first_file(&[])? {
            bail!(
                "{} exists already (pass --force to replace the run's outputs)",
                f.display()
            );
        }
    }
    if cfg.fresh {
        remove_artefacts(out, &locks[1])?;
    }
    for l in &locks {
        l.create_dir(".")?;
    }
    refuse_linked_entries(out, &locks[1])?;
    out.write_json(IN_PROGRESS, &mark(cfg, plan))?;
    Ok(locks)
}

/// Run (or resume) the whole study.
pub fn run(cfg: &Config) -> Result<Outcome> {
    let plan = cfg.plan()?;
    let p = Paths::of(cfg);
    let locks = open_run(cfg, &plan, &p)?;
    let out = &locks[0];
    let mut step = Steps::new(10);

    step.start(&format!(
        "render the default dataset at {0}×{0}",
        plan.resolution
    ));
    let stacks = stacks::load_or_render(&p.stacks, plan.resolution)?;
    let fragments: usize = stacks.iter().map(|s| s.fragment_count()).sum();
    eprintln!("  {} views, {fragments} fragments", stacks.len());

    step.start("LP grid: the smallest n within tolerance of the finest grid");
    let (refinement, chosen_grid) = lp_grids(&stacks, &plan, cfg.tolerance / 10.0, &p.out)?;
    // The LP candidates run on the finest grid any scene needs.
    let lp_grid = chosen_grid
        .iter()
        .map(|x| x.1)
        .max()
        .unwrap_or(crate::technique::lp_candidate::DEFAULT_GRID_POINTS);
    step.start(&format!(
        "closed forms, baselines and LP candidates (n = {lp_grid}) against PCF"
    ));
    let all = techniques::evaluate_all(&stacks, &plan, &p.out.join("evaluate"), lp_grid)?;
    let pictures = techniques::pictures(&stacks, &plan, &p.out.join("pictures"))?;
    let eye = techniques::eye_pictures(&stacks, &plan, &p.out.join("eye"), lp_grid)?;

    step.start("candidate sweep (racing)");
    let search_report = p.out.join("search");
    let search_notes = search_step(cfg, &stacks, &plan, &p, &search_report)?;

    step.start("optimal quantization transforms θ");
    let theta_dir = p.out.join("theta");
    let theta_rows = theta::run(&plan, &theta_dir)?;

    step.start("quantized moment shadow maps (8/16/32 bit, θ)");
    quantize::run(&plan, &p.stacks, &theta_dir, &p.out.join("quantize"))?;

    step.start("stability where methods fail");
    stability::run(&plan, &p.out.join("stability"))?;

    step.start("the pipeline on a GPU (check and bench), where there is one");
    let gpu_outcome = gpu::run(&stacks, &p.out.join("gpu"))?;

    step.start("speed against accuracy, the tuned setting per scene");
    let entries = recommend::run(&all, &p.out)?;
    let tuning = recommend::tuning(&stacks, &plan, cfg.tolerance, &p.out)?;
    let recs = recommend::recommend(&tuning, &p.out)?;

    step.start("report");
    let mut doc = report::build(report::ReportInputs {
        plan: &plan,
        config: cfg,
        stacks: &stacks,
        all: &all,
        entries: &entries,
        recs: &recs,
        tuning: &tuning,
        chosen_grid: &chosen_grid,
        refinement: &refinement,
        theta_rows: &theta_rows,
        search_notes: &search_notes,
        search_report: &search_report,
        out: &p.out,
        pictures: &pictures,
        eye: &eye,
        seconds: step.elapsed(),
    })?;
    gpu::section(&mut doc, &gpu_outcome);
    doc.write(out, ".")?;

    let seconds = step.elapsed();
    // The run's provenance and wall time (README's quick-start figures read it).
    crate::artefact::write_json(
        &p.out.join("run.json"),
        &serde_json::json!({
            "run": cfg.run,
            "configuration": cfg.preset.name(),
            "seconds": seconds,
            "provenance": crate::report::provenance::Provenance::current(),
        }),
    )?;
    // Finished: the folder is no longer an unfinished run to resume.
    out.remove(IN_PROGRESS)?;
    eprintln!("\nSummary ({seconds:.0} s):");
    for r in &recs {
        eprintln!(
            "  {:<8} tuned: {}, error {} (best {} by {}), noise above 1/255 on {}",
            r.scene,
            r.setting,
            pct(r.error),
            pct(r.best_error),
            r.best_name,
            pct(r.noise_share)
        );
    }
    Ok(Outcome {
        report: p.out.join("index.html"),
        recommendations: recs,
        seconds,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::fs;
    use std::os::unix::fs::symlink;

    use crate::artefact::out::tests::listing;

    #[test]
    fn force_removes_only_the_runs_artefacts_and_follows_no_link() {
        let root = std::env::temp_dir().join(format!("momentlab-fresh-{}", std::process::id()));
        let _ = fs::remove_dir_all(&root);
        let (report, data, outside) = (root.join("report"), root.join("data"), root.join("out"));
        for d in [
            report.join("theta"),
            data.join("stacks"),
            data.join("search-m3"),
            outside.join("sub"),
        ] {
            fs::create_dir_all(d).unwrap();
        }
        fs::write(outside.join("sub/precious"), "x").unwrap();
        fs::write(report.join("index.html"), "").unwrap();
        fs::write(report.join("theta/theta2.json"), "").unwrap();
        fs::write(report.join("user.txt"), "").unwrap();
        symlink(&outside, report.join("tune")).unwrap();
        fs::write(data.join("stacks/a_b.exr"), "").unwrap();
        symlink(&outside, data.join("stacks/inner")).unwrap();
        fs::write(data.join("search-m3/results.jsonl"), "").unwrap();
        symlink(&outside, data.join("search-m4")).unwrap();
        symlink(&outside, data.join("mine")).unwrap();
        fs::write(data.join("notes.txt"), "").unwrap();
        fs::write(data.join("search-mx"), "").unwrap();
        remove_artefacts(
            &OutDir::new(&report, true).unwrap(),
            &OutDir::new(&data, true).unwrap(),
        )
        .unwrap();
        assert_eq!(listing(&report), vec!["user.txt"]);
        assert_eq!(listing(&data), vec!["mine", "notes.txt", "search-mx"]);
        assert_eq!(listing(&outside), vec!["sub"]);
        assert_eq!(
            fs::read_to_string(outside.join("sub/precious")).unwrap(),
            "x"
        );
        fs::remove_dir_all(&root).unwrap();
    }

    #[test]
    fn the_first_differing_setting_is_named() {
        let old = serde_json::json!({"resolution": 128, "skip_search": false, "tiny": true});
        let new = serde_json::json!({"resolution": 128, "skip_search": true, "tiny": true});
        assert_eq!(
            first_difference(&old, &new),
            "skip_search = false (this run: true)"
        );
        assert_eq!(first_difference(&old, &old), "unknown");
    }

    /// A link among the entries a run writes (`evaluate` in the report, `search-m2` in the
    /// data folder) stops the run before any step; other links are not the run's business.
    #[test]
    fn linked_entries_of_a_run_are_refused() {
        let root = std::env::temp_dir().join(format!("momentlab-linked-{}", std::process::id()));
        let _ = fs::remove_dir_all(&root);
        let (report, data, outside) = (root.join("report"), root.join("data"), root.join("out"));
        for d in [&report, &data, &outside] {
            fs::create_dir_all(d).unwrap();
        }
        let dirs = || {
            (
                OutDir::new(&report, true).unwrap(),
                OutDir::new(&data, true).unwrap(),
            )
        };
        symlink(&outside, data.join("mine")).unwrap();
        let (r, d) = dirs();
        assert!(refuse_linked_entries(&r, &d).is_ok());
        for (dir, name) in [
            (&report, "evaluate"),
            (&data, "search-m2"),
            (&data, "stacks"),
        ] {
            symlink(&outside, dir.join(name)).unwrap();
            let (r, d) = dirs();
            let e = refuse_linked_entries(&r, &d).unwrap_err().to_string();
            assert!(e.contains(name) && e.contains("symbolic link"), "{e}");
            fs::remove_file(dir.join(name)).unwrap();
        }
        fs::remove_dir_all(&root).unwrap();
    }
}
