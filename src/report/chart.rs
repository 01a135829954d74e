//! Charts written as SVG (plotters' SVG backend: pure Rust, no fonts needed).

use super::pareto::{pareto_front, Entry};
use anyhow::{anyhow, Result};
use plotters::coord::Shift;
use plotters::prelude::*;

/// A tick label as a plain number: thousands separated by a space, no trailing ".0"
/// (10, 100, 1 000, 0.5).
pub fn plain(v: f64) -> String {
    if !v.is_finite() {
        return String::new();
    }
    if v.abs() >= 1.0 && (v - v.round()).abs() < 1e-9 * v.abs().max(1.0) {
        let digits = format!("{}", v.round().abs() as u64);
        let mut out = String::new();
        for (i, ch) in digits.chars().enumerate() {
            if i > 0 && (digits.len() - i) % 3 == 0 {
                out.push(' ');
            }
            out.push(ch);
        }
        return if v < 0.0 { format!("-{out}") } else { out };
    }
    let s = format!("{v:.3}");
    s.trim_end_matches('0').trim_end_matches('.').to_string()
}

fn err<E: std::fmt::Debug>(title: &str) -> impl Fn(E) -> anyhow::Error + '_ {
    move |e| anyhow!("drawing chart '{title}': {e:?}")
}

/// Draw an SVG of `size` pixels in memory with `draw` (which presents its root) and return the
/// SVG text; callers write it through the output writer ([`crate::artefact::OutDir`]).
pub fn svg_string(
    size: (u32, u32),
    draw: impl for<'a> FnOnce(DrawingArea<SVGBackend<'a>, Shift>) -> Result<()>,
) -> Result<String> {
    let mut svg = String::new();
    draw(SVGBackend::with_string(&mut svg, size).into_drawing_area())?;
    Ok(svg)
}

/// Speed against accuracy: error against PCF (y) over nanoseconds per fragment (x, log scale,
/// plain-number ticks). Every point carries a number, placed next to it without overlapping
/// other numbers or markers (with a leader line when it had to move); the numbered legend on the
/// right names each point (technique, precision, bits, error, ns) and marks the Pareto front
/// (★, also drawn as a red line). Colour: LP candidates (Algorithm 1 on a grid, references)
/// blue, closed forms black; marker: f32 circle, f64 triangle; marker size grows with bits per
/// texel.
pub fn speed_accuracy_svg(title: &str, entries: &[Entry]) -> Result<String> {
    let ok =
        |e: &Entry| e.error.is_finite() && e.ns_per_fragment.is_finite() && e.ns_per_fragment > 0.0;
    let idx: Vec<usize> = (0..entries.len()).filter(|&i| ok(&entries[i])).collect();
    let (mut x0, mut x1) = (f64::INFINITY, 0.0f64);
    let mut y1 = 0.0f64;
    for &i in &idx {
        x0 = x0.min(entries[i].ns_per_fragment);
        x1 = x1.max(entries[i].ns_per_fragment);
        y1 = y1.max(entries[i].error);
    }
    if idx.is_empty() {
        (x0, x1, y1) = (1.0, 10.0, 1.0);
    }
    let (lx0, lx1) = (x0.log10() - 0.15, x1.log10() + 0.15);
    let legend_w = 380;
    let height = (120 + 16 * idx.len() as u32).max(600);
    svg_string((1000 + legend_w, height), |root| {
        root.fill(&WHITE).map_err(err(title))?;
        let (plot_area, legend_area) = root.split_horizontally(1000);
        let mut chart = ChartBuilder::on(&plot_area)
            .caption(title, ("sans-serif", 20))
            .margin(20)
            .x_label_area_size(50)
            .y_label_area_size(80)
            .build_cartesian_2d(lx0..lx1, 0.0..y1 * 1.12 + 1e-6)
            .map_err(err(title))?;
        let fmt_x = |x: &f64| {
            if (x - x.round()).abs() < 1e-6 {
                plain(10f64.powf(x.round()))
            } else {
                String::new()
            }
        };
        let fmt_y = |y: &f64| format!("{} %", plain(100.0 * y));
        chart
            .configure_mesh()
            .x_desc("nanoseconds per fragment (one core, log scale)")
            .y_desc("mean |G − PCF|")
            .x_labels(((lx1.floor() - lx0.ceil()) as usize + 1).clamp(2, 10))
            .x_label_formatter(&fmt_x)
            .y_label_formatter(&fmt_y)
            .draw()
            .map_err(err(title))?;
        let front = pareto_front(entries);
        let mut front_pts: Vec<(f64, f64)> = front
            .iter()
            .map(|&i| (entries[i].ns_per_fragment.log10(), entries[i].error))
            .collect();
        front_pts.sort_by(|a, b| a.0.total_cmp(&b.0));
        chart
            .draw_series(LineSeries::new(front_pts, RED.stroke_width(2)))
            .map_err(err(title))?;
        let colour = |e: &Entry| {
            if e.name.starts_with("lp:") {
                RGBColor(30, 90, 200)
            } else {
                RGBColor(40, 40, 40)
            }
        };
        // Markers, and their pixel boxes as obstacles for the numbers.
        let mut boxes: Vec<(i32, i32, i32, i32)> = Vec::new();
        let mut pix = Vec::new();
        for &i in &idx {
            let e = &entries[i];
            let r = (3.0 + e.bits_per_texel as f64 / 48.0).min(10.0) as i32;
            let p = (e.ns_per_fragment.log10(), e.error);
            let c = colour(e);
            if e.precision == "f64" {
                chart
                    .draw_series(std::iter::once(TriangleMarker::new(
                        p,
                        r + 1,
                        c.mix(0.6).filled(),
                    )))
                    .map_err(err(title))?;
            } else {
                chart
                    .draw_series(std::iter::once(Circle::new(p, r, c.mix(0.6).filled())))
                    .map_err(err(title))?;
            }
            let (px, py) = chart.backend_coord(&p);
            boxes.push((px - r, py - r, px + r, py + r));
            pix.push((px, py, r));
        }
        draw_numbers(&plot_area, &pix, boxes, title)?;
        draw_legend(&legend_area, entries, &idx, &front, title)?;
        root.present().map_err(err(title))?;
        Ok(())
    })
}

/// The number of each marker in `pix` (pixel x, y, radius) at the first free spot on rings of
/// growing radius around it, clear of `boxes` (the markers' boxes) and of the numbers placed
/// before; a leader line where it had to move.
fn draw_numbers(
    plot_area: &DrawingArea<SVGBackend, Shift>,
    pix: &[(i32, i32, i32)],
    mut boxes: Vec<PixelBox>,
    title: &str,
) -> Result<()> {
    // Numbers: the first free spot on rings of growing radius around the marker.
    let (pw, ph) = plot_area.dim_in_pixel();
    let inside = |b: &(i32, i32, i32, i32)| {
        b.0 >= 85 && b.2 <= pw as i32 - 5 && b.1 >= 40 && b.3 <= ph as i32 - 55
    };
    let overlaps = |a: &(i32, i32, i32, i32), b: &(i32, i32, i32, i32)| {
        a.0 < b.2 && b.0 < a.2 && a.1 < b.3 && b.1 < a.3
    };
    for (k, &(px, py, r)) in pix.iter().enumerate() {
        let label = format!("{}", k + 1);
        let (tw, th) = (7 * label.len() as i32 + 2, 12);
        let placed = label_spot((px, py, r), (tw, th), |b| {
            inside(b) && !boxes.iter().any(|o| overlaps(o, b))
        });
        let Some((b, far)) = placed else { continue };
        boxes.push(b);
        if far {
            let (cx, cy) = ((b.0 + b.2) / 2, (b.1 + b.3) / 2);
            plot_area
                .draw(&PathElement::new(vec![(px, py), (cx, cy)], BLACK.mix(0.35)))
                .map_err(err(title))?;
        }
        plot_area
            .draw(&Text::new(
                label,
                (b.0 + 1, b.1),
                ("sans-serif", 12).into_font().color(&BLACK),
            ))
            .map_err(err(title))?;
    }
    Ok(())
}

/// A pixel box (x0, y0, x1, y1).
type PixelBox = (i32, i32, i32, i32);

/// Where a `tw`×`th` label of the marker of radius `r` at (`px`, `py`) goes: the first box
/// that is `free`, on eight directions of rings of growing radius (12 rings, 7 px apart); with
/// whether it left the first ring (then a leader line joins it to the marker).
fn label_spot(
    (px, py, r): (i32, i32, i32),
    (tw, th): (i32, i32),
    free: impl Fn(&PixelBox) -> bool,
) -> Option<(PixelBox, bool)> {
    for ring in 0..12 {
        let d = r + 3 + ring * 7;
        for (dx, dy) in [
            (1, -1),
            (1, 0),
            (1, 1),
            (0, -1),
            (-1, -1),
            (-1, 0),
            (-1, 1),
            (0, 1),
        ] {
            let (cx, cy) = (px + dx * d, py + dy * d);
            let bx = (
                if dx < 0 {
                    cx - tw
                } else if dx == 0 {
                    cx - tw / 2
                } else {
                    cx
                },
                if dy < 0 {
                    cy - th
                } else if dy == 0 {
                    cy - th / 2
                } else {
                    cy
                },
            );
            let b = (bx.0, bx.1, bx.0 + tw, bx.1 + th);
            if free(&b) {
                return Some((b, ring > 0));
            }
        }
    }
    None
}

/// The legend of [`speed_accuracy_svg`]: the key, then one numbered line per point of `idx`
/// (★ on the Pareto `front`); `title` names the chart in errors.
fn draw_legend(
    legend_area: &DrawingArea<SVGBackend, Shift>,
    entries: &[Entry],
    idx: &[usize],
    front: &[usize],
    title: &str,
) -> Result<()> {
    // Legend: key, then one numbered line per point.
    let font = ("sans-serif", 12).into_font();
    let mut y = 30;
    let line = |area: &DrawingArea<SVGBackend, Shift>, text: String, y: &mut i32| {
        let r = area.draw(&Text::new(text, (10, *y), font.clone()));
        *y += 16;
        r
    };
    line(legend_area, "Key".into(), &mut y).map_err(err(title))?;
    legend_area
        .draw(&Circle::new(
            (16, y + 6),
            5,
            RGBColor(40, 40, 40).mix(0.6).filled(),
        ))
        .map_err(err(title))?;
    legend_area
        .draw(&Text::new(
            "closed form, f32 (● f32, ▲ f64)",
            (28, y),
            font.clone(),
        ))
        .map_err(err(title))?;
    y += 16;
    legend_area
        .draw(&Circle::new(
            (16, y + 6),
            5,
            RGBColor(30, 90, 200).mix(0.6).filled(),
        ))
        .map_err(err(title))?;
    legend_area
        .draw(&Text::new(
            "LP candidate (Algorithm 1, reference)",
            (28, y),
            font.clone(),
        ))
        .map_err(err(title))?;
    y += 16;
    legend_area
        .draw(&PathElement::new(
            vec![(8, y + 6), (24, y + 6)],
            RED.stroke_width(2),
        ))
        .map_err(err(title))?;
    legend_area
        .draw(&Text::new(
            "Pareto front (★ in the list)",
            (28, y),
            font.clone(),
        ))
        .map_err(err(title))?;
    y += 16;
    line(legend_area, "marker size: bits per texel".into(), &mut y).map_err(err(title))?;
    y += 8;
    for (k, &i) in idx.iter().enumerate() {
        let e = &entries[i];
        let star = if front.contains(&i) { "★" } else { " " };
        let text = format!(
            "{:>2}{star} {} ({}, {} bit): {} %, {} ns",
            k + 1,
            e.name,
            e.precision,
            e.bits_per_texel,
            plain((1e4 * e.error).round() / 100.0),
            plain(e.ns_per_fragment.round())
        );
        line(legend_area, text, &mut y).map_err(err(title))?;
    }
    Ok(())
}

/// Where an empty bin is drawn on the log₁₀ count axis: a count of 0.5 (log₁₀ = −0.30), on a
/// dashed baseline, so a line goes down to it instead of jumping over the bin.
pub const EMPTY_BIN_COUNT: f64 = 0.5;

/// The points of one histogram: x = log₁₀ of each bin's upper edge (`recommend::HIST_EDGES`;
/// the first bin [0, 1e-4) is at −4), y = log₁₀ of its count, [`EMPTY_BIN_COUNT`] for empty
/// bins. Empty when the histogram does not have one count per bin.
pub fn histogram_points(h: &[u64]) -> Vec<(f64, f64)> {
    use super::recommend::HIST_EDGES;
    if h.len() != HIST_EDGES.len() - 1 {
        return Vec::new();
    }
    h.iter()
        .enumerate()
        .map(|(k, &c)| {
            let count = if c == 0 { EMPTY_BIN_COUNT } else { c as f64 };
            (HIST_EDGES[k + 1].log10(), count.log10())
        })
        .collect()
}

/// Error histograms, one line per technique ([`histogram_points`]; every bin drawn, empty bins
/// at the dashed baseline [`EMPTY_BIN_COUNT`]), the legend in a margin right of the plot so it
/// covers no line. The paper's way to see where a technique fails: the mass in the right-hand
/// bins.
pub fn histograms_svg(title: &str, hists: &[(String, Vec<u64>)]) -> Result<String> {
    let series: Vec<(String, Vec<(f64, f64)>)> = hists
        .iter()
        .map(|(name, h)| (name.clone(), histogram_points(h)))
        .filter(|s| !s.1.is_empty())
        .collect();
    let floor = EMPTY_BIN_COUNT.log10();
    let top = series
        .iter()
        .flat_map(|s| s.1.iter().map(|p| p.1))
        .fold(1.0f64, f64::max);
    let (x0, x1) = (-4.0, 0.0);
    let legend_w = 330;
    svg_string((800 + legend_w, 520), |root| {
        root.fill(&WHITE).map_err(err(title))?;
        let (plot_area, legend_area) = root.split_horizontally(800);
        let mut chart = ChartBuilder::on(&plot_area)
            .caption(title, ("sans-serif", 20))
            .margin(15)
            .x_label_area_size(45)
            .y_label_area_size(70)
            .build_cartesian_2d(x0 - 0.1..x1 + 0.1, floor - 0.3..top.ceil() + 0.2)
            .map_err(err(title))?;
        chart
            .configure_mesh()
            .x_desc("log₁₀ |G − PCF| (upper edge of the bin)")
            .y_desc("log₁₀ fragments (empty bin: 0.5)")
            .draw()
            .map_err(err(title))?;
        chart
            .draw_series(DashedLineSeries::new(
                vec![(x0 - 0.1, floor), (x1 + 0.1, floor)],
                6,
                4,
                BLACK.stroke_width(1),
            ))
            .map_err(err(title))?;
        let font = ("sans-serif", 13).into_font();
        let mut y = 20;
        legend_area
            .draw(&Text::new(
                "- - - empty bins (count 0 drawn as 0.5)",
                (8, y),
                font.clone(),
            ))
            .map_err(err(title))?;
        y += 24;
        for (k, (name, s)) in series.iter().enumerate() {
            let c = Palette99::pick(k).to_rgba();
            chart
                .draw_series(LineSeries::new(s.clone(), c.stroke_width(2)))
                .map_err(err(title))?;
            chart
                .draw_series(s.iter().map(|&p| Circle::new(p, 3, c.filled())))
                .map_err(err(title))?;
            legend_area
                .draw(&PathElement::new(
                    vec![(8, y + 6), (32, y + 6)],
                    c.stroke_width(2),
                ))
                .map_err(err(title))?;
            legend_area
                .draw(&Text::new(name.clone(), (38, y), font.clone()))
                .map_err(err(title))?;
            y += 18;
        }
        root.present().map_err(err(title))?;
        Ok(())
    })
}

/// A line chart of several named series (x log-scaled when `log_x`).
pub fn lines_svg(
    title: &str,
    x_desc: &str,
    y_desc: &str,
    series: &[(String, Vec<(f64, f64)>)],
    log_x: bool,
) -> Result<String> {
    let pts = series.iter().flat_map(|s| s.1.iter());
    let (mut x0, mut x1, mut y0, mut y1) = (
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
    );
    for &(x, y) in pts.filter(|p| p.0.is_finite() && p.1.is_finite()) {
        x0 = x0.min(x);
        x1 = x1.max(x);
        y0 = y0.min(y);
        y1 = y1.max(y);
    }
    if !x0.is_finite() {
        (x0, x1, y0, y1) = (1.0, 2.0, 0.0, 1.0);
    }
    if x1 <= x0 {
        x1 = x0 + 1.0;
    }
    if y1 <= y0 {
        y1 = y0 + 1e-9;
    }
    let pad = 0.05 * (y1 - y0);
    // A log x axis is drawn as a linear axis in log₂ x with a tick at every power of two,
    // labelled with the plain number (no "1000.0 1000.0" from rounded log-scale ticks).
    let log = log_x && x0 > 0.0;
    let tx = |x: f64| if log { x.log2() } else { x };
    let (lx0, lx1) = (tx(x0), tx(x1));
    let series: Vec<(String, Vec<(f64, f64)>)> = series
        .iter()
        .map(|(n, s)| (n.clone(), s.iter().map(|&(x, y)| (tx(x), y)).collect()))
        .collect();
    svg_string((800, 500), |root| {
        root.fill(&WHITE).map_err(err(title))?;
        let mut chart = ChartBuilder::on(&root)
            .caption(title, ("sans-serif", 20))
            .margin(15)
            .x_label_area_size(45)
            .y_label_area_size(70)
            .build_cartesian_2d(
                lx0 - 0.05 * (lx1 - lx0)..lx1 + 0.05 * (lx1 - lx0),
                y0 - pad..y1 + pad,
            )
            .map_err(err(title))?;
        let ticks = if log {
            (lx1.floor() - lx0.ceil()) as usize + 1
        } else {
            10
        };
        let fmt_x = |x: &f64| {
            if !log {
                plain(*x)
            } else if (x - x.round()).abs() < 1e-6 {
                plain(x.round().exp2())
            } else {
                String::new()
            }
        };
        chart
            .configure_mesh()
            .x_desc(x_desc)
            .y_desc(y_desc)
            .x_labels(ticks.clamp(2, 16))
            .x_label_formatter(&fmt_x)
            .draw()
            .map_err(err(title))?;
        for (k, (name, s)) in series.iter().enumerate() {
            let c = Palette99::pick(k).to_rgba();
            chart
                .draw_series(LineSeries::new(s.clone(), c.stroke_width(2)))
                .map_err(err(title))?
                .label(name.as_str())
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], c));
            chart
                .draw_series(s.iter().map(|&p| Circle::new(p, 3, c.filled())))
                .map_err(err(title))?;
        }
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.8))
            .border_style(BLACK)
            .draw()
            .map_err(err(title))?;
        root.present().map_err(err(title))?;
        Ok(())
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn plain_numbers() {
        assert_eq!(plain(10.0), "10");
        assert_eq!(plain(1000.0), "1 000");
        assert_eq!(plain(4096.0), "4 096");
        assert_eq!(plain(1_234_567.0), "1 234 567");
        assert_eq!(plain(0.5), "0.5");
        assert_eq!(plain(2.25), "2.25");
    }

    #[test]
    fn histogram_draws_empty_bins_at_the_floor_and_keeps_the_legend_outside() {
        use crate::report::recommend::HIST_EDGES;
        let mut h = vec![0u64; HIST_EDGES.len() - 1];
        h[0] = 1000;
        h[5] = 10;
        let pts = histogram_points(&h);
        assert_eq!(pts.len(), h.len());
        assert!((pts[0].1 - 3.0).abs() < 1e-12 && (pts[5].1 - 1.0).abs() < 1e-12);
        assert!((pts[1].1 - EMPTY_BIN_COUNT.log10()).abs() < 1e-12);
        assert!(histogram_points(&h[1..]).is_empty());
        let svg = histograms_svg("t", &[("tech-a".into(), h)]).unwrap();
        // The legend text starts right of the 800-px plot area.
        let at = svg.find(">\ntech-a\n<").expect("legend entry");
        let tag = &svg[svg[..at].rfind("<text").unwrap()..at];
        let x: f64 = tag
            .split("x=\"")
            .nth(1)
            .unwrap()
            .split('"')
            .next()
            .unwrap()
            .parse()
            .unwrap();
        assert!(x > 800.0, "{tag}");
    }

    #[test]
    fn log_x_line_chart_has_one_label_per_power_of_two() {
        let s = vec![(
            "a".to_string(),
            vec![(64.0, 0.03), (1024.0, 0.02), (4096.0, 0.019)],
        )];
        let svg = lines_svg("t", "n", "e", &s, true).unwrap();
        for n in ["64", "128", "1 024", "4 096"] {
            assert_eq!(svg.matches(&format!(">\n{n}\n<")).count(), 1, "{n}");
        }
        assert!(!svg.contains("1000.0"));
    }

    #[test]
    fn speed_accuracy_chart_is_valid_svg_with_front_labels() {
        let v = vec![
            Entry {
                name: "vsm".into(),
                precision: "f32".into(),
                error: 0.05,
                ns_per_fragment: 3.0,
                bits_per_texel: 64,
            },
            Entry {
                name: "hamburger4".into(),
                precision: "f32".into(),
                error: 0.02,
                ns_per_fragment: 20.0,
                bits_per_texel: 128,
            },
            Entry {
                name: "slow-bad".into(),
                precision: "f32".into(),
                error: 0.06,
                ns_per_fragment: 50.0,
                bits_per_texel: 128,
            },
        ];
        let s = speed_accuracy_svg("t", &v).unwrap();
        assert!(s.starts_with("<svg") && s.trim_end().ends_with("</svg>"));
        // Every point is in the numbered legend; the front is starred, dominated points not.
        assert!(s.contains("★ hamburger4 (f32, 128 bit)"), "{s}");
        assert!(s.contains("★ vsm (f32, 64 bit)"));
        assert!(s.contains("  slow-bad (f32, 128 bit)") || s.contains(" slow-bad (f32, 128 bit)"));
        assert!(!s.contains("★ slow-bad"));
        for k in ["1", "2", "3"] {
            assert!(s.contains(&format!(">\n{k}\n<")), "number {k} drawn");
        }
    }
}
