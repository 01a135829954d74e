//! The volume of the moment space of [0,1] and convex hulls of curves in R³ (Fig. 5).
//!
//! Volume of {E_Z(z, …, z^m)} = ∏_{j=1..m} ((j−1)!)² / (2j−1)! (Peters & Klein 2015,
//! Proposition 19, quoted in the 2016 supplementary, Section 3: 1/44008272000 for m = 6).
//! An affine θ multiplies volumes by |det θ|, so log₂ of the reciprocal bounds the gain of θ
//! on a uniform distribution of moments.

use crate::linalg::v3::{cross, dot as dot3, sub};
use anyhow::{bail, Result};

/// 1/volume as an exact integer, if it fits in u128 (m ≤ 8).
pub fn volume_bound_reciprocal(m: usize) -> Option<u128> {
    let mut r: u128 = 1;
    for j in 1..=m as u128 {
        // (2j−1)! / ((j−1)!)² = (2j−1)·C(2j−2, j−1)
        let mut binom: u128 = 1;
        for k in 0..(j - 1) {
            binom = binom.checked_mul(2 * j - 2 - k)? / (k + 1);
        }
        r = r.checked_mul((2 * j - 1).checked_mul(binom)?)?;
    }
    Some(r)
}

/// −log₂ of the moment-space volume: the most bits an (any) transform could gain.
pub fn volume_bound_bits(m: usize) -> f64 {
    let mut l = 0.0;
    for j in 1..=m {
        // log2 of (2j−1)! − 2 log2 (j−1)!
        let f = |n: usize| (1..=n).map(|k| (k as f64).log2()).sum::<f64>();
        l += f(2 * j - 1) - 2.0 * f(j - 1);
    }
    l
}

/// A closed triangulated convex polyhedron: faces index `points`, outward counter-clockwise.
#[derive(Clone, Debug)]
pub struct Hull {
    /// Vertices.
    pub points: Vec<[f64; 3]>,
    /// Triangles as indices into `points`, outward counter-clockwise.
    pub faces: Vec<[usize; 3]>,
}

/// 6 × signed volume of the tetrahedron (a, b, c, d): > 0 if d is above face (a, b, c).
fn orient(a: [f64; 3], b: [f64; 3], c: [f64; 3], d: [f64; 3]) -> f64 {
    dot3(cross(sub(b, a), sub(c, a)), sub(d, a))
}

/// Convex hull of points in R³ (incremental; O(n·faces), fine for a few thousand points).
pub fn convex_hull_3d(pts: &[[f64; 3]]) -> Result<Hull> {
    let n = pts.len();
    if n < 4 || pts.iter().flatten().any(|v| !v.is_finite()) {
        bail!("convex hull needs at least 4 finite points");
    }
    let dist2 = |a: [f64; 3], b: [f64; 3]| dot3(sub(a, b), sub(a, b));
    let i0 = 0;
    let i1 = (0..n)
        .max_by(|&i, &j| dist2(pts[i], pts[i0]).total_cmp(&dist2(pts[j], pts[i0])))
        .unwrap();
    let diag = dist2(pts[i0], pts[i1]).sqrt();
    let i2 = (0..n)
        .max_by(|&i, &j| {
            let ci = cross(sub(pts[i1], pts[i0]), sub(pts[i], pts[i0]));
            let cj = cross(sub(pts[i1], pts[i0]), sub(pts[j], pts[i0]));
            dot3(ci, ci).total_cmp(&dot3(cj, cj))
        })
        .unwrap();
    let i3 = (0..n)
        .max_by(|&i, &j| {
            orient(pts[i0], pts[i1], pts[i2], pts[i])
                .abs()
                .total_cmp(&orient(pts[i0], pts[i1], pts[i2], pts[j]).abs())
        })
        .unwrap();
    let eps = 1e-13 * diag.powi(3);
    let o = orient(pts[i0], pts[i1], pts[i2], pts[i3]);
    if !(o.abs() > eps) {
        bail!("convex hull: points are (nearly) coplanar");
    }
    let mut faces: Vec<[usize; 3]> = if o > 0.0 {
        // i3 above (i0,i1,i2): flip that face
        vec![[i0, i2, i1], [i0, i1, i3], [i1, i2, i3], [i2, i0, i3]]
    } else {
        vec![[i0, i1, i2], [i0, i3, i1], [i1, i3, i2], [i2, i3, i0]]
    };
    for p in 0..n {
        if p == i0 || p == i1 || p == i2 || p == i3 {
            continue;
        }
        let visible: Vec<bool> = faces
            .iter()
            .map(|f| orient(pts[f[0]], pts[f[1]], pts[f[2]], pts[p]) > eps)
            .collect();
        if !visible.iter().any(|&v| v) {
            continue;
        }
        // The visible faces' edges in face order (the set only answers membership), so the
        // new faces, and with them the output, do not depend on the hash seed.
        let mut edges = std::collections::HashSet::new();
        let mut order = Vec::new();
        for (f, _) in faces.iter().zip(&visible).filter(|(_, &v)| v) {
            for k in 0..3 {
                let e = (f[k], f[(k + 1) % 3]);
                if edges.insert(e) {
                    order.push(e);
                }
            }
        }
        let mut new_faces: Vec<[usize; 3]> = faces
            .iter()
            .zip(&visible)
            .filter(|(_, &v)| !v)
            .map(|(f, _)| *f)
            .collect();
        for &(a, b) in &order {
            if !edges.contains(&(b, a)) {
                new_faces.push([a, b, p]);
            }
        }
        faces = new_faces;
    }
    Ok(Hull {
        points: pts.to_vec(),
        faces,
    })
}

impl Hull {
    /// Enclosed volume (divergence theorem over the outward faces).
    pub fn volume(&self) -> f64 {
        let o = self.points[self.faces[0][0]];
        self.faces
            .iter()
            .map(|f| orient(o, self.points[f[0]], self.points[f[1]], self.points[f[2]]))
            .sum::<f64>()
            / 6.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};

    #[test]
    fn hull_is_the_same_on_every_call() {
        // Each HashSet has its own random seed: with edges visited in set order the faces
        // (and the volume's rounding) came out in a different order on every call.
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        let pts: Vec<[f64; 3]> = (0..300)
            .map(|_| [rng.gen(), rng.gen(), rng.gen()])
            .collect();
        let first = convex_hull_3d(&pts).unwrap();
        for _ in 0..8 {
            let again = convex_hull_3d(&pts).unwrap();
            assert_eq!(again.faces, first.faces);
            assert_eq!(again.volume().to_bits(), first.volume().to_bits());
        }
    }

    #[test]
    fn bound_matches_the_supplementary() {
        assert_eq!(volume_bound_reciprocal(6), Some(44_008_272_000));
        assert_eq!(volume_bound_reciprocal(2), Some(6));
        assert_eq!(volume_bound_reciprocal(3), Some(180));
        assert!((volume_bound_bits(6) - 35.357).abs() < 5e-4);
        for m in 1..=8 {
            let r = volume_bound_reciprocal(m).unwrap() as f64;
            assert!((r.log2() - volume_bound_bits(m)).abs() < 1e-9);
        }
    }

    #[test]
    fn hull_of_cube_with_interior_points() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(1);
        let mut pts: Vec<[f64; 3]> = (0..300)
            .map(|_| [rng.gen(), rng.gen(), rng.gen()])
            .collect();
        for c in 0..8 {
            pts.push([(c & 1) as f64, ((c >> 1) & 1) as f64, ((c >> 2) & 1) as f64]);
        }
        let h = convex_hull_3d(&pts).unwrap();
        assert!((h.volume() - 1.0).abs() < 1e-12, "{}", h.volume());
        // every point is inside or on every face plane
        for f in &h.faces {
            for p in &pts {
                assert!(orient(pts[f[0]], pts[f[1]], pts[f[2]], *p) <= 1e-12);
            }
        }
    }

    #[test]
    fn hull_of_moment_curve_approaches_proposition_19() {
        let pts: Vec<[f64; 3]> = (0..=1500)
            .map(|i| {
                let z = i as f64 / 1500.0;
                [z, z * z, z * z * z]
            })
            .collect();
        let v = convex_hull_3d(&pts).unwrap().volume();
        assert!(v <= 1.0 / 180.0 && v > (1.0 / 180.0) * (1.0 - 1e-4), "{v}");
    }
}
