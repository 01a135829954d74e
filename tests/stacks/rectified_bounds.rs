//! Rectified-coordinate bounds (supplementary Section 1) against dense sampling of the far plane.
//! Containment: every sample lies in the bounds (1e-9). Tightness: each bound is within the
//! sampling tolerance of the sampled extreme, where the tolerance is the largest change of that
//! coordinate between neighbouring samples (an extremum lies inside one sample cell).

use crate::common::geom::{cross, normalize};
use momentlab::render::rectified::{direction_in_frustum, rectified, rectified_bounds};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::f64::consts::{PI, TAU};

/// Far-plane corners of a camera at the origin looking along `fwd`.
fn frustum(fwd: [f64; 3], up_hint: [f64; 3], tx: f64, ty: f64, far: f64) -> [[f64; 3]; 4] {
    let f = normalize(fwd);
    let r = normalize(cross(f, up_hint));
    let u = cross(r, f);
    let c = |sx: f64, sy: f64| {
        [
            far * (f[0] + sx * tx * r[0] + sy * ty * u[0]),
            far * (f[1] + sx * tx * r[1] + sy * ty * u[1]),
            far * (f[2] + sx * tx * r[2] + sy * ty * u[2]),
        ]
    };
    [c(1.0, 1.0), c(-1.0, 1.0), c(-1.0, -1.0), c(1.0, -1.0)]
}

fn wrap(d: f64) -> f64 {
    let d = d.rem_euclid(TAU);
    d.min(TAU - d)
}

fn check(q: &[[f64; 3]; 4], n: usize) -> (bool, bool) {
    let b = rectified_bounds(q);
    let lerp = |s: f64, t: f64| {
        let mut p = [0.0; 3];
        for (k, pk) in p.iter_mut().enumerate() {
            let top = q[0][k] + s * (q[1][k] - q[0][k]);
            let bot = q[3][k] + s * (q[2][k] - q[3][k]);
            *pk = top + t * (bot - top);
        }
        p
    };
    let mut v = vec![(0.0, 0.0, 0.0); (n + 1) * (n + 1)];
    for i in 0..=n {
        for j in 0..=n {
            v[i * (n + 1) + j] = rectified(lerp(i as f64 / n as f64, j as f64 / n as f64));
        }
    }
    let (mut tr, mut tp, mut tt) = (0.0f64, 0.0f64, 0.0f64);
    let (mut tpb, mut on_boundary) = (0.0f64, Vec::new());
    for i in 0..=n {
        for j in 0..=n {
            let a = v[i * (n + 1) + j];
            let boundary = i == 0 || j == 0 || i == n || j == n;
            if boundary {
                on_boundary.push(a.1);
            }
            for (di, dj) in [(1, 0), (0, 1)] {
                if i + di <= n && j + dj <= n {
                    let c = v[(i + di) * (n + 1) + j + dj];
                    tr = tr.max((a.0 - c.0).abs());
                    tp = tp.max(wrap(a.1 - c.1));
                    tt = tt.max((a.2 - c.2).abs());
                    let cb = i + di == 0 || j + dj == 0 || i + di == n || j + dj == n;
                    if boundary && cb {
                        tpb = tpb.max(wrap(a.1 - c.1));
                    }
                }
            }
        }
    }
    // containment
    for &(r, phi, th) in &v {
        assert!(
            r >= b.r_min - 1e-9 && r <= b.r_max + 1e-9,
            "r {r} outside {b:?}"
        );
        assert!(b.contains_phi(phi, 1e-9), "phi {phi} outside {b:?}");
        assert!(
            th >= b.theta_min - 1e-9 && th <= b.theta_max + 1e-9,
            "theta {th} outside {b:?}"
        );
    }
    // tightness
    let smax_r = v.iter().map(|a| a.0).fold(0.0, f64::max);
    let smin_t = v.iter().map(|a| a.2).fold(f64::INFINITY, f64::min);
    let smax_t = v.iter().map(|a| a.2).fold(0.0, f64::max);
    assert!(
        b.r_max - smax_r <= tr + 1e-9,
        "r_max {} vs sampled {smax_r}",
        b.r_max
    );
    assert!(
        smin_t - b.theta_min <= tt + 1e-9,
        "theta_min {} vs sampled {smin_t} (tol {tt})",
        b.theta_min
    );
    assert!(
        b.theta_max - smax_t <= tt + 1e-9,
        "theta_max {} vs sampled {smax_t} (tol {tt})",
        b.theta_max
    );
    // φ: the sampled boundary azimuths cover an arc of width 2π − (largest gap).
    let mut az = on_boundary;
    az.sort_by(|a, b| a.partial_cmp(b).unwrap());
    let mut gap = az[0] + TAU - az[az.len() - 1];
    for w in az.windows(2) {
        gap = gap.max(w[1] - w[0]);
    }
    let full = b.phi_width >= TAU - 1e-12;
    let sampled_width = if full {
        TAU - gap
    } else {
        b.phi_width.min(TAU - gap)
    };
    let tol = if full { tpb } else { tp };
    assert!(
        b.phi_width - sampled_width <= tol + 1e-9,
        "phi width {} vs sampled {sampled_width} (tol {tol})",
        b.phi_width
    );
    (
        direction_in_frustum(q, [0.0, 0.0, 1.0]),
        direction_in_frustum(q, [0.0, 0.0, -1.0]),
    )
}

#[test]
fn rectified_bounds_contain_and_are_tight() {
    let mut rng = ChaCha8Rng::seed_from_u64(1);
    let (mut ups, mut downs, mut outs) = (0, 0, 0);
    for it in 0..300 {
        let fwd = match it % 6 {
            0 => [0.0, 0.0, 1.0],  // light direction in view
            1 => [0.0, 0.0, -1.0], // flipped light direction
            2 => [rng.gen_range(-0.3..0.3), rng.gen_range(-0.3..0.3), 1.0], // near it
            3 => [rng.gen_range(-1.0..1.0), rng.gen_range(-1.0..1.0), 0.0], // perpendicular
            _ => [
                rng.gen_range(-1.0..1.0),
                rng.gen_range(-1.0..1.0),
                rng.gen_range(-1.0..1.0),
            ],
        };
        let up_hint = normalize([
            rng.gen_range(-1.0..1.0),
            rng.gen_range(-1.0..1.0),
            rng.gen_range(-1.0..1.0),
        ]);
        let tx = (rng.gen_range(10.0f64..120.0) * PI / 360.0).tan();
        let ty = (rng.gen_range(10.0f64..100.0) * PI / 360.0).tan();
        let q = frustum(fwd, up_hint, tx, ty, rng.gen_range(1.0..100.0));
        let (u, d) = check(&q, 160);
        if u {
            ups += 1;
        } else if d {
            downs += 1;
        } else {
            outs += 1;
        }
    }
    eprintln!("light direction inside {ups}, flipped inside {downs}, neither {outs}");
    assert!(ups > 30 && downs > 30 && outs > 100);
}
