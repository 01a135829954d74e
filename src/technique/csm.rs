//! Convolution shadow maps (Annen et al. 2007; notes 004_…) with M Fourier terms.
//! Basis (m = 2M): b(z) = (cos(c₁ z), sin(c₁ z), …, cos(c_M z), sin(c_M z)), c_k = (2k − 1)π.
//! The step 1[z < z_f] (a square wave of period 2 in z_f − z) is expanded as
//! s(z) = ½ + 2 Σ_k sin(c_k (z_f − z)) / c_k, so by linearity
//! E[s(Z)] = ½ + 2 Σ_k (sin(c_k z_f)·E[cos(c_k Z)] − cos(c_k z_f)·E[sin(c_k Z)]) / c_k.
//! Biasing against self-shadowing: G = clamp(2·E[s(Z)] − 1, 0, 1), which maps the value ½ of
//! the truncated series at the discontinuity (a surface at z_f itself) to 0. Not a sharp bound
//! and, because of Gibbs ringing, not a guaranteed lower bound.

use super::linalg::{bias, Precision, Real};
use super::{ClosedForm, Technique};

/// Default number of Fourier terms M (m = 2M = 8 stored values).
pub const DEFAULT_TERMS: usize = 4;

/// Frequency c_k = (2k − 1)π for k = 1, 2, ….
pub fn frequency(k: usize) -> f64 {
    (2 * k - 1) as f64 * std::f64::consts::PI
}

/// E[s(Z)] (the truncated Fourier step) from the (biased) moments; unclamped.
#[inline]
pub fn csm_expectation<T: Real>(b: &[T], zf: T) -> T {
    let mut e = T::of(0.5);
    for k in 0..b.len() / 2 {
        let c = T::of(frequency(k + 1));
        let (s, co) = ((c * zf).sin(), (c * zf).cos());
        e += T::of(2.0) * (s * b[2 * k] - co * b[2 * k + 1]) / c;
    }
    e
}

/// CSM with M terms, bias (α, b*) and arithmetic precision.
#[derive(Clone, Debug)]
pub struct Csm {
    /// Length 2M.
    pub b_star: Vec<f64>,
    /// Bias weight α of b' = (1 − α)·b + α·b*.
    pub alpha: f64,
    /// Arithmetic precision of the solve.
    pub precision: Precision,
}

impl Csm {
    fn run<T: Real>(&self, m: &[f64], zf: f64) -> f64 {
        let a = T::of(self.alpha);
        let mut buf = [T::ZERO; 64];
        let n = m.len().min(64);
        for i in 0..n {
            buf[i] = bias(T::of(m[i]), a, T::of(self.b_star[i]));
        }
        let e = csm_expectation(&buf[..n], T::of(zf));
        (T::of(2.0) * e - T::ONE).to_f64()
    }
    /// Number of Fourier terms M.
    pub fn terms(&self) -> usize {
        self.b_star.len() / 2
    }
}

impl ClosedForm for Csm {
    fn shadow(&self, moments: &[f64], zf: f64) -> f64 {
        let g = match self.precision {
            Precision::F32 => self.run::<f32>(moments, zf),
            Precision::F64 => self.run::<f64>(moments, zf),
        };
        g.clamp(0.0, 1.0)
    }
}

impl Technique for Csm {
    fn name(&self) -> String {
        "csm".into()
    }
    fn moment_count(&self) -> usize {
        self.b_star.len()
    }
    fn basis(&self, z: f64, out: &mut [f64]) {
        for k in 0..self.terms() {
            let c = frequency(k + 1);
            out[2 * k] = (c * z).cos();
            out[2 * k + 1] = (c * z).sin();
        }
    }
    stateless_evaluator!();
}
