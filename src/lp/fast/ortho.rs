//! Orthonormalisation of the table: M = [1, b_1(z), …, b_m(z)] = Q R on the grid (modified
//! Gram–Schmidt with reorthogonalisation, dependent functions dropped), the transformed columns
//! a_i = √n Q_{i,·}, cond_F(R), and the transformed moments c = √n R^{-T} b̄.

use super::linalg::{invert, norm};
use super::TOL_DEP;
use crate::lp::ortho::gram_schmidt;
use crate::lp::GridTable;

/// The orthonormalised table: the coordinates every LP of the table is solved in, fixed for
/// the solver's life.
pub(super) struct Ortho {
    /// Numerical rank (number of kept functions).
    pub(super) r: usize,
    /// Transformed columns, row-major: rows[i*r + k] = a_i[k].
    pub(super) rows: Vec<f64>,
    /// For function j (0 = constant): coefficients R[k][j], k < r, at rcoef[j*r + k].
    pub(super) rcoef: Vec<f64>,
    /// For function j: its position among the kept (independent) functions, if kept.
    pub(super) kept: Vec<Option<usize>>,
    /// For function j: max |M_j| over the grid (scale of the consistency check).
    pub(super) fscale: Vec<f64>,
    /// cond_F of [1, b_1..b_m] on the grid (via R).
    pub(super) condition: f64,
    /// max_i ‖a_i‖₂.
    pub(super) amax: f64,
}

/// M = Q R for the table; Q scaled to the transformed columns (see [`Ortho`]), and the same
/// columns column-major (cols[k*n + i] = a_i[k]) for the pricing tables.
pub(super) fn orthonormalise(table: &GridTable) -> (Ortho, Vec<f64>) {
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
    let condition = r_condition(&rcoef, &kept, r);
    let amax = (0..n)
        .map(|i| norm(&rows[i * r..(i + 1) * r]))
        .fold(0.0, f64::max);
    let ortho = Ortho {
        r,
        rows,
        rcoef,
        kept,
        fscale,
        condition,
        amax,
    };
    (ortho, cols)
}

/// cond_F(R) over the kept functions (= condition of M on the grid); ∞ if R is singular.
fn r_condition(rcoef: &[f64], kept: &[Option<usize>], r: usize) -> f64 {
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
    if invert(&mut Default::default(), &rk, &mut inv, r) {
        nr * norm(&inv)
    } else {
        f64::INFINITY
    }
}

impl Ortho {
    /// Transform b̄ = [1, b] to c = √n R^{-T} b̄ (`u` = R^{-T} b̄ is scratch); false if a
    /// dependent function's moment is inconsistent (then no distribution on the grid has these
    /// moments).
    pub(super) fn transform(&self, moments: &[f64], u: &mut [f64], c: &mut [f64]) -> bool {
        let r = self.r;
        let mut done = 0usize;
        for j in 0..self.kept.len() {
            let bj = if j == 0 { 1.0 } else { moments[j - 1] };
            let coef = &self.rcoef[j * r..(j + 1) * r];
            let mut acc = bj;
            for k in 0..done {
                acc -= coef[k] * u[k];
            }
            match self.kept[j] {
                Some(t) => {
                    u[t] = acc / coef[t];
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
        let sn = ((self.rows.len() / r.max(1)) as f64).sqrt();
        for k in 0..r {
            c[k] = sn * u[k];
        }
        true
    }

    /// For moments a dependent function contradicts ([`Self::transform`] false): the ray
    /// y = ±(e_j − Σ_t a_t e_{k_t}) over the rows 0..=m of the first such function j, where
    /// M_j ≈ Σ_t a_t M_{k_t} expresses its column through the kept functions k_t
    /// (R_kept a = R_{·,j}, back substitution). y·ā_i is the dependency's residual on the grid,
    /// y·b̄ the moments' inconsistency; the sign makes y·b̄ negative, so y is a Farkas ray
    /// when the inconsistency exceeds the residual ([`crate::lp::certify`] decides).
    pub(super) fn inconsistency_ray(&self, moments: &[f64]) -> Option<Vec<f64>> {
        let (r, mm) = (self.r, self.kept.len());
        let mut kept_fn = vec![0usize; r];
        for (j, t) in self.kept.iter().enumerate() {
            if let Some(t) = *t {
                kept_fn[t] = j;
            }
        }
        let bbar = |j: usize| if j == 0 { 1.0 } else { moments[j - 1] };
        for j in (0..mm).filter(|&j| self.kept[j].is_none()) {
            let rj = &self.rcoef[j * r..(j + 1) * r];
            let mut a = vec![0.0; r];
            for t in (0..r).rev() {
                let mut acc = rj[t];
                for s in t + 1..r {
                    acc -= self.rcoef[kept_fn[s] * r + t] * a[s];
                }
                a[t] = acc / self.rcoef[kept_fn[t] * r + t];
            }
            let mut y = vec![0.0; mm];
            y[j] = 1.0;
            for t in 0..r {
                y[kept_fn[t]] -= a[t];
            }
            let yb: f64 = (0..mm).map(|k| y[k] * bbar(k)).sum();
            let scale = self.fscale[j].max(bbar(j).abs()).max(1e-300);
            if yb.abs() > TOL_DEP * scale {
                if yb > 0.0 {
                    y.iter_mut().for_each(|v| *v = -*v);
                }
                return Some(y);
            }
        }
        None
    }
}
