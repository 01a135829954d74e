//! `momentlab reproduce`: the whole study on the embedded default data, from a fresh clone.
//!
//! render → closed forms, baselines and LP candidates on the same fragments → speed → LP grid
//! refinement → candidate sweep (racing) → θ transforms → quantization study → stability →
//! report (`reports/<run>/index.html` + `report.md`). Every step writes its artefacts into the
//! run folder and is skipped when they already exist, so a killed run resumes where it stopped
//! (`--fresh` starts over). The numbers come from the same library calls as `momentlab
//! evaluate`, `search`, `theta`, `quantize` and `stability`.

use crate::metrics::{self, Bias, EvalOptions, EvalReport, Subject, Subsample};
use crate::report::document::Document;
use crate::report::pareto::{self, Entry};
use crate::report::recommend::{per_scene, recommendations, Measured, Recommendation};
use crate::report::{chart, pictures};
use crate::stack::DepthStack;
use crate::technique::{self, timing, Technique};
use anyhow::{bail, Context, Result};
use clap::Parser;
use indicatif::{ProgressBar, ProgressStyle};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;

#[derive(clap::Args, Debug)]
pub struct Args {
    /// Name of the run: the report goes to <reports>/<run>/, bulky data to <results>/<run>/.
    #[arg(long, default_value = "default")]
    pub run: String,
    /// The larger configuration (every fragment for the LP candidates, θ₆, larger stability,
    /// speed and sweep samples). Takes hours rather than minutes.
    #[arg(long)]
    pub full: bool,
    /// A tiny configuration for tests and smoke runs (64² stacks, small samples).
    #[arg(long, conflicts_with = "full")]
    pub tiny: bool,
    /// Shadow-map resolution of the rendered views (default 512, --tiny 64).
    #[arg(long)]
    pub resolution: Option<usize>,
    /// Recommendation tolerance: absolute error above the best technique that is acceptable.
    #[arg(long, default_value_t = 0.002)]
    pub tolerance: f64,
    /// Folder of reports.
    #[arg(long, default_value = "reports")]
    pub reports: PathBuf,
    /// Folder of bulky results (stacks, sweep rows).
    #[arg(long, default_value = "results")]
    pub results: PathBuf,
    /// Skip the candidate sweep (the slowest step).
    #[arg(long)]
    pub skip_search: bool,
    /// Start over: delete the run's previous artefacts.
    #[arg(long)]
    pub fresh: bool,
}

/// Sizes of one configuration.
struct Plan {
    resolution: usize,
    /// Every k-th fragment for the LP candidates (closed forms see every fragment).
    lp_stride: usize,
    grid_sizes: Vec<usize>,
    speed_inputs: usize,
    lp_speed_inputs: usize,
    theta_moments: Vec<usize>,
    theta_restarts: usize,
    quantize_stride: usize,
    stability_samples: usize,
    search_ms: Vec<usize>,
    search_first_sample: usize,
    search_top: usize,
    /// Candidates per m ≥ 3 sweep (a seeded random subset plus the paper's bases); None = all.
    search_subset: Option<usize>,
    /// Cap on the sweep's non-trivial fragments.
    search_max_fragments: usize,
    pictures: usize,
}

impl Plan {
    fn of(args: &Args) -> Plan {
        let mut p = if args.tiny {
            Plan {
                resolution: 64,
                lp_stride: 4,
                grid_sizes: vec![64, 128, 256],
                speed_inputs: 20_000,
                lp_speed_inputs: 200,
                theta_moments: vec![2, 3],
                theta_restarts: 2,
                quantize_stride: 4,
                stability_samples: 120,
                search_ms: vec![2],
                search_first_sample: 128,
                search_top: 5,
                search_subset: Some(20),
                search_max_fragments: 4096,
                pictures: 1,
            }
        } else if args.full {
            Plan {
                resolution: 512,
                lp_stride: 1,
                grid_sizes: vec![64, 128, 256, 512, 1024, 2048],
                speed_inputs: 1_000_000,
                lp_speed_inputs: 20_000,
                theta_moments: vec![2, 3, 4, 6],
                theta_restarts: 8,
                quantize_stride: 1,
                stability_samples: 5000,
                search_ms: vec![2, 3, 4],
                // The `momentlab search` defaults: the full sweeps measured in README.
                search_first_sample: 1024,
                search_top: 50,
                search_subset: None,
                search_max_fragments: 131_072,
                pictures: 12,
            }
        } else {
            Plan {
                resolution: 512,
                lp_stride: 16,
                grid_sizes: vec![64, 128, 256, 512, 1024],
                speed_inputs: 200_000,
                lp_speed_inputs: 3000,
                theta_moments: vec![2, 3, 4],
                theta_restarts: 4,
                quantize_stride: 4,
                stability_samples: 1200,
                search_ms: vec![2, 3, 4],
                search_first_sample: 1024,
                search_top: 20,
                search_subset: Some(150),
                search_max_fragments: 32_768,
                pictures: 4,
            }
        };
        if let Some(r) = args.resolution {
            p.resolution = r;
        }
        p
    }
}

/// (name, precision, technique, fragment stride, speed inputs).
type Job = (String, String, Box<dyn Technique>, usize, usize);

/// The closed-form techniques of the study: every registry name except the general
/// `hamburger` (at m = 4 it is `hamburger4`, only slower).
fn closed_forms() -> impl Iterator<Item = &'static str> {
    technique::registry::CLOSED_FORM_NAMES
        .iter()
        .copied()
        .filter(|&n| n != "hamburger")
}

/// The LP candidates of the study (Algorithm 1 with the paper's bases).
const LP_CANDIDATES: &[(&str, &str)] = &[
    ("lp:z,z^2", "LP (z, z²)"),
    ("lp:z,z^2,z^3", "LP (z, z², z³)"),
    ("lp:z,z^2,z^3,z^4", "LP b_MSM"),
    ("lp:sin(2πz),cos(2πz),sin(4πz),cos(4πz)", "LP b_TMSM"),
];

fn bar(len: u64, what: &str) -> ProgressBar {
    let b = if std::env::var_os("CI").is_some() {
        ProgressBar::hidden()
    } else {
        ProgressBar::new(len)
    };
    b.set_style(
        ProgressStyle::with_template("  {msg:<38} {wide_bar} {pos}/{len} ({eta})")
            .expect("valid template"),
    );
    b.set_message(what.to_string());
    b
}

fn write_json<T: Serialize>(path: &Path, v: &T) -> Result<()> {
    if let Some(d) = path.parent() {
        std::fs::create_dir_all(d).with_context(|| format!("creating {}", d.display()))?;
    }
    std::fs::write(path, serde_json::to_string_pretty(v)?)
        .with_context(|| format!("writing {}", path.display()))
}

fn read_json<T: for<'de> Deserialize<'de>>(path: &Path) -> Result<T> {
    let text =
        std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
    serde_json::from_str(&text).with_context(|| format!("parsing {}", path.display()))
}

/// Evaluate one technique on the stacks with a progress bar.
fn evaluate(
    stacks: &[DepthStack],
    t: &dyn Technique,
    label: &str,
    stride: usize,
) -> Result<EvalReport> {
    let b = Arc::new(bar(0, label));
    let bb = b.clone();
    let opts = EvalOptions {
        bias: Bias::default(),
        subsample: if stride > 1 {
            Subsample::Stride(stride)
        } else {
            Subsample::All
        },
        progress: Some(Arc::new(move |done, total| {
            bb.set_length(total as u64);
            bb.set_position(done as u64);
        })),
        ..Default::default()
    };
    let r = metrics::evaluate(stacks, t, &opts)?;
    b.finish_and_clear();
    Ok(r)
}

pub fn measured(
    stacks: &[DepthStack],
    t: &dyn Technique,
    name: &str,
    precision: &str,
    stride: usize,
    speed_inputs: usize,
) -> Result<Measured> {
    let r = evaluate(stacks, t, name, stride)?;
    let ns = timing::measure(t, speed_inputs, 3, 2015);
    Ok(Measured {
        name: name.to_string(),
        precision: precision.to_string(),
        // f64 storage doubles the texel size of the f32 layout the techniques report.
        bits_per_texel: if precision == "f64" {
            2 * t.bits_per_texel()
        } else {
            t.bits_per_texel()
        },
        ns_per_fragment: ns,
        error: r.error,
        fragments: r.fragments,
        trivial: r.trivial,
        non_finite: r.non_finite,
        seconds: r.seconds,
        scenes: per_scene(&r),
    })
}

/// Parse a subcommand's arguments as if typed on the command line (so `reproduce` runs the
/// exact code paths of the individual commands).
fn sub<A: clap::Args>(argv: &[String]) -> Result<A> {
    #[derive(Parser)]
    struct Wrap<B: clap::Args> {
        #[command(flatten)]
        inner: B,
    }
    let mut v = vec!["momentlab".to_string()];
    v.extend(argv.iter().cloned());
    Ok(Wrap::<A>::try_parse_from(v)
        .map_err(|e| anyhow::anyhow!("internal arguments {argv:?}: {e}"))?
        .inner)
}

fn s(x: impl ToString) -> String {
    x.to_string()
}

fn pct(x: f64) -> String {
    if x.is_finite() {
        format!("{:.3} %", 100.0 * x)
    } else {
        "n/a".into()
    }
}

struct Step {
    k: usize,
    total: usize,
    t0: Instant,
}

impl Step {
    fn start(&mut self, what: &str) {
        self.k += 1;
        eprintln!(
            "[{}/{}] {what} (elapsed {:.0} s)",
            self.k,
            self.total,
            self.t0.elapsed().as_secs_f64()
        );
    }
}

pub fn run(args: Args) -> Result<()> {
    if args.run.is_empty() || args.run.contains(['/', '\\']) || args.run.starts_with('.') {
        bail!("--run '{}': expected a plain folder name", args.run);
    }
    if !(args.tolerance.is_finite() && args.tolerance >= 0.0) {
        bail!(
            "--tolerance must be a finite number ≥ 0, got {}",
            args.tolerance
        );
    }
    let plan = Plan::of(&args);
    if plan.resolution < 16 {
        bail!("--resolution must be at least 16, got {}", plan.resolution);
    }
    let out = args.reports.join(&args.run);
    let data = args.results.join(&args.run);
    if args.fresh {
        for d in [&out, &data] {
            if d.exists() {
                std::fs::remove_dir_all(d).with_context(|| format!("removing {}", d.display()))?;
            }
        }
    }
    std::fs::create_dir_all(&out).with_context(|| format!("creating {}", out.display()))?;
    std::fs::create_dir_all(&data).with_context(|| format!("creating {}", data.display()))?;
    let t0 = Instant::now();
    let mut step = Step { k: 0, total: 9, t0 };

    // 1. Depth stacks.
    step.start(&format!(
        "render the default dataset at {0}×{0}",
        plan.resolution
    ));
    let stack_dir = data.join("stacks");
    let stacks = match crate::stack::load_dir(&stack_dir) {
        Ok(s) if s.first().map(|s| s.meta.width) == Some(plan.resolution) => s,
        _ => {
            let rs = Instant::now();
            let stacks = crate::render::default_dataset(plan.resolution)?;
            std::fs::create_dir_all(&stack_dir)?;
            for st in &stacks {
                let p = stack_dir.join(format!("{}_{}.exr", st.meta.scene, st.meta.view));
                crate::stack::write(&p, st)?;
            }
            eprintln!(
                "  rendered {} views in {:.1} s",
                stacks.len(),
                rs.elapsed().as_secs_f64()
            );
            stacks
        }
    };
    let fragments: usize = stacks.iter().map(|s| s.fragment_count()).sum();
    eprintln!("  {} views, {fragments} fragments", stacks.len());

    // 2. Techniques on the same fragments, with their speed.
    step.start("closed forms, baselines and LP candidates against PCF");
    let eval_dir = out.join("evaluate");
    let mut all: Vec<Measured> = Vec::new();
    let mut jobs: Vec<Job> = Vec::new();
    for name in closed_forms() {
        for prec in [
            technique::linalg::Precision::F32,
            technique::linalg::Precision::F64,
        ] {
            let t = match technique::registry::build(
                name,
                &technique::registry::Params::with(prec, None),
            ) {
                Ok(t) => t,
                Err(_) => technique::by_name(name)?,
            };
            jobs.push((s(name), s(prec.name()), t, 1, plan.speed_inputs));
        }
    }
    for &(spec, _) in LP_CANDIDATES {
        let t = technique::by_name(spec)?;
        jobs.push((s(spec), s("f64"), t, plan.lp_stride, plan.lp_speed_inputs));
    }
    for (name, prec, t, stride, inputs) in &jobs {
        let safe: String = name
            .replace('π', "pi")
            .chars()
            .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
            .collect();
        let file = eval_dir.join(format!("{safe}_{prec}.json"));
        let m = match read_json::<Measured>(&file) {
            Ok(m) => m,
            Err(_) => {
                let m = measured(&stacks, t.as_ref(), name, prec, *stride, *inputs)?;
                write_json(&file, &m)?;
                m
            }
        };
        eprintln!(
            "  {:<44} {prec}  error {:>9}  {:>9.1} ns/fragment  {} bit/texel",
            name,
            pct(m.error),
            m.ns_per_fragment,
            m.bits_per_texel
        );
        all.push(m);
    }

    // Pictures of Hamburger 4MSM for a few views.
    let pic_dir = out.join("pictures");
    let h4 = technique::by_name("hamburger4")?;
    let mut picture_files = Vec::new();
    for st in stacks
        .iter()
        .step_by((stacks.len() / plan.pictures.max(1)).max(1))
    {
        let name = format!("{}_{}_hamburger4.png", st.meta.scene, st.meta.view);
        let p = pic_dir.join(&name);
        if !p.exists() {
            std::fs::create_dir_all(&pic_dir)?;
            let sh = metrics::front_shadows(st, Subject::Technique(h4.as_ref()), &Bias::default())?;
            pictures::write_png(&p, &pictures::view_picture(st, &sh)?)?;
        }
        picture_files.push((
            format!("pictures/{name}"),
            format!("{} / {}", st.meta.scene, st.meta.view),
        ));
        if picture_files.len() >= plan.pictures {
            break;
        }
    }

    // 3. LP grid refinement per scene.
    step.start("LP grid: refine n until the error settles");
    let grid_file = out.join("grid_refinement.json");
    let refinement: Vec<(usize, Vec<(String, f64)>)> = match read_json(&grid_file) {
        Ok(r) => r,
        Err(_) => {
            let mut r = Vec::new();
            for &n in &plan.grid_sizes {
                let basis = crate::basis::Catalog::embedded().basis(&[
                    "z".to_string(),
                    "z^2".into(),
                    "z^3".into(),
                    "z^4".into(),
                ])?;
                let t = technique::lp_candidate::LpCandidate::new(
                    basis,
                    crate::Grid::uniform(n)?,
                    "fast",
                )?;
                let rep = evaluate(&stacks, &t, &format!("b_MSM, n = {n}"), plan.lp_stride * 2)?;
                let sc: Vec<(String, f64)> = per_scene(&rep)
                    .into_iter()
                    .map(|(a, e, _)| (a, e))
                    .collect();
                r.push((n, sc));
            }
            write_json(&grid_file, &r)?;
            r
        }
    };
    let grid_tolerance = args.tolerance / 10.0;
    let mut chosen_grid: Vec<(String, usize)> = Vec::new();
    if let Some((_, first)) = refinement.first() {
        for (scene, _) in first {
            let errs: Vec<(usize, f64)> = refinement
                .iter()
                .filter_map(|(n, sc)| sc.iter().find(|x| &x.0 == scene).map(|x| (*n, x.1)))
                .collect();
            let pick = errs
                .windows(2)
                .find(|w| (w[1].1 - w[0].1).abs() < grid_tolerance)
                .map(|w| w[0].0)
                .unwrap_or_else(|| errs.last().map_or(0, |x| x.0));
            chosen_grid.push((scene.clone(), pick));
        }
    }
    let series: Vec<(String, Vec<(f64, f64)>)> = chosen_grid
        .iter()
        .map(|(scene, _)| {
            (
                scene.clone(),
                refinement
                    .iter()
                    .filter_map(|(n, sc)| {
                        sc.iter().find(|x| &x.0 == scene).map(|x| (*n as f64, x.1))
                    })
                    .collect(),
            )
        })
        .collect();
    chart::lines_svg(
        &out.join("grid_refinement.svg"),
        "LP b_MSM error against grid size n",
        "grid points n (log scale)",
        "mean |G − PCF|",
        &series,
        true,
    )?;

    // 4. Candidate sweep.
    step.start("candidate sweep (racing)");
    let mut search_notes: Vec<String> = Vec::new();
    let search_report = out.join("search");
    if args.skip_search {
        search_notes.push("skipped (--skip-search)".into());
    } else {
        let mut compare = Vec::new();
        for &m in &plan.search_ms {
            let results = data.join(format!("search-m{m}"));
            let mut argv: Vec<String> = vec![
                "--m".into(),
                m.to_string(),
                "--stacks".into(),
                stack_dir.display().to_string(),
                "--results".into(),
                results.display().to_string(),
                "--report".into(),
                search_report.display().to_string(),
                "--first-sample".into(),
                plan.search_first_sample.to_string(),
                "--top".into(),
                plan.search_top.to_string(),
                "--max-fragments".into(),
                plan.search_max_fragments.to_string(),
                "--resolution".into(),
                plan.resolution.to_string(),
            ];
            if let (Some(k), true) = (plan.search_subset, m >= 3) {
                argv.push("--candidates".into());
                argv.push(
                    search_subset(m, k)?
                        .iter()
                        .map(|i| i.to_string())
                        .collect::<Vec<_>>()
                        .join(","),
                );
            }
            if !compare.is_empty() {
                argv.push("--compare".into());
                argv.push(compare.join(","));
            }
            let st = Instant::now();
            let a: super::search::Args = sub(&argv)?;
            match super::search::run(a) {
                Ok(()) => {
                    let scope = match (plan.search_subset, m >= 3) {
                        (Some(k), true) => format!(
                            "a seeded subset of {k} candidates including the paper's bases \
                             (`--full` sweeps all C(37,{m}))"
                        ),
                        _ => format!("all C(37,{m}) candidates"),
                    };
                    search_notes.push(format!(
                        "m = {m}: {scope}, racing over at most {} non-trivial fragments, done in \
                         {:.0} s (results in {})",
                        plan.search_max_fragments,
                        st.elapsed().as_secs_f64(),
                        results.display()
                    ));
                    compare.push(results.display().to_string());
                }
                Err(e) => search_notes.push(format!("m = {m}: not run: {e:#}")),
            }
        }
    }

    // 5. θ transforms.
    step.start("optimal quantization transforms θ");
    let theta_dir = out.join("theta");
    std::fs::create_dir_all(&theta_dir)?;
    let mut theta_rows = Vec::new();
    for &m in &plan.theta_moments {
        let file = theta_dir.join(format!("theta{m}.json"));
        let st = Instant::now();
        if !file.exists() {
            let mut argv: Vec<String> = vec![
                "--moments".into(),
                m.to_string(),
                "--restarts".into(),
                plan.theta_restarts.to_string(),
                "--output".into(),
                file.display().to_string(),
                "--snippets".into(),
                theta_dir.display().to_string(),
            ];
            if m >= 4 {
                argv.extend([
                    "--hops".into(),
                    "10".into(),
                    "--hop-sigma".into(),
                    "0.3".into(),
                ]);
            }
            super::theta::run(sub(&argv)?)?;
        }
        #[derive(Deserialize)]
        struct T {
            gain_bits: f64,
            max_violation: f64,
            seconds: f64,
        }
        let t: T = read_json(&file)?;
        let _ = st;
        theta_rows.push((m, t.gain_bits, t.max_violation, t.seconds));
    }
    super::theta::run(sub(&["--summary".into(), theta_dir.display().to_string()])?)?;

    // 6. Quantization study.
    step.start("quantized moment shadow maps (8/16/32 bit, θ)");
    let q_dir = out.join("quantize");
    if !q_dir.join("quantize.json").exists() {
        super::quantize::run(sub(&[
            "--stacks".into(),
            stack_dir.display().to_string(),
            "--theta-dir".into(),
            theta_dir.display().to_string(),
            "--out".into(),
            q_dir.display().to_string(),
            "--stride".into(),
            plan.quantize_stride.to_string(),
        ])?)?;
    }

    // 7. Stability.
    step.start("stability where methods fail");
    let stab_dir = out.join("stability");
    if !stab_dir.join("stability.json").exists() {
        super::stability::run(sub(&[
            "--out".into(),
            stab_dir.display().to_string(),
            "--samples".into(),
            plan.stability_samples.to_string(),
        ])?)?;
    }

    // 8. Speed against accuracy, recommendations.
    step.start("speed against accuracy, recommendations");
    let entries: Vec<Entry> = all
        .iter()
        .map(|m| Entry {
            name: m.name.clone(),
            precision: m.precision.clone(),
            error: m.error,
            ns_per_fragment: m.ns_per_fragment,
            bits_per_texel: m.bits_per_texel,
        })
        .collect();
    chart::speed_accuracy_svg(
        &out.join("speed_accuracy.svg"),
        "Error against PCF vs cost per fragment (marker size: bits per texel)",
        &entries,
    )?;
    let recs = recommendations(&all, args.tolerance);
    write_json(&out.join("recommend.json"), &recs)?;

    // 9. Report.
    step.start("report");
    let doc = build_report(ReportInputs {
        plan: &plan,
        args: &args,
        stacks: &stacks,
        all: &all,
        entries: &entries,
        recs: &recs,
        chosen_grid: &chosen_grid,
        refinement: &refinement,
        theta_rows: &theta_rows,
        search_notes: &search_notes,
        search_report: &search_report,
        out: &out,
        pictures: &picture_files,
        seconds: t0.elapsed().as_secs_f64(),
    })?;
    doc.write(&out)?;

    eprintln!("\nSummary ({:.0} s):", t0.elapsed().as_secs_f64());
    for r in &recs {
        eprintln!(
            "  {:<8} recommended: {} ({}), error {} (best {} by {})",
            r.scene,
            r.name,
            r.precision,
            pct(r.error),
            pct(r.best_error),
            r.best_name
        );
    }
    eprintln!("report: {}", out.join("index.html").display());
    Ok(())
}

struct ReportInputs<'a> {
    plan: &'a Plan,
    args: &'a Args,
    stacks: &'a [DepthStack],
    all: &'a [Measured],
    entries: &'a [Entry],
    recs: &'a [Recommendation],
    chosen_grid: &'a [(String, usize)],
    refinement: &'a [(usize, Vec<(String, f64)>)],
    theta_rows: &'a [(usize, f64, f64, f64)],
    search_notes: &'a [String],
    search_report: &'a Path,
    out: &'a Path,
    pictures: &'a [(String, String)],
    seconds: f64,
}

/// Copy the markdown of a sub-report in as preformatted text and its SVG figures as figures.
fn include_folder(doc: &mut Document, dir: &Path, out: &Path) -> Result<()> {
    let Ok(rd) = std::fs::read_dir(dir) else {
        return Ok(());
    };
    let mut files: Vec<PathBuf> = rd.filter_map(|e| e.ok().map(|e| e.path())).collect();
    files.sort();
    let rel = |p: &Path| {
        p.strip_prefix(out)
            .map(|r| r.to_string_lossy().replace('\\', "/"))
            .unwrap_or_else(|_| p.display().to_string())
    };
    for f in &files {
        match f.extension().and_then(|e| e.to_str()) {
            // Sub-reports' own image links are relative to their folder: the figures are
            // added below as figures of this report, so drop those lines from the text.
            Some("md") => doc.code(
                std::fs::read_to_string(f)?
                    .lines()
                    .filter(|l| !l.trim_start().starts_with("!["))
                    .collect::<Vec<_>>()
                    .join("\n")
                    .trim()
                    .to_string(),
            ),
            Some("svg") | Some("png") => doc.figure(
                rel(f),
                f.file_name()
                    .map(|n| n.to_string_lossy().to_string())
                    .unwrap_or_default(),
            ),
            _ => {}
        }
    }
    Ok(())
}

fn build_report(r: ReportInputs) -> Result<Document> {
    let mut d = Document::new("momentlab: Moment Shadow Mapping, reproduced");
    d.paragraph(format!(
        "Run '{}' ({} configuration): {} views at {}×{}, {} fragments, {:.0} s on this machine. \
         Every number below is produced by momentlab from these depth stacks, except where a \
         column or sentence says 'paper' (Peters & Klein, I3D 2015, and its supplementary).",
        r.args.run,
        if r.args.full {
            "full"
        } else if r.args.tiny {
            "tiny"
        } else {
            "default"
        },
        r.stacks.len(),
        r.plan.resolution,
        r.plan.resolution,
        r.stacks.iter().map(|s| s.fragment_count()).sum::<usize>(),
        r.seconds
    ));

    d.heading("The paper's numbers side by side with ours");
    let find = |n: &str, p: &str| r.all.iter().find(|m| m.name == n && m.precision == p);
    let err_of = |n: &str, p: &str| find(n, p).map_or("n/a".to_string(), |m| pct(m.error));
    let mut rows = vec![
        vec![
            s("b_MSM error (LP, 4 moments)"),
            s("2.19 %"),
            err_of("lp:z,z^2,z^3,z^4", "f64"),
        ],
        vec![
            s("b_TMSM error (LP)"),
            s("1.93 %"),
            err_of("lp:sin(2πz),cos(2πz),sin(4πz),cos(4πz)", "f64"),
        ],
        vec![
            s("Hamburger 4MSM (closed form, f32)"),
            s("—"),
            err_of("hamburger4", "f32"),
        ],
        vec![s("TMSM (closed form, f32)"), s("—"), err_of("tmsm", "f32")],
        vec![
            s("candidates evaluated, time"),
            s("66045, several weeks on a cluster"),
            r.search_notes.join("; "),
        ],
    ];
    for &(m, gain, _, secs) in r.theta_rows {
        let paper = match m {
            2 => "2 bits",
            3 => "6.2 bits",
            4 => "12.2783 bits",
            6 => "30.511 bits",
            _ => "—",
        };
        rows.push(vec![
            format!("θ{m} entropy gain"),
            s(paper),
            format!("{gain:.4} bits ({secs:.1} s)"),
        ]);
    }
    d.table(&["quantity", "paper", "momentlab (this run)"], rows);

    d.heading("Techniques against PCF on the same fragments");
    d.paragraph(format!(
        "Error = mean |G − PCF| over all fragments of all layers (9×9 Gaussian PCF, σ = 2.4 \
         texels). Closed forms see every fragment; LP candidates (Algorithm 1, n = 1024 grid) \
         every {}-th fragment. Speed: nanoseconds per evaluation on one core over random \
         few-Dirac inputs (momentlab's timing loop, the same as `momentlab bench shadow`).",
        r.plan.lp_stride
    ));
    let mut sorted: Vec<&Measured> = r.all.iter().collect();
    sorted.sort_by(|a, b| a.error.total_cmp(&b.error));
    d.table(
        &[
            "technique",
            "precision",
            "error",
            "ns / fragment",
            "bits / texel",
            "fragments",
            "trivial",
            "non-finite",
        ],
        sorted
            .iter()
            .map(|m| {
                vec![
                    m.name.clone(),
                    m.precision.clone(),
                    pct(m.error),
                    format!("{:.1}", m.ns_per_fragment),
                    m.bits_per_texel.to_string(),
                    m.fragments.to_string(),
                    m.trivial.to_string(),
                    m.non_finite.to_string(),
                ]
            })
            .collect(),
    );
    d.heading("Speed against accuracy");
    d.figure(
        "speed_accuracy.svg",
        "Error against PCF over nanoseconds per fragment; marker area grows with bits per texel; \
         the Pareto front is drawn in red and labelled.",
    );
    let front = pareto::pareto_front(r.entries);
    d.paragraph(format!(
        "Pareto front: {}.",
        front
            .iter()
            .map(|&i| format!("{} ({})", r.entries[i].name, r.entries[i].precision))
            .collect::<Vec<_>>()
            .join(", ")
    ));

    d.heading("No more model than a scene needs");
    d.paragraph(format!(
        "Recommendation per scene: the cheapest closed-form technique (fewest bits per texel, \
         then fewest ns per fragment) whose error is within {} of the best closed form on that \
         scene (`momentlab recommend --tolerance`).",
        pct(r.args.tolerance)
    ));
    d.table(
        &[
            "scene",
            "recommended",
            "error",
            "bits / texel",
            "ns / fragment",
            "best",
            "best error",
        ],
        r.recs
            .iter()
            .map(|x| {
                vec![
                    x.scene.clone(),
                    format!("{} ({})", x.name, x.precision),
                    pct(x.error),
                    x.bits_per_texel.to_string(),
                    format!("{:.1}", x.ns_per_fragment),
                    x.best_name.clone(),
                    pct(x.best_error),
                ]
            })
            .collect(),
    );
    d.paragraph(format!(
        "LP grid: b_MSM evaluated with n = {} grid points (every {}-th fragment); the chosen n \
         is the first whose error differs from the next finer grid by less than {}.",
        r.refinement
            .iter()
            .map(|x| x.0.to_string())
            .collect::<Vec<_>>()
            .join(", "),
        r.plan.lp_stride * 2,
        pct(r.args.tolerance / 10.0)
    ));
    d.table(
        &["scene", "chosen n"],
        r.chosen_grid
            .iter()
            .map(|(s, n)| vec![s.clone(), n.to_string()])
            .collect(),
    );
    d.figure(
        "grid_refinement.svg",
        "LP b_MSM error per scene against the grid size n.",
    );

    d.heading("Shadow pictures (Hamburger 4MSM)");
    d.paragraph(
        "Panels, left to right: front depth, layer count, PCF shadow, technique shadow, |error| \
         heat map.",
    );
    for (f, c) in r.pictures {
        d.figure(f.clone(), c.clone());
    }

    d.heading("Candidate sweep (Fig. 3 and Fig. 4 analogues)");
    for n in r.search_notes {
        d.paragraph(n.clone());
    }
    include_folder(&mut d, r.search_report, r.out)?;

    d.heading("Quantization transforms θ (Fig. 5 analogue) and 16-bit moment shadow maps");
    include_folder(&mut d, &r.out.join("theta"), r.out)?;
    include_folder(&mut d, &r.out.join("quantize"), r.out)?;

    d.heading("Stability: where each method fails");
    include_folder(&mut d, &r.out.join("stability"), r.out)?;
    Ok(d)
}

/// A seeded random subset of `k` candidate indices of the embedded catalog for m functions,
/// always including the paper's polynomial basis (z, …, z^m) and, for m = 4, b_TMSM.
fn search_subset(m: usize, k: usize) -> Result<Vec<u64>> {
    use crate::basis::candidates;
    use rand::{Rng, SeedableRng};
    let cat = crate::basis::Catalog::embedded();
    let total = candidates::count(cat.len(), m);
    let mut pick: Vec<u64> = Vec::new();
    let mut named = vec![(1..=m)
        .map(|k| {
            if k == 1 {
                "z".to_string()
            } else {
                format!("z^{k}")
            }
        })
        .collect::<Vec<_>>()];
    if m == 4 {
        named.push(
            ["sin(2πz)", "cos(2πz)", "sin(4πz)", "cos(4πz)"]
                .iter()
                .map(|s| s.to_string())
                .collect(),
        );
    }
    for names in named {
        let mut idx: Vec<usize> = names
            .iter()
            .map(|n| {
                cat.position(n)
                    .with_context(|| format!("catalog has no '{n}'"))
            })
            .collect::<Result<_>>()?;
        idx.sort();
        pick.push(candidates::subset_to_index(&idx)?);
    }
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(2015 + m as u64);
    while pick.len() < k.min(total as usize) {
        let i = rng.gen_range(0..total);
        if !pick.contains(&i) {
            pick.push(i);
        }
    }
    pick.sort();
    Ok(pick)
}
