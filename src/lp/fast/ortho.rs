//! Orthonormalisation of the table: M = [1, b_1(z), …, b_m(z)] = Q R on the grid (modified
//! Gram–Schmidt with reorthogonalisation, dependent functions dropped), the transformed columns
//! a_i = √n Q_{i,·}, cond_F(R), and the transformed moments c = √n R^{-T} b̄.

use super::linalg::{dot, invert, norm};
use super::{FastSolver, TOL_DEP, TOL_RANK};
use crate::lp::GridTable;

/// The orthonormalised table.
pub(super) struct Ortho {
    /// Numerical rank (number of kept functions).
    pub(super) r: usize,
    /// Transformed columns, row-major: rows[i*r + k] = a_i[k].
    pub(super) rows: Vec<f64>,
    /// The same, column-major: cols[k*n + i] = a_i[k].
    pub(super) cols: Vec<f64>,
    /// For function j (0 = constant): coefficients R[k][j], k < r, at rcoef[j*r + k].
    pub(super) rcoef: Vec<f64>,
    /// For function j: its position among the kept (independent) functions, if kept.
    pub(super) kept: Vec<Option<usize>>,
    /// For function j: max |M_j| over the grid.
    pub(super) fscale: Vec<f64>,
}

/// The Gram–Schmidt factors of M: the orthonormal columns q of the kept functions, R (all
/// m+1 functions, (m+1)² entries, column j at j*(m+1)), which functions were kept, and their
/// scales max_i |M_j(z_i)|.
type Factors = (Vec<Vec<f64>>, Vec<f64>, Vec<Option<usize>>, Vec<f64>);

/// M = Q R for the table; Q scaled to the transformed columns (see [`Ortho`]).
pub(super) fn orthonormalise(table: &GridTable) -> Ortho {
    let (n, mm) = (table.n(), table.m() + 1);
    let (q, rcoef_full, kept, fscale) = gram_schmidt(table);
    let r = q.len();
    let sn = (n as f64).sqrt();
    let mut cols = vec![0.0; r * n];
    let mut rows = vec![0.0; n * r];
    for (k, qk) in q.iter().enumerate() {
        for i in 0..n {
            let a = sn * qk[i];
            cols[k * n + i] = a;
            rows[i * r + k] = a;
        }
    }
    let mut rcoef = vec![0.0; mm * r];
    for j in 0..mm {
        rcoef[j * r..(j + 1) * r].copy_from_slice(&rcoef_full[j * mm..j * mm + r]);
    }
    Ortho {
        r,
        rows,
        cols,
        rcoef,
        kept,
        fscale,
    }
}

/// Modified Gram–Schmidt with reorthogonalisation over the functions 1, b_1, …, b_m on the
/// grid; a function whose relative residual is below TOL_RANK is dropped (dependent).
fn gram_schmidt(table: &GridTable) -> Factors {
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
        let unit = crate::lp::dense::inv_pow2(fscale[j]);
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

/// cond_F(R) over the kept functions (= condition of M on the grid); ∞ if R is singular.
pub(super) fn r_condition(rcoef: &[f64], kept: &[Option<usize>], r: usize) -> f64 {
    let mut rk = vec![0.0; r * r];
    let mut t = 0;
    for j in 0..kept.len() {
        if let Some(tj) = kept[j] {
            for k in 0..r {
                rk[k * r + tj] = rcoef[j * r + k];
            }
            t += 1;
        }
    }
    debug_assert_eq!(t, r);
    let nr = norm(&rk);
    let mut inv = vec![0.0; r * r];
    if invert(&mut rk, &mut inv, r) {
        nr * norm(&inv)
    } else {
        f64::INFINITY
    }
}

impl FastSolver {
    /// Transform b̄ = [1, b] to c = √n R^{-T} b̄; false if a dependent function's moment is
    /// inconsistent (then no distribution on the grid has these moments).
    pub(super) fn transform(&mut self, moments: &[f64]) -> bool {
        let r = self.r;
        let mut done = 0usize;
        for j in 0..=self.m {
            let bj = if j == 0 { 1.0 } else { moments[j - 1] };
            let coef = &self.rcoef[j * r..(j + 1) * r];
            let mut acc = bj;
            for k in 0..done {
                acc -= coef[k] * self.u[k];
            }
            match self.kept[j] {
                Some(t) => {
                    self.u[t] = acc / coef[t];
                    done = t + 1;
                }
                None => {
                    let scale = self.fscale[j].max(bj.abs()).max(1e-300);
                    if acc.abs() > TOL_DEP * scale {
                        return false;
                    }
                }
            }
        }
        let sn = (self.n as f64).sqrt();
        for k in 0..r {
            self.c[k] = sn * self.u[k];
        }
        true
    }
}
