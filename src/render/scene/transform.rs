//! Placing objects: the affine map of an object's `transform` (scale, then Euler rotation,
//! then translation) and the placement of a loaded mesh (up axis, rotation, fit).

use super::{bounds, pos, Tri, V3};
use crate::linalg::v3::{scale, sub};
use anyhow::{bail, Result};
use serde::Deserialize;

/// A transform must be invertible with a finite, not vanishing scale: |det A| in
/// [1e-30, 1e30] and every entry finite (scale 0 or 1e300 are errors, not an empty stack).
pub(super) fn check_affine(m: &Affine) -> Result<()> {
    let a = &m.a;
    if a.iter().flatten().chain(m.t.iter()).any(|v| !v.is_finite()) {
        bail!("not finite");
    }
    let det = a[0][0] * (a[1][1] * a[2][2] - a[1][2] * a[2][1])
        - a[0][1] * (a[1][0] * a[2][2] - a[1][2] * a[2][0])
        + a[0][2] * (a[1][0] * a[2][1] - a[1][1] * a[2][0]);
    if !(det.abs() >= 1e-30 && det.abs() <= 1e30) {
        bail!("degenerate (determinant {det:e}): a scale must be finite and not 0");
    }
    Ok(())
}

/// Scale: uniform or per axis.
#[derive(Deserialize, Clone, Copy)]
#[serde(untagged)]
enum Scale {
    Uniform(f64),
    Axes(V3),
}

#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub(super) struct Transform {
    /// Applied last.
    #[serde(default)]
    translate: Option<V3>,
    /// Euler angles in degrees, applied about X, then Y, then Z (after scaling).
    #[serde(default)]
    rotate: Option<V3>,
    /// Applied first.
    #[serde(default)]
    scale: Option<Scale>,
}

/// Affine map x ↦ A x + t.
#[derive(Clone, Copy, Debug)]
pub struct Affine {
    /// Linear part A (row-major).
    pub a: [[f64; 3]; 3],
    /// Translation t.
    pub t: V3,
}

impl Affine {
    /// A p + t.
    pub fn apply(&self, p: V3) -> V3 {
        let mut r = self.t;
        for (i, ri) in r.iter_mut().enumerate() {
            *ri += self.a[i][0] * p[0] + self.a[i][1] * p[1] + self.a[i][2] * p[2];
        }
        r
    }
}

fn matmul(x: [[f64; 3]; 3], y: [[f64; 3]; 3]) -> [[f64; 3]; 3] {
    let mut r = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            r[i][j] = (0..3).map(|k| x[i][k] * y[k][j]).sum();
        }
    }
    r
}

impl Transform {
    pub(super) fn matrix(&self) -> Affine {
        let s = match self.scale {
            None => [1.0; 3],
            Some(Scale::Uniform(s)) => [s; 3],
            Some(Scale::Axes(s)) => s,
        };
        let a = [[s[0], 0.0, 0.0], [0.0, s[1], 0.0], [0.0, 0.0, s[2]]];
        Affine {
            a: matmul(euler(self.rotate.unwrap_or([0.0; 3])), a),
            t: self.translate.unwrap_or([0.0; 3]),
        }
    }
}

/// R = R_z · R_y · R_x for Euler angles `r` in degrees (about X first, then Y, then Z).
fn euler(r: V3) -> [[f64; 3]; 3] {
    let (sx, cx) = r[0].to_radians().sin_cos();
    let (sy, cy) = r[1].to_radians().sin_cos();
    let (sz, cz) = r[2].to_radians().sin_cos();
    let rx = [[1.0, 0.0, 0.0], [0.0, cx, -sx], [0.0, sx, cx]];
    let ry = [[cy, 0.0, sy], [0.0, 1.0, 0.0], [-sy, 0.0, cy]];
    let rz = [[cz, -sz, 0.0], [sz, cz, 0.0], [0.0, 0.0, 1.0]];
    matmul(rz, matmul(ry, rx))
}

/// Which axis of a mesh file points up. momentlab's world is y-up; a z-up mesh (common for
/// STL and PLY scans) is turned by −90° about X, which maps (x, y, z) to (x, z, −y).
#[derive(Deserialize, Clone, Copy, Debug, Default, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub enum UpAxis {
    /// y points up (momentlab's world convention).
    #[default]
    Y,
    /// z points up; turned by −90° about X.
    Z,
}

impl std::str::FromStr for UpAxis {
    type Err = anyhow::Error;
    fn from_str(s: &str) -> Result<UpAxis> {
        match s {
            "y" | "Y" => Ok(UpAxis::Y),
            "z" | "Z" => Ok(UpAxis::Z),
            _ => bail!("up axis '{s}': expected y or z"),
        }
    }
}

/// Places a loaded mesh in its object's local frame, in this order: `up_axis` (z-up → y-up),
/// then `rotate` (Euler degrees, X then Y then Z), then `fit` (uniform scale so the largest
/// extent is `fit`, centred in x/z, lowest point at y = 0). The object's `transform` is applied
/// after this, so a fitted mesh always stands on the ground before it is moved.
pub fn orient_mesh(
    tris: &mut [Tri],
    up_axis: UpAxis,
    rotate: Option<V3>,
    fit: Option<f64>,
) -> Result<()> {
    let mut r = euler(rotate.unwrap_or([0.0; 3]));
    if up_axis == UpAxis::Z {
        r = matmul(r, euler([-90.0, 0.0, 0.0]));
    }
    if up_axis != UpAxis::Y || rotate.is_some() {
        let m = Affine { a: r, t: [0.0; 3] };
        for v in tris.iter_mut().flatten() {
            *v = m.apply(*v);
        }
    }
    if let Some(f) = fit {
        pos("mesh fit", f)?;
        fit_mesh(tris, f);
    }
    Ok(())
}

/// Uniform scale so the largest extent is `fit`, centred in x/z, lowest point at y = 0.
fn fit_mesh(tris: &mut [Tri], fit: f64) {
    let (lo, hi) = bounds(tris);
    let ext = (0..3).map(|k| hi[k] - lo[k]).fold(0.0, f64::max);
    let s = if ext > 0.0 { fit / ext } else { 1.0 };
    let c = [(lo[0] + hi[0]) / 2.0, lo[1], (lo[2] + hi[2]) / 2.0];
    for v in tris.iter_mut().flatten() {
        *v = scale(sub(*v, c), s);
    }
}
