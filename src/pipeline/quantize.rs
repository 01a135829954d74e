//! The quantization study as artefacts (8/16/32-bit moment shadow maps, canonical and θ
//! storage): `quantize.json`, `quantize.md`, `quantize_alpha.svg`. Step 6 of the pipeline
//! ([`run`]) and `momentlab quantize` call these with typed options.

use super::Plan;
use crate::artefact::{Checkpoint, OutDir};
use crate::metrics::{Bias, Subsample};
use crate::quantize::curve::MonomialCurve;
use crate::quantize::study::{self, Sweep, Tech};
use crate::quantize::theta::{verify, Theta};
use crate::report::quantize::{markdown, plot};
use crate::stack::DepthStack;
use anyhow::{bail, Context, Result};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// The files of the study; `quantize.json` is written last, so it marks a finished study.
pub const FILES: [&str; 3] = ["quantize.json", "quantize.md", "quantize_alpha.svg"];

/// What one study runs on.
#[derive(Clone, Debug)]
pub struct Study {
    /// Directory of depth stacks; None: render the embedded default dataset at `resolution`.
    pub stacks: Option<PathBuf>,
    /// Shadow-map resolution of the rendered default dataset.
    pub resolution: usize,
    /// Folder with theta{m}.json for every technique.
    pub theta_dir: PathBuf,
    /// The techniques studied.
    pub techniques: Vec<Tech>,
    /// Evaluate every k-th fragment only.
    pub stride: usize,
    /// Bias strengths α in (0, 1).
    pub alphas: Vec<f64>,
}

/// The written study: the JSON text and the Markdown.
pub struct Written {
    /// The study as JSON.
    pub json: String,
    /// The study as Markdown.
    pub markdown: String,
}

fn load_stacks(s: &Study) -> Result<Vec<DepthStack>> {
    match &s.stacks {
        Some(dir) => crate::stack::load_dir(dir)
            .with_context(|| format!("loading stacks from {}", dir.display())),
        None => {
            eprintln!("rendering the default dataset at {0}×{0} …", s.resolution);
            crate::render::default_dataset(s.resolution)
        }
    }
}

/// Write the Markdown, the plot and then the JSON (the marker of a finished study) into `od`.
fn write(od: &OutDir, json: &serde_json::Value, md: String, all: &[Sweep]) -> Result<Written> {
    od.write_text(FILES[1], &md)?;
    od.write_text(FILES[2], &plot(all)?)?;
    let text = serde_json::to_string_pretty(json)? + "\n";
    od.write_text(FILES[0], &text)?;
    Ok(Written {
        json: text,
        markdown: md,
    })
}

/// The checkpoint of the study in its output folder.
pub const CHECKPOINT: &str = "quantize";

/// Run the study and write [`FILES`] into `od`. Every θ is read and verified before the stacks
/// are loaded or rendered. The sweeps of each technique are kept in the checkpoint
/// [`CHECKPOINT`] of `od`'s folder, valid for the same stacks (by content), θ, techniques,
/// stride and α; a technique found there is not swept again. A checkpoint of other parameters
/// is refused, or with `discard` replaced. The outputs of `od` may exist only where a
/// checkpoint does ([`Checkpoint::exists`]) or `discard`.
pub fn study(s: &Study, od: &OutDir, discard: bool) -> Result<Written> {
    if s.techniques.is_empty() {
        bail!("--technique: empty list");
    }
    let thetas: Vec<_> = s
        .techniques
        .iter()
        .map(|t| load_theta(&s.theta_dir, t.m()))
        .collect::<Result<_>>()?;
    let stacks = load_stacks(s)?;
    if stacks.is_empty() {
        bail!("no depth stacks to evaluate");
    }
    crate::metrics::require_fragments(&stacks)?;
    let sub = if s.stride > 1 {
        Subsample::Stride(s.stride)
    } else {
        Subsample::All
    };
    let views: Vec<String> = stacks
        .iter()
        .map(|v| format!("{}/{} {}", v.meta.scene, v.meta.view, v.digest()))
        .collect();
    let names: Vec<&str> = s.techniques.iter().map(|t| t.name()).collect();
    let params = serde_json::json!({
        "stacks": views, "theta": thetas, "techniques": names, "stride": s.stride,
        "alphas": s.alphas,
    });
    let cp = Checkpoint::open(od.root(), CHECKPOINT, params, discard)?;
    cp.start()?;
    if let Some(note) = cp.note("quantize", s.techniques.len(), "techniques") {
        eprintln!("{note}");
    }
    let t0 = Instant::now();
    let mut all: Vec<Sweep> = Vec::new();
    // The fragments and their PCF reference, built once for every technique still to sweep.
    let mut frags = None;
    for (tech, ours) in s.techniques.iter().zip(&thetas) {
        if let Some(done) = cp.get::<Vec<Sweep>>(tech.name())? {
            all.extend(done);
            continue;
        }
        let configs = study::configs(*tech, ours);
        eprintln!(
            "quantize: {} ({} configurations)...",
            tech.name(),
            configs.len()
        );
        let frags = match &mut frags {
            Some(f) => f,
            None => frags.insert(study::sweep_fragments(&stacks, &Bias::default(), &sub)?),
        };
        let sw = study::sweep_on(&stacks, frags, *tech, &configs, &s.alphas)?;
        cp.put(tech.name(), &sw)?;
        all.extend(sw);
    }
    if all.first().is_none_or(|s| s.fragments == 0) {
        bail!("the depth stacks have no fragments to evaluate (empty or all background)");
    }
    let seconds = t0.elapsed().as_secs_f64();
    let stacks_label = s.stacks.as_ref().map_or_else(
        || format!("default dataset rendered at {0}×{0}", s.resolution),
        |p| p.display().to_string(),
    );
    let usable = study::usability(&all);
    let json = serde_json::json!({
        "stacks": stacks_label, "views": stacks.len(), "stride": s.stride,
        "theta_dir": s.theta_dir,
        "b_star": "1/2 in every moment", "precision": "f64 reconstruction",
        "seconds": seconds, "sweeps": all, "usable_16bit": usable,
    });
    let md = markdown(
        &all,
        &usable,
        &stacks_label,
        stacks.len(),
        s.stride,
        &s.alphas,
    );
    let w = write(od, &json, md, &all)?;
    cp.finish()?;
    eprintln!("quantize: {seconds:.1} s, wrote {}", od.root().display());
    Ok(w)
}

/// Combine the sweeps of existing quantize.json files (same stacks, views and stride) and
/// write [`FILES`] into `od`.
pub fn merge(files: &[&Path], od: &OutDir) -> Result<Written> {
    let mut all: Vec<Sweep> = Vec::new();
    let mut head: Option<(serde_json::Value, serde_json::Value, serde_json::Value)> = None;
    let mut seconds = 0.0;
    for f in files {
        let text =
            crate::artefact::read_text(f, crate::artefact::Limit::ARTEFACT).context("--merge")?;
        let v: serde_json::Value = serde_json::from_str(&text)
            .with_context(|| format!("--merge: parsing {}", f.display()))?;
        let h = (v["stacks"].clone(), v["views"].clone(), v["stride"].clone());
        if head.as_ref().is_some_and(|x| *x != h) {
            bail!(
                "--merge: {} has other stacks, views or stride than the first file",
                f.display()
            );
        }
        head = Some(h);
        seconds += v["seconds"].as_f64().unwrap_or(0.0);
        let sw: Vec<Sweep> = serde_json::from_value(v["sweeps"].clone())
            .with_context(|| format!("--merge: {}: sweeps", f.display()))?;
        for s in sw {
            // One sweep per technique and storage: a file given twice, or two studies of the
            // same setting, would be counted twice.
            if all
                .iter()
                .any(|a| a.technique == s.technique && a.config == s.config)
            {
                bail!(
                    "--merge: {} repeats the sweep of {} with {} (a file given twice?)",
                    f.display(),
                    s.technique,
                    s.config
                );
            }
            all.push(s);
        }
    }
    let (stacks, views, stride) = head.context("--merge: no files")?;
    let alphas = all.first().map(|s| s.alphas.clone()).unwrap_or_default();
    let usable = study::usability(&all);
    let list = files
        .iter()
        .map(|f| f.display().to_string())
        .collect::<Vec<_>>()
        .join(",");
    let json = serde_json::json!({
        "stacks": stacks, "views": views, "stride": stride, "merged_from": list,
        "b_star": "1/2 in every moment", "precision": "f64 reconstruction",
        "seconds": seconds, "sweeps": all, "usable_16bit": usable,
    });
    let label = stacks.as_str().unwrap_or("?").to_string();
    let md = markdown(
        &all,
        &usable,
        &label,
        views.as_u64().unwrap_or(0) as usize,
        stride.as_u64().unwrap_or(1) as usize,
        &alphas,
    );
    write(od, &json, md, &all)
}

/// Step 6: the study on the run's stacks with every θ the run computed, into `out`, unless
/// `out/quantize.json` exists.
pub fn run(plan: &Plan, stacks: &Path, theta_dir: &Path, out: &Path) -> Result<()> {
    if out.join(FILES[0]).exists() {
        return Ok(());
    }
    let techniques: Vec<Tech> = Tech::ALL
        .into_iter()
        .filter(|t| theta_dir.join(format!("theta{}.json", t.m())).is_file())
        .collect();
    if techniques.is_empty() {
        return Ok(());
    }
    let od = OutDir::new(out, true)?;
    let s = Study {
        stacks: Some(stacks.to_path_buf()),
        resolution: plan.resolution,
        theta_dir: theta_dir.to_path_buf(),
        techniques,
        stride: plan.quantize_stride,
        alphas: study::DEFAULT_ALPHAS.to_vec(),
    };
    print!("{}", study(&s, &od, true)?.markdown);
    Ok(())
}

/// θ_m from `dir/theta{m}.json` (written by `momentlab theta`), checked against the exact
/// verifier: θ(b([0,1])) ⊆ [0,1]^m up to 1e-6.
fn load_theta(dir: &Path, m: usize) -> Result<Theta> {
    let p = dir.join(format!("theta{m}.json"));
    if std::fs::symlink_metadata(&p).is_err() {
        bail!(
            "--theta-dir: {} not found (create it with `momentlab theta --m {m} --out {}`)",
            p.display(),
            dir.display()
        );
    }
    let text = crate::artefact::read_text(&p, crate::artefact::Limit::ARTEFACT)?;
    #[derive(serde::Deserialize)]
    struct J {
        basis: Vec<String>,
        matrix: Vec<Vec<f64>>,
        offset: Vec<f64>,
    }
    let j: J = serde_json::from_str(&text).with_context(|| format!("parsing {}", p.display()))?;
    let th = Theta::new(j.basis, j.matrix, j.offset).with_context(|| p.display().to_string())?;
    if th.m() != m {
        bail!("{}: expected m = {m}, got {}", p.display(), th.m());
    }
    let curve = MonomialCurve::power(m)?;
    let v = verify(&th, &curve)?;
    if v.max_violation > 1e-6 {
        bail!(
            "{}: θ(b([0,1])) leaves [0,1]^{m} by {:.2e} (exact verifier)",
            p.display(),
            v.max_violation
        );
    }
    Ok(th)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A file given twice to `--merge` is refused instead of counting its sweeps twice.
    #[test]
    fn merge_refuses_a_sweep_given_twice() {
        let dir = std::env::temp_dir().join(format!("momentlab-qmerge-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        let sweep = |config: &str| study::sample_sweep("vsm", config);
        let file = |name: &str, config: &str| {
            let p = dir.join(name);
            let v = serde_json::json!({"stacks": "s", "views": 1, "stride": 1, "seconds": 1.0,
                "sweeps": [sweep(config)]});
            std::fs::write(&p, v.to_string()).unwrap();
            p
        };
        let (a, b) = (file("a.json", "16-bit"), file("b.json", "32-bit"));
        let od = OutDir::new(dir.join("out"), false).unwrap();
        let Err(e) = merge(&[&a, &a], &od) else {
            panic!("a file given twice was merged")
        };
        let e = format!("{e:#}");
        assert!(e.contains("repeats the sweep of vsm with 16-bit"), "{e}");
        assert!(!dir.join("out").join("quantize.json").exists());
        assert!(merge(&[&a, &b], &od).is_ok());
        let merged: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(dir.join("out/quantize.json")).unwrap())
                .unwrap();
        assert_eq!(merged["sweeps"].as_array().unwrap().len(), 2);
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
