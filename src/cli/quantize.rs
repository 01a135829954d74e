//! `momentlab quantize`: quantized moment shadow maps on the depth stacks. Error against PCF
//! over the bias α for canonical / optimized (θ) storage at 8 and 16 bits and 32-bit float,
//! for VSM (θ₂), Hamburger 4MSM (θ₄), 6MSM (θ₆) and 8 moments (θ₈): ours from --theta-dir,
//! the published θ₂/θ₄/θ₆ beside them.

use super::common::resolution;
use crate::artefact::OutDir;
use crate::metrics::{Bias, Subsample};
use crate::quantize::curve::MonomialCurve;
use crate::quantize::study::{identity_theta, sweep, Config, Storage, Sweep, Tech};
use crate::quantize::theta::{published, verify, Theta};
use anyhow::{bail, Context, Result};
use plotters::prelude::*;
use std::path::{Path, PathBuf};
use std::time::Instant;

#[derive(clap::Args, Debug)]
pub struct Args {
    /// Directory of depth stacks (.exr + .json); default: render the embedded default dataset.
    #[arg(long)]
    pub stacks: Option<PathBuf>,
    /// Shadow-map resolution when rendering the default dataset (16..=4096).
    #[arg(long, default_value_t = 512, value_parser = resolution())]
    pub resolution: usize,
    /// Folder with θ (theta{m}.json from `momentlab theta`) for every technique run; a missing
    /// file is an error. Default: the study's θ committed in reports/theta (read only).
    #[arg(long, default_value = "reports/theta")]
    pub theta_dir: PathBuf,
    /// Techniques (repeatable; comma lists): vsm (θ₂), hamburger4 (θ₄), hamburger6 (θ₆),
    /// hamburger8 (θ₈; the older 4msm, 6msm, 8msm are accepted).
    #[arg(
        long,
        alias = "techniques",
        default_value = "vsm,hamburger4,hamburger6,hamburger8"
    )]
    pub technique: Vec<String>,
    /// Output folder (quantize.json, quantize.md, quantize_alpha.svg).
    #[arg(long, default_value = "results/quantize")]
    pub out: PathBuf,
    /// Overwrite existing output files (otherwise a name clash is an error).
    #[arg(long)]
    pub force: bool,
    /// Evaluate every k-th fragment only, 1..=1000000.
    #[arg(long, default_value_t = 1)]
    pub stride: usize,
    /// Comma-separated bias strengths α in (0, 1).
    #[arg(long, default_value = DEFAULT_ALPHAS)]
    pub alphas: String,
    /// Print the sweeps as JSON on stdout instead of the table.
    #[arg(long)]
    pub json: bool,
    /// Instead of computing: combine the sweeps of these quantize.json files (comma-separated,
    /// same stacks and stride) and write the tables and plot into --out.
    #[arg(long)]
    pub merge: Option<String>,
}

/// The bias strengths α of the study.
pub const DEFAULT_ALPHAS: &str = "1e-8,3e-8,1e-7,3e-7,1e-6,3e-6,1e-5,3e-5,1e-4,3e-4,1e-3,3e-3,1e-2";

fn load_theta(dir: &Path, m: usize) -> Result<Theta> {
    let p = dir.join(format!("theta{m}.json"));
    if !p.is_file() {
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

fn configs(tech: Tech, ours: &Theta) -> Vec<Config> {
    let m = tech.m();
    let mut configs = vec![
        Config {
            name: "canonical 8-bit".into(),
            theta: identity_theta(m),
            storage: Storage::Unorm(8),
        },
        Config {
            name: "canonical 16-bit".into(),
            theta: identity_theta(m),
            storage: Storage::Unorm(16),
        },
        Config {
            name: "32-bit float".into(),
            theta: identity_theta(m),
            storage: Storage::Float32,
        },
    ];
    for (label, th) in [("ours", Some(ours.clone())), ("published", published(m))] {
        if let Some(th) = th {
            for bits in [8, 16] {
                configs.push(Config {
                    name: format!("optimized {bits}-bit ({label} θ{m})"),
                    theta: th.clone(),
                    storage: Storage::Unorm(bits),
                });
            }
        }
    }
    configs
}

fn load_stacks(args: &Args) -> Result<Vec<crate::stack::DepthStack>> {
    match &args.stacks {
        Some(dir) => crate::stack::load_dir(dir)
            .with_context(|| format!("loading stacks from {}", dir.display())),
        None => {
            eprintln!(
                "rendering the default dataset at {0}×{0} …",
                args.resolution
            );
            crate::render::default_dataset(args.resolution)
        }
    }
}

/// Combine the sweeps of existing quantize.json files (`--merge`).
fn merge(list: &str, od: &OutDir, files: &[&str; 3]) -> Result<()> {
    let mut all: Vec<Sweep> = Vec::new();
    let mut head: Option<(serde_json::Value, serde_json::Value, serde_json::Value)> = None;
    let mut seconds = 0.0;
    for f in list.split(',').map(str::trim) {
        let text = crate::artefact::read_text(Path::new(f), crate::artefact::Limit::ARTEFACT)
            .context("--merge")?;
        let v: serde_json::Value =
            serde_json::from_str(&text).with_context(|| format!("--merge: parsing {f}"))?;
        let h = (v["stacks"].clone(), v["views"].clone(), v["stride"].clone());
        if head.as_ref().is_some_and(|x| *x != h) {
            bail!("--merge: {f} has other stacks, views or stride than the first file");
        }
        head = Some(h);
        seconds += v["seconds"].as_f64().unwrap_or(0.0);
        let sw: Vec<Sweep> = serde_json::from_value(v["sweeps"].clone())
            .with_context(|| format!("--merge: {f}: sweeps"))?;
        all.extend(sw);
    }
    let (stacks, views, stride) = head.context("--merge: no files")?;
    let alphas = all.first().map(|s| s.alphas.clone()).unwrap_or_default();
    let usable = usability(&all);
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
    od.write_json(files[0], &json)?;
    od.write_text(files[1], &md)?;
    od.write_text(files[2], &plot(&all)?)?;
    print!("{md}");
    Ok(())
}

pub fn run(args: Args) -> Result<()> {
    let alphas: Vec<f64> = args
        .alphas
        .split(',')
        .map(|s| {
            s.trim()
                .parse::<f64>()
                .ok()
                .filter(|a| a.is_finite() && *a > 0.0 && *a < 1.0)
                .with_context(|| format!("--alphas: '{s}' is not a number in (0, 1)"))
        })
        .collect::<Result<_>>()?;
    if !(1..=1_000_000).contains(&args.stride) {
        bail!("--stride must be in 1..=1000000, got {}", args.stride);
    }
    let techs: Vec<Tech> = super::common::technique_list(&args.technique)
        .iter()
        .map(|t| {
            Tech::parse(t).with_context(|| {
                format!("--technique: '{t}' is not one of vsm, hamburger4, hamburger6, hamburger8")
            })
        })
        .collect::<Result<_>>()?;
    if techs.is_empty() {
        bail!("--technique: empty list");
    }
    let files = ["quantize.json", "quantize.md", "quantize_alpha.svg"];
    let od = OutDir::new(&args.out, args.force).context("--out")?;
    od.reserve(files).context("--out")?;
    if let Some(list) = &args.merge {
        return merge(list, &od, &files);
    }
    // every θ before any expensive work
    let thetas: Vec<Theta> = techs
        .iter()
        .map(|t| load_theta(&args.theta_dir, t.m()))
        .collect::<Result<_>>()?;
    let stacks = load_stacks(&args)?;
    if stacks.is_empty() {
        bail!("no depth stacks to evaluate");
    }
    crate::metrics::require_fragments(&stacks)?;
    let sub = if args.stride > 1 {
        Subsample::Stride(args.stride)
    } else {
        Subsample::All
    };
    let t0 = Instant::now();
    let mut all: Vec<Sweep> = Vec::new();
    for (tech, ours) in techs.iter().zip(&thetas) {
        let configs = configs(*tech, ours);
        eprintln!(
            "quantize: {} ({} configurations)...",
            tech.name(),
            configs.len()
        );
        all.extend(sweep(
            &stacks,
            *tech,
            &configs,
            &alphas,
            &Bias::default(),
            &sub,
        )?);
    }
    if all.first().is_none_or(|s| s.fragments == 0) {
        bail!("the depth stacks have no fragments to evaluate (empty or all background)");
    }
    let seconds = t0.elapsed().as_secs_f64();
    let stacks_label = args.stacks.as_ref().map_or_else(
        || format!("default dataset rendered at {0}×{0}", args.resolution),
        |p| p.display().to_string(),
    );
    let usable = usability(&all);
    let json = serde_json::json!({
        "stacks": stacks_label, "views": stacks.len(), "stride": args.stride,
        "theta_dir": args.theta_dir,
        "b_star": "1/2 in every moment", "precision": "f64 reconstruction",
        "seconds": seconds, "sweeps": all, "usable_16bit": usable,
    });
    let text = serde_json::to_string_pretty(&json)? + "\n";
    od.write_text(files[0], &text)?;
    let md = markdown(
        &all,
        &usable,
        &stacks_label,
        stacks.len(),
        args.stride,
        &alphas,
    );
    od.write_text(files[1], &md)?;
    od.write_text(files[2], &plot(&all)?)?;
    if args.json {
        print!("{text}");
    } else {
        print!("{md}");
    }
    eprintln!("quantize: {seconds:.1} s, wrote {}", args.out.display());
    Ok(())
}

/// Mean |G − G_exact| up to which storage counts as usable (0.1 % shadow intensity on average).
const USABLE_DEVIATION: f64 = 1e-3;

/// For every 16-bit configuration: the smallest α at which its deviation from unquantized
/// moments is at most USABLE_DEVIATION (an absolute threshold: at tiny α even 32-bit float
/// storage deviates by 1e-2 for 6MSM, so a threshold relative to it would pass anything).
fn usability(all: &[Sweep]) -> Vec<serde_json::Value> {
    let mut out = Vec::new();
    for s in all.iter().filter(|s| s.config.contains("16-bit")) {
        let Some(f32s) = all
            .iter()
            .find(|f| f.technique == s.technique && f.config == "32-bit float")
        else {
            continue;
        };
        let k = (0..s.alphas.len()).find(|&i| s.deviation[i] <= USABLE_DEVIATION);
        out.push(serde_json::json!({
            "technique": s.technique, "config": s.config,
            "smallest_usable_alpha": k.map(|i| s.alphas[i]),
            "deviation_there": k.map(|i| s.deviation[i]),
            "error_there": k.map(|i| s.errors[i]),
            "f32_error_there": k.map(|i| f32s.errors[i]),
        }));
    }
    out
}

fn markdown(
    all: &[Sweep],
    usable: &[serde_json::Value],
    stacks: &str,
    views: usize,
    stride: usize,
    alphas: &[f64],
) -> String {
    let i3 = alphas.iter().position(|&a| (a - 3e-5).abs() < 1e-12);
    let mut md = format!(
        "Mean |G − PCF| over {} fragments of {views} views ({stacks}), stride {stride}; bias b* = (½,…,½).\n\n`error` = mean |G − PCF|; `deviation` = mean |G − G_exact| against the same technique and α on unquantized f64 moments (the damage done by storage alone).\n\n| technique | storage | best α | error at best α | error at α = 3e-5 | deviation at best α | deviation at α = 3e-5 | non-finite at best α |\n|---|---|---|---|---|---|---|---|\n",
        all.first().map_or(0, |s| s.fragments),
    );
    for s in all {
        let k = s
            .alphas
            .iter()
            .position(|&a| a == s.best_alpha)
            .unwrap_or(0);
        md.push_str(&format!(
            "| {} | {} | {:.0e} | {:.5} | {} | {:.2e} | {} | {} |\n",
            s.technique,
            s.config,
            s.best_alpha,
            s.best_error,
            i3.map_or("—".into(), |i| format!("{:.5}", s.errors[i])),
            s.deviation[k],
            i3.map_or("—".into(), |i| format!("{:.2e}", s.deviation[i])),
            s.non_finite[k]
        ));
    }
    md.push_str(&format!(
        "\n16-bit storage counted as usable from the smallest α at which its deviation is at most {USABLE_DEVIATION:.0e}:\n\n| technique | storage | smallest usable α | deviation there | error there | 32-bit float error there |\n|---|---|---|---|---|---|\n"
    ));
    for u in usable {
        let f = |k: &str, p: &str| {
            u[k].as_f64().map_or("never".to_string(), |v| match p {
                "e" => format!("{v:.0e}"),
                "d" => format!("{v:.2e}"),
                _ => format!("{v:.5}"),
            })
        };
        md.push_str(&format!(
            "| {} | {} | {} | {} | {} | {} |\n",
            u["technique"].as_str().unwrap_or(""),
            u["config"].as_str().unwrap_or(""),
            f("smallest_usable_alpha", "e"),
            f("deviation_there", "d"),
            f("error_there", "f"),
            f("f32_error_there", "f"),
        ));
    }
    md
}

/// Error against α (log–log), one panel per technique, one line per storage configuration.
fn plot(all: &[Sweep]) -> Result<String> {
    let mut out = String::new();
    {
        let mut techs: Vec<&str> = Vec::new();
        for s in all {
            if !techs.contains(&s.technique.as_str()) {
                techs.push(&s.technique);
            }
        }
        let n = techs.len().max(1);
        let root = SVGBackend::with_string(&mut out, (500 * n as u32, 500)).into_drawing_area();
        root.fill(&WHITE)
            .map_err(|e| anyhow::anyhow!("plot: {e}"))?;
        let panels = root.split_evenly((1, n));
        for (area, tech) in panels.iter().zip(techs) {
            let sw: Vec<&Sweep> = all.iter().filter(|s| s.technique == tech).collect();
            if sw.is_empty() {
                continue;
            }
            let (mut lo, mut hi) = (f64::INFINITY, 0.0f64);
            for s in &sw {
                for &e in &s.errors {
                    lo = lo.min(e.max(1e-6));
                    hi = hi.max(e);
                }
            }
            let amin = sw[0].alphas.iter().cloned().fold(f64::INFINITY, f64::min);
            let amax = sw[0].alphas.iter().cloned().fold(0.0, f64::max);
            let mut chart = ChartBuilder::on(area)
                .caption(format!("{tech}: error vs bias α"), ("sans-serif", 18))
                .margin(10)
                .x_label_area_size(35)
                .y_label_area_size(55)
                .build_cartesian_2d(
                    (amin..amax).log_scale(),
                    (lo * 0.8..(hi * 1.25).min(1.0).max(lo * 2.0)).log_scale(),
                )
                .map_err(|e| anyhow::anyhow!("plot: {e}"))?;
            chart
                .configure_mesh()
                .x_desc("α")
                .y_desc("mean |G − PCF| (%)")
                .x_label_formatter(&|v| format!("{v:.0e}"))
                .y_label_formatter(&|v| {
                    let p = 100.0 * v;
                    if p >= 0.1 {
                        pct_tick(p)
                    } else {
                        format!("{p:.0e}")
                    }
                })
                .draw()
                .map_err(|e| anyhow::anyhow!("plot: {e}"))?;
            for (i, s) in sw.iter().enumerate() {
                let c = Palette99::pick(i).to_rgba();
                chart
                    .draw_series(LineSeries::new(
                        s.alphas
                            .iter()
                            .zip(&s.errors)
                            .map(|(&a, &e)| (a, e.max(1e-6))),
                        c.stroke_width(2),
                    ))
                    .map_err(|e| anyhow::anyhow!("plot: {e}"))?
                    .label(s.config.clone())
                    .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], c));
            }
            chart
                .configure_series_labels()
                .background_style(WHITE.mix(0.8))
                .border_style(BLACK)
                .label_font(("sans-serif", 11))
                .draw()
                .map_err(|e| anyhow::anyhow!("plot: {e}"))?;
        }
        root.present().map_err(|e| anyhow::anyhow!("plot: {e}"))?;
    }
    Ok(out)
}

/// A percentage tick label with two significant digits (1.5, 12, 0.35).
fn pct_tick(p: f64) -> String {
    if p >= 10.0 {
        format!("{p:.0}")
    } else if p >= 1.0 {
        format!("{p:.1}")
    } else {
        format!("{p:.2}")
    }
}
