//! Exponential variance shadow maps (Lauritzen & McCool 2008; notes 004_…): VSM applied to the
//! two increasing warps w₊(z) = e^{c₊ z} and w₋(z) = −e^{−c₋ z}; each gives a valid lower
//! bound of P(Z < z_f) = P(w(Z) < w(z_f)), so G = max(G₊, G₋) (the darker result). Not sharp.
//! Basis order: b(z) = (e^{c₊ z}, e^{2 c₊ z}, −e^{−c₋ z}, e^{−2 c₋ z}).
//! Minimum variance in warped space: σ²_min · (w'(z_f))² (w' = c₊ e^{c₊ z_f} resp.
//! c₋ e^{−c₋ z_f}), i.e. σ²_min is a depth-space variance.

use super::linalg::{bias, Precision, Real};
use super::vsm::vsm;
use super::{ClosedForm, DepthDomain, Technique};

/// Default positive exponent c₊.
pub const DEFAULT_C_POS: f64 = 40.0;
/// Default negative exponent c₋.
pub const DEFAULT_C_NEG: f64 = 5.0;

/// EVSM for (already biased) moments, in [0,1].
#[inline(always)]
pub fn evsm<T: Real>(b: [T; 4], zf: T, cp: T, cn: T, min_variance: T) -> T {
    let wp = (cp * zf).exp();
    let wn = -(-cn * zf).exp();
    let dp = cp * wp;
    let dn = cn * wn;
    let gp = vsm(b[0], b[1], wp, min_variance * dp * dp);
    let gn = vsm(b[2], b[3], wn, min_variance * dn * dn);
    gp.max(gn)
}

/// EVSM with exponents, bias (α, b*), minimum variance and arithmetic precision.
#[derive(Clone, Debug)]
pub struct Evsm {
    /// Positive exponent c₊ of the warp w₊(z) = e^{c₊ z}.
    pub c_pos: f64,
    /// Negative exponent c₋ of the warp w₋(z) = −e^{−c₋ z}.
    pub c_neg: f64,
    /// Bias weight α of b' = (1 − α)·b + α·b*.
    pub alpha: f64,
    /// Bias target b* (in the basis order of the module doc).
    pub b_star: [f64; 4],
    /// Depth-space minimum variance σ²_min (scaled by w'(z_f)² in each warp).
    pub min_variance: f64,
    /// Arithmetic precision of the solve.
    pub precision: Precision,
}

impl Evsm {
    fn run<T: Real>(&self, m: &[f64], zf: f64) -> f64 {
        let a = T::of(self.alpha);
        let mut b = [T::ZERO; 4];
        for i in 0..4 {
            b[i] = bias(T::of(m[i]), a, T::of(self.b_star[i]));
        }
        evsm(
            b,
            T::of(zf),
            T::of(self.c_pos),
            T::of(self.c_neg),
            T::of(self.min_variance),
        )
        .to_f64()
    }
}

impl ClosedForm for Evsm {
    fn shadow(&self, moments: &[f64], zf: f64) -> f64 {
        let g = match self.precision {
            Precision::F32 => self.run::<f32>(moments, zf),
            Precision::F64 => self.run::<f64>(moments, zf),
        };
        g.clamp(0.0, 1.0)
    }
}

impl Technique for Evsm {
    fn name(&self) -> String {
        "evsm".into()
    }
    fn moment_count(&self) -> usize {
        4
    }
    fn basis(&self, z: f64, out: &mut [f64]) {
        let p = (self.c_pos * z).exp();
        let n = (-self.c_neg * z).exp();
        out[0] = p;
        out[1] = p * p;
        out[2] = -n;
        out[3] = n * n;
    }
    stateless_evaluator!();
    fn depth_domain(&self) -> DepthDomain {
        DepthDomain::Real
    }
}
