//! Exponential shadow maps (Salvi 2008; Annen et al. 2008): b(z) = e^{c·z} and Markov's
//! inequality, G = max(0, 1 − b·e^{−c·z_f}) (notes 004_…). This is the sharp lower bound of
//! Problem 1 for I = R (the extremal distribution puts mass b·e^{−c z_f} at z_f and the rest
//! at z → −∞), but not for a bounded I. Default c = 80 (e^{80} ≈ 5.5·10³⁴ still fits f32).

use super::linalg::{bias, Precision, Real};
use super::{ClosedForm, DepthDomain, Technique};

/// Markov's bound for b = E[e^{cZ}], unclamped below 1 (≤ 1 always; may be negative).
#[inline(always)]
pub fn esm<T: Real>(b: T, zf: T, c: T) -> T {
    T::ONE - b * (-c * zf).exp()
}

/// ESM with exponent c, bias (α, b*) and arithmetic precision.
#[derive(Clone, Debug)]
pub struct Esm {
    /// Exponent c of the basis b(z) = e^{c·z}.
    pub c: f64,
    /// Bias weight α of b' = (1 − α)·b + α·b*.
    pub alpha: f64,
    /// Bias target b*.
    pub b_star: f64,
    /// Arithmetic precision of the solve.
    pub precision: Precision,
}

/// Default exponent c of ESM.
pub const DEFAULT_C: f64 = 80.0;

impl Esm {
    fn run<T: Real>(&self, m: &[f64], zf: f64) -> f64 {
        let b = bias(T::of(m[0]), T::of(self.alpha), T::of(self.b_star));
        esm(b, T::of(zf), T::of(self.c)).to_f64()
    }
}

impl ClosedForm for Esm {
    fn shadow(&self, moments: &[f64], zf: f64) -> f64 {
        let g = match self.precision {
            Precision::F32 => self.run::<f32>(moments, zf),
            Precision::F64 => self.run::<f64>(moments, zf),
        };
        g.clamp(0.0, 1.0)
    }
}

impl Technique for Esm {
    fn name(&self) -> String {
        "esm".into()
    }
    fn moment_count(&self) -> usize {
        1
    }
    fn basis(&self, z: f64, out: &mut [f64]) {
        out[0] = (self.c * z).exp();
    }
    stateless_evaluator!();
    fn depth_domain(&self) -> DepthDomain {
        DepthDomain::Real
    }
}
