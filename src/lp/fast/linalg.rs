//! Dense linear algebra on the r ≤ 9 rows of the transformed LP: dot products, the explicit
//! inverse, least squares by Gram–Schmidt, and greedy maximal-volume bases.

pub(super) use crate::lp::ortho::{dot, norm};

/// `f::<R>(args)` for the row count r = R ≤ 9 (loops unrolled at compile time), else
/// `f::<0>(args)` (any r).
macro_rules! by_rows {
    ($r:expr, $f:ident, $($arg:expr),*) => {
        match $r {
            1 => $f::<1>($($arg),*),
            2 => $f::<2>($($arg),*),
            3 => $f::<3>($($arg),*),
            4 => $f::<4>($($arg),*),
            5 => $f::<5>($($arg),*),
            6 => $f::<6>($($arg),*),
            7 => $f::<7>($($arg),*),
            8 => $f::<8>($($arg),*),
            9 => $f::<9>($($arg),*),
            _ => $f::<0>($($arg),*),
        }
    };
}

/// out = A v for row-major r × r A.
#[inline]
pub(super) fn mat_vec(a: &[f64], v: &[f64], out: &mut [f64], r: usize) {
    by_rows!(r, mat_vec_r, a, v, out, r)
}

#[inline(always)]
fn mat_vec_r<const R: usize>(a: &[f64], v: &[f64], out: &mut [f64], r: usize) {
    let r = if R > 0 { R } else { r };
    let (a, v, out) = (&a[..r * r], &v[..r], &mut out[..r]);
    for t in 0..r {
        out[t] = dot(&a[t * r..(t + 1) * r], v);
    }
}

/// The basis-inverse update of a pivot: row l of the row-major r × r `binv` divided by α_l,
/// then α_t times it subtracted from every other row t.
#[inline]
pub(super) fn pivot_rows(binv: &mut [f64], alpha: &[f64], l: usize, r: usize) {
    by_rows!(r, pivot_rows_r, binv, alpha, l, r)
}

#[inline(always)]
fn pivot_rows_r<const R: usize>(binv: &mut [f64], alpha: &[f64], l: usize, r: usize) {
    let r = if R > 0 { R } else { r };
    if r > 16 {
        return pivot_rows_wide(binv, alpha, l, r);
    }
    let (binv, alpha) = (&mut binv[..r * r], &alpha[..r]);
    let al = alpha[l];
    // Row l after the division, copied (the other rows are updated from it).
    let mut buf = [0.0f64; 16];
    let row = &mut buf[..r];
    for k in 0..r {
        binv[l * r + k] /= al;
        row[k] = binv[l * r + k];
    }
    for t in 0..r {
        let f = alpha[t];
        if t != l && f != 0.0 {
            for k in 0..r {
                binv[t * r + k] -= f * row[k];
            }
        }
    }
}

/// [`pivot_rows`] for r > 16.
fn pivot_rows_wide(binv: &mut [f64], alpha: &[f64], l: usize, r: usize) {
    let al = alpha[l];
    for k in 0..r {
        binv[l * r + k] /= al;
    }
    for t in 0..r {
        let f = alpha[t];
        if t != l && f != 0.0 {
            for k in 0..r {
                binv[t * r + k] -= f * binv[l * r + k];
            }
        }
    }
}

/// Invert the r × r row-major matrix `a` into `inv` ([`crate::linalg::Lu`]); false if a
/// pivot is below 1e-12 in magnitude (numerically singular at the transformed columns' unit
/// scale) or not finite.
/// `lu` is the workspace (no allocation once it has held an r × r factorisation).
pub(super) fn invert(lu: &mut crate::linalg::Lu, a: &[f64], inv: &mut [f64], r: usize) -> bool {
    if !lu.factor(a, r) || lu.min_pivot().is_nan() || lu.min_pivot() < 1e-12 {
        return false;
    }
    lu.inverse(inv);
    true
}

/// The basis inverse B⁻¹ (row-major r × r) of the fast simplex: a fresh factorisation of a
/// basis, kept up to date by pivots (product-form updates), and whether it is still exactly the
/// fresh factorisation of the basis it was computed for.
pub(super) struct BasisInverse {
    /// B⁻¹, row-major: `inv[t*r + k]`.
    pub(super) inv: Vec<f64>,
    /// B itself, column t = a_{B_t} (the factorisation's input).
    bmat: Vec<f64>,
    lu: crate::linalg::Lu,
    /// The basis of the last fresh factorisation.
    factored: Vec<usize>,
    /// `inv` is that factorisation (no pivot since, and it held no artificial column).
    fresh: bool,
    /// ‖B‖_F ‖B⁻¹‖_F of the last factorisation.
    pub(super) cond: f64,
}

impl BasisInverse {
    pub(super) fn new(r: usize) -> BasisInverse {
        BasisInverse {
            inv: vec![0.0; r * r],
            bmat: vec![0.0; r * r],
            lu: Default::default(),
            factored: vec![usize::MAX; r],
            fresh: false,
            cond: f64::INFINITY,
        }
    }

    /// Factorise B = [a_{B_0} … a_{B_{r−1}}] (`column(i)` = a_i) and invert it: false when a
    /// pivot is below 1e-12 or ‖B‖_F·‖B⁻¹‖_F ≥ `max_cond` (weights from such a basis carry
    /// errors of cond·ε). The result counts as fresh unless the basis holds `artificial`.
    pub(super) fn factor<'a>(
        &mut self,
        basis: &[usize],
        column: impl Fn(usize) -> &'a [f64],
        artificial: usize,
        max_cond: f64,
    ) -> bool {
        let r = basis.len();
        for (t, &bt) in basis.iter().enumerate() {
            for (k, &v) in column(bt)[..r].iter().enumerate() {
                self.bmat[k * r + t] = v;
            }
        }
        let bnorm = norm(&self.bmat);
        let ok = invert(&mut self.lu, &self.bmat, &mut self.inv, r) && {
            self.cond = bnorm * norm(&self.inv);
            self.cond < max_cond
        };
        self.factored.copy_from_slice(basis);
        self.fresh = ok && !basis.contains(&artificial);
        ok
    }

    /// `inv` is the fresh factorisation of exactly `basis`.
    pub(super) fn is_fresh_for(&self, basis: &[usize]) -> bool {
        self.fresh && basis == self.factored
    }

    /// out = B⁻¹ v.
    #[inline]
    pub(super) fn apply(&self, v: &[f64], out: &mut [f64]) {
        mat_vec(&self.inv, v, out, self.factored.len())
    }

    /// Column q replaces basis position l: the pivot update with α = B⁻¹ a_q.
    #[inline]
    pub(super) fn pivot(&mut self, alpha: &[f64], l: usize) {
        pivot_rows(&mut self.inv, alpha, l, self.factored.len());
        self.fresh = false;
    }
}

/// Least squares min ‖A w − c‖ for the column-major r × k matrix `a` (k ≤ r) by modified
/// Gram–Schmidt with reorthogonalisation, using the scratch `q` (r·k) and `rm` (k·k); false if
/// the columns are numerically dependent.
pub(super) fn least_squares(
    a: &[f64],
    r: usize,
    k: usize,
    c: &[f64],
    q: &mut [f64],
    rm: &mut [f64],
    w: &mut [f64],
) -> bool {
    rm[..k * k].iter_mut().for_each(|v| *v = 0.0);
    for j in 0..k {
        let (done, rest) = q.split_at_mut(j * r);
        let v = &mut rest[..r];
        v.copy_from_slice(&a[j * r..(j + 1) * r]);
        let n0 = norm(v);
        for _pass in 0..2 {
            for i in 0..j {
                let qi = &done[i * r..(i + 1) * r];
                let h = dot(qi, v);
                rm[i * k + j] += h;
                for (vv, qq) in v.iter_mut().zip(qi) {
                    *vv -= h * qq;
                }
            }
        }
        let nv = norm(v);
        if nv.is_nan() || nv <= 1e-13 * n0 {
            return false;
        }
        rm[j * k + j] = nv;
        let inv = 1.0 / nv;
        v.iter_mut().for_each(|x| *x *= inv);
    }
    for j in 0..k {
        w[j] = dot(&q[j * r..(j + 1) * r], &c[..r]);
    }
    for j in (0..k).rev() {
        let mut acc = w[j];
        for l in j + 1..k {
            acc -= rm[j * k + l] * w[l];
        }
        w[j] = acc / rm[j * k + j];
    }
    true
}

/// Complete the grid columns `cols` (independent) to a basis of r columns by greedily adding the
/// column with the largest component orthogonal to the span so far, first from `first` (such as
/// the cold-start basis of maximal volume: r candidates instead of the grid), then, if those do
/// not complete it, from every column; None if that fails.
pub(super) fn complete_basis(
    rows: &[f64],
    n: usize,
    r: usize,
    cols: &[usize],
    first: &[usize],
) -> Option<Vec<usize>> {
    complete_from(rows, r, cols, first.iter().copied())
        .or_else(|| complete_from(rows, r, cols, 0..n))
}

/// [`complete_basis`] from the columns `candidates` (in index order among equals).
fn complete_from(
    rows: &[f64],
    r: usize,
    cols: &[usize],
    candidates: impl Iterator<Item = usize> + Clone,
) -> Option<Vec<usize>> {
    let mut basis: Vec<usize> = cols.to_vec();
    let mut q: Vec<Vec<f64>> = Vec::with_capacity(r);
    for &i in cols {
        if !push_orthonormal(&rows[i * r..(i + 1) * r], &mut q) {
            return None;
        }
    }
    // res[i]: squared residual of candidate i after projecting out q, updated per new vector.
    let mut res: Vec<(usize, f64)> = candidates
        .map(|i| {
            let row = &rows[i * r..(i + 1) * r];
            (
                i,
                q.iter()
                    .fold(dot(row, row), |v, qi| v - dot(qi, row).powi(2)),
            )
        })
        .collect();
    while basis.len() < r {
        let mut best = None;
        let mut best_v = 0.0;
        for &(i, v) in &res {
            if v > best_v && !basis.contains(&i) {
                best_v = v;
                best = Some(i);
            }
        }
        let i = best?;
        if !push_orthonormal(&rows[i * r..(i + 1) * r], &mut q) {
            return None;
        }
        basis.push(i);
        if basis.len() < r {
            let qn = &q[q.len() - 1];
            for (k, v) in res.iter_mut() {
                *v -= dot(qn, &rows[*k * r..(*k + 1) * r]).powi(2);
            }
        }
    }
    Some(basis)
}

/// Append to the orthonormal vectors `q` the normalised component of v orthogonal to them (two
/// Gram–Schmidt passes); false when it is below 1e-10 ‖v‖ (v dependent on q).
fn push_orthonormal(v: &[f64], q: &mut Vec<Vec<f64>>) -> bool {
    let mut v = v.to_vec();
    let n0 = norm(&v);
    for _ in 0..2 {
        for qi in q.iter() {
            let h = dot(qi, &v);
            for (a, b) in v.iter_mut().zip(qi) {
                *a -= h * b;
            }
        }
    }
    let nv = norm(&v);
    if nv.is_nan() || nv <= 1e-10 * n0 {
        return false;
    }
    v.iter_mut().for_each(|a| *a /= nv);
    q.push(v);
    true
}

/// r rows of the row-major n × r matrix with (greedily) maximal volume: a well-conditioned
/// cold-start basis.
pub(super) fn max_volume_rows(rows: &[f64], n: usize, r: usize) -> Vec<usize> {
    let mut res = rows.to_vec();
    let mut chosen = Vec::with_capacity(r);
    for _ in 0..r {
        let mut best = 0usize;
        let mut best_v = -1.0;
        for i in 0..n {
            if chosen.contains(&i) {
                continue;
            }
            let v = norm(&res[i * r..(i + 1) * r]);
            if v > best_v {
                best_v = v;
                best = i;
            }
        }
        chosen.push(best);
        let pivot: Vec<f64> = res[best * r..(best + 1) * r].to_vec();
        let pn = norm(&pivot);
        if pn == 0.0 {
            continue;
        }
        let unit: Vec<f64> = pivot.iter().map(|v| v / pn).collect();
        for i in 0..n {
            let row = &mut res[i * r..(i + 1) * r];
            let h = dot(row, &unit);
            for (a, u) in row.iter_mut().zip(&unit) {
                *a -= h * u;
            }
        }
    }
    chosen
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Completion on the rows (1, i, i²), i = 0..4, by the largest residual: from the
    /// candidates first ({1} with 2 and 4: residuals 14/3 and 126, so 4 then 2), from the grid
    /// when the candidates cannot complete it ({2} with only 2 itself: 4, residual 19.2, then 0),
    /// and None for dependent columns.
    #[test]
    fn complete_basis_prefers_the_candidates() {
        let rows: Vec<f64> = (0..5)
            .flat_map(|i| [1.0, i as f64, (i * i) as f64])
            .collect();
        assert_eq!(
            complete_basis(&rows, 5, 3, &[1], &[2, 4]),
            Some(vec![1, 4, 2])
        );
        assert_eq!(complete_basis(&rows, 5, 3, &[2], &[2]), Some(vec![2, 4, 0]));
        assert_eq!(complete_basis(&rows, 5, 3, &[2], &[]), Some(vec![2, 4, 0]));
        assert_eq!(complete_basis(&rows, 5, 3, &[1, 1], &[0, 4]), None);
    }

    /// Columns of a 3-row LP: a_i = (1, i, i²) for i = 0..4, and an "artificial" (index 9).
    fn column(i: usize) -> &'static [f64] {
        const COLS: [[f64; 3]; 5] = [
            [1.0, 0.0, 0.0],
            [1.0, 1.0, 1.0],
            [1.0, 2.0, 4.0],
            [1.0, 3.0, 9.0],
            [1.0, 4.0, 16.0],
        ];
        const ART: [f64; 3] = [0.0, 0.0, 1.0];
        if i == 9 {
            &ART
        } else {
            &COLS[i]
        }
    }

    #[test]
    fn basis_inverse_factors_updates_and_knows_when_it_is_fresh() {
        let mut b = BasisInverse::new(3);
        // B = [a_0 a_1 a_2] = [[1,1,1],[0,1,2],[0,1,4]]: B⁻¹ = [[1,-1.5,0.5],[0,2,-1],[0,-0.5,0.5]].
        assert!(b.factor(&[0, 1, 2], column, 9, 1e12));
        let want = [1.0, -1.5, 0.5, 0.0, 2.0, -1.0, 0.0, -0.5, 0.5];
        for (g, w) in b.inv.iter().zip(want) {
            assert!((g - w).abs() < 1e-15, "{:?}", b.inv);
        }
        assert!(b.is_fresh_for(&[0, 1, 2]));
        assert!(!b.is_fresh_for(&[0, 1, 3]));
        // a_3 replaces position 1: the update equals a fresh inverse of [a_0 a_3 a_2].
        let mut alpha = [0.0; 3];
        b.apply(column(3), &mut alpha);
        assert_eq!(alpha, [1.0, -3.0, 3.0]); // a_3 = a_0 − 3a_1 + 3a_2
        b.pivot(&alpha, 1);
        assert!(!b.is_fresh_for(&[0, 3, 2]));
        let mut fresh = BasisInverse::new(3);
        assert!(fresh.factor(&[0, 3, 2], column, 9, 1e12));
        for (u, f) in b.inv.iter().zip(&fresh.inv) {
            assert!((u - f).abs() < 1e-14, "{:?} vs {:?}", b.inv, fresh.inv);
        }
        // A basis with the artificial column is factorised but never counts as fresh.
        assert!(b.factor(&[0, 1, 9], column, 9, 1e12));
        assert!(!b.is_fresh_for(&[0, 1, 9]));
        // Singular (a repeated column) and too ill-conditioned bases are refused.
        assert!(!b.factor(&[0, 1, 1], column, 9, 1e12));
        assert!(!b.factor(&[0, 1, 2], column, 9, 10.0));
    }
}
