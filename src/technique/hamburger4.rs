//! Hamburger four moment shadow mapping (Peters & Klein 2015, Section 4.2, Algorithm 3 with the
//! authors' erratum: the third case returns 1 − w₁). Basis b(z) = (z, z², z³, z⁴) on I = R.
//!
//! b' = (1 − α)·b + α·b*; solve B·c = (1, z_f, z_f²) for the 3×3 Hankel matrix B of
//! (1, b'₁, …, b'₄) with an LDLᵀ decomposition; z₂ ≤ z₃ are the roots of c₁ + c₂ z + c₃ z²;
//! G = 0 if z_f ≤ z₂, w₂ = (z_f z₃ − b'₁(z_f + z₃) + b'₂) / ((z₃ − z₂)(z_f − z₂)) if z_f ≤ z₃,
//! else 1 − w₁ = 1 − (z₂ z₃ − b'₁(z₂ + z₃) + b'₂) / ((z_f − z₂)(z_f − z₃)).

use super::linalg::{above, bias, pivot_tol, Precision, Real};
use super::roots::quadratic_roots;
use super::{ClosedForm, DepthDomain, Technique};

/// Relative floor of the last LDLᵀ pivot D33, in units of ε² of the arithmetic type:
/// singular B (two Diracs, Proposition 4) then yields a huge but finite c whose direction is
/// the kernel of B, i.e. the exact reconstruction.
pub(crate) fn pivot_floor<T: Real>() -> T {
    T::EPS * T::EPS
}

/// Result of the three-Dirac solution: G (unclamped) and the support (z_f, z₂, z₃).
#[derive(Clone, Copy, Debug)]
pub struct Msm4<T> {
    /// Shadow intensity G of Algorithm 3 step 4, unclamped.
    pub g: T,
    /// z₂ ≤ z₃: roots of the quadratic; with z_f they support the minimising distribution.
    pub z2: T,
    /// The larger root (see `z2`).
    pub z3: T,
}

/// Biased moments b' for four moments.
#[inline(always)]
pub fn biased4<T: Real>(b: [T; 4], alpha: T, b_star: [T; 4]) -> [T; 4] {
    [
        bias(b[0], alpha, b_star[0]),
        bias(b[1], alpha, b_star[1]),
        bias(b[2], alpha, b_star[2]),
        bias(b[3], alpha, b_star[3]),
    ]
}

/// Roots z₂ ≤ z₃ of c₁ + c₂ z + c₃ z² where c = B⁻¹(1, z_f, z_f²) for already biased moments
/// `b` (Algorithm 3, steps 2–3). LDLᵀ of the Hankel matrix exploiting its structure.
#[inline(always)]
pub fn msm4_roots<T: Real>(b: [T; 4], zf: T) -> (T, T) {
    let floor = pivot_floor::<T>();
    // B = L D Lᵀ with L = [[1,0,0],[b1,1,0],[b2,L32,1]], D = diag(1, D22, D33).
    // D22 > 4ε·b2 is guaranteed by the caller (single-Dirac branch).
    let d22 = b[1] - b[0] * b[0];
    let l32d22 = b[2] - b[0] * b[1];
    let l32 = l32d22 / d22;
    let mut d33 = (b[3] - b[1] * b[1]) - l32 * l32d22;
    let f33 = floor * (T::ONE + b[3].abs());
    if !above(d33, f33) {
        d33 = f33;
    }
    // Forward substitution L·y = (1, z_f, z_f²).
    let y1 = zf - b[0];
    let y2 = zf * zf - b[1] - l32 * y1;
    // D·u = y, then Lᵀ·c = u.
    let c3 = y2 / d33;
    let c2 = y1 / d22 - l32 * c3;
    let c1 = T::ONE - b[0] * c2 - b[1] * c3;
    quadratic_roots(c1, c2, c3)
}

/// Algorithm 3 for already biased moments `b` (= b'), unclamped.
#[inline(always)]
pub fn msm4_hamburger<T: Real>(b: [T; 4], zf: T) -> Msm4<T> {
    if !above(b[1] - b[0] * b[0], pivot_tol::<T>() * b[1]) {
        // Variance at round-off level: a single Dirac at b'₁ (Proposition 4), exact step.
        let g = if b[0] < zf { T::ONE } else { T::ZERO };
        return Msm4 {
            g,
            z2: b[0],
            z3: b[0],
        };
    }
    let (z2, z3) = msm4_roots(b, zf);
    let g = if zf <= z2 {
        T::ZERO
    } else if zf <= z3 {
        (zf * z3 - b[0] * (zf + z3) + b[1]) / ((z3 - z2) * (zf - z2))
    } else {
        T::ONE - (z2 * z3 - b[0] * (z2 + z3) + b[1]) / ((zf - z2) * (zf - z3))
    };
    Msm4 { g, z2, z3 }
}

/// The default b* = (½, ½, ½, ½): moments of Z* = ½(δ₀ + δ₁) (Section 4.2).
pub const B_STAR_STANDARD: [f64; 4] = [0.5; 4];
/// Bias for clamped depths, four moments (supplementary Section 4):
/// b* = ⅘·(½,½,½,½) + ⅕·(½,⅓,¼,⅕), used with α = 3·10⁻⁵.
pub const B_STAR_CLAMPED: [f64; 4] = [
    0.8 * 0.5 + 0.2 * 0.5,
    0.8 * 0.5 + 0.2 / 3.0,
    0.8 * 0.5 + 0.2 / 4.0,
    0.8 * 0.5 + 0.2 / 5.0,
];
/// α for 32-bit moments (Section 4.2).
pub const ALPHA_32BIT: f64 = 2e-6;
/// α for 16-bit moments (Section 4.2; supplementary Section 4).
pub const ALPHA_16BIT: f64 = 3e-5;

/// Hamburger 4MSM with bias (α, b*) and arithmetic precision.
#[derive(Clone, Debug)]
pub struct Hamburger4 {
    /// Bias weight α of b' = (1 − α)·b + α·b* (Section 4.2).
    pub alpha: f64,
    /// Bias target b* (Section 4.2).
    pub b_star: [f64; 4],
    /// Arithmetic precision of the solve.
    pub precision: Precision,
}

impl Hamburger4 {
    /// Hamburger 4MSM with the given bias and precision.
    pub fn new(alpha: f64, b_star: [f64; 4], precision: Precision) -> Hamburger4 {
        Hamburger4 {
            alpha,
            b_star,
            precision,
        }
    }

    fn run<T: Real>(&self, m: &[f64], zf: f64) -> Msm4<f64> {
        let b = [T::of(m[0]), T::of(m[1]), T::of(m[2]), T::of(m[3])];
        let s = self.b_star.map(T::of);
        let r = msm4_hamburger(biased4(b, T::of(self.alpha), s), T::of(zf));
        Msm4 {
            g: r.g.to_f64(),
            z2: r.z2.to_f64(),
            z3: r.z3.to_f64(),
        }
    }

    /// G and the support roots, unclamped (for stability analysis and tests).
    pub fn solve(&self, moments: &[f64], zf: f64) -> Msm4<f64> {
        match self.precision {
            Precision::F32 => self.run::<f32>(moments, zf),
            Precision::F64 => self.run::<f64>(moments, zf),
        }
    }
}

impl ClosedForm for Hamburger4 {
    /// G clamped to [0,1] (NaN stays NaN).
    fn shadow(&self, moments: &[f64], zf: f64) -> f64 {
        self.solve(moments, zf).g.clamp(0.0, 1.0)
    }
}

impl Technique for Hamburger4 {
    fn name(&self) -> String {
        "hamburger4".into()
    }
    fn moment_count(&self) -> usize {
        4
    }
    fn basis(&self, z: f64, out: &mut [f64]) {
        power_basis(z, out);
    }
    stateless_evaluator!();
    fn depth_domain(&self) -> DepthDomain {
        DepthDomain::Real
    }
}

/// out[j] = z^{j+1}.
pub fn power_basis(z: f64, out: &mut [f64]) {
    let mut p = 1.0;
    for o in out.iter_mut() {
        p *= z;
        *o = p;
    }
}
