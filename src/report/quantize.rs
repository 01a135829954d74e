//! The quantization study's tables and plot: Markdown of the best α, error and deviation per
//! technique and storage, the 16-bit usability table, and error against α (SVG).

use crate::quantize::pipeline::MAX_NOISE;
use crate::quantize::study::Sweep;
use anyhow::Result;
use plotters::prelude::*;

/// A share (error or deviation, a fraction of full shadow) in percent, without the sign: three
/// decimals from 0.01 %, two significant digits in scientific notation below (deviations of
/// 32-bit storage are around 10⁻⁵ %).
pub fn pct(x: f64) -> String {
    let p = 100.0 * x;
    if !p.is_finite() {
        "n/a".into()
    } else if p == 0.0 || p.abs() >= 0.01 {
        format!("{p:.3}")
    } else {
        format!("{p:.1e}")
    }
}

/// The study's Markdown: one row per sweep, then the usability table of 16-bit storage; errors
/// and deviations in %.
pub fn markdown(
    all: &[Sweep],
    usable: &[serde_json::Value],
    stacks: &str,
    views: usize,
    stride: usize,
    alphas: &[f64],
) -> String {
    let i3 = alphas.iter().position(|&a| (a - 3e-5).abs() < 1e-12);
    let mut md = format!(
        "Mean |G − PCF| over {} fragments of {views} views ({stacks}), stride {stride}; bias b* = (½,…,½).\n\n`error` = mean |G − PCF|; `deviation` = mean |G − G_exact| against the same technique and α on unquantized f64 moments (the damage done by storage and f32 filtering: texels stored in the format, two f32 filter passes each stored in the format); both in %.\n\n| technique | storage | best α | error at best α (%) | error at α = 3e-5 (%) | deviation at best α (%) | deviation at α = 3e-5 (%) | non-finite at best α |\n|---|---|---|---|---|---|---|---|\n",
        all.first().map_or(0, |s| s.fragments),
    );
    for s in all {
        let k = s
            .alphas
            .iter()
            .position(|&a| a == s.best_alpha)
            .unwrap_or(0);
        md.push_str(&format!(
            "| {} | {} | {:.0e} | {} | {} | {} | {} | {} |\n",
            s.technique,
            s.config,
            s.best_alpha,
            pct(s.best_error),
            i3.map_or("—".into(), |i| pct(s.errors[i])),
            pct(s.deviation[k]),
            i3.map_or("—".into(), |i| pct(s.deviation[i])),
            s.non_finite[k]
        ));
    }
    md.push_str(&format!(
        "\n16-bit storage counted as usable from the smallest α at which it meets `tune`'s noise bound (the shadow more than 1/255 from exact moments on at most {} % of fragments):\n\n| technique | storage | smallest usable α | noise share there (%) | deviation there (%) | error there (%) | 32-bit float error there (%) |\n|---|---|---|---|---|---|---|\n",
        pct(MAX_NOISE)
    ));
    for u in usable {
        let f = |k: &str, p: &str| {
            u[k].as_f64().map_or("never".to_string(), |v| match p {
                "e" => format!("{v:.0e}"),
                _ => pct(v),
            })
        };
        md.push_str(&format!(
            "| {} | {} | {} | {} | {} | {} | {} |\n",
            u["technique"].as_str().unwrap_or(""),
            u["config"].as_str().unwrap_or(""),
            f("smallest_usable_alpha", "e"),
            f("noise_share_there", "%"),
            f("deviation_there", "d"),
            f("error_there", "f"),
            f("f32_error_there", "f"),
        ));
    }
    md
}

/// The α axis of [`plot`] (logarithmic): the range of `alphas`, widened to a factor of 4
/// around a single value (a log axis over an empty range has no ticks to find); an error for
/// a value that is not finite and > 0.
fn alpha_axis(alphas: &[f64]) -> Result<(f64, f64)> {
    if let Some(a) = alphas.iter().find(|a| !(a.is_finite() && **a > 0.0)) {
        anyhow::bail!("plot: α = {a} cannot be drawn on a logarithmic axis");
    }
    let amin = alphas.iter().cloned().fold(f64::INFINITY, f64::min);
    let amax = alphas.iter().cloned().fold(0.0, f64::max);
    match (amin.is_finite(), amax > amin * (1.0 + 1e-9)) {
        (false, _) => anyhow::bail!("plot: no α to draw"),
        (true, false) => Ok((amin / 2.0, amin * 2.0)),
        (true, true) => Ok((amin, amax)),
    }
}

/// Error against α (log–log), one panel per technique, one line per storage configuration.
pub fn plot(all: &[Sweep]) -> Result<String> {
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
            let (amin, amax) = alpha_axis(&sw[0].alphas)?;
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

#[cfg(test)]
mod tests {
    use super::*;

    /// One α (`quantize --alphas 1e-3`) gets an axis around it; α ≤ 0 is an error, not a
    /// logarithmic axis that never ends its tick search.
    #[test]
    fn alpha_axes_of_one_value_and_bad_values() {
        assert_eq!(alpha_axis(&[1e-3]).unwrap(), (5e-4, 2e-3));
        assert_eq!(alpha_axis(&[1e-4, 1e-2, 1e-3]).unwrap(), (1e-4, 1e-2));
        for bad in [&[0.0][..], &[1e-3, f64::NAN], &[]] {
            assert!(alpha_axis(bad).is_err(), "{bad:?}");
        }
        let one = crate::quantize::study::sample_sweep("vsm", "16-bit");
        let svg = plot(&[one]).unwrap();
        assert!(svg.contains("<svg") && svg.contains("vsm: error vs bias"));
    }
}
