//! Small dense linear algebra for m×m transforms (m ≤ ~12) on row-major `Vec<Vec<f64>>`
//! matrices: the crate's LU ([`crate::linalg::Lu`]) behind that shape, products.

/// LU factorisation P·A = L·U of a square matrix given as rows ([`crate::linalg::Lu`]).
#[derive(Clone, Debug)]
pub struct Lu {
    lu: crate::linalg::Lu,
    n: usize,
}

impl Lu {
    /// Factorise `a` (n×n). Returns `None` if a pivot is exactly zero or not finite, or n is
    /// beyond [`crate::linalg::MAX_ROWS`].
    pub fn new(a: &[Vec<f64>]) -> Option<Lu> {
        crate::linalg::Lu::factor_rows(a).map(|lu| Lu { lu, n: a.len() })
    }

    /// log₂|det A| and the sign of det A.
    pub fn log2_abs_det(&self) -> (f64, f64) {
        self.lu.log2_abs_det()
    }

    /// det A.
    pub fn det(&self) -> f64 {
        let (l, s) = self.log2_abs_det();
        s * l.exp2()
    }

    /// Solve A x = b.
    pub fn solve(&self, b: &[f64]) -> Vec<f64> {
        let mut x = b[..self.n].to_vec();
        self.lu.solve(&mut x);
        x
    }

    /// Solve Aᵀ x = b.
    pub fn solve_transposed(&self, b: &[f64]) -> Vec<f64> {
        let mut x = b[..self.n].to_vec();
        self.lu.solve_t(&mut x);
        x
    }

    /// A⁻¹ (row-major).
    pub fn inverse(&self) -> Vec<Vec<f64>> {
        self.lu.inverse_rows()
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
