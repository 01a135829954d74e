//! `momentlab evaluate`: error of a technique against PCF over all fragments of the depth
//! stacks (mean |G − PCF|, Peters & Klein 2015, Section 3.2), a table per view, JSON, pictures.

use super::common::{
    fraction, non_negative, require_fragments, resolution, stacks_or_default, technique_list,
    usize_in,
};
use anyhow::{bail, Context, Result};
use momentlab::artefact::{Checkpoint, OutDir};
use momentlab::metrics::eye;
use momentlab::metrics::{self, Bias, EvalOptions, EvalReport, Subject, Subsample};
use momentlab::progress::Bar;
use momentlab::render::{self, Scene};
use momentlab::report::pictures;
use momentlab::stack::DepthStack;
use std::path::PathBuf;
use std::sync::Arc;

#[derive(clap::Args, Debug)]
pub struct Args {
    /// Technique: a closed form (vsm, esm, hamburger4, …), an LP candidate
    /// ("lp:z,z^2,z^3,z^4"), "pcf" (the reference itself; error 0) or "cdf" (the exact CDF
    /// F_Z(z_f − ε′) of the filter window at the technique's biased depth: what a technique
    /// that knew the window exactly would return. It is not a lower bound of any technique's
    /// error; its leak part, mean max(0, PCF − F_Z), is the light every technique leaks
    /// through ε′, printed as "leak"). Repeatable and comma lists (`lp:` specs keep their
    /// commas): each technique is evaluated on the same stacks, one table each; --json then
    /// prints an array of reports.
    #[arg(long, required = true)]
    pub technique: Vec<String>,
    /// Directory of depth-stack files; default: render the embedded default dataset (said so
    /// on stderr).
    #[arg(long)]
    pub stacks: Option<PathBuf>,
    /// Shadow-map resolution when rendering the default dataset (16..=4096).
    #[arg(long, default_value_t = 512, value_parser = resolution())]
    pub resolution: usize,
    /// Output folder: write per view and technique the five-panel light-view PNG and the
    /// eye-view PNG (PCF-shaded | technique-shaded | |difference| with colour bar; needs the
    /// scenes: the embedded dataset or --scenes) into it (see docs/evaluation.md); without it
    /// nothing is written.
    #[arg(long, alias = "pictures")]
    pub out: Option<PathBuf>,
    /// Scenes of the stacks (a folder of scene JSON files, a scene file, or a mesh file with
    /// its light sidecar): the geometry and cameras of the eye-view pictures. Without --stacks
    /// they are rendered at --resolution; with --stacks every stack must be a view of them.
    #[arg(long)]
    pub scenes: Option<PathBuf>,
    /// Eye-view picture resolution in pixels per side (16..=2048).
    #[arg(long, default_value_t = eye::DEFAULT_RESOLUTION, value_parser = usize_in(16, 2048), requires = "out")]
    pub eye_resolution: usize,
    /// Also write, per view and technique, light-view pictures of the first K layers
    /// (`<scene>_<view>_<technique>.layer<k>.png`: layer-k depth | PCF | technique | |error|
    /// with colour bar): where the shadows cast onto layer k fall (K in 1..=64).
    #[arg(long, value_name = "K", value_parser = usize_in(1, 64), requires = "out")]
    pub layer_pictures: Option<usize>,
    /// Replace pictures that already exist in --out (otherwise refused before the evaluation).
    #[arg(long, requires = "out")]
    pub force: bool,
    /// Print the full report as JSON on stdout instead of the table.
    #[arg(long)]
    pub json: bool,
    /// Evaluate every k-th fragment only (quick runs; k ≥ 1).
    #[arg(long, conflicts_with = "sample", value_parser = usize_in(1, u32::MAX as u64))]
    pub stride: Option<usize>,
    /// Evaluate a seeded random fraction of the fragments, e.g. 0.05 (quick runs; in (0, 1]).
    #[arg(long, value_parser = fraction, allow_negative_numbers = true)]
    pub sample: Option<f64>,
    /// Seed of --sample.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Only views whose "scene/view" name contains this string.
    #[arg(long)]
    pub only: Option<String>,
    /// PCF bias ε (in [0, 1]).
    #[arg(long, default_value_t = Bias::default().pcf_epsilon, value_parser = non_negative, allow_negative_numbers = true)]
    pub pcf_epsilon: f64,
    /// PCF receiver-plane slope scale s (in [0, 1000]).
    #[arg(long, default_value_t = Bias::default().slope_scale, value_parser = non_negative, allow_negative_numbers = true)]
    pub slope_scale: f64,
    /// Receiver plane of the PCF test per tap: "lower" (the lower of the fragment's and the
    /// tapped front surface's tangent planes; no self-shadowing on curved meshes) or
    /// "fragment" (the fragment's own tangent plane only).
    #[arg(long, default_value = "lower", value_parser = metrics::Receiver::parse)]
    pub pcf_receiver: metrics::Receiver,
    /// Constant part of the technique bias ε′ (in [0, 1]).
    #[arg(long, default_value_t = Bias::default().technique_epsilon, value_parser = non_negative, allow_negative_numbers = true)]
    pub technique_epsilon: f64,
    /// Slope part of the technique bias ε′, in texels (times |dz/du| + |dz/dv|; in [0, 1000]).
    #[arg(long, default_value_t = Bias::default().technique_slope_scale, value_parser = non_negative, allow_negative_numbers = true)]
    pub technique_slope_scale: f64,
}

fn sanitize(s: &str) -> String {
    s.chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' {
                c
            } else {
                '_'
            }
        })
        .collect()
}

pub fn run(args: Args) -> Result<()> {
    let names = technique_list(&args.technique);
    if names.is_empty() {
        bail!("--technique: no technique named");
    }
    // Every name before any work.
    let techniques: Vec<Option<Box<dyn momentlab::technique::Technique>>> = names
        .iter()
        .map(|spec| match spec.as_str() {
            "pcf" | "cdf" => Ok(None),
            spec => momentlab::technique::by_name(spec)
                .map(Some)
                .with_context(|| format!("--technique {spec}")),
        })
        .collect::<Result<_>>()?;
    let (bias, subsample) = bias_and_subsample(&args)?;
    // The scenes (eye-view geometry) before any rendering or evaluation.
    let scenes: Option<Vec<Scene>> = match (&args.scenes, &args.stacks) {
        (Some(p), _) => Some(render::load_scenes(p, &[], None).context("--scenes")?),
        (None, None) => Some(render::embedded_scenes()?),
        (None, Some(_)) => None,
    };
    let stacks = load_stacks(&args, scenes.as_deref())?;
    let subjects: Vec<Subject> = names
        .iter()
        .zip(&techniques)
        .map(|(name, technique)| match technique {
            Some(t) => Subject::Technique(t.as_ref()),
            None if name == "pcf" => Subject::Pcf,
            None => Subject::Cdf,
        })
        .collect();
    let lights = match (&scenes, &args.out) {
        (Some(sc), Some(_)) => eye_lights(sc, &stacks)?,
        _ => vec![None; stacks.len()],
    };
    let plan = PicturePlan {
        eye_resolution: args.eye_resolution,
        layers: args.layer_pictures.unwrap_or(0),
    };
    // With --out, the checkpoint, then the picture files before the evaluation: no name twice,
    // none replaced without --force (but those an interrupted run of this command wrote).
    let cp = open_checkpoint(&args, &names, (&bias, &subsample), &stacks)?;
    let resuming = cp.as_ref().is_some_and(|c| c.resuming());
    let pictures_out = match &args.out {
        Some(dir) => Some(reserve_pictures(
            dir,
            args.force || resuming,
            &plan,
            &stacks,
            &lights,
            &subjects,
            scenes.is_some(),
        )?),
        None => None,
    };
    if let Some(cp) = &cp {
        cp.start()?;
        let units = stacks.len() * (subjects.len() + 1);
        if let Some(note) = cp.note("evaluate", units, "units (technique × view, pictures)") {
            eprintln!("{note}");
        }
    }
    // Every subject on the same fragments, built once (with their PCF reference).
    let bar = Arc::new(Bar::new(&format!("evaluate {}", names.join(", ")), 0));
    let pb = bar.clone();
    let opts = EvalOptions {
        bias,
        subsample,
        progress: Some(Arc::new(move |done, total| {
            pb.set_total(total as u64);
            pb.set_done(done as u64);
        })),
        ..Default::default()
    };
    let store = cp.as_ref().map(Views);
    let store = store.as_ref().map(|v| v as &dyn metrics::ViewStore);
    let reports = metrics::evaluate_subjects_with(&stacks, &subjects, &opts, store)?;
    bar.finish();
    if reports.iter().any(|r| r.fragments == 0) {
        bail!("no fragment was evaluated (--stride / --sample leave none); nothing to report");
    }
    if !args.json {
        for (k, report) in reports.iter().enumerate() {
            if k > 0 {
                println!();
            }
            print_table(report);
        }
    }
    if let Some(od) = &pictures_out {
        write_pictures(od, &stacks, &lights, &subjects, &bias, &plan, cp.as_ref())?;
    }
    if let Some(cp) = cp {
        cp.finish()?;
    }
    if args.json {
        let text = match reports.as_slice() {
            [one] => serde_json::to_string_pretty(one)?,
            all => serde_json::to_string_pretty(all)?,
        };
        println!("{text}");
    }
    if let Some(r) = reports.iter().find(|r| r.error.is_nan()) {
        bail!(
            "{}: all {} outputs are non-finite, so no error can be given (check the bias \
             and the technique's parameters)",
            r.technique,
            r.non_finite
        );
    }
    Ok(())
}

/// With --out, the checkpoint of the evaluation (not yet started): one unit per technique and
/// view, and one per view's pictures, valid for the same techniques, biases, subsampling,
/// stacks (by content), scenes and picture options.
fn open_checkpoint(
    args: &Args,
    names: &[String],
    (bias, subsample): (&Bias, &Subsample),
    stacks: &[DepthStack],
) -> Result<Option<Checkpoint>> {
    let Some(dir) = &args.out else {
        return Ok(None);
    };
    OutDir::new(dir, args.force).context("--out")?;
    let stack_ids: Vec<String> = stacks
        .iter()
        .map(|s| format!("{}/{} {}", s.meta.scene, s.meta.view, s.digest()))
        .collect();
    let params = serde_json::json!({
        "techniques": names, "bias": bias, "subsample": subsample,
        "stacks": stack_ids, "scenes": args.scenes,
        "eye_resolution": args.eye_resolution, "layer_pictures": args.layer_pictures,
    });
    Ok(Some(
        Checkpoint::open(dir, "evaluate", params, args.force).context("--out")?,
    ))
}

/// The biases (validated) and the fragment subsample of `args`.
fn bias_and_subsample(args: &Args) -> Result<(Bias, Subsample)> {
    let bias = Bias {
        pcf_epsilon: args.pcf_epsilon,
        slope_scale: args.slope_scale,
        technique_epsilon: args.technique_epsilon,
        technique_slope_scale: args.technique_slope_scale,
        receiver: args.pcf_receiver,
    };
    bias.validate()?;
    let subsample = match (args.stride, args.sample) {
        (Some(k), _) => Subsample::Stride(k),
        (None, Some(f)) => Subsample::Random {
            fraction: f,
            seed: args.seed,
        },
        (None, None) => Subsample::All,
    };
    Ok((bias, subsample))
}

/// The stacks to evaluate: the views of --scenes rendered at --resolution (without --stacks),
/// else --stacks or the default dataset; then those --only keeps.
fn load_stacks(args: &Args, scenes: Option<&[Scene]>) -> Result<Vec<DepthStack>> {
    let mut stacks = match (&args.scenes, scenes) {
        (Some(p), Some(sc)) if args.stacks.is_none() => {
            eprintln!(
                "evaluate: rendering the scenes of {} at {1}×{1}",
                p.display(),
                args.resolution
            );
            let st: Vec<DepthStack> = sc
                .iter()
                .flat_map(|s| (0..s.lights.len()).map(move |i| (s, i)))
                .map(|(s, i)| render::try_render_view(s, i, args.resolution))
                .collect::<Result<_>>()?;
            require_fragments(&st, Some(p))?;
            st
        }
        _ => stacks_or_default(args.stacks.as_deref(), args.resolution, "evaluate")?,
    };
    if let Some(only) = &args.only {
        stacks.retain(|s| format!("{}/{}", s.meta.scene, s.meta.view).contains(only.as_str()));
        if stacks.is_empty() {
            bail!("--only '{only}': no view matches");
        }
        require_fragments(&stacks, args.stacks.as_deref())?;
    }
    Ok(stacks)
}

/// The eye view of each stack: its scene and light (checked against the stack's frame).
fn eye_lights<'s>(
    scenes: &'s [Scene],
    stacks: &[DepthStack],
) -> Result<Vec<Option<(&'s Scene, usize)>>> {
    stacks
        .iter()
        .map(|st| match eye::light_of(scenes, st)? {
            Some(l) => Ok(Some(l)),
            None => bail!(
                "--scenes: no scene named '{}' for stack {}/{} (scenes: {})",
                st.meta.scene,
                st.meta.scene,
                st.meta.view,
                scenes
                    .iter()
                    .map(|s| s.name.as_str())
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
        })
        .collect()
}

/// The output folder with every picture name of the run reserved (no name twice, none
/// replaced without `force`); says on stderr when there are no eye views (`has_scenes` false).
fn reserve_pictures(
    dir: &std::path::Path,
    force: bool,
    plan: &PicturePlan,
    stacks: &[DepthStack],
    lights: &[Option<(&Scene, usize)>],
    subjects: &[Subject],
    has_scenes: bool,
) -> Result<OutDir> {
    let od = OutDir::new(dir, force).context("--out")?;
    let mut names = Vec::new();
    for &subject in subjects {
        for (st, light) in stacks.iter().zip(lights) {
            names.extend(plan.names(st, subject, light.is_some()));
        }
    }
    od.reserve(names).context("--out")?;
    if !has_scenes {
        eprintln!(
            "evaluate: no eye-view pictures (they need the scenes of the stacks: pass \
             --scenes)"
        );
    }
    Ok(od)
}

/// The picture file of view `s`: `<scene>_<view>_<technique>.png`.
fn picture_name(s: &DepthStack, subject: Subject) -> String {
    format!(
        "{}_{}_{}.png",
        sanitize(&s.meta.scene),
        sanitize(&s.meta.view),
        sanitize(&subject.name())
    )
}

/// Which pictures a run writes besides the light-view ones.
struct PicturePlan {
    eye_resolution: usize,
    /// Per-layer pictures of the first `layers` layers (0 = none).
    layers: usize,
}

impl PicturePlan {
    /// The files of view `s` and `subject`: the light-view picture, `.eye.png` (when the view
    /// has its scene; not for cdf, which has no shadow map) and `.layer<k>.png`.
    fn names(&self, s: &DepthStack, subject: Subject, has_scene: bool) -> Vec<String> {
        let base = picture_name(s, subject);
        let stem = base.trim_end_matches(".png");
        let mut v = vec![base.clone()];
        if has_scene && !matches!(subject, Subject::Cdf) {
            v.push(format!("{stem}.eye.png"));
        }
        for k in 0..self.layers.min(s.depth.len()) {
            v.push(format!("{stem}.layer{k}.png"));
        }
        v
    }
}

/// The units of an evaluation kept in its checkpoint.
struct Views<'a>(&'a Checkpoint);

impl metrics::ViewStore for Views<'_> {
    fn get(&self, key: &str) -> Result<Option<metrics::ViewReport>> {
        self.0.get(key)
    }
    fn put(&self, key: &str, report: &metrics::ViewReport) -> Result<()> {
        self.0.put(key, report)
    }
}

/// Write the pictures of every view; with a checkpoint, the pictures of a view written by an
/// interrupted run of the same command (unit `pictures.<view index>`) are kept as they are.
fn write_pictures(
    od: &OutDir,
    stacks: &[DepthStack],
    lights: &[Option<(&Scene, usize)>],
    subjects: &[Subject],
    bias: &Bias,
    plan: &PicturePlan,
    cp: Option<&Checkpoint>,
) -> Result<()> {
    let bar = Bar::new("pictures (views)", stacks.len() as u64);
    let mut files = 0;
    for (v, (st, light)) in stacks.iter().zip(lights).enumerate() {
        let key = format!("pictures.{v}");
        if let Some(n) = cp.map(|c| c.get::<usize>(&key)).transpose()?.flatten() {
            files += n;
            bar.inc(1);
            continue;
        }
        let before = files;
        let cmp = match light {
            Some((sc, i)) => Some(eye::EyeComparison::new(
                sc,
                *i,
                st,
                bias,
                plan.eye_resolution,
            )?),
            None => None,
        };
        for &subject in subjects {
            let names = plan.names(st, subject, light.is_some());
            let shadows = metrics::front_shadows(st, subject, bias)?;
            pictures::write_png_to(od, &names[0], &pictures::view_picture(st, &shadows)?)?;
            let mut rest = names[1..].iter();
            if let Some(c) = &cmp {
                if !matches!(subject, Subject::Cdf) {
                    let img = pictures::eye_comparison(c, st, subject, bias)?;
                    pictures::write_png_to(od, rest.next().expect("eye name"), &img)?;
                }
            }
            for (k, name) in rest.enumerate() {
                let sh = metrics::layer_shadows(st, k, subject, bias)?;
                pictures::write_png_to(od, name, &pictures::layer_picture(st, k, &sh)?)?;
            }
            files += names.len();
        }
        if let Some(cp) = cp {
            cp.put(&key, &(files - before))?;
        }
        bar.inc(1);
    }
    bar.finish();
    eprintln!(
        "wrote {files} pictures to {} (light view: front depth | layers | PCF | technique | \
         |error|; .eye.png: PCF | technique | |difference| from the eye camera; .layer<k>.png: \
         layer-k depth | PCF | technique | |error|)",
        od.root().display()
    );
    Ok(())
}

fn print_table(r: &EvalReport) {
    println!("technique: {}", r.technique);
    println!(
        "bias: pcf ε = {:e}, slope scale s = {}, technique ε′ = {:e} + {}·(|dz/du|+|dz/dv|)",
        r.bias.pcf_epsilon,
        r.bias.slope_scale,
        r.bias.technique_epsilon,
        r.bias.technique_slope_scale
    );
    println!(
        "{:<14} {:<10} {:>10} {:>10} {:>8} {:>8} {:>10} {:>8}",
        "scene", "view", "fragments", "of total", "trivial", "NaN/inf", "error %", "time s"
    );
    for v in &r.views {
        println!(
            "{:<14} {:<10} {:>10} {:>10} {:>7.1}% {:>8} {:>10.4} {:>8.2}",
            v.scene,
            v.view,
            v.fragments,
            v.fragments_total,
            100.0 * v.trivial as f64 / v.fragments.max(1) as f64,
            v.non_finite,
            100.0 * v.error,
            v.seconds
        );
    }
    println!(
        "{:<14} {:<10} {:>10} {:>10} {:>7.1}% {:>8} {:>10.4} {:>8.2}",
        "all",
        "",
        r.fragments,
        r.fragments_total,
        100.0 * r.trivial as f64 / r.fragments.max(1) as f64,
        r.non_finite,
        100.0 * r.error,
        r.seconds
    );
    println!(
        "error with the PCF constant ε/3: {:.4} %, 3ε: {:.4} % (reference sensitivity); \
         leak (mean max(0, PCF − G)): {:.4} %, over-darkening: {:.4} %",
        100.0 * r.error_scaled[0],
        100.0 * r.error_scaled[1],
        100.0 * r.leak,
        100.0 * (r.error - r.leak)
    );
    if r.out_of_range > 0 {
        println!("warning: {} outputs outside [0,1]", r.out_of_range);
    }
    if r.unsettled > 0 {
        println!(
            "warning: {} LPs unsettled (no certificate either way), scored as the trivial bound G = 0",
            r.unsettled
        );
    }
    if r.non_finite > 0 {
        println!(
            "warning: {} non-finite outputs (excluded from the mean)",
            r.non_finite
        );
    }
    println!(
        "throughput: {:.0} technique calls/s over {} non-skipped fragments; {:.0} fragments/s overall",
        r.solves_per_second, r.solved, r.fragments_per_second
    );
}
