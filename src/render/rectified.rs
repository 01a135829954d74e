//! Bounds of rectified coordinates (r, φ, θ) for a camera view frustum in light view space
//! (supplementary document of Peters et al. 2016, Section 1).
//!
//! Coordinates are relative to the camera position (the origin): r = √(x² + y²) (distance from
//! the light's z axis), φ = atan2(y, x) (azimuth), θ = arccos(z/‖q‖) (inclination against +z).
//! The frustum is the cone from the origin through the far-plane quad q₁…q₄ (the near plane is
//! ignored, as single scattering integrates the whole view ray), so r_min = 0 and
//! * r_max = max_i √((q_i)₁² + (q_i)₂²) (a convex function peaks at a vertex);
//! * φ: the largest pairwise angle between the projected vertices; [0, 2π) when +z or −z lies
//!   in the frustum (the far-plane boundary then winds around the z axis);
//! * θ: extrema at the vertices, at the critical point of each edge
//!   t = ((q_i)₃ q_iᵀd − d₃‖q_i‖²) / (d₃ q_iᵀd − (q_i)₃‖d‖²), d = q_j − q_i, when t ∈ [0,1], and
//!   θ_min = 0 / θ_max = π when +z / −z lies in the frustum.

use crate::linalg::v3::{cross, dot, sub};
use std::f64::consts::{PI, TAU};

/// The bounds. φ is the arc [phi_start, phi_start + phi_width] (radians, phi_start ∈ (−π, π],
/// phi_width ∈ [0, 2π]; the full circle when the z axis is inside the frustum).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RectifiedBounds {
    /// Smallest distance from the light's z axis (0: the cone contains the origin).
    pub r_min: f64,
    /// Largest distance from the light's z axis, over the far-plane vertices.
    pub r_max: f64,
    /// Start of the azimuth arc, radians in (−π, π].
    pub phi_start: f64,
    /// Width of the azimuth arc, radians in [0, 2π].
    pub phi_width: f64,
    /// Smallest inclination θ against +z, radians.
    pub theta_min: f64,
    /// Largest inclination θ against +z, radians.
    pub theta_max: f64,
}

impl RectifiedBounds {
    /// Whether azimuth φ lies in the φ arc (with tolerance `eps`).
    pub fn contains_phi(&self, phi: f64, eps: f64) -> bool {
        if self.phi_width >= TAU - eps {
            return true;
        }
        let d = (phi - self.phi_start).rem_euclid(TAU);
        d <= self.phi_width + eps || d >= TAU - eps
    }
}

/// r, φ, θ of a point q (relative to the camera).
pub fn rectified(q: [f64; 3]) -> (f64, f64, f64) {
    let r = q[0].hypot(q[1]);
    let n = (q[0] * q[0] + q[1] * q[1] + q[2] * q[2]).sqrt();
    let theta = (q[2] / n).clamp(-1.0, 1.0).acos();
    (r, q[1].atan2(q[0]), theta)
}

/// Whether direction `v` lies in the cone from the origin through the convex quad `q` (none of
/// the four side planes clips it).
pub fn direction_in_frustum(q: &[[f64; 3]; 4], v: [f64; 3]) -> bool {
    let centre = [
        q.iter().map(|p| p[0]).sum::<f64>(),
        q.iter().map(|p| p[1]).sum::<f64>(),
        q.iter().map(|p| p[2]).sum::<f64>(),
    ];
    (0..4).all(|i| {
        let n = cross(q[i], q[(i + 1) % 4]);
        // orient the side-plane normal toward the inside (the centre ray)
        let s = dot(n, centre).signum();
        s * dot(n, v) >= 0.0
    })
}

/// Bounds of r, φ, θ over the frustum with far-plane vertices `q` (in order around the quad,
/// light view space, camera at the origin).
pub fn rectified_bounds(q: &[[f64; 3]; 4]) -> RectifiedBounds {
    let up = direction_in_frustum(q, [0.0, 0.0, 1.0]);
    let down = direction_in_frustum(q, [0.0, 0.0, -1.0]);
    let r_max = q.iter().map(|p| p[0].hypot(p[1])).fold(0.0, f64::max);
    // φ: the largest pairwise angle between the projected vertices.
    let (phi_start, phi_width) = if up || down {
        (-PI, TAU)
    } else {
        let az: Vec<f64> = q.iter().map(|p| p[1].atan2(p[0])).collect();
        let mut best = (az[0], 0.0);
        for i in 0..4 {
            for j in 0..4 {
                // counter-clockwise angle from i to j; the pairwise angle is ≤ π
                let d = (az[j] - az[i]).rem_euclid(TAU);
                if d <= PI && d > best.1 {
                    best = (az[i], d);
                }
            }
        }
        best
    };
    // θ: vertices, edge critical points, interior (±z in the frustum).
    let mut tmin = f64::INFINITY;
    let mut tmax = f64::NEG_INFINITY;
    let mut add = |p: [f64; 3]| {
        let (_, _, t) = rectified(p);
        tmin = tmin.min(t);
        tmax = tmax.max(t);
    };
    for i in 0..4 {
        let qi = q[i];
        add(qi);
        let d = sub(q[(i + 1) % 4], qi);
        let qd = dot(qi, d);
        let den = d[2] * qd - qi[2] * dot(d, d);
        if den != 0.0 {
            let t = (qi[2] * qd - d[2] * dot(qi, qi)) / den;
            if (0.0..=1.0).contains(&t) {
                add([qi[0] + t * d[0], qi[1] + t * d[1], qi[2] + t * d[2]]);
            }
        }
    }
    if up {
        tmin = 0.0;
    }
    if down {
        tmax = PI;
    }
    RectifiedBounds {
        r_min: 0.0,
        r_max,
        phi_start,
        phi_width,
        theta_min: tmin,
        theta_max: tmax,
    }
}
