//! Degenerate and duplicate candidates, decided on the LP grid.
//!
//! Algorithm 1 constrains w by Ā = (1; b(z_1) … b(z_n)) (Section 3.1). A candidate is
//! *degenerate* when Ā is numerically rank-deficient (some function is, to relative tolerance
//! `tol`, an affine combination of the others on the grid). Two candidates with the same affine
//! span V = span{1, b_1, …, b_m} on the grid have moments related by an invertible affine map, so
//! their feasible sets and G coincide: the sweep scores the *canonical* member of V only — the
//! componentwise smallest set of m catalog functions spanning V (matroid greedy; smallest in
//! both lexicographic and colexicographic order, hence the smallest candidate index) — and
//! flags every other member as its duplicate. The sweep also applies the basis module's
//! degeneracy check (`basis::candidates::analyze_values`); a candidate is degenerate if either
//! check says so.
//!
//! Implementation: one Householder QR of the column-normalised n × (N+1) matrix
//! (1, f_1, …, f_N) gives coordinates r_j ∈ R^(N+1) with ⟨f_i, f_j⟩ = ⟨r_i, r_j⟩ (Q orthonormal),
//! so each candidate costs a Gram–Schmidt in R^(N+1) instead of R^n.

use super::FunctionTable;
use crate::linalg::dot;

/// Rank and span decisions for subsets of a [`FunctionTable`].
#[derive(Clone, Debug)]
pub struct SpanAnalyzer {
    /// coords[0] = constant function, coords[j+1] = function j; unit norm over the grid.
    coords: Vec<Vec<f64>>,
    tol: f64,
}

/// How a candidate is treated by the sweep.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Flag {
    /// Scored.
    Ok,
    /// Numerically rank-deficient on the grid: not solved.
    Degenerate,
    /// Same affine span on the grid as the lexicographically smaller candidate (its subset).
    DuplicateOf(Vec<usize>),
}

impl SpanAnalyzer {
    /// `tol`: relative residual below which a function counts as lying in a span (e.g. 1e-9).
    pub fn new(table: &FunctionTable, tol: f64) -> SpanAnalyzer {
        let n = table.grid().len();
        let p = table.len() + 1;
        // Column-major n × p, each column normalised to unit Euclidean norm over the grid.
        let mut a: Vec<Vec<f64>> = (0..p)
            .map(|j| {
                let mut col: Vec<f64> = (0..n)
                    .map(|i| if j == 0 { 1.0 } else { table.value(i, j - 1) })
                    .collect();
                let norm = col.iter().map(|v| v * v).sum::<f64>().sqrt();
                if norm > 0.0 {
                    col.iter_mut().for_each(|v| *v /= norm);
                }
                col
            })
            .collect();
        // Householder QR: after step k, rows k.. of columns > k are transformed; R = upper part.
        let steps = n.min(p);
        for k in 0..steps {
            let x = &a[k][k..];
            let alpha = x.iter().map(|v| v * v).sum::<f64>().sqrt();
            if alpha == 0.0 {
                continue;
            }
            let alpha = if x[0] > 0.0 { -alpha } else { alpha };
            let mut v: Vec<f64> = x.to_vec();
            v[0] -= alpha;
            let vnorm2: f64 = v.iter().map(|t| t * t).sum();
            if vnorm2 == 0.0 {
                continue;
            }
            for col in a.iter_mut().skip(k) {
                let s: f64 = v.iter().zip(&col[k..]).map(|(a, b)| a * b).sum::<f64>();
                let f = 2.0 * s / vnorm2;
                for (c, vi) in col[k..].iter_mut().zip(&v) {
                    *c -= f * vi;
                }
            }
        }
        let coords = a.into_iter().map(|col| col[..steps].to_vec()).collect();
        SpanAnalyzer { coords, tol }
    }

    /// Orthonormal basis of span{1, f_c : c ∈ cols} in coordinates, or `None` if the set
    /// (with the constant) is numerically dependent.
    fn basis(&self, cols: &[usize]) -> Option<Vec<Vec<f64>>> {
        let mut q: Vec<Vec<f64>> = Vec::with_capacity(cols.len() + 1);
        for j in std::iter::once(0).chain(cols.iter().map(|c| c + 1)) {
            let r = residual(&q, &self.coords[j]);
            let norm = dot(&r, &r).sqrt();
            if norm <= self.tol {
                return None;
            }
            q.push(r.into_iter().map(|v| v / norm).collect());
        }
        Some(q)
    }

    /// The flag of the candidate `cols` (sorted, distinct function indices).
    pub fn flag(&self, cols: &[usize]) -> Flag {
        let Some(v) = self.basis(cols) else {
            return Flag::Degenerate;
        };
        // Greedy: smallest function indices lying in V and independent of those chosen.
        let mut chosen: Vec<usize> = Vec::with_capacity(cols.len());
        let mut q: Vec<Vec<f64>> = vec![self.coords[0].clone()];
        for k in 0..self.coords.len() - 1 {
            if chosen.len() == cols.len() {
                break;
            }
            let x = &self.coords[k + 1];
            let in_v = residual(&v, x);
            if dot(&in_v, &in_v).sqrt() > self.tol {
                continue;
            }
            let r = residual(&q, x);
            let norm = dot(&r, &r).sqrt();
            if norm <= self.tol {
                continue;
            }
            q.push(r.into_iter().map(|t| t / norm).collect());
            chosen.push(k);
        }
        if chosen.len() == cols.len() && chosen != cols {
            Flag::DuplicateOf(chosen)
        } else {
            Flag::Ok
        }
    }
}

/// x minus its projection onto the orthonormal vectors q (Gram–Schmidt, twice for stability).
fn residual(q: &[Vec<f64>], x: &[f64]) -> Vec<f64> {
    let mut r = x.to_vec();
    for _ in 0..2 {
        for qi in q {
            let s = dot(qi, &r);
            for (a, b) in r.iter_mut().zip(qi) {
                *a -= s * b;
            }
        }
    }
    r
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Grid;

    fn table() -> FunctionTable {
        // 0: z, 1: z^2, 2: 1-z (affine in z), 3: sin^2(pi z), 4: cos(2 pi z) (= 1 - 2 sin^2),
        // 5: exp(z), 6: 2z^2 + 3 (affine in z^2)
        let names = [
            "z",
            "z^2",
            "1-z",
            "sin^2(pi z)",
            "cos(2 pi z)",
            "exp(z)",
            "2z^2+3",
        ];
        let pi = std::f64::consts::PI;
        FunctionTable::new(
            &Grid::uniform(64).unwrap(),
            names.iter().map(|s| s.to_string()).collect(),
            |j, z| match j {
                0 => z,
                1 => z * z,
                2 => 1.0 - z,
                3 => (pi * z).sin().powi(2),
                4 => (2.0 * pi * z).cos(),
                5 => z.exp(),
                _ => 2.0 * z * z + 3.0,
            },
        )
        .unwrap()
    }

    #[test]
    fn degenerate_and_duplicates_are_found() {
        let s = SpanAnalyzer::new(&table(), 1e-9);
        assert_eq!(s.flag(&[0, 1]), Flag::Ok);
        assert_eq!(s.flag(&[0, 2]), Flag::Degenerate); // z and 1-z
        assert_eq!(s.flag(&[1, 6]), Flag::Degenerate);
        assert_eq!(s.flag(&[0, 1, 6]), Flag::Degenerate);
        assert_eq!(s.flag(&[1, 2]), Flag::DuplicateOf(vec![0, 1])); // span{1,z^2,1-z}
        assert_eq!(s.flag(&[2, 6]), Flag::DuplicateOf(vec![0, 1]));
        assert_eq!(s.flag(&[0, 4]), Flag::DuplicateOf(vec![0, 3]));
        assert_eq!(s.flag(&[4, 5]), Flag::DuplicateOf(vec![3, 5]));
        assert_eq!(s.flag(&[3, 5]), Flag::Ok);
        assert_eq!(s.flag(&[0, 1, 5]), Flag::Ok); // exp is not a quadratic
    }

    /// Brute force on random subsets: the flag agrees with ranks of explicit grid matrices.
    #[test]
    fn agrees_with_brute_force_rank() {
        let t = table();
        let s = SpanAnalyzer::new(&t, 1e-9);
        let n = t.grid().len();
        let rank = |cols: &[usize]| -> usize {
            // Gram–Schmidt directly on grid vectors (independent of the QR coordinates).
            let mut q: Vec<Vec<f64>> = Vec::new();
            for c in std::iter::once(None).chain(cols.iter().map(|&c| Some(c))) {
                let x: Vec<f64> = (0..n).map(|i| c.map_or(1.0, |c| t.value(i, c))).collect();
                let xn = dot(&x, &x).sqrt();
                let r = residual(&q, &x);
                let rn = dot(&r, &r).sqrt();
                if rn > 1e-9 * xn {
                    q.push(r.iter().map(|v| v / rn).collect());
                }
            }
            q.len()
        };
        for m in 1..=4 {
            for (_, c) in crate::search::select::all_subsets(t.len(), m) {
                let full = rank(&c) == m + 1;
                match s.flag(&c) {
                    Flag::Degenerate => assert!(!full, "{c:?}"),
                    Flag::Ok => assert!(full, "{c:?}"),
                    Flag::DuplicateOf(d) => {
                        assert!(full && d < c, "{c:?} -> {d:?}");
                        // Same span: the union has rank m+1.
                        let mut u = c.clone();
                        u.extend(&d);
                        u.sort();
                        u.dedup();
                        assert_eq!(rank(&u), m + 1, "{c:?} vs {d:?}");
                        assert_eq!(s.flag(&d), Flag::Ok);
                    }
                }
            }
        }
    }
}
