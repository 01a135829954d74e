//! Hamburger moment shadow mapping for any even number m of power moments (Peters & Klein
//! 2015, Algorithm 2; solves Problem 1 for I = R and b(z) = (z, z², …, z^m)).
//!
//! n = m/2 + 1; B = (b'_{j+k})_{j,k=0}^{n−1} with b'₀ = 1 (b' = (1 − α) b + α b*);
//! c = B⁻¹(1, z_f, …, z_f^{n−1}) by LDLᵀ; z₂…z_n = roots of Σ_k c_k z^k (Laguerre with
//! deflation: the polynomial is real-rooted for positive-definite B); the weights w of the
//! Diracs at z₁ = z_f, z₂, …, z_n solve the Vandermonde system with right-hand side
//! (1, b'₁, …, b'_{n−1}); G = Σ_{z_i < z_f} w_i, computed as E[p(Z)] for the Newton
//! interpolation polynomial p with p(z_i) = [z_i < z_f]. m = 2 is VSM (Cantelli's bound).

use super::hamburger4::power_basis;
use super::linalg::{bias, ldlt_solve, pivot_tol, weight_sum, Precision, Real};
use super::roots::real_roots;
use super::{ClosedForm, DepthDomain, Technique};

/// Algorithm 2 for already biased moments b' (length m, even), unclamped G and the support
/// (z_f first, then the roots ascending).
///
/// If the Hankel matrix is numerically singular already at size r + 1 < n (Z has r < m/2
/// Diracs, Proposition 4), the problem is solved with the first 2r moments, whose Hankel
/// matrix has a one-dimensional kernel: its polynomial has exactly the r support points as
/// roots, so the reconstruction is exact.
pub fn msm_hamburger<T: Real>(b: &[T], zf: T) -> (T, Vec<T>) {
    let n = b.len() / 2 + 1;
    let mut r = n;
    loop {
        match solve_size(b, zf, r) {
            Ok(out) => return out,
            Err(rank) => r = rank + 1,
        }
    }
}

/// Algorithm 2 with the leading r×r Hankel block (moments b'_1 … b'_{2r−2}); Err(rank) if a
/// pivot before the last one is negligible.
fn solve_size<T: Real>(b: &[T], zf: T, n: usize) -> Result<(T, Vec<T>), usize> {
    let moment = |k: usize| if k == 0 { T::ONE } else { b[k - 1] };
    let mut a = vec![T::ZERO; n * n];
    for j in 0..n {
        for k in 0..n {
            a[j * n + k] = moment(j + k);
        }
    }
    let mut c = vec![T::ZERO; n];
    let mut p = T::ONE;
    for ck in c.iter_mut() {
        *ck = p;
        p *= zf;
    }
    let rank = ldlt_solve(&mut a, n, &mut c, pivot_tol::<T>());
    if rank + 1 < n {
        return Err(rank);
    }
    if n == 1 {
        // Not reachable for valid b (the 1×1 block is 1); keep G defined.
        return Ok((T::ZERO, vec![zf]));
    }
    let roots = real_roots(&c);
    let mut nodes = Vec::with_capacity(n);
    nodes.push(zf);
    nodes.extend_from_slice(&roots);
    let f: Vec<T> = nodes
        .iter()
        .map(|&z| if z < zf { T::ONE } else { T::ZERO })
        .collect();
    let moments: Vec<T> = (0..nodes.len()).map(moment).collect();
    Ok((weight_sum(&nodes, &f, &moments), nodes))
}

/// Hamburger MSM with m (even) moments, bias (α, b*) and arithmetic precision.
#[derive(Clone, Debug)]
pub struct Hamburger {
    /// Bias weight α of b' = (1 − α)·b + α·b* (Section 4.2).
    pub alpha: f64,
    /// Length m.
    pub b_star: Vec<f64>,
    /// Arithmetic precision of the solve.
    pub precision: Precision,
}

impl Hamburger {
    /// `b_star.len()` is the (even, ≥ 2) moment count m.
    pub fn new(alpha: f64, b_star: Vec<f64>, precision: Precision) -> Hamburger {
        assert!(
            b_star.len() >= 2 && b_star.len().is_multiple_of(2),
            "Hamburger MSM needs an even number of moments"
        );
        Hamburger {
            alpha,
            b_star,
            precision,
        }
    }
    fn run<T: Real>(&self, m: &[f64], zf: f64) -> (f64, Vec<f64>) {
        let a = T::of(self.alpha);
        let b: Vec<T> = m
            .iter()
            .zip(&self.b_star)
            .map(|(&x, &s)| bias(T::of(x), a, T::of(s)))
            .collect();
        let (g, nodes) = msm_hamburger(&b, T::of(zf));
        (g.to_f64(), nodes.into_iter().map(|z| z.to_f64()).collect())
    }
    /// G (unclamped) and the support (z_f, then the roots ascending).
    pub fn solve(&self, moments: &[f64], zf: f64) -> (f64, Vec<f64>) {
        match self.precision {
            Precision::F32 => self.run::<f32>(moments, zf),
            Precision::F64 => self.run::<f64>(moments, zf),
        }
    }
}

impl ClosedForm for Hamburger {
    fn shadow(&self, moments: &[f64], zf: f64) -> f64 {
        self.solve(moments, zf).0.clamp(0.0, 1.0)
    }
}

impl Technique for Hamburger {
    fn name(&self) -> String {
        // The registry name that builds this solver (`hamburger4`/`hamburger6` are the
        // dedicated closed forms).
        match self.b_star.len() {
            m @ (4 | 6) => format!("hamburger{m}-general"),
            m => format!("hamburger{m}"),
        }
    }
    fn moment_count(&self) -> usize {
        self.b_star.len()
    }
    fn basis(&self, z: f64, out: &mut [f64]) {
        power_basis(z, out);
    }
    stateless_evaluator!();
    fn depth_domain(&self) -> DepthDomain {
        DepthDomain::Real
    }
}
