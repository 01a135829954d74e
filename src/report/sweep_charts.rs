//! The SVG charts of a sweep report (plotters, drawn in memory and written by the caller through
//! `artefact::OutDir`): the Fig. 4 analogue (histogram of every candidate's error on the common
//! sample, the set tied for first marked, the race's deeper estimates as an outline, reference
//! values as lines), error
//! distributions of several m side by side, and the Fig. 3 analogue (F_Z and the sharp lower
//! bounds of Algorithm 1).

use super::chart::svg_string;
use crate::search::reference::{Fig3Panel, Reference};
use crate::search::results::Row;
use anyhow::Result;
use plotters::prelude::*;

/// The error of drawing chart `what`.
fn drawing<E: std::fmt::Debug>(what: &str) -> impl Fn(E) -> anyhow::Error + '_ {
    move |e| anyhow::anyhow!("drawing chart '{what}': {e:?}")
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

/// The layout of a histogram panel: caption font size, margin, label areas (pixels), x label.
struct HistogramStyle {
    caption: u32,
    margin: u32,
    x_area: u32,
    y_area: u32,
    x_desc: &'static str,
}

/// A white `area` with the histogram of `errors` in % (`bins` bins on [lo, hi]) as blue bars
/// and its axes; returns the chart (for markers drawn over it) and the top of its y range.
#[allow(clippy::type_complexity)]
fn histogram_bars<'a, DB: DrawingBackend>(
    area: &'a DrawingArea<DB, plotters::coord::Shift>,
    title: &str,
    errors: &[f64],
    (lo, hi, bins): (f64, f64, usize),
    style: &HistogramStyle,
) -> Result<(
    ChartContext<
        'a,
        DB,
        Cartesian2d<plotters::coord::types::RangedCoordf64, plotters::coord::types::RangedCoordf64>,
    >,
    f64,
)>
where
    DB::ErrorType: 'static,
{
    area.fill(&WHITE).map_err(|e| anyhow::anyhow!("{e:?}"))?;
    let h = histogram_bins(errors, lo, hi, bins);
    let ymax = h.iter().copied().max().unwrap_or(1).max(1) as f64 * 1.15;
    let mut chart = ChartBuilder::on(area)
        .caption(title, ("sans-serif", style.caption))
        .margin(style.margin)
        .x_label_area_size(style.x_area)
        .y_label_area_size(style.y_area)
        .build_cartesian_2d(lo * 100.0..hi * 100.0, 0.0..ymax)
        .map_err(|e| anyhow::anyhow!("{e:?}"))?;
    chart
        .configure_mesh()
        .x_desc(style.x_desc)
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
    Ok((chart, ymax))
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
    let (lo, hi) = range_of(errors, refs);
    let style = HistogramStyle {
        caption: 18,
        margin: 10,
        x_area: 40,
        y_area: 55,
        x_desc: "mean error |G - PCF| (%)",
    };
    let (mut chart, ymax) = histogram_bars(area, title, errors, (lo, hi, bins), &style)?;
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

/// What Fig. 4 draws: every candidate's error on the common sample (the same fragments for
/// every candidate), split into tied for first, unresolved and the others; the race's deeper
/// estimates (candidates scored on more fragments than the common sample); the common sample's
/// size and the median standard error of a candidate's estimate on it.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Fig4Data {
    /// Errors of the candidates tied for first, unresolved, and the others.
    pub classes: [Vec<f64>; 3],
    /// Errors of the candidates scored on more fragments than the common sample.
    pub deeper: Vec<f64>,
    /// Fragments of the common sample.
    pub fragments: u64,
    /// Median standard error of a candidate's estimate on the common sample.
    pub median_se: f64,
}

/// The Fig. 4 values of `rows`: a candidate's `common_error` (racing: stage 0's block), or its
/// error when it was scored on every fragment of an exhaustive run; duplicates count with
/// their representative's values. Candidates without either are left out.
pub fn fig4_data(rows: &[Row]) -> Fig4Data {
    let by_index: std::collections::HashMap<u64, &Row> =
        rows.iter().map(|r| (r.index, r)).collect();
    let mut out = Fig4Data::default();
    let mut ses = Vec::new();
    for r in rows.iter().filter(|r| !r.degenerate) {
        let own = r
            .duplicate_of
            .and_then(|d| by_index.get(&d))
            .map_or(r, |x| *x);
        let (value, se, n) = match (own.common_error, own.error) {
            (Some(c), _) => (c, own.common_stderr.unwrap_or(0.0), own.common_fragments),
            (None, Some(e)) if own.full && own.eliminated.is_none() && !own.tied => {
                (e, own.stderr.unwrap_or(0.0), own.fragments)
            }
            _ => continue,
        };
        let k = if own.tied {
            0
        } else if own.unresolved {
            1
        } else {
            2
        };
        out.classes[k].push(value);
        ses.push(se);
        out.fragments = out.fragments.max(n);
        if own.common_error.is_some() && own.fragments > own.common_fragments {
            if let Some(e) = own.error {
                out.deeper.push(e);
            }
        }
    }
    ses.sort_by(f64::total_cmp);
    out.median_se = ses.get(ses.len() / 2).copied().unwrap_or(0.0);
    out
}

/// Fig. 4 analogue: the histogram of every candidate's error on the common sample, with the
/// set tied for first (red) and unresolved candidates (grey) stacked apart from the rest, the
/// race's deeper estimates as a black outline, the references (the paper's bases, the closed
/// forms) as lines; below, the same zoomed on the top of the ranking.
pub fn plot_fig4(title: &str, rows: &[Row], refs: &[Reference]) -> Result<String> {
    let data = fig4_data(rows);
    svg_string((900, 900), |root| {
        let (top, bottom) = root.split_vertically(500);
        let classes = &data.classes;
        let all: Vec<f64> = classes.iter().flatten().copied().collect();
        let (lo, hi) = range_of(&all, refs);
        let head = format!(
            "{title}: {} candidates on a common sample of {} fragments (median s.e. {:.3} pp)",
            all.len(),
            data.fragments,
            data.median_se * 100.0
        );
        draw_stacked(&top, &head, classes, &data.deeper, refs, lo, hi, 60)?;
        let best = all
            .iter()
            .chain(&data.deeper)
            .copied()
            .fold(f64::INFINITY, f64::min);
        let worst_tied = classes[0].iter().copied().fold(best, f64::max);
        let zhi = best + (2.0 * (worst_tied - best)).max(0.004);
        let cut = |v: &Vec<f64>| -> Vec<f64> { v.iter().copied().filter(|&e| e <= zhi).collect() };
        let zoom: [Vec<f64>; 3] = [cut(&classes[0]), cut(&classes[1]), cut(&classes[2])];
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
            &cut(&data.deeper),
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
    deeper: &[f64],
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
    let hd = histogram_bins(deeper, lo, hi, bins);
    let ymax = tot.iter().chain(&hd).copied().max().unwrap_or(1).max(1) as f64 * 1.15;
    let mut chart = ChartBuilder::on(area)
        .caption(title, ("sans-serif", 15))
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
            format!("unresolved, LP budget ({})", classes[1].len()),
        ),
        (
            BLUE.mix(0.5),
            format!("eliminated by evidence ({})", classes[2].len()),
        ),
    ];
    // Stack: tied at the bottom, then unresolved, then the eliminated.
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
    if !deeper.is_empty() {
        // The race's deeper estimates (more fragments than the common sample) as an outline.
        let mut pts = Vec::with_capacity(2 * bins + 2);
        for (k, &c) in hd.iter().enumerate() {
            let x0 = lo * 100.0 + k as f64 * w;
            pts.push((x0, c as f64));
            pts.push((x0 + w, c as f64));
        }
        chart
            .draw_series(LineSeries::new(pts, BLACK.stroke_width(1)))
            .map_err(err)?
            .label(format!("deeper estimate of the race ({})", deeper.len()))
            .legend(|(a, b)| PathElement::new(vec![(a, b), (a + 15, b)], BLACK.stroke_width(1)));
    }
    let colors = [
        full_palette::PINK,
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
    let style = HistogramStyle {
        caption: 16,
        margin: 8,
        x_area: 35,
        y_area: 50,
        x_desc: "mean error (%)",
    };
    let (mut chart, ymax) = histogram_bars(area, title, errors, (lo, hi, 40), &style)?;
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::search::reference::{fig3_panels, pick_kernels};
    use crate::search::Dataset;

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
