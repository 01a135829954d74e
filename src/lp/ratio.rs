//! The ratio test of the primal simplex, shared by the fast solver's loop, the scaled
//! double-double simplex and the certificate's accurate pivots. The exact simplex (exact.rs)
//! compares its ratios exactly by cross-multiplying integers, and the θ search's tableau
//! simplex (`quantize::lpsmall`) ties ratios within an absolute window; neither uses it.

#![allow(clippy::needless_range_loop)] // x, alpha and the keys are indexed together

/// Harris's two-pass ratio test: the leaving row for the entering column α = B⁻¹a_q at basic
/// weights `x` (negative weights read as 0). Pass 1: θ_max = min over pivots α_t > `piv` of
/// (x_t + `tol`)/α_t. Pass 2: among the rows with x_t/α_t ≤ θ_max, the largest pivot α_t, or
/// with `bland` = Some(keys) the smallest key. With tol = 0 and keys this is Bland's ratio test
/// itself (the smallest ratio, ties to the smallest key). None when no α_t exceeds `piv` (an
/// unbounded direction).
#[inline]
pub(super) fn harris(
    x: &[f64],
    alpha: &[f64],
    piv: f64,
    tol: f64,
    bland: Option<&[usize]>,
) -> Option<usize> {
    let r = alpha.len();
    let mut theta = f64::INFINITY;
    for t in 0..r {
        if alpha[t] > piv {
            theta = theta.min((x[t].max(0.0) + tol) / alpha[t]);
        }
    }
    let mut pick = usize::MAX;
    for t in 0..r {
        let a = alpha[t];
        if a > piv && x[t].max(0.0) / a <= theta {
            let better = pick == usize::MAX
                || match bland {
                    Some(keys) => keys[t] < keys[pick],
                    None => a > alpha[pick],
                };
            if better {
                pick = t;
            }
        }
    }
    (pick != usize::MAX).then_some(pick)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn harris_prefers_the_largest_pivot_among_near_ties() {
        // Ratios 1.0, 1.0 + 1e-13, 2.0; θ_max = (1 + 1e-12)/1 admits the first two; the larger
        // pivot (row 1, α = 4) leaves.
        let x = [1.0, 4.0 * (1.0 + 1e-13), 2.0];
        let a = [1.0, 4.0, 1.0];
        assert_eq!(harris(&x, &a, 1e-9, 1e-12, None), Some(1));
        // Without the tolerance only the exact minimum qualifies.
        assert_eq!(harris(&x, &a, 1e-9, 0.0, None), Some(0));
        // Bland: the smallest key among the admitted rows.
        assert_eq!(harris(&x, &a, 1e-9, 1e-12, Some(&[7, 3, 1])), Some(1));
        assert_eq!(harris(&x, &a, 1e-9, 1e-12, Some(&[2, 3, 1])), Some(0));
    }

    #[test]
    fn bland_ratio_test_takes_the_smallest_ratio_then_the_smallest_key() {
        // Ratios 0.5, 0.25, 0.25 (row 2's weight is negative: read as 0 → ratio 0 wins).
        let x = [1.0, 0.5, -1e-13];
        let a = [2.0, 2.0, 1.0];
        assert_eq!(harris(&x, &a, 1e-9, 0.0, Some(&[0, 1, 2])), Some(2));
        let x = [1.0, 0.5, 0.25];
        assert_eq!(harris(&x, &a, 1e-9, 0.0, Some(&[0, 9, 4])), Some(2));
        assert_eq!(harris(&x, &a, 1e-9, 0.0, Some(&[0, 3, 4])), Some(1));
    }

    #[test]
    fn no_pivot_above_the_tolerance_is_unbounded() {
        assert_eq!(harris(&[1.0, 1.0], &[1e-10, -3.0], 1e-9, 0.0, None), None);
        assert_eq!(harris(&[], &[], 1e-9, 0.0, None), None);
        // A negative column entry never leaves, however small its ratio.
        assert_eq!(harris(&[0.0, 5.0], &[-1.0, 1.0], 1e-9, 0.0, None), Some(1));
    }
}
