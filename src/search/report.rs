//! Sweep reports (SVG via plotters, Markdown): the Fig. 4 analogue (histogram of candidate
//! errors with reference values), the top-20 table, the Fig. 3 analogue (F_Z and the sharp
//! lower bounds of Algorithm 1 for m = 2, 3, 4 with polynomial and trigonometric bases), error
//! distributions for several m side by side, and where b_MSM / b_TMSM rank.

use super::results::{ranking, read_json, read_rows, Row};
use super::score::bound_curve;
use super::{Dataset, FunctionTable, Scorer, SweepConfig};
use crate::metrics::{self, Bias, EvalOptions};
use crate::stack::DepthStack;
use anyhow::{bail, Context, Result};
use plotters::prelude::*;
use serde::Serialize;
use std::f64::consts::PI;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// A labelled error value marked in the histogram (e.g. "b_MSM (LP)").
#[derive(Clone, Debug, PartialEq)]
pub struct Reference {
    pub label: String,
    /// Number of functions (ranks are only stated among candidates of the same m).
    pub m: usize,
    pub error: f64,
    pub stderr: f64,
    /// A closed-form technique evaluated by [`metrics::evaluate`] on every fragment of the
    /// stacks (not an LP candidate on the sweep's fragments).
    pub closed_form: bool,
}

/// The paper's reference bases (Eq. 1 and VSM/ESM) tabulated on a grid, for reference values
/// and Fig. 3: columns z, z², z³, z⁴, sin 2πz, cos 2πz, sin 4πz, cos 4πz, exp(80(z−1)).
pub fn paper_bases(grid: &crate::Grid) -> Result<FunctionTable> {
    let names = [
        "z",
        "z^2",
        "z^3",
        "z^4",
        "sin(2pi z)",
        "cos(2pi z)",
        "sin(4pi z)",
        "cos(4pi z)",
        "exp(80(z-1))",
    ];
    FunctionTable::new(
        grid,
        names.iter().map(|s| s.to_string()).collect(),
        |j, z| match j {
            0..=3 => z.powi(j as i32 + 1),
            4 => (2.0 * PI * z).sin(),
            5 => (2.0 * PI * z).cos(),
            6 => (4.0 * PI * z).sin(),
            7 => (4.0 * PI * z).cos(),
            _ => (80.0 * (z - 1.0)).exp(),
        },
    )
}

/// Column sets of [`paper_bases`]: polynomial and trigonometric bases with m functions.
pub fn poly_cols(m: usize) -> Vec<usize> {
    (0..m).collect()
}
pub fn trig_cols(m: usize) -> Vec<usize> {
    (4..4 + m).collect()
}

/// Reference values as LP candidates on every fragment: PCF (0), VSM = (z, z²),
/// ESM = exp(80(z−1)) (c = 80), b_MSM, b_TMSM.
pub fn lp_references(data: &Dataset, solver: &str, chunk: usize) -> Result<Vec<Reference>> {
    let table = paper_bases(data.grid())?;
    let s = Scorer::new(data, &table, solver, chunk)?;
    let ids: Vec<u32> = (0..data.fragments().len() as u32).collect();
    let sets: [(&str, Vec<usize>); 4] = [
        ("VSM (LP)", vec![0, 1]),
        ("ESM c=80 (LP)", vec![8]),
        ("b_MSM (LP)", poly_cols(4)),
        ("b_TMSM (LP)", trig_cols(4)),
    ];
    let subsets: Vec<Vec<usize>> = sets.iter().map(|s| s.1.clone()).collect();
    let errs = s.errors_many(&subsets, &ids, &|_| {})?;
    let mut out = vec![Reference {
        label: "PCF".into(),
        m: 0,
        error: 0.0,
        stderr: 0.0,
        closed_form: false,
    }];
    for ((label, cols), e) in sets.iter().zip(errs) {
        let sum: f64 = e.errors.iter().sum();
        let sumsq: f64 = e.errors.iter().map(|x| x * x).sum();
        let (error, stderr) = data.error_estimate(e.errors.len() as u64, sum, sumsq);
        out.push(Reference {
            label: label.to_string(),
            m: cols.len(),
            error,
            stderr: if stderr.is_finite() { stderr } else { 0.0 },
            closed_form: false,
        });
    }
    Ok(out)
}

/// Closed-form techniques marked in the Fig. 4 analogue: (registry name, label, m).
pub const CLOSED_FORMS: [(&str, &str, usize); 4] = [
    ("hamburger4", "4MSM Hamburger (closed form)", 4),
    ("tmsm", "TMSM (closed form)", 4),
    ("vsm", "VSM (closed form)", 2),
    ("esm", "ESM (closed form)", 1),
];

/// The closed forms of [`CLOSED_FORMS`] (`technique::by_name`, default parameters) evaluated
/// with [`metrics::evaluate`] on every fragment of `stacks` with `bias`: the population value
/// the sweep's sampled candidate errors estimate (standard error 0: nothing is sampled).
pub fn closed_form_references(stacks: &[DepthStack], bias: &Bias) -> Result<Vec<Reference>> {
    let opts = EvalOptions {
        bias: *bias,
        ..EvalOptions::default()
    };
    let mut out = Vec::new();
    for (name, label, m) in CLOSED_FORMS {
        let t = crate::technique::by_name(name)?;
        let r = metrics::evaluate(stacks, t.as_ref(), &opts)
            .with_context(|| format!("evaluating {name}"))?;
        out.push(Reference {
            label: label.to_string(),
            m,
            error: r.error,
            stderr: 0.0,
            closed_form: true,
        });
    }
    Ok(out)
}

/// A reference value with its rank among the scored candidates of the same m.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct RankedReference {
    pub label: String,
    pub m: usize,
    pub error: f64,
    pub stderr: f64,
    pub closed_form: bool,
    /// 1 + number of candidates with a smaller error (None: different m or PCF).
    pub rank: Option<usize>,
}

/// The best candidate of a results set.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Best {
    pub index: u64,
    pub functions: Vec<String>,
    pub error: f64,
    pub stderr: f64,
    /// Scored on every fragment of the dataset (not only a racing sample).
    pub full: bool,
}

/// What a report says, as numbers (for `momentlab reproduce`).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Summary {
    /// Candidates with an error (scored, or duplicates of a scored one).
    pub scored: usize,
    pub best: Option<Best>,
    pub references: Vec<RankedReference>,
}

impl Summary {
    /// The reference with this label, if present.
    pub fn reference(&self, label: &str) -> Option<&RankedReference> {
        self.references.iter().find(|r| r.label == label)
    }
}

/// Best candidate and the ranks of `refs` among `rows` (same m only).
pub fn summarize(rows: &[Row], refs: &[Reference]) -> Summary {
    let errs = errors_of(rows);
    let ranked = ranking(rows);
    let best = ranked.first().map(|r| Best {
        index: r.index,
        functions: r.functions.clone(),
        error: r.error.unwrap_or(f64::NAN),
        stderr: r.stderr.unwrap_or(0.0),
        full: r.full,
    });
    let m = best.as_ref().map(|b| b.functions.len());
    Summary {
        scored: errs.len(),
        references: refs
            .iter()
            .map(|r| RankedReference {
                label: r.label.clone(),
                m: r.m,
                error: r.error,
                stderr: r.stderr,
                closed_form: r.closed_form,
                rank: (Some(r.m) == m && r.label != "PCF").then(|| rank_of(&errs, r.error)),
            })
            .collect(),
        best,
    }
}

/// Options of [`write`].
#[derive(Clone, Debug)]
pub struct ReportOptions {
    /// Solver and chunk size for the Fig. 3 curves.
    pub solver: String,
    pub chunk: usize,
    /// Results directories of other sweeps (e.g. m = 2 and 3) for the side-by-side plot.
    pub compare: Vec<PathBuf>,
    /// Depths at which the Fig. 3 curves are solved.
    pub fig3_points: usize,
    /// How the results are named in the text (e.g. their directory).
    pub results_label: String,
}

impl Default for ReportOptions {
    fn default() -> Self {
        ReportOptions {
            solver: "fast-strict".into(),
            chunk: 4096,
            compare: Vec::new(),
            fig3_points: 96,
            results_label: String::new(),
        }
    }
}

/// Write the report of a sweep into `dir`: `fig4_m<m>.svg` (histogram with `refs` marked),
/// `distributions.svg` (this sweep and `opts.compare` side by side), `fig3.svg` and
/// `search_m<m>.md` (ranking text, top-20 table). Returns the numbers the text states.
pub fn write(
    dir: &Path,
    rows: &[Row],
    data: &Dataset,
    refs: &[Reference],
    opts: &ReportOptions,
) -> Result<Summary> {
    let summary = summarize(rows, refs);
    let Some(best) = &summary.best else {
        bail!("no scored candidates to report");
    };
    let m = best.functions.len();
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    let errs = errors_of(rows);
    plot_histogram(
        &dir.join(format!("fig4_m{m}.svg")),
        &format!("Candidate errors, m = {m} ({} candidates)", errs.len()),
        &errs,
        refs,
    )?;
    let mut sets = vec![(format!("m = {m}"), errs.clone())];
    for d in &opts.compare {
        let r = read_rows(d)?;
        let cfg: SweepConfig = read_json(&d.join(super::results::CONFIG_FILE))?;
        if cfg.m != m {
            sets.push((format!("m = {}", cfg.m), errors_of(&r)));
        }
    }
    sets.sort_by(|a, b| a.0.cmp(&b.0));
    plot_side_by_side(&dir.join("distributions.svg"), &sets)?;
    let kernels = pick_kernels(data, 3);
    let panels = fig3_panels(data, &kernels, opts.fig3_points, &opts.solver)?;
    plot_fig3(&dir.join("fig3.svg"), &panels)?;
    let sampled = data.sampled_fraction();
    let mut md = format!(
        "# Candidate sweep, m = {m}\n\nResults: `{}`. {} fragments, {} non-trivial; the sweep's dataset \
         holds {} of the non-trivial ones ({:.2} %, stratified by view and layer), trivial fragments \
         (G = 0 for every candidate) are counted exactly.\n\n![Fig. 4 analogue](fig4_m{m}.svg)\n\n\
         ## Ranking\n\n{}\n## Top 20\n\n{}\n![error distributions](distributions.svg)\n\n\
         ![Fig. 3 analogue](fig3.svg)\n",
        opts.results_label,
        data.total_count(),
        data.nontrivial_population(),
        data.fragments().len(),
        sampled * 100.0,
        ranking_text(rows, refs),
        top_table(rows, 20)
    );
    md.push_str(
        "\nReference values: LP candidates (label \"(LP)\") are scored on every fragment of the \
         sweep's dataset with the same grid and solver as the candidates; closed forms (label \
         \"(closed form)\") are `momentlab evaluate` values (metrics::evaluate, same bias) on every \
         fragment of the stacks. Errors and standard errors estimate the mean |G − PCF| over all \
         fragments of the stacks.\n",
    );
    std::fs::write(dir.join(format!("search_m{m}.md")), md)
        .with_context(|| format!("writing {}", dir.display()))?;
    Ok(summary)
}

/// Scored errors of a results set (duplicates resolved), ascending.
pub fn errors_of(rows: &[Row]) -> Vec<f64> {
    ranking(rows).iter().filter_map(|r| r.error).collect()
}

fn histogram_bins(values: &[f64], lo: f64, hi: f64, bins: usize) -> Vec<u32> {
    let mut h = vec![0u32; bins];
    let w = (hi - lo) / bins as f64;
    for &v in values {
        let k = (((v - lo) / w).floor().max(0.0) as usize).min(bins - 1);
        h[k] += 1;
    }
    h
}

fn range_of(values: &[f64], refs: &[Reference]) -> (f64, f64) {
    let mut lo = f64::INFINITY;
    let mut hi = f64::NEG_INFINITY;
    for v in values.iter().copied().chain(refs.iter().map(|r| r.error)) {
        if v.is_finite() {
            lo = lo.min(v);
            hi = hi.max(v);
        }
    }
    if !lo.is_finite() {
        return (0.0, 1.0);
    }
    let pad = ((hi - lo) * 0.03).max(1e-4);
    ((lo - pad).max(0.0), hi + pad)
}

/// Fig. 4 analogue: histogram of candidate errors (%) with vertical reference markers.
pub fn plot_histogram(path: &Path, title: &str, errors: &[f64], refs: &[Reference]) -> Result<()> {
    let root = SVGBackend::new(path, (900, 500)).into_drawing_area();
    draw_histogram(&root, title, errors, refs, 60)?;
    root.present()
        .with_context(|| format!("writing {}", path.display()))?;
    Ok(())
}

fn draw_histogram<DB: DrawingBackend>(
    area: &DrawingArea<DB, plotters::coord::Shift>,
    title: &str,
    errors: &[f64],
    refs: &[Reference],
    bins: usize,
) -> Result<()>
where
    DB::ErrorType: 'static,
{
    area.fill(&WHITE).map_err(|e| anyhow::anyhow!("{e:?}"))?;
    let (lo, hi) = range_of(errors, refs);
    let h = histogram_bins(errors, lo, hi, bins);
    let ymax = h.iter().copied().max().unwrap_or(1).max(1) as f64 * 1.15;
    let mut chart = ChartBuilder::on(area)
        .caption(title, ("sans-serif", 18))
        .margin(10)
        .x_label_area_size(40)
        .y_label_area_size(55)
        .build_cartesian_2d(lo * 100.0..hi * 100.0, 0.0..ymax)
        .map_err(|e| anyhow::anyhow!("{e:?}"))?;
    chart
        .configure_mesh()
        .x_desc("mean error |G - PCF| (%)")
        .y_desc("candidates")
        .draw()
        .map_err(|e| anyhow::anyhow!("{e:?}"))?;
    let w = (hi - lo) / bins as f64 * 100.0;
    chart
        .draw_series(h.iter().enumerate().map(|(k, &c)| {
            let x0 = lo * 100.0 + k as f64 * w;
            Rectangle::new([(x0, 0.0), (x0 + w, c as f64)], BLUE.mix(0.5).filled())
        }))
        .map_err(|e| anyhow::anyhow!("{e:?}"))?;
    let colors = [
        BLACK,
        RED,
        GREEN,
        MAGENTA,
        CYAN,
        full_palette::ORANGE,
        full_palette::BROWN,
    ];
    for (i, r) in refs.iter().enumerate() {
        let c = colors[i % colors.len()];
        let x = r.error * 100.0;
        chart
            .draw_series(LineSeries::new(
                vec![(x, 0.0), (x, ymax)],
                c.stroke_width(2),
            ))
            .map_err(|e| anyhow::anyhow!("{e:?}"))?
            .label(format!("{} {:.3}%", r.label, x))
            .legend(move |(a, b)| PathElement::new(vec![(a, b), (a + 15, b)], c.stroke_width(2)));
    }
    if !refs.is_empty() {
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .draw()
            .map_err(|e| anyhow::anyhow!("{e:?}"))?;
    }
    Ok(())
}

/// Error distributions of several sweeps (e.g. m = 2, 3, 4) side by side on a common axis.
pub fn plot_side_by_side(path: &Path, sets: &[(String, Vec<f64>)]) -> Result<()> {
    let root = SVGBackend::new(path, (420 * sets.len().max(1) as u32, 420)).into_drawing_area();
    let all: Vec<f64> = sets.iter().flat_map(|s| s.1.iter().copied()).collect();
    let (lo, hi) = range_of(&all, &[]);
    let areas = root.split_evenly((1, sets.len().max(1)));
    for (area, (label, v)) in areas.iter().zip(sets) {
        let refs = [Reference {
            label: "best".into(),
            m: 0,
            error: v.first().copied().unwrap_or(f64::NAN),
            stderr: 0.0,
            closed_form: false,
        }];
        let finite: Vec<f64> = v.iter().copied().filter(|x| x.is_finite()).collect();
        draw_histogram_range(area, label, &finite, &refs, lo, hi)?;
    }
    root.present()
        .with_context(|| format!("writing {}", path.display()))?;
    Ok(())
}

fn draw_histogram_range<DB: DrawingBackend>(
    area: &DrawingArea<DB, plotters::coord::Shift>,
    title: &str,
    errors: &[f64],
    refs: &[Reference],
    lo: f64,
    hi: f64,
) -> Result<()>
where
    DB::ErrorType: 'static,
{
    let bins = 40;
    area.fill(&WHITE).map_err(|e| anyhow::anyhow!("{e:?}"))?;
    let h = histogram_bins(errors, lo, hi, bins);
    let ymax = h.iter().copied().max().unwrap_or(1).max(1) as f64 * 1.15;
    let mut chart = ChartBuilder::on(area)
        .caption(title, ("sans-serif", 16))
        .margin(8)
        .x_label_area_size(35)
        .y_label_area_size(50)
        .build_cartesian_2d(lo * 100.0..hi * 100.0, 0.0..ymax)
        .map_err(|e| anyhow::anyhow!("{e:?}"))?;
    chart
        .configure_mesh()
        .x_desc("mean error (%)")
        .y_desc("candidates")
        .draw()
        .map_err(|e| anyhow::anyhow!("{e:?}"))?;
    let w = (hi - lo) / bins as f64 * 100.0;
    chart
        .draw_series(h.iter().enumerate().map(|(k, &c)| {
            let x0 = lo * 100.0 + k as f64 * w;
            Rectangle::new([(x0, 0.0), (x0 + w, c as f64)], BLUE.mix(0.5).filled())
        }))
        .map_err(|e| anyhow::anyhow!("{e:?}"))?;
    for r in refs.iter().filter(|r| r.error.is_finite()) {
        let x = r.error * 100.0;
        chart
            .draw_series(LineSeries::new(
                vec![(x, 0.0), (x, ymax)],
                RED.stroke_width(2),
            ))
            .map_err(|e| anyhow::anyhow!("{e:?}"))?;
    }
    Ok(())
}

/// One Fig. 3 panel: F_Z and the bounds G for m = 2, 3, 4 of one basis family.
pub struct Fig3Panel {
    pub title: String,
    /// z_f values.
    pub z: Vec<f64>,
    pub cdf: Vec<f64>,
    /// (label, G values) for m = 2, 3, 4.
    pub bounds: Vec<(String, Vec<f64>)>,
}

/// Fig. 3 analogue data for `kernels` (distribution ids): polynomial and trigonometric bases,
/// m = 2, 3, 4, G at up to `points` grid depths.
pub fn fig3_panels(
    data: &Dataset,
    kernels: &[u32],
    points: usize,
    solver: &str,
) -> Result<Vec<Fig3Panel>> {
    let table = paper_bases(data.grid())?;
    let n = data.grid().len();
    let step = n.div_ceil(points.max(2)).max(1);
    let mut idx: Vec<usize> = (0..n).step_by(step).collect();
    if *idx.last().unwrap() != n - 1 {
        idx.push(n - 1);
    }
    let z: Vec<f64> = idx.iter().map(|&i| data.grid().points()[i]).collect();
    let mut out = Vec::new();
    for &k in kernels {
        let dist = data.distribution(k);
        let cdf: Vec<f64> = idx.iter().map(|&i| data.cdf(k, i as u32)).collect();
        for (family, cols) in [
            ("polynomial", poly_cols as fn(usize) -> Vec<usize>),
            ("trigonometric", trig_cols),
        ] {
            let mut bounds = Vec::new();
            for m in 2..=4 {
                let g = bound_curve(&table, &cols(m), dist, &idx, solver)?;
                bounds.push((format!("m = {m}"), g));
            }
            out.push(Fig3Panel {
                title: format!("kernel {k}, {family}"),
                z: z.clone(),
                cdf: cdf.clone(),
                bounds,
            });
        }
    }
    Ok(out)
}

/// Kernels for Fig. 3: the `count` distributions with the most distinct depths (ties: id).
pub fn pick_kernels(data: &Dataset, count: usize) -> Vec<u32> {
    let mut d: Vec<(usize, u32)> = (0..data.distribution_count() as u32)
        .map(|k| (data.distribution(k).len(), k))
        .collect();
    d.sort_by(|a, b| b.0.cmp(&a.0).then(a.1.cmp(&b.1)));
    d.into_iter().take(count).map(|x| x.1).collect()
}

/// Draw Fig. 3 panels in a grid (two columns: polynomial, trigonometric).
pub fn plot_fig3(path: &Path, panels: &[Fig3Panel]) -> Result<()> {
    let rows = panels.len().div_ceil(2).max(1);
    let root = SVGBackend::new(path, (900, 300 * rows as u32)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| anyhow::anyhow!("{e:?}"))?;
    let areas = root.split_evenly((rows, 2));
    for (area, p) in areas.iter().zip(panels) {
        let (zlo, zhi) = (p.z[0], *p.z.last().unwrap());
        let mut chart = ChartBuilder::on(area)
            .caption(&p.title, ("sans-serif", 14))
            .margin(6)
            .x_label_area_size(30)
            .y_label_area_size(35)
            .build_cartesian_2d(zlo..zhi, 0.0..1.05)
            .map_err(|e| anyhow::anyhow!("{e:?}"))?;
        chart
            .configure_mesh()
            .x_desc("z_f")
            .draw()
            .map_err(|e| anyhow::anyhow!("{e:?}"))?;
        let series: Vec<(String, RGBColor, &Vec<f64>)> =
            std::iter::once(("F_Z".into(), BLUE, &p.cdf))
                .chain(
                    p.bounds
                        .iter()
                        .zip([RED, CYAN, GREEN])
                        .map(|((l, g), c)| (l.clone(), c, g)),
                )
                .collect();
        for (label, c, v) in series {
            chart
                .draw_series(LineSeries::new(
                    p.z.iter()
                        .zip(v)
                        .filter(|(_, g)| g.is_finite())
                        .map(|(&z, &g)| (z, g)),
                    c.stroke_width(2),
                ))
                .map_err(|e| anyhow::anyhow!("{e:?}"))?
                .label(label)
                .legend(move |(a, b)| {
                    PathElement::new(vec![(a, b), (a + 15, b)], c.stroke_width(2))
                });
        }
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperLeft)
            .background_style(WHITE.mix(0.85))
            .draw()
            .map_err(|e| anyhow::anyhow!("{e:?}"))?;
    }
    root.present()
        .with_context(|| format!("writing {}", path.display()))?;
    Ok(())
}

/// Markdown table of the `count` best candidates.
pub fn top_table(rows: &[Row], count: usize) -> String {
    let mut s = String::from("| rank | index | functions | error (%) | ± s.e. (%) | fragments | scored on |\n|---:|---:|---|---:|---:|---:|---|\n");
    for (k, r) in ranking(rows).iter().take(count).enumerate() {
        let _ = writeln!(
            s,
            "| {} | {} | {} | {:.4} | {:.4} | {} | {} |",
            k + 1,
            r.index,
            r.functions.join(", "),
            r.error.unwrap() * 100.0,
            r.stderr.unwrap_or(0.0) * 100.0,
            r.fragments,
            if r.full { "all fragments" } else { "sample" }
        );
    }
    s
}

/// Rank of an error value among the scored candidates: 1 + #candidates strictly better.
pub fn rank_of(errors_sorted: &[f64], e: f64) -> usize {
    1 + errors_sorted.partition_point(|&x| x < e)
}

/// Text: where the references rank and how far the best candidate is below them.
pub fn ranking_text(rows: &[Row], refs: &[Reference]) -> String {
    let errs = errors_of(rows);
    let mut s = String::new();
    let Some(&best) = errs.first() else {
        return "No scored candidates.\n".into();
    };
    let top = &ranking(rows)[0];
    let _ = writeln!(
        s,
        "The best of {} scored candidates is {} = ({}) with {:.4} % ± {:.4} %.\n",
        errs.len(),
        top.index,
        top.functions.join(", "),
        best * 100.0,
        top.stderr.unwrap_or(0.0) * 100.0
    );
    let m = top.functions.len();
    for r in refs.iter().filter(|r| r.label != "PCF" && r.m != m) {
        let _ = writeln!(
            s,
            "- {} (m = {}): {:.4} % ± {:.4} % (not ranked: different m).",
            r.label,
            r.m,
            r.error * 100.0,
            r.stderr * 100.0
        );
    }
    for r in refs.iter().filter(|r| r.label != "PCF" && r.m == m) {
        let _ = writeln!(
            s,
            "- {}: {:.4} % ± {:.4} %, rank {} of {} (the best candidate is {:.4} percentage points, {:.1} % relative, below it).",
            r.label,
            r.error * 100.0,
            r.stderr * 100.0,
            rank_of(&errs, r.error),
            errs.len(),
            (r.error - best) * 100.0,
            if r.error > 0.0 { (r.error - best) / r.error * 100.0 } else { 0.0 }
        );
    }
    s.push_str(
        "\nPaper (Peters & Klein 2015, Section 3.2): b_MSM 2.19 %, b_TMSM 1.93 % (the minimum over all 66045 candidates).\n",
    );
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(index: u64, e: Option<f64>, dup: Option<u64>) -> Row {
        Row {
            index,
            functions: vec![format!("f{index}")],
            error: e,
            stderr: e.map(|_| 0.001),
            fragments: 10,
            degenerate: e.is_none() && dup.is_none(),
            duplicate_of: dup,
            seconds: 0.0,
            stage: 0,
            full: true,
            lp_failures: 0,
        }
    }

    #[test]
    fn ranking_table_and_text() {
        let rows = vec![
            row(0, Some(0.03), None),
            row(1, Some(0.02), None),
            row(2, None, None),
            row(3, None, Some(1)),
        ];
        let r = ranking(&rows);
        assert_eq!(r.iter().map(|r| r.index).collect::<Vec<_>>(), vec![1, 3, 0]);
        assert_eq!(rank_of(&errors_of(&rows), 0.025), 3);
        assert_eq!(rank_of(&errors_of(&rows), 0.01), 1);
        let t = top_table(&rows, 2);
        assert_eq!(t.lines().count(), 4);
        assert!(t.contains("| 1 | 1 | f1 | 2.0000 |"), "{t}");
        let refs = [Reference {
            label: "b_MSM (LP)".into(),
            m: 1,
            error: 0.025,
            stderr: 0.0,
            closed_form: false,
        }];
        let text = ranking_text(&rows, &refs);
        assert!(text.contains("rank 3 of 3"), "{text}");
        assert!(text.contains("0.5000 percentage points"), "{text}");
    }

    #[test]
    fn svg_files_are_written() {
        let dir = std::env::temp_dir().join(format!("momentlab-report-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let errs: Vec<f64> = (0..100).map(|k| 0.02 + k as f64 * 1e-4).collect();
        let refs = vec![Reference {
            label: "b_MSM (LP)".into(),
            m: 4,
            error: 0.025,
            stderr: 0.0,
            closed_form: false,
        }];
        plot_histogram(&dir.join("h.svg"), "test", &errs, &refs).unwrap();
        plot_side_by_side(
            &dir.join("s.svg"),
            &[("m = 2".into(), errs.clone()), ("m = 4".into(), errs)],
        )
        .unwrap();
        let svg = std::fs::read_to_string(dir.join("h.svg")).unwrap();
        assert!(svg.contains("<svg") && svg.contains("b_MSM"));
        let g = crate::Grid::uniform(16).unwrap();
        let data = Dataset::synthetic(1, &g, 1, 5, 2).unwrap();
        let panels = fig3_panels(&data, &pick_kernels(&data, 1), 8, "reference").unwrap();
        assert_eq!(panels.len(), 2);
        for p in &panels {
            // Lower bounds: G ≤ F_Z, and more moments never hurt (m=4 ≥ m=2 pointwise).
            for (k, &c) in p.cdf.iter().enumerate() {
                for (_, g) in &p.bounds {
                    assert!(g[k] <= c + 1e-7, "{} {}", g[k], c);
                }
                assert!(p.bounds[2].1[k] >= p.bounds[0].1[k] - 1e-7);
            }
        }
        plot_fig3(&dir.join("f3.svg"), &panels).unwrap();
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
