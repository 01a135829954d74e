//! The Fig. 5 analogue of Peters & Klein 2015: the curves b([0,1]) and θ₃∘b([0,1]) for the
//! power basis of m = 3 with their convex hulls and hull volumes (paper: transformed volume
//! 0.41, 73.9 times the untransformed one). Rendered with plotters' SVG backend.

use super::theta::Theta;
use super::volume::{convex_hull_3d, Hull};
use anyhow::{bail, Result};
use plotters::prelude::*;
use serde::Serialize;

/// Hull volumes of the Fig. 5 analogue.
#[derive(Clone, Debug, Serialize)]
pub struct Fig5Volumes {
    /// Hull of n points on b([0,1]) (a lower bound converging to 1/180).
    pub volume_b: f64,
    /// Exact moment-space volume 1/180 (Proposition 19).
    pub volume_b_exact: f64,
    /// Hull of the same points mapped by θ₃.
    pub volume_theta: f64,
    /// volume_theta / volume_b (= |det θ₃| up to rounding).
    pub ratio: f64,
    /// det θ₃ = 2^gain_bits.
    pub det: f64,
    /// Number of curve points in each hull.
    pub points: usize,
}

fn curve_points(theta: Option<&Theta>, n: usize) -> Vec<[f64; 3]> {
    (0..=n)
        .map(|i| {
            let z = i as f64 / n as f64;
            let b = [z, z * z, z * z * z];
            match theta {
                None => b,
                Some(t) => {
                    let mut s = [0.0; 3];
                    t.encode(&b, &mut s);
                    s
                }
            }
        })
        .collect()
}

/// Volumes of conv b([0,1]) and conv θ₃(b([0,1])) from `n` + 1 curve points.
pub fn volumes(theta3: &Theta, n: usize) -> Result<Fig5Volumes> {
    if theta3.m() != 3 {
        bail!("Fig. 5 needs a θ for m = 3, got m = {}", theta3.m());
    }
    let vb = convex_hull_3d(&curve_points(None, n))?.volume();
    let vt = convex_hull_3d(&curve_points(Some(theta3), n))?.volume();
    Ok(Fig5Volumes {
        volume_b: vb,
        volume_b_exact: 1.0 / 180.0,
        volume_theta: vt,
        ratio: vt / vb,
        det: 2f64.powf(theta3.gain_bits()),
        points: n + 1,
    })
}

fn panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, plotters::coord::Shift>,
    title: &str,
    pts: &[[f64; 3]],
    hull: &Hull,
    color: RGBColor,
) -> Result<()>
where
    DB::ErrorType: 'static,
{
    let mut chart = ChartBuilder::on(area)
        .caption(title, ("sans-serif", 18))
        .margin(10)
        .build_cartesian_3d(0.0..1.0, 0.0..1.0, 0.0..1.0)
        .map_err(|e| anyhow::anyhow!("plot: {e}"))?;
    chart.with_projection(|mut p| {
        p.yaw = 0.6;
        p.pitch = 0.35;
        p.scale = 0.85;
        p.into_matrix()
    });
    chart
        .configure_axes()
        .max_light_lines(2)
        .draw()
        .map_err(|e| anyhow::anyhow!("plot: {e}"))?;
    // plotters' 3D coordinates are (x, y = up, z); map (s1, s2, s3) -> (s1, s3, s2)
    let p3 = |p: [f64; 3]| (p[0], p[2], p[1]);
    chart
        .draw_series(hull.faces.iter().map(|f| {
            Polygon::new(
                vec![
                    p3(hull.points[f[0]]),
                    p3(hull.points[f[1]]),
                    p3(hull.points[f[2]]),
                ],
                color.mix(0.18).filled(),
            )
        }))
        .map_err(|e| anyhow::anyhow!("plot: {e}"))?;
    chart
        .draw_series(LineSeries::new(
            pts.iter().map(|&p| p3(p)),
            BLACK.stroke_width(2),
        ))
        .map_err(|e| anyhow::anyhow!("plot: {e}"))?;
    Ok(())
}

/// SVG with two panels: b([0,1]) and θ₃∘b([0,1]) in the unit cube with their hulls.
pub fn svg(theta3: &Theta, vols: &Fig5Volumes, plot_points: usize) -> Result<String> {
    let pb = curve_points(None, plot_points);
    let pt = curve_points(Some(theta3), plot_points);
    let hb = convex_hull_3d(&pb)?;
    let ht = convex_hull_3d(&pt)?;
    let mut out = String::new();
    {
        let root = SVGBackend::with_string(&mut out, (1100, 560)).into_drawing_area();
        root.fill(&WHITE)
            .map_err(|e| anyhow::anyhow!("plot: {e}"))?;
        let (l, r) = root.split_horizontally(550);
        panel(
            &l,
            &format!("b([0,1]) = (z, z², z³): hull volume {:.5}", vols.volume_b),
            &pb,
            &hb,
            BLUE,
        )?;
        panel(
            &r,
            &format!(
                "θ₃∘b([0,1]): hull volume {:.4} ({:.1}×)",
                vols.volume_theta, vols.ratio
            ),
            &pt,
            &ht,
            RED,
        )?;
        root.present().map_err(|e| anyhow::anyhow!("plot: {e}"))?;
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn volumes_scale_by_the_determinant() {
        // any regular θ for m = 3: the hull volume ratio is |det|
        let th = Theta::new(
            vec!["z".into(), "z^2".into(), "z^3".into()],
            vec![
                vec![-9.0, 24.0, -16.0],
                vec![0.577, -4.6, 3.08],
                vec![4.0, -4.0, 0.0],
            ],
            vec![1.0, 1.0, 0.0],
        )
        .unwrap();
        let v = volumes(&th, 800).unwrap();
        assert!((v.ratio - v.det).abs() < 1e-6 * v.det, "{v:?}");
        assert!((v.volume_b - 1.0 / 180.0).abs() < 1e-4 / 180.0);
        let s = svg(&th, &v, 40).unwrap();
        assert!(s.contains("<svg") && s.contains("polygon"));
    }
}
