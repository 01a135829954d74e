//! Six moment shadow mapping (Hamburger, b(z) = (z, …, z⁶); Peters et al. 2016, supplementary
//! Section 3): 4×4 LDLᵀ of the Hankel matrix B of (1, b'₁, …, b'₆), c = B⁻¹(1, z_f, z_f², z_f³),
//! the three real roots of c₁ + c₂ z + c₃ z² + c₄ z³ (trigonometric cubic formula), and
//! G = Σ_{z_i < z_f} w_i via the Newton interpolation polynomial (f₁ = 0 at z₁ = z_f,
//! f_i = [z_i < z_f]): G = d₁ + Σ_{i=1}^{3} d_{i+1} b'_i.
//! Biases (supplementary Section 4): standard b* = (½,…,½); clamped depths α = 4·10⁻³ with
//! b* = ½·(½,…,½) + ½·(½,⅓,¼,⅕,⅙,⅐).

use super::hamburger::msm_hamburger;
use super::hamburger4::power_basis;
use super::linalg::{bias, ldlt_solve, pivot_tol, weight_sum, Precision, Real};
use super::roots::cubic_roots;
use super::{ClosedForm, DepthDomain, Technique};

/// b* = (½, …, ½): Z* = ½(δ₀ + δ₁).
pub const B_STAR_STANDARD: [f64; 6] = [0.5; 6];
/// b* for clamped depths with six moments (supplementary Section 4).
pub const B_STAR_CLAMPED: [f64; 6] = [
    0.5 * 0.5 + 0.5 * 0.5,
    0.5 * 0.5 + 0.5 / 3.0,
    0.5 * 0.5 + 0.5 / 4.0,
    0.5 * 0.5 + 0.5 / 5.0,
    0.5 * 0.5 + 0.5 / 6.0,
    0.5 * 0.5 + 0.5 / 7.0,
];
/// α for clamped depths with six moments (supplementary Section 4).
pub const ALPHA_CLAMPED: f64 = 4e-3;

/// The registry's default α for six moments with the clamped b* at 32-bit float storage: the
/// smallest α at which 6MSM meets `tune`'s noise bound (the shadow more than 1/255 from exact
/// moments on at most 0.1 % of fragments, in the modelled GPU pipeline) on every default scene
/// and on all of them together — the largest `hamburger6 f32` α floor of the committed
/// `reports/default/tune/tune.json`, rounded up (a test keeps it so). The supplementary's
/// 4·10⁻³ ([`ALPHA_CLAMPED`]) is below it.
pub const ALPHA_NOISE_BOUND_F32: f64 = 6e-3;

/// As [`ALPHA_NOISE_BOUND_F32`] for 16-bit storage with θ₆ (`quant_bits` = 16).
pub const ALPHA_NOISE_BOUND_16BIT: f64 = 2.2e-2;

/// 6MSM for already biased moments b', unclamped G and the roots.
#[inline(always)]
pub fn msm6<T: Real>(b: [T; 6], zf: T) -> (T, [T; 3]) {
    let mo = [T::ONE, b[0], b[1], b[2], b[3], b[4], b[5]];
    let mut a = [T::ZERO; 16];
    for j in 0..4 {
        for k in 0..4 {
            a[j * 4 + k] = mo[j + k];
        }
    }
    let mut c = [T::ONE, zf, zf * zf, zf * zf * zf];
    let rank = ldlt_solve(&mut a, 4, &mut c, pivot_tol::<T>());
    if rank < 3 {
        // At most two Diracs (Proposition 4): exact reconstruction from fewer moments.
        let (g, nodes) = msm_hamburger(&b[..2 * rank], zf);
        let mut r = [T::ZERO; 3];
        for (i, z) in nodes.iter().skip(1).enumerate().take(3) {
            r[i] = *z;
        }
        return (g, r);
    }
    let r = cubic_roots(c[0], c[1], c[2], c[3]);
    let nodes = [zf, r[0], r[1], r[2]];
    let ind = |z: T| if z < zf { T::ONE } else { T::ZERO };
    let f = [T::ZERO, ind(r[0]), ind(r[1]), ind(r[2])];
    (weight_sum(&nodes, &f, &mo[..4]), r)
}

/// 6MSM with bias (α, b*) and arithmetic precision.
#[derive(Clone, Debug)]
pub struct Hamburger6 {
    /// Bias weight α of b' = (1 − α)·b + α·b* (Section 4.2).
    pub alpha: f64,
    /// Bias target b*.
    pub b_star: [f64; 6],
    /// Arithmetic precision of the solve.
    pub precision: Precision,
}

impl Hamburger6 {
    /// Hamburger 6MSM with the given bias and precision.
    pub fn new(alpha: f64, b_star: [f64; 6], precision: Precision) -> Hamburger6 {
        Hamburger6 {
            alpha,
            b_star,
            precision,
        }
    }
    fn run<T: Real>(&self, m: &[f64], zf: f64) -> (f64, [f64; 3]) {
        let a = T::of(self.alpha);
        let mut b = [T::ZERO; 6];
        for i in 0..6 {
            b[i] = bias(T::of(m[i]), a, T::of(self.b_star[i]));
        }
        let (g, r) = msm6(b, T::of(zf));
        (g.to_f64(), r.map(|x| x.to_f64()))
    }
    /// G (unclamped) and the three roots.
    pub fn solve(&self, moments: &[f64], zf: f64) -> (f64, [f64; 3]) {
        match self.precision {
            Precision::F32 => self.run::<f32>(moments, zf),
            Precision::F64 => self.run::<f64>(moments, zf),
        }
    }
}

impl ClosedForm for Hamburger6 {
    fn shadow(&self, moments: &[f64], zf: f64) -> f64 {
        self.solve(moments, zf).0.clamp(0.0, 1.0)
    }
}

impl Technique for Hamburger6 {
    fn name(&self) -> String {
        "hamburger6".into()
    }
    fn moment_count(&self) -> usize {
        6
    }
    fn basis(&self, z: f64, out: &mut [f64]) {
        power_basis(z, out);
    }
    stateless_evaluator!();
    fn depth_domain(&self) -> DepthDomain {
        DepthDomain::Real
    }
}
