//! Real polynomials on [0,1] (coefficients in ascending powers): evaluation, real roots in
//! [0,1] by the derivative chain (between consecutive critical points a polynomial is
//! monotone, so every root there is bracketed and found by bisection), and exact extrema.

/// p(z) = Σ_k c_k z^k (Horner).
pub fn eval(c: &[f64], z: f64) -> f64 {
    c.iter().rev().fold(0.0, |acc, &ck| acc * z + ck)
}

/// Coefficients of p'.
pub fn derivative(c: &[f64]) -> Vec<f64> {
    c.iter()
        .enumerate()
        .skip(1)
        .map(|(k, &ck)| k as f64 * ck)
        .collect()
}

/// Drop leading coefficients that are negligible relative to the largest one.
fn trimmed(c: &[f64]) -> &[f64] {
    let scale = c.iter().fold(0.0f64, |a, &v| a.max(v.abs()));
    let mut n = c.len();
    while n > 0 && c[n - 1].abs() <= 1e-300_f64.max(scale * 1e-15) {
        n -= 1;
    }
    &c[..n]
}

/// All real roots of p in [lo, hi], ascending, each to (nearly) machine precision.
/// Roots of even multiplicity are reported as critical points where |p| is tiny.
pub fn roots_in(c: &[f64], lo: f64, hi: f64) -> Vec<f64> {
    let c = trimmed(c);
    match c.len() {
        0 | 1 => return vec![],
        2 => {
            let r = -c[0] / c[1];
            return if (lo..=hi).contains(&r) {
                vec![r]
            } else {
                vec![]
            };
        }
        _ => {}
    }
    let mut breaks = vec![lo];
    breaks.extend(roots_in(&derivative(c), lo, hi));
    breaks.push(hi);
    let scale: f64 = c.iter().map(|v| v.abs()).sum::<f64>() * 1e-14;
    let mut out: Vec<f64> = Vec::new();
    for w in breaks.windows(2) {
        let (mut a, mut b) = (w[0], w[1]);
        let (mut fa, fb) = (eval(c, a), eval(c, b));
        if fa.abs() <= scale {
            out.push(a);
            continue;
        }
        if fb.abs() <= scale || (fa > 0.0) == (fb > 0.0) {
            continue;
        }
        for _ in 0..200 {
            let mid = 0.5 * (a + b);
            if mid <= a || mid >= b {
                break;
            }
            let fm = eval(c, mid);
            if (fm > 0.0) == (fa > 0.0) {
                a = mid;
                fa = fm;
            } else {
                b = mid;
            }
        }
        out.push(0.5 * (a + b));
    }
    if eval(c, hi).abs() <= scale {
        out.push(hi);
    }
    out.dedup_by(|x, y| (*x - *y).abs() < 1e-13);
    out
}

/// Candidate extremal points of p on [0,1]: the endpoints and the roots of p' in (0,1), with
/// their values, ascending in z.
pub fn extrema_candidates(c: &[f64]) -> Vec<(f64, f64)> {
    let mut zs = vec![0.0];
    zs.extend(roots_in(&derivative(c), 0.0, 1.0));
    zs.push(1.0);
    zs.dedup_by(|x, y| (*x - *y).abs() < 1e-15);
    zs.into_iter().map(|z| (z, eval(c, z))).collect()
}

/// (z_min, min, z_max, max) of p over [0,1], exact up to rounding.
pub fn min_max(c: &[f64]) -> (f64, f64, f64, f64) {
    arg_min_max(extrema_candidates(c))
}

/// (z_min, min, z_max, max) over the points (z, v): the first point of the least v and the
/// first of the greatest; (0, ∞, 0, −∞) for none.
pub fn arg_min_max(points: impl IntoIterator<Item = (f64, f64)>) -> (f64, f64, f64, f64) {
    let mut r = (0.0, f64::INFINITY, 0.0, f64::NEG_INFINITY);
    for (z, v) in points {
        if v < r.1 {
            r.0 = z;
            r.1 = v;
        }
        if v > r.3 {
            r.2 = z;
            r.3 = v;
        }
    }
    r
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};

    #[test]
    fn roots_of_products_of_known_factors() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        for _ in 0..2000 {
            let k = rng.gen_range(1..7);
            let mut rs: Vec<f64> = (0..k).map(|_| rng.gen_range(-0.5..1.5)).collect();
            rs.sort_by(f64::total_cmp);
            let mut c = vec![rng.gen_range(0.5..3.0)];
            for &r in &rs {
                // multiply by (z - r)
                let mut n = vec![0.0; c.len() + 1];
                for (i, &ci) in c.iter().enumerate() {
                    n[i + 1] += ci;
                    n[i] -= r * ci;
                }
                c = n;
            }
            let want: Vec<f64> = rs
                .iter()
                .copied()
                .filter(|r| (0.0..=1.0).contains(r))
                .collect();
            let close = rs.windows(2).any(|w| w[1] - w[0] < 1e-3);
            let got = roots_in(&c, 0.0, 1.0);
            if close {
                continue; // clustered roots are ill-conditioned; covered by the extrema test
            }
            assert_eq!(got.len(), want.len(), "{rs:?} -> {got:?}");
            for (g, w) in got.iter().zip(&want) {
                assert!((g - w).abs() < 1e-9, "{g} vs {w}");
            }
        }
    }

    #[test]
    fn min_max_matches_dense_sampling() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
        for _ in 0..2000 {
            let d = rng.gen_range(1..9);
            let c: Vec<f64> = (0..=d).map(|_| rng.gen_range(-50.0..50.0)).collect();
            let (_, lo, _, hi) = min_max(&c);
            let n = 20000;
            let (mut slo, mut shi) = (f64::INFINITY, f64::NEG_INFINITY);
            for i in 0..=n {
                let v = eval(&c, i as f64 / n as f64);
                slo = slo.min(v);
                shi = shi.max(v);
            }
            // exact extrema bound the samples and are approached by them
            assert!(lo <= slo + 1e-9 && hi >= shi - 1e-9);
            assert!(slo - lo < 1e-4 && hi - shi < 1e-4, "{c:?}");
        }
    }
}
