//! Orthonormalisation of the table: M = [1, b_1(z), …, b_m(z)] = Q R on the grid (modified
//! Gram–Schmidt with reorthogonalisation, dependent functions dropped), the transformed columns
//! a_i = √n Q_{i,·}, cond_F(R), and the transformed moments c = √n R^{-T} b̄; or coordinates
//! local to a few reference points, computed in double-double ([`local_coordinates`]).

use super::linalg::{invert, norm};
use super::TOL_DEP;
use crate::lp::dense::{inv_pow2, DdLu};
use crate::lp::ortho::gram_schmidt;
use crate::lp::GridTable;

/// Coordinates local to r reference grid points: a_i = S B⁻¹ ā_i with B the reference
/// points' columns ā = [1; b(z)] and S diagonal (powers of two), in place of √n R⁻ᵀ.
pub(super) struct Local {
    /// B in double-double LU.
    lu: DdLu,
    /// The diagonal of S.
    scale: Vec<f64>,
    /// The mean of the columns from the first to the last reference point: the moments of
    /// the uniform distribution on them, an interior point of their moment space.
    mean: Vec<f64>,
}

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
    /// Local coordinates ([`local_coordinates`]) instead of the orthonormalised ones.
    local: Option<Local>,
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
        local: None,
    };
    (ortho, cols)
}

/// Coordinates of `table` local to its grid points `refs` (r = m + 1 of them): a_i = S B⁻¹ ā_i,
/// B = [ā_ref…] factorised in double-double and each a_i solved in double-double and rounded,
/// S the powers of two that bring each row's RMS over the grid points from the first to the
/// last reference point near 1 (points beyond, far from the references, have far larger
/// coordinates). The LP is the same in any coordinates (both sides multiplied by S B⁻¹).
/// Where the columns of neighbouring grid points agree to 12 digits (a cluster of depths on a
/// fine grid under z, …, z⁴), the orthonormalised coordinates keep their differences only to
/// the rounding of Q and R relative to the whole column; these keep them to the rounding of
/// each a_i, so bases of points near the reference points are well conditioned and their
/// weights accurate. None when B is singular or a coordinate is not finite. Returns the
/// coordinates and the columns column-major (cols[k·n + i] = a_i[k]).
pub(super) fn local_coordinates(table: &GridTable, refs: &[usize]) -> Option<(Ortho, Vec<f64>)> {
    let (n, mm) = (table.n(), table.m() + 1);
    if refs.len() != mm || mm > 32 {
        return None;
    }
    let column = |i: usize, out: &mut [f64]| {
        out[0] = 1.0;
        out[1..].copy_from_slice(table.row(i));
    };
    let mut b = vec![0.0; mm * mm];
    let mut v = vec![0.0; mm];
    for (t, &i) in refs.iter().enumerate() {
        column(i, &mut v);
        for k in 0..mm {
            b[k * mm + t] = v[k];
        }
    }
    let mut lu = DdLu::default();
    if !lu.factor(&b, mm) {
        return None;
    }
    let mut rows = vec![0.0; n * mm];
    for i in 0..n {
        column(i, &mut v);
        lu.solve(&mut v);
        rows[i * mm..(i + 1) * mm].copy_from_slice(&v);
    }
    let (lo, hi) = (refs[0].min(refs[mm - 1]), refs[0].max(refs[mm - 1]));
    let scale: Vec<f64> = (0..mm)
        .map(|k| {
            let sq = (lo..=hi).map(|i| rows[i * mm + k].powi(2)).sum::<f64>();
            inv_pow2((sq / (hi - lo + 1) as f64).sqrt())
        })
        .collect();
    let mut cols = vec![0.0; mm * n];
    for i in 0..n {
        for k in 0..mm {
            let a = rows[i * mm + k] * scale[k];
            rows[i * mm + k] = a;
            cols[k * n + i] = a;
        }
    }
    if !rows.iter().all(|a| a.is_finite()) {
        return None;
    }
    let mut mean = vec![0.0; mm];
    for i in lo..=hi {
        for (mk, ak) in mean.iter_mut().zip(&rows[i * mm..(i + 1) * mm]) {
            *mk += ak / (hi - lo + 1) as f64;
        }
    }
    let amax = (0..n)
        .map(|i| norm(&rows[i * mm..(i + 1) * mm]))
        .fold(0.0, f64::max);
    let fscale = (0..mm)
        .map(|j| match j {
            0 => 1.0,
            _ => (0..n).fold(0.0f64, |a, i| a.max(table.row(i)[j - 1].abs())),
        })
        .collect();
    let ortho = Ortho {
        r: mm,
        rows,
        rcoef: Vec::new(),
        kept: (0..mm).map(Some).collect(),
        fscale,
        // The coordinates are exact to the rounding of each column: no loss to the table's
        // own condition.
        condition: 1.0,
        amax,
        local: Some(Local { lu, scale, mean }),
    };
    Some((ortho, cols))
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
        if self.local.is_some() {
            u[0] = 1.0;
            u[1..r].copy_from_slice(&moments[..r - 1]);
            self.apply(u, c);
            return true;
        }
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

    /// For local coordinates, the mean column of the points between the reference points
    /// (an interior point of their moment space).
    pub(super) fn local_mean(&self) -> Option<&[f64]> {
        self.local.as_ref().map(|l| &l.mean[..])
    }

    /// c = T v for v over the rows 0..=m, every function kept (r = m + 1): T = √n R⁻ᵀ by
    /// forward substitution, or S B⁻¹ in double-double for local coordinates.
    pub(super) fn apply(&self, v: &[f64], c: &mut [f64]) {
        let r = self.r;
        if let Some(local) = &self.local {
            c[..r].copy_from_slice(&v[..r]);
            local.lu.solve(c);
            for (ck, s) in c.iter_mut().zip(&local.scale) {
                *ck *= s;
            }
            return;
        }
        for j in 0..r {
            let coef = &self.rcoef[j * r..(j + 1) * r];
            let mut acc = v[j];
            for k in 0..j {
                acc -= coef[k] * c[k];
            }
            c[j] = acc / coef[j];
        }
        let sn = ((self.rows.len() / r.max(1)) as f64).sqrt();
        c[..r].iter_mut().for_each(|ck| *ck *= sn);
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lp::fast::escalate::exact::tests::solve_q;
    use crate::Grid;
    use num_rational::BigRational;
    use num_traits::ToPrimitive;

    /// z, …, z⁴ on 4096 points, coordinates local to 5 points 8 apart.
    fn power_local() -> (GridTable, Ortho, Vec<f64>, [usize; 5]) {
        let grid = Grid::uniform(4096).unwrap();
        let t = GridTable::from_fn(&grid, 4, |z, o| {
            let mut p = 1.0;
            for v in o.iter_mut() {
                p *= z;
                *v = p;
            }
        })
        .unwrap();
        let refs = [2000, 2008, 2016, 2024, 2031];
        let (o, cols) = local_coordinates(&t, &refs).unwrap();
        (t, o, cols, refs)
    }

    /// Each a_i is S B⁻¹ ā_i rounded once: against the exact rational solve, to within one
    /// rounding of the largest coordinate, near the reference points and far from them; the
    /// reference points are the scaled unit vectors; rows and columns agree.
    #[test]
    fn local_coordinates_are_the_rounded_exact_solve() {
        let (t, o, cols, refs) = power_local();
        let local = o.local.as_ref().unwrap();
        let q = |v: f64| BigRational::from_float(v).unwrap();
        let column = |i: usize| -> Vec<BigRational> {
            std::iter::once(1.0)
                .chain(t.row(i).iter().copied())
                .map(q)
                .collect()
        };
        let b: Vec<Vec<BigRational>> = (0..5)
            .map(|k| refs.iter().map(|&i| column(i)[k].clone()).collect())
            .collect();
        for i in [0, 1, 1999, 2003, 2012, 2030, 2040, 3000, 4095] {
            let exact = solve_q(b.clone(), column(i)).unwrap();
            let a = &o.rows[i * 5..(i + 1) * 5];
            let big = a.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            for k in 0..5 {
                let want = exact[k].to_f64().unwrap() * local.scale[k];
                assert!(
                    (a[k] - want).abs() <= 2.0 * f64::EPSILON * big,
                    "{i} {k}: {a:?}"
                );
                assert_eq!(cols[k * 4096 + i], a[k]);
            }
        }
        for (t, &i) in refs.iter().enumerate() {
            for k in 0..5 {
                let want = if k == t { local.scale[k] } else { 0.0 };
                assert!((o.rows[i * 5 + k] - want).abs() <= 1e-15 * local.scale[k]);
            }
        }
    }

    /// Moments of neighbouring grid points: in local coordinates the basis of five
    /// consecutive points is well conditioned (its inverse's entries about 8e3) where the
    /// orthonormalised coordinates of the whole grid put them beyond 1e11, and the
    /// transformed moments of a distribution on them are its weighted sum of columns to the
    /// rounding of the moments.
    #[test]
    fn local_coordinates_resolve_a_cluster() {
        let (t, o, _, _) = power_local();
        let (g, _) = orthonormalise(&t);
        let cluster = [2010, 2011, 2012, 2013, 2014];
        let inverse_size = |ortho: &Ortho| {
            let mut m = vec![0.0; 25];
            for (c, &i) in cluster.iter().enumerate() {
                for k in 0..5 {
                    m[k * 5 + c] = ortho.rows[i * 5 + k];
                }
            }
            let mut inv = vec![0.0; 25];
            assert!(invert(&mut Default::default(), &m, &mut inv, 5));
            inv.iter().fold(0.0f64, |a, v| a.max(v.abs()))
        };
        assert!(inverse_size(&o) < 2e4, "{}", inverse_size(&o));
        assert!(inverse_size(&g) > 1e11, "{}", inverse_size(&g));
        let w = [0.1, 0.3, 0.35, 0.2, 0.05];
        let dist: Vec<(u32, f64)> = cluster.iter().zip(w).map(|(&i, w)| (i as u32, w)).collect();
        let b = crate::lp::distribution_moments(&t, &dist).unwrap();
        let (mut u, mut c) = ([0.0; 5], [0.0; 5]);
        assert!(o.transform(&b, &mut u, &mut c));
        for k in 0..5 {
            let want: f64 = cluster
                .iter()
                .zip(w)
                .map(|(&i, w)| w * o.rows[i * 5 + k])
                .sum();
            // The moments carry rounding of 1e-16 of their size, about 1e-6 here (the
            // coordinates of neighbouring points differ by 1e-1 to 1e-4).
            assert!((c[k] - want).abs() <= 1e-5, "{k}: {c:?} vs {want}");
        }
    }
}
