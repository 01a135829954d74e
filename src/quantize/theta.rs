//! The affine quantization transform θ(b) = A·b + t (Peters & Klein 2015, Section 4.3):
//! maximise the entropy gain log₂|det A| (Proposition 6) subject to θ(b([0,1])) ⊆ [0,1]^m.
//! Also the published transforms θ₂, θ₄ (paper, Section 4.3) and θ₆ (supplementary of
//! Peters et al. 2016, Table 1), and exact containment verification.

use super::curve::{row_min_max, Curve};
use super::linalg::Lu;
use anyhow::{bail, Result};
use serde::{Deserialize, Serialize};

/// θ: stored vector s = matrix·b + offset; b = inverse·(s − offset).
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct Theta {
    /// Basis function names, in the order of b's components.
    pub basis: Vec<String>,
    /// A (m × m, rows): s = A·b + offset.
    pub matrix: Vec<Vec<f64>>,
    /// The offset t (length m).
    pub offset: Vec<f64>,
    /// A⁻¹, for decoding b = A⁻¹·(s − t).
    pub inverse: Vec<Vec<f64>>,
}

impl Theta {
    /// Build from matrix and offset; errors if the shapes disagree or the matrix is singular.
    pub fn new(basis: Vec<String>, matrix: Vec<Vec<f64>>, offset: Vec<f64>) -> Result<Theta> {
        let m = matrix.len();
        if m == 0 || offset.len() != m || basis.len() != m || matrix.iter().any(|r| r.len() != m) {
            bail!("theta: matrix must be m×m with m offsets and m basis names");
        }
        if matrix
            .iter()
            .flatten()
            .chain(&offset)
            .any(|v| !v.is_finite())
        {
            bail!("theta: non-finite coefficient");
        }
        let Some(lu) = Lu::new(&matrix) else {
            bail!("theta: matrix is singular");
        };
        let inverse = lu.inverse();
        Ok(Theta {
            basis,
            matrix,
            offset,
            inverse,
        })
    }

    /// Moment count m.
    pub fn m(&self) -> usize {
        self.matrix.len()
    }

    /// Entropy gain log₂|det A| in bits (Proposition 6 of the 2015 paper).
    pub fn gain_bits(&self) -> f64 {
        Lu::new(&self.matrix)
            .map(|lu| lu.log2_abs_det().0)
            .unwrap_or(f64::NEG_INFINITY)
    }

    /// s = A·b + t.
    pub fn encode(&self, b: &[f64], out: &mut [f64]) {
        for ((o, row), t) in out.iter_mut().zip(&self.matrix).zip(&self.offset) {
            *o = row.iter().zip(b).map(|(p, q)| p * q).sum::<f64>() + t;
        }
    }

    /// b = A⁻¹·(s − t).
    pub fn decode(&self, s: &[f64], out: &mut [f64]) {
        for (o, row) in out.iter_mut().zip(&self.inverse) {
            *o = row
                .iter()
                .zip(s.iter().zip(&self.offset))
                .map(|(a, (p, q))| a * (p - q))
                .sum();
        }
    }
}

/// Result of checking θ(b([0,1])) ⊆ [0,1]^m.
#[derive(Clone, Debug, Serialize)]
pub struct Verification {
    /// max over rows and z of how far θ_i(b(z)) leaves [0,1] (≤ 0: contained, and −value is
    /// the worst margin).
    pub max_violation: f64,
    /// Per row: (min, max) of θ_i(b(z)) over z ∈ [0,1].
    pub row_ranges: Vec<(f64, f64)>,
    /// True if the extrema came from an exact oracle (derivative roots).
    pub exact: bool,
}

/// Verify containment of θ∘b over [0,1] with the curve's extrema oracle.
pub fn verify(theta: &Theta, curve: &dyn Curve) -> Result<Verification> {
    if curve.dim() != theta.m() {
        bail!(
            "theta has {} rows but the basis has {} functions",
            theta.m(),
            curve.dim()
        );
    }
    let mut worst = f64::NEG_INFINITY;
    let mut ranges = Vec::with_capacity(theta.m());
    for (row, &t) in theta.matrix.iter().zip(&theta.offset) {
        let (_, lo, _, hi) = row_min_max(curve, row);
        let (lo, hi) = (lo + t, hi + t);
        worst = worst.max(-lo).max(hi - 1.0);
        ranges.push((lo, hi));
    }
    Ok(Verification {
        max_violation: worst,
        row_ranges: ranges,
        exact: curve.exact(),
    })
}

/// Rescale every row to range exactly `1 − margin` inside [0,1] (centred), which keeps the
/// transform strictly feasible; returns the new θ. Gain changes by Σ log₂(1/range_i).
pub fn normalize_rows(theta: &Theta, curve: &dyn Curve, margin: f64) -> Result<Theta> {
    let mut matrix = theta.matrix.clone();
    let mut offset = theta.offset.clone();
    for (row, t) in matrix.iter_mut().zip(offset.iter_mut()) {
        let (_, lo, _, hi) = row_min_max(curve, row);
        let range = hi - lo;
        if !(range > 0.0) || !range.is_finite() {
            bail!("theta row has zero or non-finite range over [0,1]");
        }
        let s = (1.0 - margin) / range;
        row.iter_mut().for_each(|v| *v *= s);
        *t = -lo * s + 0.5 * margin;
    }
    Theta::new(theta.basis.clone(), matrix, offset)
}

fn power_names(m: usize) -> Vec<String> {
    (1..=m)
        .map(|e| if e == 1 { "z".into() } else { format!("z^{e}") })
        .collect()
}

/// θ₂ of Peters & Klein 2015, Section 4.3: [[1,0],[4,−4]], offset 0 (2 bits).
pub fn published_theta2() -> Theta {
    Theta::new(
        power_names(2),
        vec![vec![1.0, 0.0], vec![4.0, -4.0]],
        vec![0.0, 0.0],
    )
    .expect("published theta2 is regular")
}

/// θ₄ of Peters & Klein 2015, Section 4.3 (quoted: 12.2783 bits, "12.3 bits").
pub fn published_theta4() -> Theta {
    Theta::new(
        power_names(4),
        vec![
            vec![-2.07224649, 32.2370378, -68.5710746, 39.3703274],
            vec![13.7948857, -59.4683976, 82.035975, -35.3649032],
            vec![0.105877704, -1.90774663, 9.34965551, -6.65434907],
            vec![9.79240621, -33.76521106, 47.9456097, -23.9728048],
        ],
        vec![0.0359558848, 0.0, 0.0, 0.0],
    )
    .expect("published theta4 is regular")
}

/// θ₆ of the supplementary document of Peters et al., "Beyond Hard Shadows" (I3D 2016),
/// Section 3, Table 1 (quoted gain 30.511 / "30.5 bits"). Both text extractions of the table
/// (papers 000 and 003) agree digit for digit.
pub fn published_theta6() -> Theta {
    Theta::new(
        power_names(6),
        vec![
            vec![
                -0.39982174417,
                5.372499433,
                -19.400931206,
                5.9601506283,
                21.716342727,
                -14.2481344,
            ],
            vec![
                -0.2036458037,
                61.687438614,
                -280.26108456,
                480.86777452,
                -370.6170286,
                109.52605942,
            ],
            vec![
                35.997693025,
                -419.96056141,
                1791.8207666,
                -3455.6578547,
                3071.7060681,
                -1023.906108,
            ],
            vec![
                24.253667437,
                -187.46243964,
                499.10228252,
                -516.52881873,
                144.63179523,
                37.003250859,
            ],
            vec![
                14.571662352,
                -64.120119623,
                75.292307128,
                8.798154992,
                -43.073239823,
                8.5315616209,
            ],
            vec![
                2.5464326857,
                -78.04982013,
                350.77691236,
                -674.56153641,
                598.68902736,
                -199.39897152,
            ],
        ],
        vec![
            0.9999446933,
            0.0003698424,
            0.0000000000,
            0.0000807802,
            0.0000059274,
            0.9774602669,
        ],
    )
    .expect("published theta6 is regular")
}

/// The published transform for m moments of the power basis, if any (2, 4, 6).
pub fn published(m: usize) -> Option<Theta> {
    match m {
        2 => Some(published_theta2()),
        4 => Some(published_theta4()),
        6 => Some(published_theta6()),
        _ => None,
    }
}

/// Gains quoted in the papers' text, in bits, as printed: θ₂ 2, θ₃ 6.2, θ₄ 12.2783 (Peters &
/// Klein 2015, Section 4.3) and θ₆ 30.511 (supplementary of Peters et al. 2016, Section 3).
pub const QUOTED_GAIN_BITS: [(usize, &str); 4] =
    [(2, "2"), (3, "6.2"), (4, "12.2783"), (6, "30.511")];

/// The quoted gain of θ_m as printed in the papers ([`QUOTED_GAIN_BITS`]), if any.
pub fn quoted_gain(m: usize) -> Option<&'static str> {
    QUOTED_GAIN_BITS.iter().find(|q| q.0 == m).map(|q| q.1)
}

/// θ₂ / θ₄ in the channel order of the 2015 paper (Section 4.3; the order MJP's Shadows sample
/// and Unity HDRP ship): each published row is matched to the row of `theta` (or its
/// reflection s ↦ 1 − s, i.e. row −a and offset 1 − t) nearest to it, relative to the published
/// row's largest entry. Returns the reordered θ and the largest relative difference to the
/// published matrix; None if m ∉ {2, 4}, the basis is not (z, …, z^m) or no one-to-one matching
/// lies within 1 % (a different optimum).
pub fn paper_order(theta: &Theta) -> Option<(Theta, f64)> {
    let m = theta.m();
    if !matches!(m, 2 | 4) || theta.basis != power_names(m) {
        return None;
    }
    let p = published(m)?;
    let mut used = vec![false; m];
    let (mut rows, mut offs, mut worst) = (Vec::new(), Vec::new(), 0.0f64);
    for (prow, &pt) in p.matrix.iter().zip(&p.offset) {
        let scale = prow.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        let mut best: Option<(f64, usize, f64)> = None;
        for (j, row) in theta.matrix.iter().enumerate() {
            if used[j] {
                continue;
            }
            for sign in [1.0, -1.0] {
                let d = row
                    .iter()
                    .zip(prow)
                    .fold(0.0f64, |a, (r, q)| a.max((sign * r - q).abs()))
                    / scale;
                let t = if sign > 0.0 {
                    theta.offset[j]
                } else {
                    1.0 - theta.offset[j]
                };
                let d = d.max((t - pt).abs());
                if best.is_none_or(|b| d < b.0) {
                    best = Some((d, j, sign));
                }
            }
        }
        let (d, j, sign) = best?;
        if d > 1e-2 {
            return None;
        }
        used[j] = true;
        worst = worst.max(d);
        rows.push(theta.matrix[j].iter().map(|v| sign * v).collect());
        offs.push(if sign > 0.0 {
            theta.offset[j]
        } else {
            1.0 - theta.offset[j]
        });
    }
    let th = Theta::new(theta.basis.clone(), rows, offs).ok()?;
    Some((th, worst))
}
