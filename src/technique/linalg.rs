//! Small numeric helpers shared by the closed-form solvers, generic over the arithmetic
//! precision ([`Real`] is implemented for `f32` and `f64`, so the f32 paths really compute in
//! single precision): LDLᵀ (square-root-free Cholesky) solves and weight sums of a discrete distribution through a Newton interpolation polynomial
//! (supplementary document of Peters et al. 2016, Section 3). Polynomial roots are in
//! [`super::roots`].

use std::ops::{Add, AddAssign, Div, DivAssign, Mul, MulAssign, Neg, Sub, SubAssign};

/// The floating-point operations the solvers need; implemented for `f32` and `f64`.
pub trait Real:
    Copy
    + PartialOrd
    + std::fmt::Debug
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
    + AddAssign
    + SubAssign
    + MulAssign
    + DivAssign
{
    /// 0
    const ZERO: Self;
    /// 1
    const ONE: Self;
    /// Machine epsilon of the type.
    const EPS: Self;
    /// The nearest value of this type to `x`.
    fn of(x: f64) -> Self;
    /// The value as f64 (exact).
    fn to_f64(self) -> f64;
    /// √x
    fn sqrt(self) -> Self;
    /// |x|
    fn abs(self) -> Self;
    /// e^x
    fn exp(self) -> Self;
    /// cos(x)
    fn cos(self) -> Self;
    /// sin(x)
    fn sin(self) -> Self;
    /// acos(x)
    fn acos(self) -> Self;
    /// atan2(self, x): the angle of the point (x, self).
    fn atan2(self, x: Self) -> Self;
    /// True unless NaN or ±∞.
    fn is_finite(self) -> bool;
    /// True for NaN.
    fn is_nan(self) -> bool;
    /// The larger of the two (the other one when one is NaN).
    fn max(self, o: Self) -> Self;
    /// The smaller of the two (the other one when one is NaN).
    fn min(self, o: Self) -> Self;
}

macro_rules! impl_real {
    ($t:ty) => {
        impl Real for $t {
            const ZERO: Self = 0.0;
            const ONE: Self = 1.0;
            const EPS: Self = <$t>::EPSILON;
            #[inline(always)]
            fn of(x: f64) -> Self {
                x as $t
            }
            #[inline(always)]
            fn to_f64(self) -> f64 {
                self as f64
            }
            #[inline(always)]
            fn sqrt(self) -> Self {
                <$t>::sqrt(self)
            }
            #[inline(always)]
            fn abs(self) -> Self {
                <$t>::abs(self)
            }
            #[inline(always)]
            fn exp(self) -> Self {
                <$t>::exp(self)
            }
            #[inline(always)]
            fn cos(self) -> Self {
                <$t>::cos(self)
            }
            #[inline(always)]
            fn sin(self) -> Self {
                <$t>::sin(self)
            }
            #[inline(always)]
            fn acos(self) -> Self {
                <$t>::acos(self)
            }
            #[inline(always)]
            fn atan2(self, x: Self) -> Self {
                <$t>::atan2(self, x)
            }
            #[inline(always)]
            fn is_finite(self) -> bool {
                <$t>::is_finite(self)
            }
            #[inline(always)]
            fn is_nan(self) -> bool {
                <$t>::is_nan(self)
            }
            #[inline(always)]
            fn max(self, o: Self) -> Self {
                <$t>::max(self, o)
            }
            #[inline(always)]
            fn min(self, o: Self) -> Self {
                <$t>::min(self, o)
            }
        }
    };
}
impl_real!(f32);
impl_real!(f64);

/// Arithmetic precision of a closed-form solver.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Precision {
    /// Single precision throughout (inputs rounded to f32, all arithmetic in f32).
    F32,
    /// Double precision throughout.
    #[default]
    F64,
}

impl Precision {
    /// "f32" or "f64".
    pub fn name(self) -> &'static str {
        match self {
            Precision::F32 => "f32",
            Precision::F64 => "f64",
        }
    }
}

impl std::str::FromStr for Precision {
    type Err = anyhow::Error;
    fn from_str(s: &str) -> anyhow::Result<Precision> {
        match s {
            "f32" => Ok(Precision::F32),
            "f64" => Ok(Precision::F64),
            _ => anyhow::bail!("unknown precision '{s}' (expected 'f32' or 'f64')"),
        }
    }
}

/// `x > y`, false when either is NaN (so NaN pivots get floored too).
#[inline(always)]
pub fn above<T: Real>(x: T, y: T) -> bool {
    matches!(x.partial_cmp(&y), Some(std::cmp::Ordering::Greater))
}

/// Biased moments b' = (1 − α)·b + α·b* (Peters & Klein 2015, Section 4.2).
#[inline(always)]
pub fn bias<T: Real>(b: T, alpha: T, b_star: T) -> T {
    b + alpha * (b_star - b)
}

/// Relative pivot tolerance of [`ldlt_solve`]: a pivot D_j ≤ 4ε·A_jj is at the round-off
/// level of its own computation, i.e. numerically zero.
pub fn pivot_tol<T: Real>() -> T {
    T::of(4.0) * T::EPS
}

/// Solve A·x = rhs in place for a symmetric positive (semi-)definite n×n matrix `a`
/// (row-major) with an LDLᵀ decomposition A = L·D·Lᵀ (L unit lower triangular, D diagonal).
///
/// Returns the numerical rank r: if a pivot D_j with j < n − 1 is ≤ `tol`·A_jj the
/// factorisation stops and returns j (`rhs` is then meaningless). A negligible *last* pivot
/// is raised to `tol`·A_jj and the solve completes (returns n − 1): for a singular Hankel
/// matrix (Proposition 4 of Peters & Klein 2015) the solution is then dominated by the kernel
/// direction, whose polynomial vanishes on the support of the unique distribution.
/// `a` is overwritten with the factors.
pub fn ldlt_solve<T: Real>(a: &mut [T], n: usize, rhs: &mut [T], tol: T) -> usize {
    debug_assert!(a.len() >= n * n && rhs.len() >= n);
    let mut rank = n;
    // Factor: column j of L below the diagonal, D_j on the diagonal.
    for j in 0..n {
        let ajj = a[j * n + j];
        let mut d = ajj;
        for k in 0..j {
            let l = a[j * n + k];
            d -= l * l * a[k * n + k];
        }
        let thr = tol * ajj.abs();
        if !above(d, thr) {
            if j + 1 < n {
                return j;
            }
            rank = j;
            d = if thr > T::ZERO { thr } else { tol };
        }
        a[j * n + j] = d;
        for i in j + 1..n {
            let mut s = a[i * n + j];
            for k in 0..j {
                s -= a[i * n + k] * a[j * n + k] * a[k * n + k];
            }
            a[i * n + j] = s / d;
        }
    }
    // Forward substitution L·y = rhs.
    for i in 0..n {
        for k in 0..i {
            let l = a[i * n + k];
            let v = rhs[k];
            rhs[i] -= l * v;
        }
    }
    // D·u = y.
    for i in 0..n {
        rhs[i] /= a[i * n + i];
    }
    // Back substitution Lᵀ·x = u.
    for i in (0..n).rev() {
        for k in i + 1..n {
            let l = a[k * n + i];
            let v = rhs[k];
            rhs[i] -= l * v;
        }
    }
    rank
}

/// Σ_i f_i·w_i for the distribution Σ_i w_i·δ_{x_i} whose power moments are
/// `moments` = (1, b_1, …, b_{k−1}) (k = number of nodes), without solving the Vandermonde
/// system: with the interpolation polynomial p(x_i) = f_i, Σ f_i w_i = E[p(Z)] (Peters et al.
/// 2016, supplementary Section 3). p is built in Newton form with divided differences;
/// E[Π_{j<i}(Z − x_j)] is accumulated from the moments. Coincident nodes with equal values
/// contribute a zero divided difference.
pub fn weight_sum<T: Real>(nodes: &[T], f: &[T], moments: &[T]) -> T {
    let k = nodes.len();
    debug_assert!(f.len() == k && moments.len() >= k);
    // Divided differences, in place.
    let mut a = [T::ZERO; 16];
    let mut av;
    let a: &mut [T] = if k <= 16 {
        &mut a[..k]
    } else {
        av = vec![T::ZERO; k];
        &mut av[..]
    };
    a.copy_from_slice(f);
    for j in 1..k {
        for i in (j..k).rev() {
            let num = a[i] - a[i - 1];
            let den = nodes[i] - nodes[i - j];
            a[i] = if num == T::ZERO { T::ZERO } else { num / den };
        }
    }
    // Newton basis polynomial π_i(z) = Π_{j<i}(z − x_j) in monomial coefficients.
    let mut pi = [T::ZERO; 17];
    let mut piv;
    let pi: &mut [T] = if k < 17 {
        &mut pi[..k]
    } else {
        piv = vec![T::ZERO; k];
        &mut piv[..]
    };
    pi[0] = T::ONE;
    let mut sum = a[0] * moments[0];
    for i in 1..k {
        // π_i = π_{i−1}·(z − x_{i−1}); π_{i−1} has degree i−1.
        let x = nodes[i - 1];
        for d in (0..=i).rev() {
            let hi = if d >= 1 { pi[d - 1] } else { T::ZERO };
            let lo = if d < i { pi[d] } else { T::ZERO };
            if d < k {
                pi[d] = hi - x * lo;
            }
        }
        let mut e = T::ZERO;
        for d in 0..=i {
            e += pi[d] * moments[d];
        }
        sum += a[i] * e;
    }
    sum
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    #[test]
    fn ldlt_solves_random_spd() {
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        for n in 1..6 {
            for _ in 0..50 {
                let m: Vec<f64> = (0..n * n).map(|_| rng.gen_range(-1.0..1.0)).collect();
                let mut a = vec![0.0; n * n];
                for i in 0..n {
                    for j in 0..n {
                        a[i * n + j] = (0..n).map(|k| m[i * n + k] * m[j * n + k]).sum::<f64>()
                            + if i == j { 0.5 } else { 0.0 };
                    }
                }
                let x: Vec<f64> = (0..n).map(|_| rng.gen_range(-1.0..1.0)).collect();
                let mut rhs: Vec<f64> = (0..n)
                    .map(|i| (0..n).map(|j| a[i * n + j] * x[j]).sum())
                    .collect();
                let mut f = a.clone();
                ldlt_solve(&mut f, n, &mut rhs, 1e-300);
                assert!(n > 0);
                for i in 0..n {
                    assert!((rhs[i] - x[i]).abs() < 1e-9, "n={n}: {rhs:?} vs {x:?}");
                }
            }
        }
    }

    #[test]
    fn weight_sum_matches_vandermonde_solution() {
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        for k in 1..6 {
            for _ in 0..200 {
                let x: Vec<f64> = (0..k).map(|_| rng.gen_range(-1.0..2.0)).collect();
                let w: Vec<f64> = (0..k).map(|_| rng.gen_range(0.0..1.0)).collect();
                let f: Vec<f64> = (0..k).map(|_| rng.gen_range(-1.0..1.0)).collect();
                let moments: Vec<f64> = (0..k)
                    .map(|d| x.iter().zip(&w).map(|(xi, wi)| wi * xi.powi(d)).sum())
                    .collect();
                let expect: f64 = f.iter().zip(&w).map(|(a, b)| a * b).sum();
                let got = weight_sum(&x, &f, &moments);
                let sep = x
                    .iter()
                    .enumerate()
                    .flat_map(|(i, a)| x[i + 1..].iter().map(move |b| (a - b).abs()))
                    .fold(f64::INFINITY, f64::min);
                if sep < 0.05 {
                    continue;
                }
                assert!((got - expect).abs() < 1e-8, "{got} vs {expect}");
            }
        }
    }
}
