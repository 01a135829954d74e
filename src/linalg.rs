//! The one small dense LU of the crate: P A = L U with partial pivoting for r ≤ [`MAX_ROWS`]
//! rows (the LP's basis matrices, the quantization transforms, the stability study's
//! inverses), with solves for A and Aᵀ, the inverse and log₂|det A|. Sizes up to 9 are
//! unrolled at compile time; every size runs the same operations in the same order.

#![allow(clippy::needless_range_loop)] // index-heavy dense linear algebra on tiny matrices

/// Largest number of rows.
pub const MAX_ROWS: usize = 32;

/// `f::<R>(r, args)` with R = r for r ≤ 9 (loops unrolled at compile time), else `f::<0>`
/// (any r): the same operations in the same order either way.
macro_rules! by_size {
    ($r:expr, $f:ident, $($arg:expr),*) => {
        match $r {
            1 => $f::<1>(1, $($arg),*),
            2 => $f::<2>(2, $($arg),*),
            3 => $f::<3>(3, $($arg),*),
            4 => $f::<4>(4, $($arg),*),
            5 => $f::<5>(5, $($arg),*),
            6 => $f::<6>(6, $($arg),*),
            7 => $f::<7>(7, $($arg),*),
            8 => $f::<8>(8, $($arg),*),
            9 => $f::<9>(9, $($arg),*),
            r => $f::<0>(r, $($arg),*),
        }
    };
}

/// LU factorisation P A = L U of a row-major r × r matrix with partial pivoting.
#[derive(Clone, Debug, Default)]
pub struct Lu {
    r: usize,
    lu: Vec<f64>,
    perm: Vec<usize>,
    /// Sign of the permutation P (±1).
    sign: f64,
}

impl Lu {
    /// Factorise `a` (row-major r × r); false if a pivot is exactly zero or not finite.
    pub fn factor(&mut self, a: &[f64], r: usize) -> bool {
        if r > MAX_ROWS {
            return false;
        }
        self.r = r;
        self.sign = 1.0;
        self.lu.clear();
        self.lu.extend_from_slice(&a[..r * r]);
        self.perm.clear();
        self.perm.extend(0..r);
        let lu = &mut self.lu;
        for k in 0..r {
            let p = (k..r)
                .max_by(|&i, &j| lu[i * r + k].abs().total_cmp(&lu[j * r + k].abs()))
                .unwrap_or(k);
            let piv = lu[p * r + k];
            if piv == 0.0 || !piv.is_finite() {
                return false;
            }
            if p != k {
                for c in 0..r {
                    lu.swap(p * r + c, k * r + c);
                }
                self.perm.swap(p, k);
                self.sign = -self.sign;
            }
            for i in k + 1..r {
                let l = lu[i * r + k] / piv;
                lu[i * r + k] = l;
                for c in k + 1..r {
                    lu[i * r + c] -= l * lu[k * r + c];
                }
            }
        }
        true
    }

    /// max |u_kk| / min |u_kk| over the pivots of the last factorisation: a lower bound on
    /// the condition of A (∞ before any factorisation).
    pub fn pivot_ratio(&self) -> f64 {
        let r = self.r;
        let d = (0..r).map(|k| self.lu[k * r + k].abs());
        let (lo, hi) = d.fold((f64::INFINITY, 0.0f64), |(lo, hi), v| {
            (lo.min(v), hi.max(v))
        });
        if r == 0 || lo == 0.0 {
            f64::INFINITY
        } else {
            hi / lo
        }
    }

    /// log₂|det A| and the sign of det A, from the pivots of the last factorisation.
    pub fn log2_abs_det(&self) -> (f64, f64) {
        let r = self.r;
        let mut l = 0.0;
        let mut s = self.sign;
        for k in 0..r {
            let u = self.lu[k * r + k];
            l += u.abs().log2();
            if u < 0.0 {
                s = -s;
            }
        }
        (l, s)
    }

    /// A⁻¹, row-major, column by column from the factorisation.
    pub fn inverse(&self, inv: &mut [f64]) {
        let r = self.r;
        let mut e = [0.0f64; MAX_ROWS];
        for j in 0..r {
            e[..r].iter_mut().for_each(|v| *v = 0.0);
            e[j] = 1.0;
            self.solve(&mut e[..r]);
            for i in 0..r {
                inv[i * r + j] = e[i];
            }
        }
    }

    /// The factorisation of a square matrix given as rows; None when the rows are not square,
    /// a pivot is exactly zero or not finite, or there are more than [`MAX_ROWS`] rows.
    pub fn factor_rows(a: &[Vec<f64>]) -> Option<Lu> {
        let n = a.len();
        if a.iter().any(|row| row.len() != n) {
            return None;
        }
        let flat: Vec<f64> = a.iter().flatten().copied().collect();
        let mut lu = Lu::default();
        lu.factor(&flat, n).then_some(lu)
    }

    /// A⁻¹ as rows.
    pub fn inverse_rows(&self) -> Vec<Vec<f64>> {
        let n = self.r;
        let mut inv = vec![0.0; n * n];
        self.inverse(&mut inv);
        inv.chunks(n.max(1)).map(|r| r.to_vec()).collect()
    }

    /// min |u_kk| over the pivots of the last factorisation (0 before any).
    pub fn min_pivot(&self) -> f64 {
        let r = self.r;
        (0..r)
            .map(|k| self.lu[k * r + k].abs())
            .fold(if r == 0 { 0.0 } else { f64::INFINITY }, f64::min)
    }

    /// Solve A x = b in place (x holds b on entry).
    pub fn solve(&self, x: &mut [f64]) {
        by_size!(self.r, lu_solve, &self.lu, &self.perm, x)
    }

    /// Solve Aᵀ x = b in place (x holds b on entry).
    pub fn solve_t(&self, x: &mut [f64]) {
        by_size!(self.r, lu_solve_t, &self.lu, &self.perm, x)
    }
}

/// L U y = P b by forward then back substitution, in place in x (R = r, or 0 for any r).
#[inline(always)]
fn lu_solve<const R: usize>(r: usize, lu: &[f64], perm: &[usize], x: &mut [f64]) {
    let r = if R > 0 { R } else { r };
    let (lu, perm) = (&lu[..r * r], &perm[..r]);
    let mut y = [0.0f64; MAX_ROWS];
    for i in 0..r {
        y[i] = x[perm[i]];
    }
    for i in 0..r {
        for c in 0..i {
            y[i] -= lu[i * r + c] * y[c];
        }
    }
    for i in (0..r).rev() {
        for c in i + 1..r {
            y[i] -= lu[i * r + c] * y[c];
        }
        y[i] /= lu[i * r + i];
    }
    x[..r].copy_from_slice(&y[..r]);
}

/// (P⁻¹ L U)ᵀ x = b: Uᵀ z = b, Lᵀ w = z, x = Pᵀ w, in place (R = r, or 0 for any r).
#[inline(always)]
fn lu_solve_t<const R: usize>(r: usize, lu: &[f64], perm: &[usize], x: &mut [f64]) {
    let r = if R > 0 { R } else { r };
    let (lu, perm) = (&lu[..r * r], &perm[..r]);
    let mut y = [0.0f64; MAX_ROWS];
    y[..r].copy_from_slice(&x[..r]);
    for i in 0..r {
        for c in 0..i {
            y[i] -= lu[c * r + i] * y[c];
        }
        y[i] /= lu[i * r + i];
    }
    for i in (0..r).rev() {
        for c in i + 1..r {
            y[i] -= lu[c * r + i] * y[c];
        }
    }
    for i in 0..r {
        x[perm[i]] = y[i];
    }
}

/// a·b = Σ a_i b_i over the common length, summed left to right.
pub fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// 3-vectors `[x, y, z]`: the one implementation of their products for the renderer, the
/// scene builder and the quantization hulls.
pub mod v3 {
    /// A 3-vector.
    pub type V3 = [f64; 3];

    /// a + b.
    pub fn add(a: V3, b: V3) -> V3 {
        [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
    }
    /// a − b.
    pub fn sub(a: V3, b: V3) -> V3 {
        [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
    }
    /// s·a.
    pub fn scale(a: V3, s: f64) -> V3 {
        [a[0] * s, a[1] * s, a[2] * s]
    }
    /// a·b = a_x b_x + a_y b_y + a_z b_z (in that order).
    pub fn dot(a: V3, b: V3) -> f64 {
        a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
    }
    /// a × b.
    pub fn cross(a: V3, b: V3) -> V3 {
        [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ]
    }
    /// ‖a‖₂ = √(a·a).
    pub fn norm(a: V3) -> f64 {
        dot(a, a).sqrt()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lu_solves_both_systems() {
        let a = [4.0, 1.0, 2.0, 0.5, 3.0, 1.0, 2.0, -1.0, 5.0];
        let mut lu = Lu::default();
        assert!(lu.factor(&a, 3));
        let b = [1.0, 2.0, 3.0];
        let mut x = b;
        lu.solve(&mut x);
        for i in 0..3 {
            let ax: f64 = (0..3).map(|c| a[i * 3 + c] * x[c]).sum();
            assert!((ax - b[i]).abs() < 1e-14, "row {i}: {ax}");
        }
        let mut y = b;
        lu.solve_t(&mut y);
        for c in 0..3 {
            let aty: f64 = (0..3).map(|i| a[i * 3 + c] * y[i]).sum();
            assert!((aty - b[c]).abs() < 1e-14, "col {c}: {aty}");
        }
        assert!(!lu.factor(&[1.0, 2.0, 2.0, 4.0], 2));
    }

    /// The inverse times A is the identity; det from the pivots and the permutation's sign.
    #[test]
    fn inverse_and_determinant() {
        // det [[0, 2, 1], [1, 1, 0], [3, 0, 1]] = 0·1 − 2·1 + 1·(−3) = −5 (a row swap).
        let a = [0.0, 2.0, 1.0, 1.0, 1.0, 0.0, 3.0, 0.0, 1.0];
        let mut lu = Lu::default();
        assert!(lu.factor(&a, 3));
        let (l, s) = lu.log2_abs_det();
        assert!((s * l.exp2() + 5.0).abs() < 1e-12, "{s} {l}");
        let mut inv = [0.0; 9];
        lu.inverse(&mut inv);
        for i in 0..3 {
            for j in 0..3 {
                let p: f64 = (0..3).map(|k| a[i * 3 + k] * inv[k * 3 + j]).sum();
                assert!(
                    (p - f64::from(u8::from(i == j))).abs() < 1e-14,
                    "{i} {j}: {p}"
                );
            }
        }
        // The first pivot is the largest |a_i0| = 3.
        assert!(lu.min_pivot() > 0.0 && lu.min_pivot() <= 3.0);
        assert!(!lu.factor(&vec![1.0; 33 * 33], 33), "beyond MAX_ROWS");
    }

    /// The 3-vector products: a right-handed cross product orthogonal to both factors.
    #[test]
    fn three_vector_products() {
        use super::v3::*;
        let (a, b) = ([1.0, 2.0, 3.0], [-2.0, 0.5, 4.0]);
        let c = cross(a, b);
        assert_eq!(c, [6.5, -10.0, 4.5]);
        assert_eq!((dot(c, a), dot(c, b)), (0.0, 0.0));
        assert_eq!(cross([1.0, 0.0, 0.0], [0.0, 1.0, 0.0]), [0.0, 0.0, 1.0]);
        assert_eq!(norm([3.0, 4.0, 12.0]), 13.0);
        assert_eq!(add(a, scale(b, 2.0)), sub(a, scale(b, -2.0)));
        assert_eq!(super::dot(&a, &b), dot(a, b));
        assert_eq!(super::dot(&[1.0, 2.0], &[3.0]), 3.0, "common length");
    }
}
