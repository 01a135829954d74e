//! Hausdorff four moment shadow mapping (Peters & Klein 2015, Section 4 and supplementary
//! material): Problem 1 for I = [0,1] and b(z) = (z, z², z³, z⁴).
//!
//! First the three-Dirac solution of Hamburger 4MSM (support z_f, z₂, z₃). If a root leaves
//! [0,1] (z₂ < 0 or z₃ > 1) the minimiser is instead supported on {0, z_f, z_free, 1}, where
//! z_free makes E[Z(Z−1)(Z−z_f)(Z−z_free)] = 0:
//! z_free = (b₄ − (1+z_f) b₃ + z_f b₂) / (b₃ − (1+z_f) b₂ + z_f b₁),
//! and G = w₀ + [z_free < z_f]·w_free, evaluated via the Newton interpolation polynomial
//! (weights from the moments 1, b₁, b₂, b₃). z_f ≤ 0 gives 0, z_f > 1 gives 1.

use super::hamburger4::{biased4, msm4_hamburger, power_basis};
use super::linalg::{weight_sum, Precision, Real};
use super::{ClosedForm, Technique};

/// Hausdorff 4MSM for already biased moments `b`, unclamped.
pub fn msm4_hausdorff<T: Real>(b: [T; 4], zf: T) -> T {
    if zf <= T::ZERO {
        return T::ZERO;
    }
    if zf > T::ONE {
        return T::ONE;
    }
    let r = msm4_hamburger(b, zf);
    if r.z2 >= T::ZERO && r.z3 <= T::ONE {
        return r.g;
    }
    let num = b[3] - (T::ONE + zf) * b[2] + zf * b[1];
    let den = b[2] - (T::ONE + zf) * b[1] + zf * b[0];
    let zfree = num / den;
    let nodes = [T::ZERO, zf, zfree, T::ONE];
    let f = [
        T::ONE,
        T::ZERO,
        if zfree < zf { T::ONE } else { T::ZERO },
        T::ZERO,
    ];
    weight_sum(&nodes, &f, &[T::ONE, b[0], b[1], b[2]])
}

/// Hausdorff 4MSM with bias (α, b*) and arithmetic precision.
#[derive(Clone, Debug)]
pub struct Hausdorff4 {
    /// Bias weight α of b' = (1 − α)·b + α·b* (Section 4.2).
    pub alpha: f64,
    /// Bias target b*.
    pub b_star: [f64; 4],
    /// Arithmetic precision of the solve.
    pub precision: Precision,
}

impl Hausdorff4 {
    /// Hausdorff 4MSM with the given bias and precision.
    pub fn new(alpha: f64, b_star: [f64; 4], precision: Precision) -> Hausdorff4 {
        Hausdorff4 {
            alpha,
            b_star,
            precision,
        }
    }
    fn run<T: Real>(&self, m: &[f64], zf: f64) -> f64 {
        let b = [T::of(m[0]), T::of(m[1]), T::of(m[2]), T::of(m[3])];
        let s = self.b_star.map(T::of);
        msm4_hausdorff(biased4(b, T::of(self.alpha), s), T::of(zf)).to_f64()
    }
    /// G unclamped.
    pub fn raw(&self, moments: &[f64], zf: f64) -> f64 {
        match self.precision {
            Precision::F32 => self.run::<f32>(moments, zf),
            Precision::F64 => self.run::<f64>(moments, zf),
        }
    }
}

impl ClosedForm for Hausdorff4 {
    fn shadow(&self, moments: &[f64], zf: f64) -> f64 {
        self.raw(moments, zf).clamp(0.0, 1.0)
    }
}

impl Technique for Hausdorff4 {
    fn name(&self) -> String {
        "hausdorff4".into()
    }
    fn moment_count(&self) -> usize {
        4
    }
    fn basis(&self, z: f64, out: &mut [f64]) {
        power_basis(z, out);
    }
    stateless_evaluator!();
}
