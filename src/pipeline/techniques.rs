//! Step 2: every technique of the study on the same fragments (error against PCF, speed), one
//! artefact `evaluate/<technique>_<precision>.json` each, and the shadow pictures.

use super::progress::{bar, pct};
use super::Plan;
use crate::artefact::{read_json, write_json};
use crate::metrics::eye;
use crate::metrics::{self, Bias, EvalOptions, EvalReport, Subject, Subsample};
use crate::report::pictures;
use crate::report::recommend::{per_scene, Measured, HIST_EDGES};
use crate::stack::DepthStack;
use crate::technique::linalg::Precision;
use crate::technique::lp_candidate::LpCandidate;
use crate::technique::timing::Corpus;
use crate::technique::{self, registry, timing, Technique};
use anyhow::Result;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// The LP candidates of the study (Algorithm 1 with the paper's bases).
pub const LP_CANDIDATES: &[(&str, &str)] = &[
    ("lp:z,z^2", "LP (z, z²)"),
    ("lp:z,z^2,z^3", "LP (z, z², z³)"),
    ("lp:z,z^2,z^3,z^4", "LP b_MSM"),
    ("lp:sin(2πz),cos(2πz),sin(4πz),cos(4πz)", "LP b_TMSM"),
];

/// The closed-form techniques of the study: every registry name except the general
/// `hamburger` (at m = 4 it is `hamburger4`, only slower).
pub fn closed_forms() -> impl Iterator<Item = &'static str> {
    registry::CLOSED_FORM_NAMES
        .iter()
        .copied()
        .filter(|&n| n != "hamburger")
}

/// One evaluation of the study: a technique at a storage precision, the fragments it sees
/// (every `stride`-th) and the random inputs of its speed measurement.
pub struct Job {
    /// Technique spec name.
    pub name: String,
    /// Moment storage precision ("f32", "f64").
    pub precision: String,
    /// The technique at that precision.
    pub technique: Box<dyn Technique>,
    /// Evaluate every `stride`-th fragment.
    pub stride: usize,
    /// Fragments of the speed measurement.
    pub speed_inputs: usize,
}

/// The jobs of a plan: closed forms at f32 and f64, the LP candidates at f64 on `lp_grid`
/// uniform points.
pub fn jobs(plan: &Plan, lp_grid: usize) -> Result<Vec<Job>> {
    let mut jobs = Vec::new();
    for name in closed_forms() {
        for prec in [Precision::F32, Precision::F64] {
            let technique = match registry::build(name, &registry::Params::with(prec, None)) {
                Ok(t) => t,
                Err(_) => technique::by_name(name)?,
            };
            jobs.push(Job {
                name: name.into(),
                precision: prec.name().into(),
                technique,
                stride: 1,
                speed_inputs: plan.speed_inputs,
            });
        }
    }
    for &(spec, _) in LP_CANDIDATES {
        let list = spec.strip_prefix("lp:").unwrap_or(spec);
        jobs.push(Job {
            name: spec.into(),
            precision: "f64".into(),
            technique: Box::new(LpCandidate::from_spec_on(list, lp_grid)?),
            stride: plan.lp_stride,
            speed_inputs: plan.lp_speed_inputs,
        });
    }
    Ok(jobs)
}

/// The artefact file of a job: the name with non-alphanumerics replaced.
pub fn artefact_name(name: &str, precision: &str) -> String {
    let safe: String = name
        .replace('π', "pi")
        .chars()
        .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
        .collect();
    format!("{safe}_{precision}.json")
}

/// Every job, read back from `dir` when its artefact exists, otherwise measured and written.
/// LP candidates run on `lp_grid` points (their artefact names carry it, so a different grid
/// is measured afresh). The jobs left to measure are evaluated together per stride
/// ([`metrics::evaluate_subjects`]): each view's fragments and their PCF reference, most of
/// the work of a closed form, are built once for all of them.
pub fn evaluate_all(
    stacks: &[DepthStack],
    plan: &Plan,
    dir: &Path,
    lp_grid: usize,
) -> Result<Vec<Measured>> {
    let jobs = jobs(plan, lp_grid)?;
    let files: Vec<PathBuf> = jobs
        .iter()
        .map(|j| {
            let stem = if j.name.starts_with("lp:") {
                format!("{} n{lp_grid}", j.name)
            } else {
                j.name.clone()
            };
            dir.join(artefact_name(&stem, &j.precision))
        })
        .collect();
    let mut all: Vec<Option<Measured>> = files.iter().map(|f| read_json(f).ok()).collect();
    let mut strides: Vec<usize> = Vec::new();
    let mut corpora = Corpora::default();
    for (j, m) in jobs.iter().zip(&all) {
        if m.is_none() && !strides.contains(&j.stride) {
            strides.push(j.stride);
        }
    }
    for stride in strides {
        let group: Vec<usize> = (0..jobs.len())
            .filter(|&i| all[i].is_none() && jobs[i].stride == stride)
            .collect();
        let subjects: Vec<Subject> = group
            .iter()
            .map(|&i| Subject::Technique(jobs[i].technique.as_ref()))
            .collect();
        let names: Vec<&str> = group.iter().map(|&i| jobs[i].name.as_str()).collect();
        let reports = evaluate(stacks, &subjects, &names, stride)?;
        for (&i, r) in group.iter().zip(reports) {
            let corpus = corpora.get(stacks, jobs[i].speed_inputs)?;
            let m = measured(&jobs[i], corpus, &r);
            write_json(&files[i], &m)?;
            all[i] = Some(m);
        }
    }
    let all: Vec<Measured> = all.into_iter().flatten().collect();
    for m in &all {
        eprintln!(
            "  {:<44} {}  error {:>9}  {:>9.1} ns/fragment  {} bit/texel",
            m.name,
            m.precision,
            pct(m.error),
            m.ns_per_fragment,
            m.bits_per_texel
        );
    }
    Ok(all)
}

/// Evaluate `subjects` (named `names`) on every `stride`-th fragment of the stacks, with one
/// progress bar, counting |G − PCF| in the bins of [`HIST_EDGES`].
pub(super) fn evaluate(
    stacks: &[DepthStack],
    subjects: &[Subject<'_>],
    names: &[&str],
    stride: usize,
) -> Result<Vec<EvalReport>> {
    let label = match names {
        [one] => one.to_string(),
        _ => format!("{} techniques", names.len()),
    };
    let b = Arc::new(bar(0, &label));
    let bb = b.clone();
    let opts = EvalOptions {
        bias: Bias::default(),
        subsample: if stride > 1 {
            Subsample::Stride(stride)
        } else {
            Subsample::All
        },
        histogram: Some(Arc::from(&HIST_EDGES[..])),
        progress: Some(Arc::new(move |done, total| {
            bb.set_total(total as u64);
            bb.set_done(done as u64);
        })),
        ..Default::default()
    };
    let r = metrics::evaluate_subjects(stacks, subjects, &opts)?;
    b.finish();
    Ok(r)
}

/// The speed corpora of the jobs (filter windows of real fragments,
/// [`crate::metrics::windows::stacks_corpus`]), one per size, built on first use: the same
/// seed draws the same windows for every job of that size.
#[derive(Default)]
struct Corpora(Vec<(usize, Corpus)>);

impl Corpora {
    fn get(&mut self, stacks: &[DepthStack], count: usize) -> Result<&Corpus> {
        let k = match self.0.iter().position(|(n, _)| *n == count) {
            Some(k) => k,
            None => {
                let c = crate::metrics::windows::stacks_corpus(stacks, count, SPEED_SEED)?;
                self.0.push((count, c));
                self.0.len() - 1
            }
        };
        Ok(&self.0[k].1)
    }
}

/// Seed of the speed corpora.
const SPEED_SEED: u64 = 2015;

/// The artefact of `job` from its evaluation `r` (error against PCF, error histogram) and its
/// speed: mean ns over `corpus`, `job.speed_inputs` filter windows of real fragments (the same
/// kind of input as the error).
fn measured(job: &Job, corpus: &Corpus, r: &EvalReport) -> Measured {
    let t = job.technique.as_ref();
    let histogram = crate::report::recommend::histogram_of(r);
    let ns = timing::measure(t, corpus, 3).mean;
    Measured {
        name: job.name.clone(),
        precision: job.precision.clone(),
        // f64 storage doubles the texel size of the f32 layout the techniques report.
        bits_per_texel: if job.precision == "f64" {
            2 * t.bits_per_texel()
        } else {
            t.bits_per_texel()
        },
        ns_per_fragment: ns,
        error: r.error,
        fragments: r.fragments,
        trivial: r.trivial,
        non_finite: r.non_finite,
        unsettled: r.unsettled,
        seconds: r.seconds,
        scenes: per_scene(r),
        histogram,
        error_scaled: Some(r.error_scaled),
        leak: Some(r.leak),
    }
}

/// The `plan.pictures` evenly spaced views of the pictures.
fn picture_views<'a>(stacks: &'a [DepthStack], plan: &Plan) -> Vec<&'a DepthStack> {
    stacks
        .iter()
        .step_by((stacks.len() / plan.pictures.max(1)).max(1))
        .take(plan.pictures)
        .collect()
}

/// Hamburger 4MSM pictures of `plan.pictures` evenly spaced views into `dir` (kept when they
/// exist); returns (path relative to the report, caption).
pub fn pictures(stacks: &[DepthStack], plan: &Plan, dir: &Path) -> Result<Vec<(String, String)>> {
    let h4 = technique::by_name("hamburger4")?;
    let mut files = Vec::new();
    for st in picture_views(stacks, plan) {
        let name = format!("{}_{}_hamburger4.png", st.meta.scene, st.meta.view);
        let p = dir.join(&name);
        if !p.exists() {
            let sh = metrics::front_shadows(st, Subject::Technique(h4.as_ref()), &Bias::default())?;
            pictures::write_png(&p, &pictures::view_picture(st, &sh)?)?;
        }
        files.push((
            format!("pictures/{name}"),
            format!("{} / {}", st.meta.scene, st.meta.view),
        ));
    }
    Ok(files)
}

/// One eye-view picture of the report.
#[derive(Clone, Debug)]
pub struct EyeFigure {
    /// Technique name as evaluated ("pcf", "hamburger4", "lp:z,z^2", …).
    pub technique: String,
    /// "scene / view".
    pub view: String,
    /// Path relative to the report.
    pub file: String,
}

/// Eye-view resolution of the pipeline: [`eye::DEFAULT_RESOLUTION`], or the shadow-map
/// resolution when that is smaller.
pub fn eye_resolution(plan: &Plan) -> usize {
    plan.resolution.min(eye::DEFAULT_RESOLUTION)
}

/// Eye-view pictures (PCF-shaded | technique-shaded | |difference| with colour bar, each
/// view's default camera) of the views of [`pictures`] for PCF, every closed form and every LP
/// candidate (on `lp_grid` points) into `dir` as `<scene>_<view>_<technique>.png` (kept when
/// they exist). The stacks are the default dataset's.
pub fn eye_pictures(
    stacks: &[DepthStack],
    plan: &Plan,
    dir: &Path,
    lp_grid: usize,
) -> Result<Vec<EyeFigure>> {
    let scenes = crate::render::embedded_scenes()?;
    let mut subjects: Vec<(String, Option<Box<dyn Technique>>)> = vec![("pcf".into(), None)];
    for name in closed_forms() {
        subjects.push((name.into(), Some(technique::by_name(name)?)));
    }
    for &(spec, _) in LP_CANDIDATES {
        let list = spec.strip_prefix("lp:").unwrap_or(spec);
        subjects.push((
            spec.into(),
            Some(Box::new(LpCandidate::from_spec_on(list, lp_grid)?)),
        ));
    }
    let bias = Bias::default();
    let views = picture_views(stacks, plan);
    let b = bar((views.len() * subjects.len()) as u64, "eye-view pictures");
    let mut out = Vec::new();
    for st in views {
        let Some((sc, light)) = eye::light_of(&scenes, st)? else {
            continue;
        };
        let mut cmp = None;
        for (name, t) in &subjects {
            let stem = if name.starts_with("lp:") {
                format!("{name} n{lp_grid}")
            } else {
                name.clone()
            };
            let file = format!(
                "{}_{}_{}",
                st.meta.scene,
                st.meta.view,
                artefact_name(&stem, "eye").replace(".json", ".png")
            );
            let p = dir.join(&file);
            if !p.exists() {
                if cmp.is_none() {
                    cmp = Some(eye::EyeComparison::new(
                        sc,
                        light,
                        st,
                        &bias,
                        eye_resolution(plan),
                    )?);
                }
                let c = cmp.as_ref().expect("set above");
                let subject = match t {
                    Some(t) => Subject::Technique(t.as_ref()),
                    None => Subject::Pcf,
                };
                pictures::write_png(&p, &pictures::eye_comparison(c, st, subject, &bias)?)?;
            }
            b.inc(1);
            out.push(EyeFigure {
                technique: name.clone(),
                view: format!("{} / {}", st.meta.scene, st.meta.view),
                file: format!("eye/{file}"),
            });
        }
    }
    b.finish();
    Ok(out)
}
