//! Real roots of real-rooted polynomials, generic over the arithmetic precision ([`Real`]):
//! the quadratic in cancellation-free form, the trigonometric cubic, and Laguerre's method with
//! deflation for any degree.

use super::linalg::Real;

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

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

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
}
