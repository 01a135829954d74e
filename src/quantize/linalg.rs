//! Small dense linear algebra for m×m transforms (m ≤ ~12): LU with partial pivoting,
//! determinants, inverses. Row-major `Vec<Vec<f64>>` matrices.

/// LU factorisation P·A = L·U of a square matrix (partial pivoting).
#[derive(Clone, Debug)]
pub struct Lu {
    lu: Vec<Vec<f64>>,
    perm: Vec<usize>,
    sign: f64,
}

impl Lu {
    /// Factorise `a` (n×n). Returns `None` if a pivot is exactly zero or not finite.
    pub fn new(a: &[Vec<f64>]) -> Option<Lu> {
        let n = a.len();
        let mut lu: Vec<Vec<f64>> = a.to_vec();
        let mut perm: Vec<usize> = (0..n).collect();
        let mut sign = 1.0;
        for k in 0..n {
            if lu[k].len() != n {
                return None;
            }
            let p = (k..n).max_by(|&i, &j| lu[i][k].abs().total_cmp(&lu[j][k].abs()))?;
            let piv = lu[p][k];
            if piv == 0.0 || !piv.is_finite() {
                return None;
            }
            if p != k {
                lu.swap(p, k);
                perm.swap(p, k);
                sign = -sign;
            }
            for i in k + 1..n {
                let f = lu[i][k] / lu[k][k];
                lu[i][k] = f;
                for j in k + 1..n {
                    lu[i][j] -= f * lu[k][j];
                }
            }
        }
        Some(Lu { lu, perm, sign })
    }

    /// log₂|det A| and the sign of det A.
    pub fn log2_abs_det(&self) -> (f64, f64) {
        let mut l = 0.0;
        let mut s = self.sign;
        for (k, row) in self.lu.iter().enumerate() {
            l += row[k].abs().log2();
            if row[k] < 0.0 {
                s = -s;
            }
        }
        (l, s)
    }

    pub fn det(&self) -> f64 {
        let (l, s) = self.log2_abs_det();
        s * l.exp2()
    }

    /// Solve A x = b.
    pub fn solve(&self, b: &[f64]) -> Vec<f64> {
        let n = self.lu.len();
        let mut x: Vec<f64> = self.perm.iter().map(|&p| b[p]).collect();
        for i in 0..n {
            for j in 0..i {
                x[i] -= self.lu[i][j] * x[j];
            }
        }
        for i in (0..n).rev() {
            for j in i + 1..n {
                x[i] -= self.lu[i][j] * x[j];
            }
            x[i] /= self.lu[i][i];
        }
        x
    }

    /// Solve Aᵀ x = b.
    pub fn solve_transposed(&self, b: &[f64]) -> Vec<f64> {
        let n = self.lu.len();
        // Aᵀ = Uᵀ Lᵀ P, so solve Uᵀ y = b, Lᵀ w = y, x = Pᵀ w.
        let mut y = b.to_vec();
        for i in 0..n {
            for j in 0..i {
                y[i] -= self.lu[j][i] * y[j];
            }
            y[i] /= self.lu[i][i];
        }
        for i in (0..n).rev() {
            for j in i + 1..n {
                y[i] -= self.lu[j][i] * y[j];
            }
        }
        let mut x = vec![0.0; n];
        for (i, &p) in self.perm.iter().enumerate() {
            x[p] = y[i];
        }
        x
    }

    /// A⁻¹ (row-major).
    pub fn inverse(&self) -> Vec<Vec<f64>> {
        let n = self.lu.len();
        let mut inv = vec![vec![0.0; n]; n];
        let mut e = vec![0.0; n];
        for j in 0..n {
            e.iter_mut().for_each(|v| *v = 0.0);
            e[j] = 1.0;
            let col = self.solve(&e);
            for i in 0..n {
                inv[i][j] = col[i];
            }
        }
        inv
    }
}

/// y = A x.
pub fn mat_vec(a: &[Vec<f64>], x: &[f64]) -> Vec<f64> {
    a.iter()
        .map(|r| r.iter().zip(x).map(|(p, q)| p * q).sum())
        .collect()
}

/// C = A B.
pub fn mat_mul(a: &[Vec<f64>], b: &[Vec<f64>]) -> Vec<Vec<f64>> {
    let k = b.len();
    let n = if k > 0 { b[0].len() } else { 0 };
    a.iter()
        .map(|r| {
            (0..n)
                .map(|j| (0..k).map(|l| r[l] * b[l][j]).sum())
                .collect()
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};

    #[test]
    fn inverse_and_transposed_solve_agree_with_products() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        for n in 1..8 {
            for _ in 0..50 {
                let a: Vec<Vec<f64>> = (0..n)
                    .map(|_| (0..n).map(|_| rng.gen_range(-3.0..3.0)).collect())
                    .collect();
                let lu = Lu::new(&a).unwrap();
                let inv = lu.inverse();
                let p = mat_mul(&a, &inv);
                for (i, row) in p.iter().enumerate() {
                    for (j, v) in row.iter().enumerate() {
                        let e = if i == j { 1.0 } else { 0.0 };
                        assert!((v - e).abs() < 1e-8, "n={n} {v}");
                    }
                }
                let b: Vec<f64> = (0..n).map(|_| rng.gen_range(-1.0..1.0)).collect();
                let x = lu.solve_transposed(&b);
                // Aᵀ x = b
                for j in 0..n {
                    let s: f64 = (0..n).map(|i| a[i][j] * x[i]).sum();
                    assert!((s - b[j]).abs() < 1e-8);
                }
            }
        }
        // det of a known matrix
        let a = vec![vec![1.0, 0.0], vec![4.0, -4.0]];
        assert!((Lu::new(&a).unwrap().det() + 4.0).abs() < 1e-12);
        assert!(Lu::new(&[vec![1.0, 2.0], vec![2.0, 4.0]]).is_none());
    }
}
