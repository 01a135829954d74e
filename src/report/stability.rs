//! The stability study on disk: stress every technique where it fails (harness in
//! [`crate::stability`], docs/stability.md) and write `stability.json`,
//! `stability.md` and the SVG heat maps of mean |G − sharp bound| into a folder.

use crate::artefact::Checkpoint;
use crate::stability::{self, Config, Entry, Mode, Report, Scenario};
use crate::technique::by_name;
use crate::technique::registry::{build, Params};
use anyhow::{anyhow, bail, Context, Result};
use plotters::prelude::*;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// The techniques stressed by default.
pub const DEFAULT_TECHNIQUES: &str = "vsm,esm,evsm,csm,hamburger4,hausdorff4,hamburger6,tmsm";

/// What the study runs and where it writes.
#[derive(Clone, Debug)]
pub struct Options {
    /// Output folder.
    pub out: PathBuf,
    /// Number of inputs (cycled over the scenarios), ≥ 1.
    pub samples: usize,
    /// Random seed.
    pub seed: u64,
    /// Uniform grid points of the oracle (Algorithm 1) on [0,1], ≥ 2.
    pub grid: usize,
    /// Technique names (an unknown name is an error before any work).
    pub techniques: Vec<String>,
    /// Replace existing files in `out` (otherwise refused before the study runs).
    pub force: bool,
}

/// The files the study writes into its folder; `stability.json` is written last, so it marks
/// a finished study.
pub const FILES: [&str; 5] = [
    "stability.json",
    "stability.md",
    "heatmap_f64.svg",
    "heatmap_f32.svg",
    "heatmap_u16.svg",
];

/// What a finished study reports.
#[derive(Clone, Debug)]
pub struct Outcome {
    /// Inputs (samples) evaluated.
    pub inputs: usize,
    /// Techniques tested.
    pub techniques: usize,
    /// Wall time of the study, seconds.
    pub seconds: f64,
}

/// Run the study and write its files; `progress(k)` is called after every k finished inputs,
/// `started(total)` once before.
pub fn study(
    opts: &Options,
    started: &dyn Fn(usize),
    progress: &(dyn Fn(usize) + Sync),
) -> Result<Outcome> {
    if opts.samples == 0 {
        bail!("--inputs must be at least 1");
    }
    if opts.grid < 2 {
        bail!("--grid must be at least 2");
    }
    let mut techs: Vec<Entry> = Vec::new();
    let p16 = Params {
        quant_bits: 16,
        ..Params::default()
    };
    for name in opts
        .techniques
        .iter()
        .map(|s| s.trim())
        .filter(|s| !s.is_empty())
    {
        let t32 = by_name(name).with_context(|| format!("--technique {name}"))?;
        // 16-bit moments get the technique's 16-bit defaults (e.g. a stronger bias).
        let t16 = build(name, &p16).or_else(|_| by_name(name))?;
        techs.push(Entry {
            name: name.to_string(),
            t32,
            t16,
        });
    }
    if techs.is_empty() {
        bail!(
            "--technique: no technique named in '{}'",
            opts.techniques.join(",")
        );
    }
    let cfg = Config {
        samples: opts.samples,
        seed: opts.seed,
        grid_points: opts.grid,
        ..Config::default()
    };
    // The checkpoint (one unit per technique and family), then the outputs: nothing is replaced
    // without --force but what an interrupted run of this study wrote.
    crate::artefact::OutDir::new(&opts.out, opts.force).context("--out")?;
    let names: Vec<&str> = techs.iter().map(|e| e.name.as_str()).collect();
    let params = serde_json::json!({ "config": cfg, "techniques": names });
    let cp = Checkpoint::open(&opts.out, "stability", params, opts.force).context("--out")?;
    let od = crate::artefact::OutDir::new(&opts.out, opts.force || cp.resuming())?;
    od.reserve(FILES).context("--out")?;
    cp.start()?;
    let units = techs.len() * stability::Scenario::ALL.len();
    if let Some(note) = cp.note("stability", units, "units (technique × family)") {
        eprintln!("{note}");
    }
    let samples = stability::generate(&cfg);
    started(samples.len() * techs.len());
    let t0 = std::time::Instant::now();
    let report = stability::run(&cfg, &techs, &samples, progress, Some(&Units(&cp)))?;
    let secs = t0.elapsed().as_secs_f64();
    let md = markdown(&report, secs, opts);
    od.write_text("stability.md", &md)?;
    for mode in [Mode::F64, Mode::F32, Mode::U16] {
        let name = format!("heatmap_{}.svg", mode.name());
        let mut svg = String::new();
        heat_maps(&mut svg, &od.path(&name)?, &report, mode)?;
        od.write_text(&name, &svg)?;
    }
    // Last: its presence marks a finished study (the pipeline's step keeps the folder then).
    od.write_json("stability.json", &report)?;
    cp.finish()?;
    Ok(Outcome {
        inputs: samples.len(),
        techniques: techs.len(),
        seconds: secs,
    })
}

/// The units of the study kept in its checkpoint.
struct Units<'a>(&'a Checkpoint);

impl stability::UnitStore for Units<'_> {
    fn get(&self, key: &str) -> Result<Option<stability::UnitBits>> {
        self.0.get(key)
    }
    fn put(&self, key: &str, unit: &stability::UnitBits) -> Result<()> {
        self.0.put(key, unit)
    }
}

fn pct(x: f64) -> String {
    format!("{:.1}", 100.0 * x)
}
fn sci(x: f64) -> String {
    if x.is_nan() {
        "–".into()
    } else {
        format!("{x:.2e}")
    }
}

fn markdown(r: &Report, secs: f64, args: &Options) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "# Stability of the shadow techniques\n");
    let _ = writeln!(
        s,
        "Generated by `momentlab stability --inputs {} --seed {} --grid {}` in {secs:.0} s; \
         oracle: Algorithm 1 ({} LP) on {} uniform points of [0,1] plus the input's Diracs and z_f, \
         with each technique's basis and the input's distribution (certified answers only; \
         'oracle failures' are inputs where the LP returned `failed`, excluded). \
         Deviation = G − sharp bound \
         (negative: light leaking; positive: darker than any distribution allows). Techniques \
         use their default parameters; for u16 moments their 16-bit defaults (quant_bits = 16). \
         'above bound' counts G > sharp bound + {}. See docs/stability.md.\n",
        args.samples,
        args.seed,
        args.grid,
        r.lp_solver,
        r.config.grid_points,
        r.config.over_tolerance
    );
    let _ = writeln!(s, "## Per technique and input precision\n");
    let _ = writeln!(
        s,
        "| technique | moments | n | NaN/inf % | outside [0,1] % | max abs dev | mean abs dev | above bound % | oracle failures |"
    );
    let _ = writeln!(s, "|---|---|---|---|---|---|---|---|---|");
    for (t, name) in r.techniques.iter().enumerate() {
        for (mode, sm) in &r.by_mode[t] {
            let _ = writeln!(
                s,
                "| {name} | {} | {} | {} | {} | {} | {} | {} | {} |",
                mode.name(),
                sm.count,
                pct(sm.nan_share),
                pct(sm.outside_share),
                sci(sm.max_abs_dev),
                sci(sm.mean_abs_dev),
                pct(sm.over_share),
                sm.oracle_failures
            );
        }
    }
    let mut head = "| technique |".to_string();
    let mut line = "|---|".to_string();
    for sc in Scenario::ALL {
        let _ = write!(head, " {} |", sc.name());
        line.push_str("---|");
    }
    for mode in [Mode::F64, Mode::F32, Mode::U16] {
        let _ = writeln!(
            s,
            "\n## Moments {}: mean abs deviation per scenario (share above the bound by > {} in brackets if > 0)\n",
            mode.name(),
            r.config.over_tolerance
        );
        let _ = writeln!(s, "{head}\n{line}");
        for (t, name) in r.techniques.iter().enumerate() {
            let mut row = format!("| {name} |");
            for sc in Scenario::ALL {
                let d: Vec<f64> = r
                    .points
                    .iter()
                    .filter(|p| p.technique == t && p.mode == mode && p.scenario == sc)
                    .map(|p| if p.g_finite { p.dev } else { f64::INFINITY })
                    .filter(|d| !d.is_nan())
                    .collect();
                let finite: Vec<f64> = d.iter().copied().filter(|x| x.is_finite()).collect();
                let mean = finite.iter().map(|x| x.abs()).sum::<f64>() / finite.len().max(1) as f64;
                let over = d.iter().filter(|&&x| x > r.config.over_tolerance).count();
                if over > 0 {
                    let _ = write!(
                        row,
                        " {} ({}%) |",
                        sci(mean),
                        pct(over as f64 / d.len() as f64)
                    );
                } else {
                    let _ = write!(row, " {} |", sci(mean));
                }
            }
            let _ = writeln!(s, "{row}");
        }
    }
    let _ = writeln!(
        s,
        "\nHeat maps of mean |G − sharp bound| over log₁₀ variance × (z_f − mean), one panel per \
         technique: `heatmap_f64.svg`, `heatmap_f32.svg`, `heatmap_u16.svg` (NaN/inf count as 1)."
    );
    s
}

/// A perceptual-ish colour ramp (dark blue → green → yellow) for t ∈ [0,1].
fn ramp(t: f64) -> RGBColor {
    let stops = [
        (0.0, (40.0, 30.0, 110.0)),
        (0.35, (30.0, 130.0, 140.0)),
        (0.7, (110.0, 200.0, 80.0)),
        (1.0, (250.0, 230.0, 40.0)),
    ];
    let t = t.clamp(0.0, 1.0);
    for w in stops.windows(2) {
        let ((a, ca), (b, cb)) = (w[0], w[1]);
        if t <= b {
            let u = (t - a) / (b - a);
            let l = |x: f64, y: f64| (x + u * (y - x)) as u8;
            return RGBColor(l(ca.0, cb.0), l(ca.1, cb.1), l(ca.2, cb.2));
        }
    }
    RGBColor(250, 230, 40)
}

fn heat_maps(svg: &mut String, path: &Path, r: &Report, mode: Mode) -> Result<()> {
    let e = |e: &dyn std::fmt::Debug| anyhow!("writing {}: {e:?}", path.display());
    let nt = r.techniques.len();
    let cols = 4.min(nt).max(1);
    let rows_p = nt.div_ceil(cols);
    let width = (300 * cols as u32 + 20).max(760);
    let root = SVGBackend::with_string(svg, (width, 270 * rows_p as u32 + 70)).into_drawing_area();
    root.fill(&WHITE).map_err(|x| e(&x))?;
    let (title, body) = root.split_vertically(50);
    title
        .draw_text(
            &format!(
                "mean |G − sharp bound|, moments {} (colour: log10 from −6 to 0; white: no input)",
                mode.name()
            ),
            &("sans-serif", 16).into_text_style(&title),
            (10, 15),
        )
        .map_err(|x| e(&x))?;
    let panels = body.split_evenly((rows_p, cols));
    let (nr, nc) = (16, 24);
    for (t, panel) in panels.iter().enumerate().take(nt) {
        let (cells, (v0, v1), (d0, d1)) = stability::heat_map(&r.points, t, mode, nr, nc);
        let mut chart = ChartBuilder::on(panel)
            .caption(&r.techniques[t], ("sans-serif", 15))
            .margin(6)
            .x_label_area_size(30)
            .y_label_area_size(40)
            .build_cartesian_2d(d0..d1, v0..v1)
            .map_err(|x| e(&x))?;
        chart
            .configure_mesh()
            .disable_mesh()
            .x_desc("z_f − mean")
            .y_desc("log10 variance")
            .x_labels(5)
            .y_labels(6)
            .draw()
            .map_err(|x| e(&x))?;
        let (dw, vh) = ((d1 - d0) / nc as f64, (v1 - v0) / nr as f64);
        let rects = cells.iter().enumerate().flat_map(|(ri, row)| {
            row.iter().enumerate().filter_map(move |(ci, c)| {
                c.map(|v| {
                    let t = (v.max(1e-6).log10() + 6.0) / 6.0;
                    let x = d0 + ci as f64 * dw;
                    let y = v0 + ri as f64 * vh;
                    Rectangle::new([(x, y), (x + dw, y + vh)], ramp(t).filled())
                })
            })
        });
        chart.draw_series(rects).map_err(|x| e(&x))?;
    }
    root.present().map_err(|x| e(&x))?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A study that stops before its last file leaves no `stability.json`, so a resumed
    /// pipeline runs it again instead of keeping a folder without its report.
    #[test]
    fn the_summary_is_written_last() {
        let dir = std::env::temp_dir().join(format!("momentlab-stab-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let opts = Options {
            out: dir.clone(),
            samples: 3,
            seed: 1,
            grid: 16,
            techniques: vec!["vsm".into()],
            force: true,
        };
        // Once the files are reserved, a folder where the last heat map goes: that write fails.
        let block = |_| std::fs::create_dir_all(dir.join("heatmap_u16.svg/x")).unwrap();
        let Err(e) = study(&opts, &block, &|_| {}) else {
            panic!("a heat map over a folder was written")
        };
        assert!(format!("{e:#}").contains("heatmap_u16.svg"), "{e:#}");
        assert!(dir.join("stability.md").exists() && !dir.join("stability.json").exists());
        std::fs::remove_dir_all(dir.join("heatmap_u16.svg")).unwrap();
        study(&opts, &|_| {}, &|_| {}).unwrap();
        for f in FILES {
            assert!(dir.join(f).is_file(), "{f}");
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
