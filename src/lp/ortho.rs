//! Modified Gram–Schmidt with reorthogonalisation of M = [1, b_1(z), …, b_m(z)] on the grid:
//! M = Q R with dependent functions dropped. The fast solver works in the coordinates it gives
//! (`fast::ortho`); the reference solver offers microlp the same orthonormalised rows.

use super::dense::inv_pow2;
use super::GridTable;
pub(super) use crate::linalg::dot;

/// Relative residual below which a basis function counts as dependent on the previous ones.
pub(super) const TOL_RANK: f64 = 1e-10;

/// ‖a‖₂.
pub(super) fn norm(a: &[f64]) -> f64 {
    dot(a, a).sqrt()
}

/// The Gram–Schmidt factors of M: the orthonormal columns q of the kept functions, R (all
/// m+1 functions, (m+1)² entries, column j at j*(m+1)), which functions were kept, and their
/// scales max_i |M_j(z_i)|.
pub(super) type Factors = (Vec<Vec<f64>>, Vec<f64>, Vec<Option<usize>>, Vec<f64>);

/// Modified Gram–Schmidt with reorthogonalisation over the functions 1, b_1, …, b_m on the
/// grid; a function whose relative residual is below [`TOL_RANK`] is dropped (dependent).
pub(super) fn gram_schmidt(table: &GridTable) -> Factors {
    let (n, mm) = (table.n(), table.m() + 1);
    let mut q: Vec<Vec<f64>> = Vec::with_capacity(mm);
    let mut rcoef_full = vec![0.0; mm * mm];
    let mut kept = vec![None; mm];
    let mut fscale = vec![0.0; mm];
    for j in 0..mm {
        let mut v: Vec<f64> = if j == 0 {
            vec![1.0; n]
        } else {
            (0..n).map(|i| table.row(i)[j - 1]).collect()
        };
        fscale[j] = v.iter().fold(0.0f64, |a, &b| a.max(b.abs()));
        // Work on v·2^-e (exact) so that ‖v‖² cannot overflow (exp(400z) reaches 1e173).
        let unit = inv_pow2(fscale[j]);
        v.iter_mut().for_each(|x| *x *= unit);
        let norm0 = norm(&v);
        let coef = &mut rcoef_full[j * mm..(j + 1) * mm];
        for _pass in 0..2 {
            for (k, qk) in q.iter().enumerate() {
                let h = dot(qk, &v);
                coef[k] += h;
                for (vi, qi) in v.iter_mut().zip(qk) {
                    *vi -= h * qi;
                }
            }
        }
        let nv = norm(&v);
        if norm0 > 0.0 && nv > TOL_RANK * norm0 {
            coef[q.len()] = nv;
            kept[j] = Some(q.len());
            for vi in v.iter_mut() {
                *vi /= nv;
            }
            q.push(v);
        }
        // R's column of the unscaled function.
        coef.iter_mut().for_each(|c| *c /= unit);
    }
    (q, rcoef_full, kept, fscale)
}
