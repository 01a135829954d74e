//! `momentlab quantize`: quantized moment shadow maps on the depth stacks. Error against PCF
//! over the bias α for canonical / optimized (θ) storage at 8 and 16 bits and 32-bit float,
//! for VSM (θ₂), Hamburger 4MSM (θ₄) and 6MSM (θ₆).

use crate::metrics::{Bias, Subsample};
use crate::quantize::study::{identity_theta, sweep, Config, Storage, Sweep, Tech};
use crate::quantize::theta::{published, Theta};
use anyhow::{bail, Context, Result};
use plotters::prelude::*;
use std::path::{Path, PathBuf};
use std::time::Instant;

#[derive(clap::Args, Debug)]
pub struct Args {
    /// Directory of depth stacks (.exr + .json).
    #[arg(long, default_value = "stacks/default")]
    pub stacks: PathBuf,
    /// Directory with our θ (theta2.json, theta4.json, theta6.json from `momentlab theta`).
    #[arg(long, default_value = "reports/theta")]
    pub theta_dir: PathBuf,
    /// Output directory (quantize.json, quantize.md, quantize_alpha.svg).
    #[arg(long, default_value = "reports/theta/quantize")]
    pub out: PathBuf,
    /// Evaluate every k-th fragment only.
    #[arg(long, default_value_t = 1)]
    pub stride: usize,
    /// Comma-separated bias strengths α (> 0).
    #[arg(long, default_value = DEFAULT_ALPHAS)]
    pub alphas: String,
}

/// The bias strengths α of the study.
pub const DEFAULT_ALPHAS: &str = "1e-8,3e-8,1e-7,3e-7,1e-6,3e-6,1e-5,3e-5,1e-4,3e-4,1e-3,3e-3,1e-2";

fn load_theta(dir: &Path, m: usize) -> Result<Option<Theta>> {
    let p = dir.join(format!("theta{m}.json"));
    if !p.exists() {
        return Ok(None);
    }
    let text = std::fs::read_to_string(&p).with_context(|| format!("reading {}", p.display()))?;
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
    Ok(Some(th))
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
    if args.stride == 0 {
        bail!("--stride must be >= 1");
    }
    let stacks = crate::stack::load_dir(&args.stacks)
        .with_context(|| format!("loading stacks from {}", args.stacks.display()))?;
    let sub = if args.stride > 1 {
        Subsample::Stride(args.stride)
    } else {
        Subsample::All
    };
    let t0 = Instant::now();
    let mut all: Vec<Sweep> = Vec::new();
    for tech in [Tech::Vsm, Tech::Msm4, Tech::Msm6] {
        let m = tech.m();
        let ours = load_theta(&args.theta_dir, m)?;
        let pubd = published(m);
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
        for (label, th) in [("ours", ours), ("published", pubd)] {
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
        eprintln!(
            "quantize: {} ({} configurations)...",
            tech.name(),
            configs.len()
        );
        all.extend(sweep(
            &stacks,
            tech,
            &configs,
            &alphas,
            &Bias::default(),
            &sub,
        )?);
    }
    let seconds = t0.elapsed().as_secs_f64();
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("creating {}", args.out.display()))?;
    let json = serde_json::json!({
        "stacks": args.stacks, "views": stacks.len(), "stride": args.stride,
        "b_star": "1/2 in every moment", "precision": "f64 reconstruction",
        "seconds": seconds, "sweeps": all,
    });
    let p = args.out.join("quantize.json");
    std::fs::write(&p, serde_json::to_string_pretty(&json)? + "\n")
        .with_context(|| format!("writing {}", p.display()))?;
    let i3 = alphas.iter().position(|&a| (a - 3e-5).abs() < 1e-12);
    let mut md = format!(
        "Mean |G − PCF| over {} fragments of {} views ({}), stride {}; bias b* = (½,…,½).\n\n`error` = mean |G − PCF|; `deviation` = mean |G − G_exact| against the same technique and α on unquantized f64 moments (the damage done by storage alone).\n\n| technique | storage | best α | error at best α | error at α = 3e-5 | deviation at best α | deviation at α = 3e-5 | non-finite at best α |\n|---|---|---|---|---|---|---|---|\n",
        all.first().map_or(0, |s| s.fragments),
        stacks.len(),
        args.stacks.display(),
        args.stride
    );
    for s in &all {
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
    let p = args.out.join("quantize.md");
    std::fs::write(&p, &md).with_context(|| format!("writing {}", p.display()))?;
    let p = args.out.join("quantize_alpha.svg");
    std::fs::write(&p, plot(&all)?).with_context(|| format!("writing {}", p.display()))?;
    print!("{md}");
    eprintln!("quantize: {seconds:.1} s, wrote {}", args.out.display());
    Ok(())
}

/// Error against α (log–log), one panel per technique, one line per storage configuration.
fn plot(all: &[Sweep]) -> Result<String> {
    let mut out = String::new();
    {
        let root = SVGBackend::with_string(&mut out, (1500, 500)).into_drawing_area();
        root.fill(&WHITE)
            .map_err(|e| anyhow::anyhow!("plot: {e}"))?;
        let panels = root.split_evenly((1, 3));
        for (area, tech) in panels.iter().zip(["vsm", "4msm", "6msm"]) {
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
                .y_desc("mean |G − PCF|")
                .x_label_formatter(&|v| format!("{v:.0e}"))
                .y_label_formatter(&|v| format!("{v:.1e}"))
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
