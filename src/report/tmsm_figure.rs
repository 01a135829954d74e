//! `tmsm_geometry.svg`: the construction of docs/tmsm.md drawn for one depth distribution.
//!
//! Left: depths on the circle, z ↦ e^{i(2πz − a)} with a = πz_f, so the shadowed arc [0, z_f)
//! is the symmetric arc (−a, a) (the fragment at s = a, the seam 0 ≡ 1 at s = −a) and a point
//! is shadowed exactly when its real part exceeds cos a (the dashed chord). The input Diracs
//! (blue, area ∝ weight), their rotated trigonometric moments c₁ = E[e^{is}] and
//! c₂ = E[e^{2is}] (crosses inside the disk), and the minimiser [`tmsm::solve`] returns (red
//! rings): a distribution with the same c₁, c₂ and the least mass on the shadowed arc, which
//! is G. Right: G(b, z_f) of the same moments over z_f against the input's CDF F_Z(z_f) (G is
//! a lower bound: it never exceeds F_Z).

use crate::technique::tmsm;
use anyhow::{bail, Result};
use std::f64::consts::TAU;
use std::fmt::Write as _;

/// The depth distribution drawn: (depth, weight).
pub const DIRACS: [(f64, f64); 3] = [(0.12, 0.3), (0.42, 0.45), (0.78, 0.25)];
/// The fragment depth of the left panel.
pub const ZF: f64 = 0.55;

fn moments(diracs: &[(f64, f64)]) -> [f64; 4] {
    let mut b = [0.0; 4];
    let mut v = [0.0; 4];
    for &(z, w) in diracs {
        tmsm::basis(z, &mut v);
        for (bk, vk) in b.iter_mut().zip(v) {
            *bk += w * vk;
        }
    }
    b
}

fn cdf(diracs: &[(f64, f64)], zf: f64) -> f64 {
    diracs.iter().filter(|d| d.0 < zf).map(|d| d.1).sum()
}

/// Names of the branches of docs/tmsm.md.
fn branch(c: tmsm::Case) -> &'static str {
    use tmsm::Case::*;
    match c {
        Trivial => "trivial",
        OneDirac => "one Dirac, §2",
        TwoDiracs => "two Diracs, §2",
        LitArc => "a distribution on the lit arc, §3",
        ThroughZf => "canonical representation through z_f, §4.1",
        ThroughZero => "canonical representation through 0, §4.1",
        Symmetric => "Diracs at both ends and a symmetric pair, §4.3",
        Quartic => "Diracs at both ends and the quartic's pair, §4.4",
    }
}

/// The SVG (two panels, 820 × 440).
pub fn svg() -> Result<String> {
    let b = moments(&DIRACS);
    let sol = tmsm::solve(b, ZF);
    if !sol.g.is_finite() || sol.support.is_empty() {
        bail!("tmsm figure: no minimiser for the example ({:?})", sol.case);
    }
    let mut o = String::new();
    let _ = writeln!(
        o,
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"820\" height=\"440\" viewBox=\"0 0 820 440\" font-family=\"sans-serif\" font-size=\"13\">\n<rect width=\"820\" height=\"440\" fill=\"white\"/>"
    );
    circle_panel(&mut o, &sol);
    bound_panel(&mut o, b, &sol)?;
    Ok(o)
}

/// The left panel: the depths on the circle, the shadowed arc and its chord, the input
/// distribution, its rotated moments c₁, c₂ and the minimiser of the mass on the shadowed arc.
fn circle_panel(o: &mut String, sol: &tmsm::Detail<f64>) {
    let a = std::f64::consts::PI * ZF;
    let (cx, cy, r) = (215.0, 225.0, 135.0);
    let at = |s: f64, rho: f64| (cx + rho * r * s.cos(), cy - rho * r * s.sin());
    let s_of = |z: f64| TAU * z - a;
    let _ = writeln!(
        o,
        "<text x=\"215\" y=\"24\" text-anchor=\"middle\" font-size=\"15\">depths on the circle: z ↦ e^(i(2πz − a)), a = πz_f</text>"
    );
    // The lit arc (light) and the shadowed arc (dark).
    let arc = |o: &mut String, s0: f64, s1: f64, colour: &str, width: f64| {
        let (x0, y0) = at(s0, 1.0);
        let (x1, y1) = at(s1, 1.0);
        let large = i32::from(s1 - s0 > std::f64::consts::PI);
        let _ = writeln!(
            o,
            "<path d=\"M {x0:.2} {y0:.2} A {r} {r} 0 {large} 0 {x1:.2} {y1:.2}\" fill=\"none\" stroke=\"{colour}\" stroke-width=\"{width}\"/>"
        );
    };
    arc(o, a, TAU - a, "#cfcfcf", 7.0);
    arc(o, -a, a, "#404040", 7.0);
    // The chord Re = cos a between the ends of the shadowed arc.
    let (xa, ya) = at(a, 1.0);
    let (_, yb) = at(-a, 1.0);
    let _ = writeln!(
        o,
        "<line x1=\"{xa:.2}\" y1=\"{:.2}\" x2=\"{xa:.2}\" y2=\"{:.2}\" stroke=\"#404040\" stroke-dasharray=\"5 4\"/>",
        ya - 12.0,
        yb + 12.0
    );
    let _ = writeln!(
        o,
        "<text x=\"{:.2}\" y=\"{:.2}\" text-anchor=\"end\" fill=\"#404040\">Re = cos a</text>",
        xa - 6.0,
        cy + 0.45 * r
    );
    let label = |o: &mut String, s: f64, rho: f64, text: &str, colour: &str| {
        let (x, y) = at(s, rho);
        let anchor = if s.cos() > 0.3 {
            "start"
        } else if s.cos() < -0.3 {
            "end"
        } else {
            "middle"
        };
        let _ = writeln!(
            o,
            "<text x=\"{x:.2}\" y=\"{:.2}\" text-anchor=\"{anchor}\" fill=\"{colour}\">{text}</text>",
            y + 4.0
        );
    };
    label(o, a, 1.13, &format!("z_f = {ZF}"), "#000");
    label(o, -a, 1.13, "seam: z = 0 ≡ 1", "#000");
    label(o, -0.35, 0.55, "shadowed arc", "#404040");
    label(o, 2.5, 0.75, "lit arc", "#808080");
    // Input Diracs.
    for &(z, w) in &DIRACS {
        let (x, y) = at(s_of(z), 1.0);
        let _ = writeln!(
            o,
            "<circle cx=\"{x:.2}\" cy=\"{y:.2}\" r=\"{:.2}\" fill=\"#1f5fbf\" fill-opacity=\"0.8\"/>",
            3.0 + 14.0 * w.sqrt()
        );
        label(o, s_of(z), 1.16, &format!("z = {z}"), "#1f5fbf");
    }
    // The minimiser.
    for &(z, w) in &sol.support {
        let (x, y) = at(s_of(z), 1.0);
        let _ = writeln!(
            o,
            "<circle cx=\"{x:.2}\" cy=\"{y:.2}\" r=\"{:.2}\" fill=\"none\" stroke=\"#c8102e\" stroke-width=\"2.5\"/>",
            3.0 + 14.0 * w.max(0.0).sqrt()
        );
    }
    // Rotated moments c₁, c₂.
    for (k, name) in [(1.0, "c₁"), (2.0, "c₂")] {
        let (re, im) = DIRACS.iter().fold((0.0, 0.0), |(re, im), &(z, w)| {
            let s = k * s_of(z);
            (re + w * s.cos(), im + w * s.sin())
        });
        let (x, y) = (cx + r * re, cy - r * im);
        let _ = writeln!(
            o,
            "<path d=\"M {:.2} {:.2} l 10 10 m 0 -10 l -10 10\" stroke=\"#000\" stroke-width=\"2\"/>\n<text x=\"{:.2}\" y=\"{:.2}\">{name}</text>",
            x - 5.0,
            y - 5.0,
            x + 8.0,
            y - 6.0
        );
    }
    let _ = writeln!(
        o,
        "<text x=\"20\" y=\"405\" fill=\"#1f5fbf\">● input distribution, weights {} (area ∝ weight)</text>\n<text x=\"20\" y=\"423\" fill=\"#c8102e\">○ minimiser: same c₁, c₂, least mass on the shadowed arc</text>\n<text x=\"20\" y=\"48\">G = {:.3} ({}); F_Z(z_f) = {:.2}</text>",
        DIRACS
            .iter()
            .map(|d| d.1.to_string())
            .collect::<Vec<_>>()
            .join(", "),
        sol.g,
        branch(sol.case),
        cdf(&DIRACS, ZF)
    );
}

/// The right panel: the depth CDF F_Z and the sharp bound G over z_f, with the example's z_f
/// marked; closes the document.
fn bound_panel(o: &mut String, b: [f64; 4], sol: &tmsm::Detail<f64>) -> Result<()> {
    let (px, py, pw, ph) = (470.0, 60.0, 320.0, 300.0);
    let to = |zf: f64, g: f64| (px + pw * zf, py + ph * (1.0 - g));
    let _ = writeln!(
        o,
        "<text x=\"{:.1}\" y=\"24\" text-anchor=\"middle\" font-size=\"15\">the bound over the fragment depth</text>\n<rect x=\"{px}\" y=\"{py}\" width=\"{pw}\" height=\"{ph}\" fill=\"none\" stroke=\"#000\"/>",
        px + pw / 2.0
    );
    for t in [0.0, 0.25, 0.5, 0.75, 1.0] {
        let (x, _) = to(t, 0.0);
        let (_, y) = to(0.0, t);
        let _ = writeln!(
            o,
            "<line x1=\"{x:.1}\" y1=\"{:.1}\" x2=\"{x:.1}\" y2=\"{:.1}\" stroke=\"#000\"/><text x=\"{x:.1}\" y=\"{:.1}\" text-anchor=\"middle\">{t}</text>\n<line x1=\"{:.1}\" y1=\"{y:.1}\" x2=\"{px}\" y2=\"{y:.1}\" stroke=\"#000\"/><text x=\"{:.1}\" y=\"{:.1}\" text-anchor=\"end\">{t}</text>",
            py + ph,
            py + ph + 5.0,
            py + ph + 20.0,
            px - 5.0,
            px - 8.0,
            y + 4.0
        );
    }
    let _ = writeln!(
        o,
        "<text x=\"{:.1}\" y=\"{:.1}\" text-anchor=\"middle\">fragment depth z_f</text>\n<text x=\"{:.1}\" y=\"{:.1}\" text-anchor=\"middle\" transform=\"rotate(-90 {:.1} {:.1})\">shadow</text>",
        px + pw / 2.0,
        py + ph + 38.0,
        px - 38.0,
        py + ph / 2.0,
        px - 38.0,
        py + ph / 2.0
    );
    // F_Z: a step function.
    let mut d = String::new();
    let mut mass = 0.0;
    let mut sorted = DIRACS.to_vec();
    sorted.sort_by(|p, q| p.0.total_cmp(&q.0));
    let (x, y) = to(0.0, 0.0);
    let _ = write!(d, "M {x:.2} {y:.2}");
    for &(z, w) in &sorted {
        let (x, y) = to(z, mass);
        let _ = write!(d, " L {x:.2} {y:.2}");
        mass += w;
        let (x, y) = to(z, mass);
        let _ = write!(d, " L {x:.2} {y:.2}");
    }
    let (x, y) = to(1.0, mass);
    let _ = write!(d, " L {x:.2} {y:.2}");
    let _ = writeln!(
        o,
        "<path d=\"{d}\" fill=\"none\" stroke=\"#1f5fbf\" stroke-width=\"2\"/>"
    );
    // G over z_f.
    let mut d = String::new();
    let n = 400;
    for i in 1..n {
        let zf = i as f64 / n as f64;
        let g = tmsm::sharp_bound(b, zf);
        if !g.is_finite() {
            bail!("tmsm figure: G({zf}) = {g}");
        }
        let (x, y) = to(zf, g);
        let _ = write!(d, "{} {x:.2} {y:.2}", if i == 1 { "M" } else { " L" });
    }
    let _ = writeln!(
        o,
        "<path d=\"{d}\" fill=\"none\" stroke=\"#c8102e\" stroke-width=\"2\"/>"
    );
    let (x, y) = to(ZF, sol.g);
    let _ = writeln!(
        o,
        "<circle cx=\"{x:.2}\" cy=\"{y:.2}\" r=\"4\" fill=\"#c8102e\"/>\n<line x1=\"{x:.2}\" y1=\"{py}\" x2=\"{x:.2}\" y2=\"{:.1}\" stroke=\"#808080\" stroke-dasharray=\"3 3\"/>",
        py + ph
    );
    let _ = writeln!(
        o,
        "<text x=\"{:.1}\" y=\"{:.1}\" fill=\"#1f5fbf\">F_Z(z_f), the depth CDF</text>\n<text x=\"{:.1}\" y=\"{:.1}\" fill=\"#c8102e\">G(b, z_f), TMSM's sharp bound</text>\n</svg>",
        px + 8.0,
        py + 18.0,
        px + 8.0,
        py + 36.0
    );
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The drawn minimiser reproduces the input's moments, its mass on [0, z_f) is the G the
    /// figure states, and G stays below F_Z over the right panel's z_f.
    #[test]
    fn the_figure_draws_a_minimiser_of_the_moments() {
        let b = moments(&DIRACS);
        let sol = tmsm::solve(b, ZF);
        let m = moments(&sol.support);
        for (k, (mk, bk)) in m.iter().zip(b).enumerate() {
            assert!((mk - bk).abs() < 1e-8, "moment {k}: {mk} vs {bk}");
        }
        let shadowed: f64 = sol.support.iter().filter(|d| d.0 < ZF).map(|d| d.1).sum();
        assert!((shadowed - sol.g).abs() < 1e-8, "{shadowed} vs {}", sol.g);
        assert!(
            sol.g < cdf(&DIRACS, ZF) - 0.05,
            "the bound is not tight here"
        );
        for i in 1..100 {
            let zf = i as f64 / 100.0;
            assert!(
                tmsm::sharp_bound(b, zf) <= cdf(&DIRACS, zf) + 1e-9,
                "z_f = {zf}"
            );
        }
        let s = svg().unwrap();
        assert!(s.contains(&format!("G = {:.3}", sol.g)), "{s}");
        assert_eq!(
            s.matches("stroke=\"#c8102e\" stroke-width=\"2.5\"").count(),
            sol.support.len()
        );
    }
}
/// The committed copy (reports/default/tmsm_geometry.svg, written by `reproduce`) is what
/// [`svg`] draws; `MOMENTLAB_UPDATE_README=1` rewrites it.
#[cfg(test)]
mod committed {
    #[test]
    fn the_committed_figure_is_what_the_code_draws() {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("reports/default/tmsm_geometry.svg");
        let now = super::svg().unwrap();
        if std::env::var("MOMENTLAB_UPDATE_README").as_deref() == Ok("1") {
            std::fs::write(&path, &now).unwrap();
        }
        let committed = std::fs::read_to_string(&path).unwrap();
        assert!(
            committed == now,
            "{} differs from what tmsm_figure::svg draws; run MOMENTLAB_UPDATE_README=1 cargo test --release --lib tmsm_figure",
            path.display()
        );
    }
}
