//! Variance shadow maps (Donnelly & Lauritzen 2006): b(z) = (z, z²) and the one-tailed
//! Chebyshev (Cantelli) inequality, the sharp lower bound of Problem 1 for I = R and m = 2
//! (Peters & Klein 2015, Section 3; notes 004_…):
//! μ = b₁, σ² = max(b₂ − b₁², σ²_min), G = (z_f − μ)² / (σ² + (z_f − μ)²) if z_f > μ, else 0.

use super::linalg::{bias, Precision, Real};
use super::{ClosedForm, DepthDomain, Technique};

/// Cantelli's lower bound for mean `mu`, variance `var` (already floored) at depth `zf`.
#[inline(always)]
pub fn cantelli<T: Real>(mu: T, var: T, zf: T) -> T {
    let t = zf - mu;
    if t > T::ZERO {
        t * t / (var + t * t)
    } else {
        T::ZERO
    }
}

/// VSM for moments (b₁, b₂), unclamped (the result is in [0,1] by construction).
#[inline(always)]
pub fn vsm<T: Real>(b1: T, b2: T, zf: T, min_variance: T) -> T {
    let var = (b2 - b1 * b1).max(min_variance);
    cantelli(b1, var, zf)
}

/// VSM with bias (α, b*), minimum variance and arithmetic precision.
#[derive(Clone, Debug)]
pub struct Vsm {
    /// Bias weight α of b' = (1 − α)·b + α·b*.
    pub alpha: f64,
    /// Bias target b* = (b*₁, b*₂).
    pub b_star: [f64; 2],
    /// Lower limit σ²_min on the variance b₂ − b₁².
    pub min_variance: f64,
    /// Arithmetic precision of the solve.
    pub precision: Precision,
}

impl Vsm {
    fn run<T: Real>(&self, m: &[f64], zf: f64) -> f64 {
        let a = T::of(self.alpha);
        let b1 = bias(T::of(m[0]), a, T::of(self.b_star[0]));
        let b2 = bias(T::of(m[1]), a, T::of(self.b_star[1]));
        vsm(b1, b2, T::of(zf), T::of(self.min_variance)).to_f64()
    }
}

impl ClosedForm for Vsm {
    fn shadow(&self, moments: &[f64], zf: f64) -> f64 {
        let g = match self.precision {
            Precision::F32 => self.run::<f32>(moments, zf),
            Precision::F64 => self.run::<f64>(moments, zf),
        };
        g.clamp(0.0, 1.0)
    }
}

impl Technique for Vsm {
    fn name(&self) -> String {
        "vsm".into()
    }
    fn moment_count(&self) -> usize {
        2
    }
    fn basis(&self, z: f64, out: &mut [f64]) {
        out[0] = z;
        out[1] = z * z;
    }
    stateless_evaluator!();
    fn depth_domain(&self) -> DepthDomain {
        DepthDomain::Real
    }
}
