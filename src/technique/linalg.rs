//! Small numeric helpers shared by the closed-form solvers, generic over the arithmetic
//! precision ([`Real`] is implemented for `f32` and `f64`, so the f32 paths really compute in
//! single precision): LDLᵀ (square-root-free Cholesky) solves, real polynomial roots (quadratic,
//! trigonometric cubic, Laguerre with deflation for real-rooted polynomials of any degree) and
//! weight sums of a discrete distribution through a Newton interpolation polynomial
//! (supplementary document of Peters et al. 2016, Section 3).

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
    const ZERO: Self;
    const ONE: Self;
    /// Machine epsilon of the type.
    const EPS: Self;
    fn of(x: f64) -> Self;
    fn to_f64(self) -> f64;
    fn sqrt(self) -> Self;
    fn abs(self) -> Self;
    fn exp(self) -> Self;
    fn cos(self) -> Self;
    fn sin(self) -> Self;
    fn acos(self) -> Self;
    fn atan2(self, x: Self) -> Self;
    fn is_finite(self) -> bool;
    fn is_nan(self) -> bool;
    fn max(self, o: Self) -> Self;
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

/// Both roots of c0 + c1·z + c2·z² (c2 ≠ 0, discriminant ≥ 0), ascending. A negative
/// discriminant (only from rounding for the real-rooted polynomials used here) is clamped to 0.
/// Uses the cancellation-free form q = −(c1 + sign(c1)·√D)/2, roots q/c2 and c0/q.
#[inline(always)]
pub fn quadratic_roots<T: Real>(c0: T, c1: T, c2: T) -> (T, T) {
    let disc = (c1 * c1 - T::of(4.0) * c0 * c2).max(T::ZERO);
    let s = disc.sqrt();
    let q = if c1 >= T::ZERO {
        -(c1 + s) * T::of(0.5)
    } else {
        (s - c1) * T::of(0.5)
    };
    let (r1, r2) = if q != T::ZERO {
        (q / c2, c0 / q)
    } else {
        // c1 = 0 and c0·c2 = 0 (double root at 0) or c1 = 0 with disc = 0.
        (T::ZERO, T::ZERO)
    };
    if r1 <= r2 {
        (r1, r2)
    } else {
        (r2, r1)
    }
}

/// The three real roots of c0 + c1·z + c2·z² + c3·z³ (c3 ≠ 0), ascending, by the
/// trigonometric method (valid when all roots are real, as for the 6MSM polynomial with
/// positive-definite Hankel matrix); one Newton polish step per root.
pub fn cubic_roots<T: Real>(c0: T, c1: T, c2: T, c3: T) -> [T; 3] {
    let a = c2 / c3;
    let b = c1 / c3;
    let c = c0 / c3;
    let third = T::of(1.0 / 3.0);
    // Depressed cubic t³ + p·t + q with z = t − a/3.
    let p = b - a * a * third;
    let q = T::of(2.0 / 27.0) * a * a * a - a * b * third + c;
    let shift = a * third;
    let mut r = if p < T::ZERO {
        let m = T::of(2.0) * (-p * third).sqrt();
        // cos(3φ) = 3q / (p·m)
        let arg = (T::of(3.0) * q / (p * m)).max(-T::ONE).min(T::ONE);
        let phi = arg.acos() * third;
        // cos(φ ∓ 2π/3) = −½ cos φ ± (√3/2) sin φ; φ ∈ [0, π/3] so sin φ ≥ 0.
        let (cp, sp) = (phi.cos(), phi.sin());
        let h = T::of(0.5) * cp;
        let s3 = T::of(0.75f64.sqrt()) * sp;
        [m * cp - shift, m * (s3 - h) - shift, m * (-h - s3) - shift]
    } else {
        // Only one real root (or a triple root): not expected for valid input; return it thrice.
        let d = (q * q * T::of(0.25) + p * p * p * T::of(1.0 / 27.0)).max(T::ZERO);
        let sd = d.sqrt();
        let u = cbrt(-q * T::of(0.5) + sd);
        let v = cbrt(-q * T::of(0.5) - sd);
        let t = u + v - shift;
        [t, t, t]
    };
    for z in r.iter_mut() {
        // One Newton step on the monic cubic.
        let f = ((*z + a) * *z + b) * *z + c;
        let df = (T::of(3.0) * *z + T::of(2.0) * a) * *z + b;
        if df != T::ZERO {
            let nz = *z - f / df;
            if nz.is_finite() {
                *z = nz;
            }
        }
    }
    sort3(&mut r);
    r
}

fn cbrt<T: Real>(x: T) -> T {
    T::of(x.to_f64().cbrt())
}

#[inline(always)]
fn sort3<T: Real>(r: &mut [T; 3]) {
    if r[0] > r[1] {
        r.swap(0, 1);
    }
    if r[1] > r[2] {
        r.swap(1, 2);
    }
    if r[0] > r[1] {
        r.swap(0, 1);
    }
}

/// Evaluate p, p', p'' of Σ c_k z^k (coefficients ascending) by Horner.
fn horner2<T: Real>(c: &[T], x: T) -> (T, T, T) {
    let mut p = T::ZERO;
    let mut d1 = T::ZERO;
    let mut d2 = T::ZERO;
    for &ck in c.iter().rev() {
        d2 = d2 * x + d1;
        d1 = d1 * x + p;
        p = p * x + ck;
    }
    (p, d1, T::of(2.0) * d2)
}

/// All roots of the real-rooted polynomial Σ_k c_k z^k (coefficients ascending, leading
/// coefficient non-zero) by Laguerre's method with deflation, each root polished with Newton
/// steps on the undeflated polynomial; ascending. For polynomials with only real roots
/// Laguerre's iteration converges monotonically from any real start, so starting below the
/// Cauchy bound finds the smallest root first. Complex square roots (only from rounding)
/// are clamped to 0.
pub fn real_roots<T: Real>(c: &[T]) -> Vec<T> {
    let mut deg = c.len().saturating_sub(1);
    while deg > 0 && c[deg] == T::ZERO {
        deg -= 1;
    }
    let mut roots = Vec::with_capacity(deg);
    if deg == 0 {
        return roots;
    }
    let mut p: Vec<T> = c[..=deg].to_vec();
    while p.len() > 1 {
        let n = p.len() - 1;
        let lead = p[n];
        // Cauchy bound: all roots have |z| ≤ 1 + max |c_k / c_n|.
        let mut bound = T::ZERO;
        for &ck in &p[..n] {
            bound = bound.max((ck / lead).abs());
        }
        let mut x = -(T::ONE + bound);
        if n == 1 {
            x = -p[0] / p[1];
        } else {
            let nf = T::of(n as f64);
            for _ in 0..200 {
                let (v, d1, d2) = horner2(&p, x);
                if v == T::ZERO {
                    break;
                }
                let g = d1 / v;
                let h = g * g - d2 / v;
                let s = ((nf - T::ONE) * (nf * h - g * g)).max(T::ZERO).sqrt();
                let den = if g >= T::ZERO { g + s } else { g - s };
                if den == T::ZERO {
                    break;
                }
                let step = nf / den;
                let nx = x - step;
                if !nx.is_finite() {
                    break;
                }
                let done = (nx - x).abs() <= T::EPS * T::of(4.0) * nx.abs().max(T::EPS);
                x = nx;
                if done {
                    break;
                }
            }
        }
        roots.push(x);
        // Deflate by (z − x): synthetic division.
        let mut q = vec![T::ZERO; n];
        let mut carry = p[n];
        for k in (0..n).rev() {
            q[k] = carry;
            carry = p[k] + carry * x;
        }
        p = q;
    }
    // Polish on the original polynomial.
    let orig = &c[..=deg];
    for r in roots.iter_mut() {
        for _ in 0..3 {
            let (v, d1, _) = horner2(orig, *r);
            if d1 == T::ZERO {
                break;
            }
            let nr = *r - v / d1;
            if !nr.is_finite() {
                break;
            }
            *r = nr;
        }
    }
    roots.sort_by(|a, b| a.partial_cmp(b).unwrap_or(std::cmp::Ordering::Equal));
    roots
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
    fn polynomial_roots_match_constructed_roots() {
        let mut rng = ChaCha8Rng::seed_from_u64(2);
        for deg in 1..7 {
            for _ in 0..200 {
                let mut r: Vec<f64> = (0..deg).map(|_| rng.gen_range(-2.0..3.0)).collect();
                r.sort_by(|a, b| a.partial_cmp(b).unwrap());
                if r.windows(2).any(|w| w[1] - w[0] < 1e-2) {
                    continue;
                }
                // Expand lead·Π (z − r_i).
                let lead = rng.gen_range(0.5..4.0) * if rng.gen() { 1.0 } else { -1.0 };
                let mut c = vec![lead];
                for &ri in &r {
                    let mut n = vec![0.0; c.len() + 1];
                    for (k, &ck) in c.iter().enumerate() {
                        n[k + 1] += ck;
                        n[k] -= ri * ck;
                    }
                    c = n;
                }
                let got = real_roots(&c);
                assert_eq!(got.len(), deg);
                for (g, e) in got.iter().zip(&r) {
                    assert!((g - e).abs() < 1e-8, "deg {deg}: {got:?} vs {r:?}");
                }
                if deg == 2 {
                    let (a, b) = quadratic_roots(c[0], c[1], c[2]);
                    assert!((a - r[0]).abs() < 1e-10 && (b - r[1]).abs() < 1e-10);
                }
                if deg == 3 {
                    let q = cubic_roots(c[0], c[1], c[2], c[3]);
                    for k in 0..3 {
                        assert!((q[k] - r[k]).abs() < 1e-8, "{q:?} vs {r:?}");
                    }
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
