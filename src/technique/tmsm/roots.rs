//! Real roots of a polynomial of degree ≤ 4 in an interval, for the quartic of the TMSM
//! closed form (docs/tmsm.md §4.4): in f64 Descartes' rule of signs after a Möbius map with
//! interval bisection (Vincent–Collins–Akritas), derivative isolation as the fallback; in f32
//! derivative isolation alone (a fixed structure the shader export transcribes); safeguarded
//! Newton in every bracket.

use super::{is_single, max};
use crate::technique::linalg::Real;

/// Real roots in [lo, hi] of Σ coef[j] σ^j (degree ≤ 4), ascending.
///
/// f32: derivative isolation ([`isolate`]) at degree 4 for every input (zero leading
/// coefficients give no critical point at their level), so that the same brackets and Newton
/// solves run in the shader export (`tune::export`). f64 quartics: Descartes' rule of signs after the Möbius map σ = lo + (hi − lo)·t/(1 + t) (which
/// sends t ∈ (0, ∞) to (lo, hi)) bounds the number of roots in (lo, hi) with the right parity:
/// no sign variation ⇒ no root; one ⇒ exactly one simple root, found by safeguarded Newton;
/// more ⇒ bisect the interval and test the halves (Vincent–Collins–Akritas), up to
/// [`MAX_SPLITS`] levels. Coefficients too small to trust their sign (roots at the ends, multiple
/// or nearly multiple roots) and pieces still ambiguous at the last level fall back to derivative
/// isolation ([`isolate`]): the roots of the derivative split the piece into monotone parts,
/// each sign change is solved by safeguarded Newton, and a critical point where |p| is at
/// rounding level is reported as a (double) root. Unlike Ferrari's formula this never loses a
/// root in the interval when the quartic also has a root near infinity (the f32 failure mode).
pub fn roots_in_interval<T: Real>(coef: [T; 5], lo: T, hi: T, out: &mut [T; 4]) -> usize {
    let zero = T::ZERO;
    let scale = coef.iter().fold(zero, |m, c| max(m, c.abs()));
    if scale == zero || scale.is_nan() {
        return 0;
    }
    let inv = T::ONE / scale;
    let c = coef.map(|v| v * inv);
    if is_single::<T>() {
        return isolate(&c, 4, lo, hi, out);
    }
    let mut deg = 4;
    while deg > 0 && c[deg] == zero {
        deg -= 1;
    }
    if deg < 4 {
        return isolate(&c, deg, lo, hi, out);
    }
    let mut n = 0;
    descartes_roots(&c, lo, hi, 0, out, &mut n);
    n
}

/// Levels of interval bisection before [`roots_in_interval`] falls back to isolation.
const MAX_SPLITS: u32 = 5;

fn descartes_roots<T: Real>(c: &[T; 5], lo: T, hi: T, level: u32, out: &mut [T; 4], n: &mut usize) {
    let bound = descartes_bound(c, lo, hi);
    if bound == Some(0) {
        return;
    }
    if bound == Some(1) {
        let (pa, pb) = (horner(c, 4, lo).0, horner(c, 4, hi).0);
        if (pa < T::ZERO) != (pb < T::ZERO) && pa != T::ZERO && pb != T::ZERO {
            if *n < 4 {
                out[*n] = newton_in_bracket(c, 4, lo, hi, pa, pb);
                *n += 1;
            }
            return;
        }
    }
    if bound.is_some() && level < MAX_SPLITS {
        let mid = (lo + hi) * T::of(0.5);
        descartes_roots(c, lo, mid, level + 1, out, n);
        descartes_roots(c, mid, hi, level + 1, out, n);
        return;
    }
    let mut tmp = [T::ZERO; 4];
    let k = isolate(c, 4, lo, hi, &mut tmp);
    for &r in &tmp[..k] {
        if *n < 4 {
            out[*n] = r;
            *n += 1;
        }
    }
}

/// Sign variations of (1 + t)⁴·p(lo + (hi − lo)·t/(1 + t)) as a polynomial in t: an upper bound
/// on the number of roots of p in (lo, hi), of the same parity. `None` when a coefficient is
/// within its rounding error of 0 (its sign is not reliable; includes roots at lo or hi).
#[inline(always)]
fn descartes_bound<T: Real>(c: &[T; 5], lo: T, hi: T) -> Option<u32> {
    // p(lo + w·s): Taylor shift to lo, then scale by w = hi − lo; the same on |c| at |lo|
    // bounds the magnitude of the terms (for the rounding guard).
    let w = hi - lo;
    let (mut d, mut m) = (*c, c.map(|v| v.abs()));
    let alo = lo.abs();
    for i in 0..4 {
        for j in (i..4).rev() {
            d[j] += lo * d[j + 1];
            m[j] += alo * m[j + 1];
        }
    }
    let mut f = T::ONE;
    for j in 0..5 {
        d[j] *= f;
        m[j] *= f;
        f *= w;
    }
    // Σ d_j s^j·(1+t)⁴ with s = t/(1+t) is Σ d_j t^j (1+t)^{4−j}.
    const BINOM: [[f64; 5]; 5] = [
        [1.0, 4.0, 6.0, 4.0, 1.0],
        [0.0, 1.0, 3.0, 3.0, 1.0],
        [0.0, 0.0, 1.0, 2.0, 1.0],
        [0.0, 0.0, 0.0, 1.0, 1.0],
        [0.0, 0.0, 0.0, 0.0, 1.0],
    ];
    let mut q = [T::ZERO; 5];
    let mut mag = [T::ZERO; 5];
    for j in 0..5 {
        for k in j..5 {
            let bk = T::of(BINOM[j][k]);
            q[k] += bk * d[j];
            mag[k] += bk * m[j];
        }
    }
    let guard = T::of(64.0) * T::EPS;
    let mut changes = 0;
    let mut prev_neg: Option<bool> = None;
    for k in 0..5 {
        if mag[k] == T::ZERO && k != 0 && k != 4 {
            continue; // an exact zero coefficient
        }
        if q[k].abs() <= guard * mag[k] {
            return None;
        }
        let neg = q[k] < T::ZERO;
        if prev_neg.is_some_and(|p| p != neg) {
            changes += 1;
        }
        prev_neg = Some(neg);
    }
    Some(changes)
}

/// p(x) for a quartic.
#[inline(always)]
pub(super) fn eval<T: Real>(c: &[T; 5], x: T) -> T {
    horner(c, 4, x).0
}

/// p(x), p′(x) and Σ|c_j||x|^j (the scale of p's rounding error at x).
#[inline(always)]
fn horner<T: Real>(c: &[T; 5], deg: usize, x: T) -> (T, T, T) {
    let (mut p, mut dp, mut mag) = (T::ZERO, T::ZERO, T::ZERO);
    let ax = x.abs();
    for j in (0..=deg).rev() {
        dp = dp * x + p;
        p = p * x + c[j];
        mag = mag * ax + c[j].abs();
    }
    (p, dp, mag)
}

/// Newton steps of [`newton_in_bracket`] at most (f32, f64).
pub(crate) const NEWTON_STEPS: [usize; 2] = [30, 60];
/// A Newton step below 4ε·max(|x|, this) ends [`newton_in_bracket`].
pub(crate) const NEWTON_FLOOR: f64 = 1.0 / 1024.0;
/// |p| ≤ this·ε at a critical point (coefficients scaled to max |c_j| = 1) is a touching root
/// in [`isolate`].
pub(crate) const TOUCHING: f64 = 64.0;

/// The root of p in [a, b] given p(a) = `pa`, p(b) = `pb` of opposite signs: from the secant
/// point, Newton steps kept inside the shrinking bracket (bisection otherwise), stopped when p
/// is at rounding level, a step is at rounding level of x or the bracket has collapsed.
pub(super) fn newton_in_bracket<T: Real>(
    c: &[T; 5],
    deg: usize,
    mut a: T,
    mut b: T,
    pa: T,
    pb: T,
) -> T {
    let half = T::of(0.5);
    let iters = NEWTON_STEPS[usize::from(!is_single::<T>())];
    let stop = T::EPS * T::of(4.0);
    let floor = T::of(NEWTON_FLOOR);
    let neg_at_a = pa < T::ZERO;
    let secant = a - pa * (b - a) / (pb - pa);
    let mut x = if secant > a && secant < b {
        secant
    } else {
        (a + b) * half
    };
    for _ in 0..iters {
        let (px, dpx, mag) = horner(c, deg, x);
        if px.abs() <= stop * mag {
            break;
        }
        if (px < T::ZERO) == neg_at_a {
            a = x;
        } else {
            b = x;
        }
        let nx = if dpx != T::ZERO { x - px / dpx } else { a };
        if nx > a && nx < b {
            let step = (nx - x).abs();
            x = nx;
            if step <= stop * max(x.abs(), floor) {
                break;
            }
        } else {
            x = (a + b) * half;
        }
        if b - a <= stop * max(a.abs(), b.abs()) {
            break;
        }
    }
    x
}

/// Derivative isolation (see [`roots_in_interval`]); roots come out ascending.
fn isolate<T: Real>(c: &[T; 5], deg: usize, lo: T, hi: T, out: &mut [T; 4]) -> usize {
    let zero = T::ZERO;
    match deg {
        0 => 0,
        1 => {
            let r = -c[0] / c[1];
            if r >= lo && r <= hi {
                out[0] = r;
                1
            } else {
                0
            }
        }
        _ => {
            // Critical points from the derivative (ascending).
            let mut d = [zero; 5];
            for j in 1..=deg {
                d[j - 1] = c[j] * T::of(j as f64);
            }
            let mut crit = [zero; 4];
            let nc = isolate(&d, deg - 1, lo, hi, &mut crit);
            let mut pts = [lo; 6];
            pts[1..1 + nc].copy_from_slice(&crit[..nc]);
            pts[1 + nc] = hi;
            let np = nc + 2;
            let mut n = 0;
            let mut pa = horner(c, deg, pts[0]).0;
            for w in 0..np - 1 {
                let (a, b) = (pts[w], pts[w + 1]);
                let pb = horner(c, deg, b).0;
                let root = if pa == zero && w == 0 {
                    Some(a)
                } else if (pa < zero) == (pb < zero) || pb == zero {
                    // No sign change; a touching (double) root at a critical point shows up
                    // as |p| tiny there.
                    let touching =
                        pb == zero || (w + 1 < np - 1 && pb.abs() <= T::of(TOUCHING) * T::EPS);
                    touching.then_some(b)
                } else {
                    Some(newton_in_bracket(c, deg, a, b, pa, pb))
                };
                if let (Some(r), true) = (root, n < 4) {
                    out[n] = r;
                    n += 1;
                }
                pa = pb;
            }
            n
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Ascending coefficients of lead·Π(σ − r_i).
    fn poly_from_roots(r: &[f64], lead: f64) -> [f64; 5] {
        let mut c = [0.0; 5];
        c[0] = lead;
        for (n, &x) in r.iter().enumerate() {
            for j in (0..=n + 1).rev() {
                let lower = if j > 0 { c[j - 1] } else { 0.0 };
                c[j] = lower - x * c[j];
            }
        }
        c
    }

    #[test]
    fn roots_in_interval_finds_exactly_the_roots_inside() {
        // (roots, distinct roots in [−1, 1]); a double root may be reported once or twice.
        let cases: [(&[f64], &[f64]); 6] = [
            (&[0.3, -0.7, 0.9, -0.05], &[-0.7, -0.05, 0.3, 0.9]),
            (&[0.3, 2.0, -3.0, 5.0], &[0.3]),
            (&[1e-3, -1e-3, 7.0, 9.0], &[-1e-3, 1e-3]),
            (&[0.5, 0.5, 3.0, -4.0], &[0.5]),
            (&[2.0, 3.0, -2.0, 1e6], &[]),
            (&[-0.999, 0.2, 0.21, 0.999], &[-0.999, 0.2, 0.21, 0.999]),
        ];
        for (roots, want) in cases {
            let c = poly_from_roots(roots, 1.7);
            let mut out = [0.0; 4];
            let n = roots_in_interval(c, -1.0, 1.0, &mut out);
            let mut got = out[..n].to_vec();
            got.dedup_by(|x, y| (*x - *y).abs() < 1e-6);
            assert_eq!(got.len(), want.len(), "{roots:?}: {got:?}");
            for (g, w) in got.iter().zip(want) {
                assert!((g - w).abs() < 1e-6, "{roots:?}: {got:?}");
            }
            // f32: derivative isolation at degree 4; a double root is found to ~√ε
            let mut out = [0.0f32; 4];
            let n = roots_in_interval(c.map(|v| v as f32), -1.0, 1.0, &mut out);
            let mut got = out[..n].to_vec();
            assert!(got.windows(2).all(|p| p[0] <= p[1]), "{roots:?}: {got:?}");
            got.dedup_by(|x, y| (*x - *y).abs() < 1e-3);
            assert_eq!(got.len(), want.len(), "f32 {roots:?}: {got:?}");
            for (g, w) in got.iter().zip(want) {
                assert!((*g as f64 - w).abs() < 1e-3, "f32 {roots:?}: {got:?}");
            }
        }
    }
}
