//! Sweep reports (SVG via plotters, Markdown): the Fig. 4 analogue (histogram of candidate
//! errors with reference values), the top-20 table, the Fig. 3 analogue (F_Z and the sharp
//! lower bounds of Algorithm 1 for m = 2, 3, 4 with polynomial and trigonometric bases), error
//! distributions for several m side by side, and where b_MSM / b_TMSM rank.

use super::race::{normal_quantile, Moments};
use super::results::{ranking, read_json, read_rows, Row};
use super::score::bound_curve;
use super::tieset::{status, tie_set, TieSet};
use super::{Dataset, FunctionTable, RaceSummary, Scorer, SweepConfig};
use crate::artefact::OutDir;
use crate::metrics::{self, Bias, EvalOptions};
use crate::report::chart::svg_string;
use crate::stack::DepthStack;
use anyhow::{bail, Context, Result};
use plotters::prelude::*;
use serde::Serialize;
use std::f64::consts::PI;
use std::fmt::Write as _;
use std::path::PathBuf;

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
    /// error − error(winner) and its standard error, paired on the same fragments
    /// ([`pair_with_winner`]); None: filled in unpaired by [`summarize`].
    pub diff: Option<(f64, f64)>,
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
/// Display names of the columns of [`paper_bases`] (Fig. 3 legends).
const FIG3_NAMES: [&str; 8] = [
    "z", "z²", "z³", "z⁴", "sin 2πz", "cos 2πz", "sin 4πz", "cos 4πz",
];

pub fn poly_cols(m: usize) -> Vec<usize> {
    (0..m).collect()
}
pub fn trig_cols(m: usize) -> Vec<usize> {
    (4..4 + m).collect()
}

/// The paper's LP reference bases: (label, columns of [`paper_bases`]).
fn lp_reference_sets() -> [(&'static str, Vec<usize>); 4] {
    [
        ("VSM (LP)", vec![0, 1]),
        ("ESM c=80 (LP)", vec![8]),
        ("b_MSM (LP)", poly_cols(4)),
        ("b_TMSM (LP)", trig_cols(4)),
    ]
}

/// Reference values as LP candidates on every fragment: PCF (0), VSM = (z, z²),
/// ESM = exp(80(z−1)) (c = 80), b_MSM, b_TMSM.
pub fn lp_references(data: &Dataset, solver: &str, chunk: usize) -> Result<Vec<Reference>> {
    Ok(lp_reference_errors(data, solver, chunk)?
        .into_iter()
        .map(|(r, _)| r)
        .collect())
}

/// [`lp_references`] with each reference's per-fragment errors (fragment order 0..n).
fn lp_reference_errors(
    data: &Dataset,
    solver: &str,
    chunk: usize,
) -> Result<Vec<(Reference, Vec<f64>)>> {
    let table = paper_bases(data.grid())?;
    let s = Scorer::new(data, &table, solver, chunk)?;
    let ids: Vec<u32> = (0..data.fragments().len() as u32).collect();
    let sets = lp_reference_sets();
    let subsets: Vec<Vec<usize>> = sets.iter().map(|s| s.1.clone()).collect();
    let errs = s.errors_many(&subsets, &ids, &|_| {})?;
    let mut out = vec![(
        Reference {
            label: "PCF".into(),
            m: 0,
            error: 0.0,
            stderr: 0.0,
            closed_form: false,
            diff: None,
        },
        Vec::new(),
    )];
    for ((label, cols), e) in sets.iter().zip(errs) {
        let m = Moments::of(&e.errors);
        let (error, stderr) = data.error_estimate(m.n, m.sum, m.sumsq);
        out.push((
            Reference {
                label: label.to_string(),
                m: cols.len(),
                error,
                stderr: if stderr.is_finite() { stderr } else { 0.0 },
                closed_form: false,
                diff: None,
            },
            e.errors,
        ));
    }
    Ok(out)
}

/// [`lp_references`] with the paired difference of each reference to the winner `cols` of
/// `table` (both scored on every fragment of `data` in one pass, same solver): mean of
/// e_ref − e_winner over the fragments, scaled like the errors, with its standard error.
pub fn lp_references_paired(
    data: &Dataset,
    table: &FunctionTable,
    winner: &[usize],
    solver: &str,
    chunk: usize,
) -> Result<Vec<Reference>> {
    let ids: Vec<u32> = (0..data.fragments().len() as u32).collect();
    let s = Scorer::new(data, table, solver, chunk)?;
    let ew = s.errors_many(&[winner.to_vec()], &ids, &|_| {})?;
    let ew = &ew[0].errors;
    let scale = data.nontrivial_population() as f64 / data.total_count().max(1) as f64;
    Ok(lp_reference_errors(data, solver, chunk)?
        .into_iter()
        .map(|(mut r, e)| {
            if !e.is_empty() {
                let d: Vec<f64> = e.iter().zip(ew).map(|(a, b)| a - b).collect();
                let m = Moments::of(&d);
                r.diff = Some((m.mean() * scale, m.se() * scale));
            }
            r
        })
        .collect())
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
            diff: None,
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
    /// error − error(winner) and its standard error (None: PCF).
    pub diff: Option<(f64, f64)>,
    /// `diff` is paired on the same fragments (LP references) rather than unpaired (closed
    /// forms: exact value minus the winner's estimate).
    pub paired: bool,
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
    /// The winner (the best survivor of the race, or the best candidate scored on every
    /// fragment).
    pub best: Option<Best>,
    pub references: Vec<RankedReference>,
    /// Racing: candidates statistically tied for first (the winner included), eliminated by
    /// confidence, eliminated by the cap (0 for exhaustive runs).
    pub tied: usize,
    pub confidence_eliminated: usize,
    pub cap_eliminated: usize,
}

impl Summary {
    /// The reference with this label, if present.
    pub fn reference(&self, label: &str) -> Option<&RankedReference> {
        self.references.iter().find(|r| r.label == label)
    }
}

/// The winner and the ranks of `refs` among `rows` (same m only), with each reference's
/// difference to the winner (paired where [`lp_references_paired`] computed it, else unpaired:
/// √(se_ref² + se_winner²)).
pub fn summarize(rows: &[Row], refs: &[Reference]) -> Summary {
    let errs = errors_of(rows);
    let t = tie_set(rows);
    let best = t.winner.as_ref().map(|r| Best {
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
            .map(|r| {
                let unpaired = best.as_ref().map(|b| {
                    (
                        r.error - b.error,
                        (r.stderr * r.stderr + b.stderr * b.stderr).sqrt(),
                    )
                });
                RankedReference {
                    label: r.label.clone(),
                    m: r.m,
                    error: r.error,
                    stderr: r.stderr,
                    closed_form: r.closed_form,
                    rank: (Some(r.m) == m && r.label != "PCF").then(|| rank_of(&errs, r.error)),
                    diff: if r.label == "PCF" {
                        None
                    } else {
                        r.diff.or(unpaired)
                    },
                    paired: r.diff.is_some(),
                }
            })
            .collect(),
        best,
        tied: t.tied.len(),
        confidence_eliminated: t.confidence,
        cap_eliminated: t.cap.len(),
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
    /// The race's own account (`complete.json` of an unsharded racing run).
    pub race: Option<RaceSummary>,
    /// Confidence of the race (intervals in the text are stated at this level).
    pub confidence: f64,
    /// The cap of the race (kept fraction per stage).
    pub keep: f64,
}

impl Default for ReportOptions {
    fn default() -> Self {
        ReportOptions {
            solver: "fast-strict".into(),
            chunk: 4096,
            compare: Vec::new(),
            fig3_points: 96,
            results_label: String::new(),
            race: None,
            confidence: 0.99,
            keep: 0.25,
        }
    }
}

/// Write the report of a sweep into `dir`: `fig4_m<m>.svg` (histogram with `refs` marked),
/// `distributions.svg` (this sweep and `opts.compare` side by side), `fig3.svg` and
/// `search_m<m>.md` (ranking text, top-20 table). Returns the numbers the text states.
pub fn write(
    out: &OutDir,
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
    let errs = errors_of(rows);
    let ties = tie_set(rows);
    out.write_text(
        &format!("fig4_m{m}.svg"),
        &plot_fig4(
            &format!("Candidate errors, m = {m} ({} candidates)", errs.len()),
            rows,
            refs,
        )?,
    )?;
    if let Some(csv) = cap_list(&ties) {
        out.write_text(&format!("cap_eliminated_m{m}.csv"), &csv)?;
    }
    let mut sets = vec![(format!("m = {m}"), errs.clone())];
    for d in &opts.compare {
        let r = read_rows(d)?;
        let cfg: SweepConfig = read_json(&d.join(super::results::CONFIG_FILE))?;
        if cfg.m != m {
            sets.push((format!("m = {}", cfg.m), errors_of(&r)));
        }
    }
    sets.sort_by(|a, b| a.0.cmp(&b.0));
    out.write_text("distributions.svg", &plot_side_by_side(&sets)?)?;
    let kernels = pick_kernels(data, 3);
    let panels = fig3_panels(data, &kernels, opts.fig3_points, &opts.solver)?;
    out.write_text("fig3.svg", &plot_fig3(&panels)?)?;
    let sampled = data.sampled_fraction();
    let mut md = format!(
        "# Candidate sweep, m = {m}\n\nWritten by {}.\n\nResults: `{}`. {} fragments, {} non-trivial; the sweep's dataset \
         holds {} of the non-trivial ones ({:.2} %, stratified by view and layer), trivial fragments \
         (G = 0 for every candidate) are counted exactly.\n\n![Fig. 4 analogue](fig4_m{m}.svg)\n\n\
         ## What the race resolved\n\n{}\n## The winner, the paper's bases and the closed forms\n\n{}\n\
         ## Ranking\n\n{}\n## Tied for first\n\n{}\n## Top 20\n\nCandidates scored on every fragment of the sample are ranked first; below them, \
         unranked (–), the lowest estimates of candidates that left the race on fewer fragments.\n\n{}\n\
         ![error distributions](distributions.svg)\n\n![Fig. 3 analogue](fig3.svg)\n",
        crate::report::provenance::Provenance::current().line(),
        opts.results_label,
        data.total_count(),
        data.nontrivial_population(),
        data.fragments().len(),
        sampled * 100.0,
        resolution_text(&ties, &summary, opts),
        reference_table(&summary, rows, opts.confidence),
        ranking_text(rows, refs),
        tie_table(&ties, opts.confidence, 50),
        top_table(rows, 20)
    );
    md.push_str(
        "\nReference values: LP candidates (label \"(LP)\") are scored on every fragment of the \
         sweep's dataset with the same grid and solver as the candidates; closed forms (label \
         \"(closed form)\") are `momentlab evaluate` values (metrics::evaluate, same bias) on every \
         fragment of the stacks. Errors and standard errors estimate the mean |G − PCF| over all \
         fragments of the stacks.\n",
    );
    out.write_text(&format!("search_m{m}.md"), &md)?;
    Ok(summary)
}

/// The error of drawing chart `what`.
fn drawing<E: std::fmt::Debug>(what: &str) -> impl Fn(E) -> anyhow::Error + '_ {
    move |e| anyhow::anyhow!("drawing chart '{what}': {e:?}")
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
pub fn plot_histogram(title: &str, errors: &[f64], refs: &[Reference]) -> Result<String> {
    svg_string((900, 500), |root| {
        draw_histogram(&root, title, errors, refs, 60)?;
        root.present().map_err(drawing(title))
    })
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

/// Classes of the Fig. 4 bars: tied for first, eliminated by the cap, the others.
fn fig4_classes(rows: &[Row]) -> [Vec<f64>; 3] {
    let by_index: std::collections::HashMap<u64, &Row> =
        rows.iter().map(|r| (r.index, r)).collect();
    let mut out: [Vec<f64>; 3] = Default::default();
    for r in ranking(rows) {
        let own = r
            .duplicate_of
            .and_then(|d| by_index.get(&d))
            .map_or(&r, |x| *x);
        let k = if own.tied {
            0
        } else if own.eliminated == Some(super::race::Elimination::Cap) {
            1
        } else {
            2
        };
        out[k].push(r.error.unwrap());
    }
    out
}

/// Fig. 4 analogue: the histogram of candidate errors with the set tied for first (red) and
/// the cap-eliminated candidates (grey) marked, the references as lines; below, the same
/// zoomed on the top of the ranking.
pub fn plot_fig4(title: &str, rows: &[Row], refs: &[Reference]) -> Result<String> {
    svg_string((900, 900), |root| {
        let (top, bottom) = root.split_vertically(500);
        let classes = fig4_classes(rows);
        let all: Vec<f64> = classes.iter().flatten().copied().collect();
        let (lo, hi) = range_of(&all, refs);
        draw_stacked(&top, title, &classes, refs, lo, hi, 60)?;
        let best = all.iter().copied().fold(f64::INFINITY, f64::min);
        let worst_tied = classes[0].iter().copied().fold(best, f64::max);
        let zhi = best + (2.0 * (worst_tied - best)).max(0.002);
        let zoom: [Vec<f64>; 3] = classes
            .clone()
            .map(|v| v.into_iter().filter(|&e| e <= zhi).collect());
        let zrefs: Vec<Reference> = refs
            .iter()
            .filter(|r| r.error <= zhi && r.error >= best - 1e-3)
            .cloned()
            .collect();
        draw_stacked(
            &bottom,
            &format!(
                "zoom: the best {:.2} percentage points",
                (zhi - best) * 100.0
            ),
            &zoom,
            &zrefs,
            (best - 0.02 * (zhi - best)).max(0.0),
            zhi,
            40,
        )?;
        root.present().map_err(drawing(title))
    })
}

#[allow(clippy::too_many_arguments)]
fn draw_stacked<DB: DrawingBackend>(
    area: &DrawingArea<DB, plotters::coord::Shift>,
    title: &str,
    classes: &[Vec<f64>; 3],
    refs: &[Reference],
    lo: f64,
    hi: f64,
    bins: usize,
) -> Result<()>
where
    DB::ErrorType: 'static,
{
    let err = |e: DrawingAreaErrorKind<DB::ErrorType>| anyhow::anyhow!("{e:?}");
    area.fill(&WHITE).map_err(err)?;
    let h: Vec<Vec<u32>> = classes
        .iter()
        .map(|v| histogram_bins(v, lo, hi, bins))
        .collect();
    let tot: Vec<u32> = (0..bins).map(|k| h.iter().map(|c| c[k]).sum()).collect();
    let ymax = tot.iter().copied().max().unwrap_or(1).max(1) as f64 * 1.15;
    let mut chart = ChartBuilder::on(area)
        .caption(title, ("sans-serif", 18))
        .margin(10)
        .x_label_area_size(40)
        .y_label_area_size(55)
        .build_cartesian_2d(lo * 100.0..hi * 100.0, 0.0..ymax)
        .map_err(err)?;
    chart
        .configure_mesh()
        .x_desc("mean error |G - PCF| (%)")
        .y_desc("candidates")
        .draw()
        .map_err(err)?;
    let w = (hi - lo) / bins as f64 * 100.0;
    let styles = [
        (
            RED.mix(0.8),
            format!("tied for first ({})", classes[0].len()),
        ),
        (
            RGBColor(150, 150, 150).mix(0.7),
            format!("eliminated by the cap ({})", classes[1].len()),
        ),
        (
            BLUE.mix(0.5),
            format!("worse with confidence / others ({})", classes[2].len()),
        ),
    ];
    // Stack: tied at the bottom, then cap, then the rest.
    for (c, (color, label)) in styles.iter().enumerate() {
        let color = *color;
        chart
            .draw_series((0..bins).map(|k| {
                let base: u32 = h[..c].iter().map(|v| v[k]).sum();
                let x0 = lo * 100.0 + k as f64 * w;
                Rectangle::new(
                    [(x0, base as f64), (x0 + w, (base + h[c][k]) as f64)],
                    color.filled(),
                )
            }))
            .map_err(err)?
            .label(label.clone())
            .legend(move |(a, b)| Rectangle::new([(a, b - 5), (a + 12, b + 5)], color.filled()));
    }
    let colors = [
        BLACK,
        GREEN,
        MAGENTA,
        CYAN,
        full_palette::ORANGE,
        full_palette::BROWN,
        full_palette::PURPLE,
    ];
    for (i, r) in refs.iter().enumerate() {
        let c = colors[i % colors.len()];
        let x = r.error * 100.0;
        chart
            .draw_series(LineSeries::new(
                vec![(x, 0.0), (x, ymax)],
                c.stroke_width(2),
            ))
            .map_err(err)?
            .label(format!("{} {:.3}%", r.label, x))
            .legend(move |(a, b)| PathElement::new(vec![(a, b), (a + 15, b)], c.stroke_width(2)));
    }
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .draw()
        .map_err(err)?;
    Ok(())
}

/// Error distributions of several sweeps (e.g. m = 2, 3, 4) side by side on a common axis.
pub fn plot_side_by_side(sets: &[(String, Vec<f64>)]) -> Result<String> {
    svg_string((420 * sets.len().max(1) as u32, 420), |root| {
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
                diff: None,
            }];
            let finite: Vec<f64> = v.iter().copied().filter(|x| x.is_finite()).collect();
            draw_histogram_range(area, label, &finite, &refs, lo, hi)?;
        }
        root.present().map_err(drawing("error distributions"))
    })
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
                let c = cols(m);
                let g = bound_curve(&table, &c, dist, &idx, solver)?;
                let names: Vec<&str> = c.iter().map(|&j| FIG3_NAMES[j]).collect();
                bounds.push((format!("({})", names.join(", ")), g));
            }
            out.push(Fig3Panel {
                title: format!(
                    "{family} bases; a filter window with {} distinct depths",
                    dist.len()
                ),
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
pub fn plot_fig3(panels: &[Fig3Panel]) -> Result<String> {
    let rows = panels.len().div_ceil(2).max(1);
    svg_string((900, 300 * rows as u32), |root| {
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
        root.present().map_err(drawing("Fig. 3"))
    })
}

/// Markdown table of the `count` best candidates: the candidates scored on every fragment
/// first, ranked by error; then, unranked ("–"), the lowest estimates of candidates that left
/// the race on fewer fragments (an estimate on a sample is not a rank among finished scores).
pub fn top_table(rows: &[Row], count: usize) -> String {
    let by_index: std::collections::HashMap<u64, &Row> =
        rows.iter().map(|r| (r.index, r)).collect();
    let mut s = String::from("| rank | index | functions | error (%) | ± s.e. (%) | fragments | race |\n|---:|---:|---|---:|---:|---:|---|\n");
    let (full, partial): (Vec<Row>, Vec<Row>) = ranking(rows).into_iter().partition(|r| r.full);
    let mut rank = 0;
    for r in full.iter().chain(&partial).take(count) {
        let own = r
            .duplicate_of
            .and_then(|d| by_index.get(&d))
            .map_or(r, |x| *x);
        let shown = if r.full {
            rank += 1;
            rank.to_string()
        } else {
            "–".to_string()
        };
        let _ = writeln!(
            s,
            "| {} | {} | {} | {:.4} | {:.4} | {} | {}{} |",
            shown,
            r.index,
            r.functions.join(", "),
            r.error.unwrap() * 100.0,
            r.stderr.unwrap_or(0.0) * 100.0,
            own.fragments,
            status(own),
            if r.duplicate_of.is_some() {
                " (duplicate span)"
            } else {
                ""
            }
        );
    }
    s
}

/// Two-sided interval d ± z_{1−α/2}·se at `confidence`, in percentage points.
fn interval(d: f64, se: f64, confidence: f64) -> (f64, f64) {
    let z = normal_quantile(1.0 - (1.0 - confidence) / 2.0);
    ((d - z * se) * 100.0, (d + z * se) * 100.0)
}

/// The catalog names of the paper's bases (to find their rows among the candidates).
const PAPER_CANDIDATES: [(&str, &[&str]); 3] = [
    ("b_MSM (LP)", &["z", "z^2", "z^3", "z^4"]),
    (
        "b_TMSM (LP)",
        &["sin(2πz)", "cos(2πz)", "sin(4πz)", "cos(4πz)"],
    ),
    ("VSM (LP)", &["z", "z^2"]),
];

/// The race status of a reference that is also a catalog candidate (b_MSM, b_TMSM, VSM).
fn candidate_status(label: &str, rows: &[Row]) -> Option<String> {
    let names = PAPER_CANDIDATES.iter().find(|p| p.0 == label)?.1;
    let mut want: Vec<&str> = names.to_vec();
    want.sort_unstable();
    let r = rows.iter().find(|r| {
        let mut f: Vec<&str> = r.functions.iter().map(|x| x.as_str()).collect();
        f.sort_unstable();
        f == want
    })?;
    let rep = r
        .duplicate_of
        .and_then(|d| rows.iter().find(|x| x.index == d))
        .unwrap_or(r);
    Some(format!("candidate {}: {}", r.index, status(rep)))
}

/// The winner, the references and the closed forms with their difference to the winner and
/// its interval at `confidence`.
pub fn reference_table(summary: &Summary, rows: &[Row], confidence: f64) -> String {
    let Some(best) = &summary.best else {
        return String::new();
    };
    let c = confidence * 100.0;
    let mut s = format!(
        "| | m | error (%) ± s.e. | Δ to the winner (pp) | {c:.0} % interval of Δ (pp) | pairing | verdict | in the race |\n|---|---:|---:|---:|---|---|---|---|\n| winner ({}) | {} | {:.4} ± {:.4} | 0 | | | | tied for first |\n",
        best.functions.join(", "),
        best.functions.len(),
        best.error * 100.0,
        best.stderr * 100.0
    );
    for r in summary.references.iter().filter(|r| r.label != "PCF") {
        let Some((d, se)) = r.diff else { continue };
        let (lo, hi) = interval(d, se, confidence);
        let verdict = if lo > 0.0 {
            "worse than the winner"
        } else if hi < 0.0 {
            "better than the winner"
        } else {
            "not significantly different"
        };
        let _ = writeln!(
            s,
            "| {} | {} | {:.4} ± {:.4} | {:+.4} | [{:+.4}, {:+.4}] | {} | {} | {} |",
            r.label,
            r.m,
            r.error * 100.0,
            r.stderr * 100.0,
            d * 100.0,
            lo,
            hi,
            if r.paired {
                "paired, every fragment"
            } else if r.closed_form {
                "unpaired (closed form exact on all fragments of the stacks)"
            } else {
                "unpaired"
            },
            verdict,
            candidate_status(&r.label, rows).unwrap_or_else(|| "not a catalog candidate".into())
        );
    }
    s.push_str(&format!(
        "\nIntervals are two-sided at {c:.0} % for each line separately (normal approximation). \
         Paired differences use one scoring pass of the winner and the reference on every fragment \
         of the sweep's sample; closed forms are exact population values, so their interval is \
         the winner's own.\n"
    ));
    s
}

/// The tied set: each survivor's paired difference to the winner pooled over the blocks, with
/// its interval (standard errors exact on blocks whose reference is the winner, else bounded
/// by Cauchy–Schwarz, so the intervals are conservative).
pub fn tie_table(t: &TieSet, confidence: f64, limit: usize) -> String {
    if !t.raced {
        return "Not a racing run: no tie set (every candidate was scored on every fragment).\n"
            .into();
    }
    let c = confidence * 100.0;
    let mut s = format!(
        "{} candidates are statistically tied for first{}.\n\n| # | index | functions | error (%) | Δ to the winner (pp) | {c:.0} % interval (pp) | fragments | unsettled LPs |\n|---:|---:|---|---:|---:|---|---:|---:|\n",
        t.tied.len(),
        if t.tied_duplicates > 0 {
            format!(" (plus {} duplicate spans of them)", t.tied_duplicates)
        } else {
            String::new()
        }
    );
    for (k, r) in t.tied.iter().take(limit).enumerate() {
        let (d, se) = (r.diff.unwrap_or(0.0), r.diff_se.unwrap_or(0.0));
        let (lo, hi) = interval(d, se, confidence);
        let _ = writeln!(
            s,
            "| {} | {} | {} | {:.4} | {:+.4} | [{:+.4}, {:+.4}] | {} | {} |",
            k + 1,
            r.index,
            r.functions.join(", "),
            r.error.unwrap_or(f64::NAN) * 100.0,
            d * 100.0,
            lo,
            hi,
            r.fragments,
            r.lp_failures
        );
    }
    if t.tied.len() > limit {
        let _ = writeln!(
            s,
            "\n… and {} more (`tied: true` in results.jsonl).",
            t.tied.len() - limit
        );
    }
    s
}

/// What the race resolved, with its budget and whether the budget bound.
pub fn resolution_text(t: &TieSet, summary: &Summary, opts: &ReportOptions) -> String {
    if !t.raced {
        return "Exhaustive run: every candidate on every fragment of the sample, no racing. \
                Differences between candidates are exact on the sample; ± s.e. is the \
                uncertainty of an absolute error against the full stacks.\n"
            .into();
    }
    let c = opts.confidence * 100.0;
    let m = summary.best.as_ref().map_or(0, |b| b.functions.len());
    let mut s = String::new();
    if let Some(r) = &opts.race {
        let _ = writeln!(
            s,
            "Budget: the sweep's sample of {} non-trivial fragments (`--max-fragments`) and a cap of \
             max(⌈{}·|C|⌉, top) candidates per stage. Tests: {} bound, {}, confidence {c:.0} % for all \
             eliminations together (Bonferroni over {} stages, the candidates of each stage and the shards).\n",
            r.fragment_budget,
            opts.keep,
            r.bound.name(),
            if r.paired { "paired differences to the stage reference" } else { "independent intervals" },
            r.stages.len()
        );
        s.push_str("| stage | candidates | fragments | reference | z | cap | eliminated by confidence | by the cap |\n|---:|---:|---:|---:|---:|---:|---:|---:|\n");
        for (k, st) in r.stages.iter().enumerate() {
            let _ = writeln!(
                s,
                "| {k} | {} | {} | {} | {:.2} | {} | {} | {} |",
                st.candidates,
                st.fragments,
                st.reference,
                st.z,
                st.cap,
                st.confidence_eliminated,
                st.cap_eliminated
            );
        }
        let _ = writeln!(
            s,
            "\nThe race used {} of the {} fragments (pilot block {}), then completed the survivors on \
             the fragments they had not seen. {}\n",
            r.fragments_used,
            r.fragment_budget,
            r.pilot_fragments,
            if r.resolved {
                "**Resolved**: one candidate was left before the fragment budget was reached (the budget did not bind).".to_string()
            } else {
                format!(
                    "**The fragment budget bound**: {} candidates are still statistically tied for first; \
                     the {} fragments of the sample do not separate them at {c:.0} %.",
                    r.tied, r.fragment_budget
                )
            }
        );
    } else {
        let _ = writeln!(
            s,
            "Merged shards (or a run without its `complete.json`): the tied set below is the union \
             of the shards' tied sets, each relative to its own shard's winner.\n"
        );
    }
    let _ = writeln!(
        s,
        "- {} candidates were **eliminated by confidence**: each is worse than its stage reference; \
         all these statements hold together with probability ≥ {c:.0} % (normal approximation of \
         block means).",
        t.confidence
    );
    if t.cap.is_empty() {
        let _ = writeln!(
            s,
            "- The cap never bound: no candidate left without evidence."
        );
    } else {
        let b = &t.cap[0];
        let _ = writeln!(
            s,
            "- {} candidates were **eliminated by the cap**, without evidence against them (all listed \
             in `cap_eliminated_m{m}.csv`); the best of them by its sampled estimate is {} ({}) with \
             {:.4} % ± {:.4} % on {} fragments.",
            t.cap.len(),
            b.index,
            b.functions.join(", "),
            b.error.unwrap_or(f64::NAN) * 100.0,
            b.stderr.unwrap_or(0.0) * 100.0,
            b.fragments
        );
    }
    let _ = writeln!(
        s,
        "- **Resolved**: with probability ≥ {c:.0} %, the best candidate (smallest mean error over the \
         sample's fragments) is one of the {} candidates tied for first{}.\n\
         - **Not resolved**: the order within the tied set{}; the absolute errors against the full \
         stacks carry the ± s.e. of the sample (the same for every candidate, since all see the same \
         fragments).",
        t.tied.len(),
        if t.cap.is_empty() {
            String::new()
        } else {
            format!(" or the {} eliminated by the cap", t.cap.len())
        },
        if t.cap.is_empty() { "" } else { "; whether a cap-eliminated candidate would have been tied" }
    );
    s
}

/// Every candidate eliminated by the cap (CSV: index, functions, error, stderr, fragments,
/// stage, versus, diff, diff_se); None for a run without racing.
fn cap_list(t: &TieSet) -> Option<String> {
    if !t.raced {
        return None;
    }
    let mut s = String::from("index,functions,error,stderr,fragments,stage,versus,diff,diff_se\n");
    for r in &t.cap {
        let o = |x: Option<f64>| x.map_or(String::new(), |v| format!("{v:.8}"));
        let _ = writeln!(
            s,
            "{},\"{}\",{},{},{},{},{},{},{}",
            r.index,
            r.functions.join(", "),
            o(r.error),
            o(r.stderr),
            r.fragments,
            r.stage,
            r.versus.map_or(String::new(), |v| v.to_string()),
            o(r.diff),
            o(r.diff_se)
        );
    }
    Some(s)
}

/// Rank of an error value among the scored candidates: 1 + #candidates strictly better.
pub fn rank_of(errors_sorted: &[f64], e: f64) -> usize {
    1 + errors_sorted.partition_point(|&x| x < e)
}

/// Text: where the references rank and how far the best candidate is below them.
pub fn ranking_text(rows: &[Row], refs: &[Reference]) -> String {
    let errs = errors_of(rows);
    let mut s = String::new();
    let Some(top) = super::tieset::winner_of(rows) else {
        return "No scored candidates.\n".into();
    };
    let best = top.error.unwrap_or(f64::NAN);
    let _ = writeln!(
        s,
        "The winner of {} scored candidates is {} = ({}) with {:.4} % ± {:.4} %{}.",
        errs.len(),
        top.index,
        top.functions.join(", "),
        best * 100.0,
        top.stderr.unwrap_or(0.0) * 100.0,
        if top.full {
            ", scored on every fragment"
        } else {
            ""
        }
    );
    let lowest = &ranking(rows)[0];
    if lowest.index != top.index {
        let _ = writeln!(
            s,
            "The lowest estimate is that of {} = ({}), {:.4} % ± {:.4} % on a sample of {} fragments \
             ({}): an estimate of a candidate that left the race, not a measured improvement.",
            lowest.index,
            lowest.functions.join(", "),
            lowest.error.unwrap_or(f64::NAN) * 100.0,
            lowest.stderr.unwrap_or(0.0) * 100.0,
            lowest.fragments,
            status(lowest)
        );
    }
    s.push_str("Ranks below count every candidate's estimate, sampled ones included.\n\n");
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
            error: e,
            stderr: e.map(|_| 0.001),
            fragments: 10,
            degenerate: e.is_none() && dup.is_none(),
            duplicate_of: dup,
            full: true,
            ..Row::plain(index, vec![format!("f{index}")])
        }
    }

    #[test]
    fn top_table_ranks_only_candidates_scored_on_every_fragment() {
        // Candidate 7 left the race early with the lowest estimate: it is listed below the
        // finished candidates without a rank, and rank 1 goes to the best finished one.
        let mut early = row(7, Some(0.01), None);
        early.full = false;
        early.fragments = 3;
        let rows = vec![row(0, Some(0.03), None), row(1, Some(0.02), None), early];
        let t = top_table(&rows, 3);
        let body: Vec<&str> = t.lines().skip(2).collect();
        assert!(body[0].starts_with("| 1 | 1 | f1 |"), "{t}");
        assert!(body[1].starts_with("| 2 | 0 | f0 |"), "{t}");
        assert!(body[2].starts_with("| – | 7 | f7 |"), "{t}");
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
            diff: None,
        }];
        let text = ranking_text(&rows, &refs);
        assert!(text.contains("rank 3 of 3"), "{text}");
        assert!(text.contains("0.5000 percentage points"), "{text}");
    }

    #[test]
    fn svg_charts_are_drawn() {
        let errs: Vec<f64> = (0..100).map(|k| 0.02 + k as f64 * 1e-4).collect();
        let refs = vec![Reference {
            label: "b_MSM (LP)".into(),
            m: 4,
            error: 0.025,
            stderr: 0.0,
            closed_form: false,
            diff: None,
        }];
        let svg = plot_histogram("test", &errs, &refs).unwrap();
        assert!(svg.contains("<svg") && svg.contains("b_MSM"));
        let svg =
            plot_side_by_side(&[("m = 2".into(), errs.clone()), ("m = 4".into(), errs)]).unwrap();
        assert!(svg.contains("<svg") && svg.contains("m = 4"));
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
        let svg = plot_fig3(&panels).unwrap();
        assert!(svg.trim_end().ends_with("</svg>") && svg.contains("F_Z"));
    }
}
