//! The reference solver: Algorithm 1 handed verbatim to good_lp's pure-Rust microlp backend.
//!
//! Two numerical touches that leave the LP unchanged: when microlp reports the LP infeasible
//! (or fails),
//! it is asked again with every equality row divided by its largest coefficient (row
//! equilibration), and the weights of the support microlp returns are
//! polished by least squares on that support (microlp works to tolerances of about 1e-10 per
//! pivot, which leaves residuals and errors in G of a few 1e-9 on ill-conditioned bases).
//! The combinatorial answer (which support) is microlp's; the polish is accepted only when it
//! keeps the weights non-negative and reduces the residual.

use super::{Error, GridTable, MomentSolver, Result, Solution, Status};
use good_lp::{
    constraint, microlp, variable, variables, Expression, ResolutionError, Solution as _,
    SolverModel, Variable,
};

/// Algorithm 1 through a general-purpose LP solver. Slow (milliseconds per LP) but
/// independent of our own code: the oracle for the fast solver.
pub struct ReferenceSolver {
    table: GridTable,
}

impl ReferenceSolver {
    /// The reference solver on `table`.
    pub fn new(table: GridTable) -> ReferenceSolver {
        ReferenceSolver { table }
    }
}

impl MomentSolver for ReferenceSolver {
    fn table(&self) -> &GridTable {
        &self.table
    }

    fn solve(&mut self, moments: &[f64], zf: f64) -> Result<Solution> {
        let t = &self.table;
        let (n, m) = (t.n(), t.m());
        if moments.len() != m {
            return Err(Error::MomentCount {
                expected: m,
                got: moments.len(),
            });
        }
        if let Some(j) = moments.iter().position(|v| !v.is_finite()) {
            return Err(Error::MomentNotFinite {
                index: j + 1,
                value: moments[j],
            });
        }
        if zf.is_nan() {
            return Err(Error::ZfNaN);
        }
        // Row equilibration: row j of [A; b] divided by max_i |b_j(z_i)|.
        let scale: Vec<f64> = (0..m)
            .map(|j| {
                let s = (0..n).map(|i| t.row(i)[j].abs()).fold(0.0, f64::max);
                if s > 0.0 {
                    1.0 / s
                } else {
                    1.0
                }
            })
            .collect();
        let z = t.grid().points();
        // The LP verbatim; if microlp reports it infeasible or fails ("singular matrix"), a
        // second opinion on the row-equilibrated LP, then a third on the LP with orthonormalised
        // rows (microlp's phase 1 works to absolute tolerances, so badly scaled rows can turn a
        // boundary point of the moment space "infeasible").
        let mut found = None;
        let mut failure = None;
        let mm = m + 1;
        let diag = |d: &[f64]| -> Vec<f64> {
            let mut tm = vec![0.0; mm * mm];
            tm[0] = 1.0;
            for j in 0..m {
                tm[(j + 1) * mm + j + 1] = d[j];
            }
            tm
        };
        let mut transforms = vec![diag(&vec![1.0; m]), diag(&scale)];
        if let Some(tm) = orthonormalising_transform(t) {
            transforms.push(tm);
        }
        for tm in &transforms {
            match microlp_solve(t, moments, zf, tm) {
                Ok(Some(w)) => {
                    found = Some(w);
                    break;
                }
                Ok(None) => {}
                Err(e) => failure = Some(e),
            }
        }
        if let (None, Some(e)) = (&found, failure) {
            return Err(e);
        }
        let Some(mut wv) = found else {
            return Ok(Solution::infeasible());
        };
        polish(t, &scale, moments, &mut wv);
        let support: Vec<(f64, f64)> = wv
            .iter()
            .zip(z)
            .map(|(&wi, &zi)| (zi, wi))
            .filter(|&(_, wi)| wi > 1e-12)
            .collect();
        let g = wv
            .iter()
            .zip(z)
            .filter(|(_, &zi)| zi < zf)
            .map(|(&wi, _)| wi)
            .sum::<f64>()
            .clamp(0.0, 1.0);
        Ok(Solution {
            status: Status::Optimal,
            g,
            support,
            reason: None,
        })
    }
}

/// Algorithm 1 through good_lp + microlp with the m+1 equality rows [1; b(z_i)] w = [1; b]
/// multiplied by the row-major (m+1)×(m+1) matrix `tm` (an invertible row transform leaves the
/// feasible set unchanged): the weights, or None when microlp reports the LP infeasible.
fn microlp_solve(t: &GridTable, moments: &[f64], zf: f64, tm: &[f64]) -> Result<Option<Vec<f64>>> {
    let (n, m) = (t.n(), t.m());
    let mm = m + 1;
    let mut vars = variables!();
    let w: Vec<Variable> = (0..n).map(|_| vars.add(variable().min(0.0))).collect();
    let z = t.grid().points();
    let objective: Expression = w
        .iter()
        .zip(z)
        .filter(|(_, &zi)| zi < zf)
        .map(|(v, _)| *v)
        .sum();
    let mut model = vars.minimise(objective).using(microlp);
    let bbar: Vec<f64> = std::iter::once(1.0)
        .chain(moments.iter().copied())
        .collect();
    for k in 0..mm {
        let tk = &tm[k * mm..(k + 1) * mm];
        let coef = |i: usize| -> f64 {
            let row = t.row(i);
            tk[0] + (0..m).map(|j| tk[j + 1] * row[j]).sum::<f64>()
        };
        let e: Expression = w.iter().enumerate().map(|(i, v)| coef(i) * *v).sum();
        let rhs: f64 = tk.iter().zip(&bbar).map(|(a, b)| a * b).sum();
        model = model.with(constraint!(e == rhs));
    }
    match model.solve() {
        Ok(sol) => Ok(Some(w.iter().map(|v| sol.value(*v)).collect())),
        Err(ResolutionError::Infeasible) => Ok(None),
        Err(e) => Err(Error::Reference(e.to_string())),
    }
}

/// T = √n R^{-T} for the QR factorisation M = Q R of M = [1, b_1(z), …, b_m(z)] on the grid
/// ([`super::ortho::gram_schmidt`]), so that T [1; b(z_i)] = √n Q_i: orthonormal rows. None if
/// M is numerically rank-deficient.
fn orthonormalising_transform(t: &GridTable) -> Option<Vec<f64>> {
    let (n, mm) = (t.n(), t.m() + 1);
    let (_, rc, kept, _) = super::ortho::gram_schmidt(t);
    if kept.iter().any(|k| k.is_none()) {
        return None;
    }
    // R[k][j] = rc[j*mm + k]. Solve Rᵀ X = √n I column by column (Rᵀ lower triangular).
    let sn = (n as f64).sqrt();
    let mut tm = vec![0.0; mm * mm];
    for col in 0..mm {
        for row in 0..mm {
            // (Rᵀ)[row][k] = R[k][row]
            let mut acc = if row == col { sn } else { 0.0 };
            for k in 0..row {
                acc -= rc[row * mm + k] * tm[k * mm + col];
            }
            tm[row * mm + col] = acc / rc[row * mm + row];
        }
    }
    Some(tm)
}

/// Scaled residual rows of [1; s_j b_j] w − [1; s_j b_j] and its sum of squares.
fn residual(t: &GridTable, scale: &[f64], moments: &[f64], w: &[f64]) -> (Vec<f64>, f64) {
    let m = t.m();
    let mut r = vec![-1.0; m + 1];
    for j in 0..m {
        r[j + 1] = -moments[j] * scale[j];
    }
    for (i, &wi) in w.iter().enumerate() {
        if wi != 0.0 {
            r[0] += wi;
            for j in 0..m {
                r[j + 1] += wi * t.row(i)[j] * scale[j];
            }
        }
    }
    let ss = r.iter().map(|v| v * v).sum();
    (r, ss)
}

/// Least-squares refinement of the weights on microlp's support (w > 1e-13): two steps of
/// iterative refinement with a Householder QR of the (m+1) × |S| support matrix. Accepted only
/// if no weight drops below −1e-12 (tiny negatives are clamped to 0) and the residual
/// shrinks.
fn polish(t: &GridTable, scale: &[f64], moments: &[f64], w: &mut [f64]) {
    let m = t.m();
    let rows = m + 1;
    let support: Vec<usize> = (0..w.len()).filter(|&i| w[i] > 1e-13).collect();
    let k = support.len();
    if k == 0 || k > rows {
        return;
    }
    // Column-major rows × k matrix of the support columns.
    let mut a = vec![0.0; rows * k];
    for (c, &i) in support.iter().enumerate() {
        a[c * rows] = 1.0;
        for j in 0..m {
            a[c * rows + j + 1] = t.row(i)[j] * scale[j];
        }
    }
    // Householder QR in place; taus in `vs`.
    let mut vs: Vec<Vec<f64>> = Vec::with_capacity(k);
    let mut rdiag = vec![0.0; k];
    for c in 0..k {
        let col: Vec<f64> = a[c * rows + c..(c + 1) * rows].to_vec();
        let nrm = col.iter().map(|v| v * v).sum::<f64>().sqrt();
        let a0 = a[c * rows];
        if nrm <= 1e-12 * a0.abs().max(1.0) {
            return; // rank deficient support: keep microlp's weights
        }
        let alpha = if col[0] > 0.0 { -nrm } else { nrm };
        let mut v = col;
        v[0] -= alpha;
        let vn = v.iter().map(|x| x * x).sum::<f64>();
        if vn == 0.0 {
            return;
        }
        for cc in c..k {
            let colc = &mut a[cc * rows + c..(cc + 1) * rows];
            let d: f64 = colc.iter().zip(&v).map(|(x, y)| x * y).sum::<f64>() * 2.0 / vn;
            for (x, y) in colc.iter_mut().zip(&v) {
                *x -= d * y;
            }
        }
        rdiag[c] = a[c * rows + c];
        vs.push(v);
    }
    let mut cur: Vec<f64> = w.to_vec();
    let (_, mut best) = residual(t, scale, moments, &cur);
    for _ in 0..2 {
        let (r, _) = residual(t, scale, moments, &cur);
        // Solve min ||A d − r||: apply Qᵀ then back-substitute R.
        let mut qr = r.clone();
        for (c, v) in vs.iter().enumerate() {
            let vn = v.iter().map(|x| x * x).sum::<f64>();
            let d: f64 = qr[c..].iter().zip(v).map(|(x, y)| x * y).sum::<f64>() * 2.0 / vn;
            for (x, y) in qr[c..].iter_mut().zip(v) {
                *x -= d * y;
            }
        }
        let mut d = vec![0.0; k];
        for c in (0..k).rev() {
            let mut acc = qr[c];
            for cc in c + 1..k {
                acc -= a[cc * rows + c] * d[cc];
            }
            d[c] = acc / rdiag[c];
        }
        let mut next = cur.clone();
        for (c, &i) in support.iter().enumerate() {
            next[i] -= d[c];
        }
        if support.iter().any(|&i| next[i] < -1e-12) {
            break;
        }
        for &i in &support {
            next[i] = next[i].max(0.0);
        }
        let (_, ss) = residual(t, scale, moments, &next);
        if ss < best {
            best = ss;
            cur = next;
        } else {
            break;
        }
    }
    w.copy_from_slice(&cur);
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Grid;

    fn msm_table(n: usize) -> GridTable {
        GridTable::from_fn(&Grid::uniform(n).unwrap(), 2, |z, o| {
            o[0] = z;
            o[1] = z * z;
        })
        .unwrap()
    }

    #[test]
    fn single_dirac_gives_zero_or_one() {
        let mut s = ReferenceSolver::new(msm_table(11));
        let z0 = 0.3;
        let b = [z0, z0 * z0];
        assert!(s.solve(&b, 0.2).unwrap().g.abs() < 1e-9);
        assert!((s.solve(&b, 0.5).unwrap().g - 1.0).abs() < 1e-9);
    }

    #[test]
    fn impossible_moments_are_infeasible() {
        let mut s = ReferenceSolver::new(msm_table(11));
        // Variance would be negative: E[z^2] < E[z]^2.
        let sol = s.solve(&[0.5, 0.1], 0.4).unwrap();
        assert_eq!(sol.status, Status::Infeasible);
    }
}
