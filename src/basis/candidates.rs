//! Candidates: m-subsets {c_1 < … < c_m} of a catalog of N functions (Peters & Klein 2015,
//! Section 3.2: C(37,4) = 66045 candidates), their numbering, and their numerical degeneracy.
//!
//! **Numbering (combinatorial number system, colexicographic order).** A subset of catalog
//! positions c_1 < c_2 < … < c_m (0-based) has index
//!
//!   index = Σ_{k=1..m} C(c_k, k),
//!
//! a bijection onto 0 .. C(N,m)−1. Subsets are ordered by their largest element first
//! (colex): for m = 2 the order is {0,1}, {0,2}, {1,2}, {0,3}, {1,3}, {2,3}, …. The index does
//! not depend on N, so appending functions to the catalog keeps every existing candidate's
//! index, and results computed on different machines (or shards) merge by index.
//!
//! **Degeneracy.** Algorithm 1 constrains Σ w_i = 1 and Σ w_i b(z_i) = b, so the constant
//! function is always part of the span. A candidate is degenerate on a grid when the n×(m+1)
//! matrix A = [1, b_1(z_i), …, b_m(z_i)], each column scaled to unit 2-norm, has
//! σ_min/σ_max < [`DEGENERACY_TOL`] (Householder QR, then one-sided Jacobi SVD of R).
//!
//! **Span signature.** Candidates spanning the same affine function space on the grid
//! (span{1, b_1, …, b_m}) give the same LP results (Problem 1 is invariant under invertible
//! affine maps of b), so the sweep scores each span once. The key: K fixed pseudo-random probe
//! vectors p_k on the grid (depending on the grid index only), y_k = Qᵀp_k with Q an orthonormal
//! basis of the span, and the normalised Gram entries y_k·y_l / (|p_k||p_l|) (a function of the
//! projector QQᵀ only, hence of the span only), rounded to multiples of [`SPAN_QUANTUM`] and
//! hashed (FNV-1a). Keys are comparable only between candidates on the same grid.

use super::{Basis, Function};
use crate::Grid;
use anyhow::{bail, Result};

/// Largest supported candidate size m.
pub const MAX_M: usize = 8;

/// Default candidate size m (the paper's four moments).
pub const DEFAULT_M: usize = 4;

/// Relative singular-value tolerance below which a candidate is degenerate.
pub const DEGENERACY_TOL: f64 = 1e-9;

/// Rounding step of the span-signature invariants (which lie in [−1, 1]).
pub const SPAN_QUANTUM: f64 = 1e-6;

/// Number of probe vectors of the span signature.
const PROBES: usize = 4;

/// Binomial coefficient C(n, k), or None on u64 overflow.
pub fn binomial(n: u64, k: u64) -> Option<u64> {
    if k > n {
        return Some(0);
    }
    let k = k.min(n - k);
    let mut r: u128 = 1;
    for i in 0..k {
        // r·(n−i)/(i+1) stays an integer at every step.
        r = r * (n - i) as u128 / (i + 1) as u128;
        if r > u64::MAX as u128 {
            return None;
        }
    }
    Some(r as u64)
}

/// Number of m-subsets of N functions, C(N, m), or None on overflow.
pub fn checked_count(n: usize, m: usize) -> Option<u64> {
    binomial(n as u64, m as u64)
}

/// Number of m-subsets of N functions, C(N, m) (saturating at u64::MAX).
pub fn count(n: usize, m: usize) -> u64 {
    checked_count(n, m).unwrap_or(u64::MAX)
}

/// Colex index Σ C(c_k, k) of a set of catalog positions (any order; duplicates are an error).
pub fn subset_to_index(subset: &[usize]) -> Result<u64> {
    let mut s = subset.to_vec();
    s.sort_unstable();
    if let Some(w) = s.windows(2).find(|w| w[0] == w[1]) {
        bail!("candidate: position {} appears twice", w[0]);
    }
    let mut index: u64 = 0;
    for (k, &c) in s.iter().enumerate() {
        let term = binomial(c as u64, k as u64 + 1)
            .ok_or_else(|| anyhow::anyhow!("candidate index overflows u64"))?;
        index = index
            .checked_add(term)
            .ok_or_else(|| anyhow::anyhow!("candidate index overflows u64"))?;
    }
    Ok(index)
}

/// The m-subset (sorted catalog positions) with colex index `index` among N functions.
pub fn index_to_subset(n: usize, m: usize, index: u64) -> Result<Vec<usize>> {
    let total = checked_count(n, m).ok_or_else(|| anyhow::anyhow!("C({n},{m}) overflows u64"))?;
    if index >= total {
        bail!("candidate index {index} out of range: C({n},{m}) = {total} candidates");
    }
    let mut out = vec![0; m];
    let mut r = index;
    let mut hi = n; // c_k < hi
    for k in (1..=m).rev() {
        // Largest c < hi with C(c, k) ≤ r (C(k−1, k) = 0 ≤ r always holds).
        let mut c = hi - 1;
        loop {
            let b = binomial(c as u64, k as u64).unwrap_or(u64::MAX);
            if b <= r {
                r -= b;
                break;
            }
            c -= 1;
        }
        out[k - 1] = c;
        hi = c;
    }
    Ok(out)
}

/// Advances a sorted subset to its colex successor among N functions; false after the last.
pub fn next_subset(subset: &mut [usize], n: usize) -> bool {
    let m = subset.len();
    for k in 0..m {
        let limit = if k + 1 < m { subset[k + 1] } else { n };
        if subset[k] + 1 < limit {
            subset[k] += 1;
            for (j, s) in subset.iter_mut().enumerate().take(k) {
                *s = j;
            }
            return true;
        }
    }
    false
}

/// Checks a candidate size m against 1..=[`MAX_M`] and the catalog size N.
pub fn check_m(n: usize, m: usize) -> Result<()> {
    if !(1..=MAX_M).contains(&m) {
        bail!("candidate size m = {m} out of range 1..={MAX_M}");
    }
    if m > n {
        bail!("candidate size m = {m} exceeds the catalog's {n} functions");
    }
    Ok(())
}

/// Numerical rank information of span{1, b_1, …, b_m} on a grid.
#[derive(Clone, Debug, PartialEq)]
pub struct SpanInfo {
    /// σ_min/σ_max of the column-normalised matrix [1, b_1, …, b_m] (0 when n < m+1 or a
    /// column vanishes on the grid).
    pub sigma_ratio: f64,
    /// `sigma_ratio < DEGENERACY_TOL`.
    pub degenerate: bool,
    /// Span signature (None for degenerate candidates).
    pub key: Option<u64>,
}

/// splitmix64: the probe vectors' deterministic pseudo-random source.
fn splitmix(mut x: u64) -> u64 {
    x = x.wrapping_add(0x9E37_79B9_7F4A_7C15);
    x = (x ^ (x >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    x = (x ^ (x >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    x ^ (x >> 31)
}

/// Probe value p_k(i) ∈ [−1, 1).
fn probe(k: usize, i: usize) -> f64 {
    let h = splitmix(((k as u64) << 40) ^ i as u64 ^ 0x6d6f_6d65_6e74);
    (h >> 11) as f64 / (1u64 << 52) as f64 - 1.0
}

/// Singular values of a small square matrix (column-major p×p) by one-sided Jacobi.
fn jacobi_singular_values(a: &mut [f64], p: usize) -> Vec<f64> {
    for _sweep in 0..80 {
        let mut rotated = false;
        for i in 0..p {
            for j in i + 1..p {
                let (mut al, mut be, mut ga) = (0.0, 0.0, 0.0);
                for r in 0..p {
                    let (x, y) = (a[i * p + r], a[j * p + r]);
                    al += x * x;
                    be += y * y;
                    ga += x * y;
                }
                if ga == 0.0 || ga.abs() <= 1e-15 * (al * be).sqrt() {
                    continue;
                }
                rotated = true;
                let zeta = (be - al) / (2.0 * ga);
                let t = zeta.signum() / (zeta.abs() + (1.0 + zeta * zeta).sqrt());
                let c = 1.0 / (1.0 + t * t).sqrt();
                let s = c * t;
                for r in 0..p {
                    let (x, y) = (a[i * p + r], a[j * p + r]);
                    a[i * p + r] = c * x - s * y;
                    a[j * p + r] = s * x + c * y;
                }
            }
        }
        if !rotated {
            break;
        }
    }
    (0..p)
        .map(|j| {
            a[j * p..(j + 1) * p]
                .iter()
                .map(|x| x * x)
                .sum::<f64>()
                .sqrt()
        })
        .collect()
}

/// Degeneracy and span signature of span{1, b_1..b_m} from the row-major n×m table
/// `values[i*m + j] = b_j(z_i)` (as in [`crate::lp::GridTable::values`]).
pub fn analyze_values(n: usize, m: usize, values: &[f64]) -> SpanInfo {
    assert_eq!(values.len(), n * m, "analyze_values: table size");
    let p = m + 1;
    let zero = SpanInfo {
        sigma_ratio: 0.0,
        degenerate: true,
        key: None,
    };
    if n < p || values.iter().any(|v| !v.is_finite()) {
        return zero;
    }
    // Column-major A with unit-norm columns.
    let mut a = vec![0.0; n * p];
    for i in 0..n {
        a[i] = 1.0;
        for j in 0..m {
            a[(j + 1) * n + i] = values[i * m + j];
        }
    }
    for j in 0..p {
        let col = &mut a[j * n..(j + 1) * n];
        let norm = col.iter().map(|x| x * x).sum::<f64>().sqrt();
        if norm == 0.0 {
            return zero;
        }
        col.iter_mut().for_each(|x| *x /= norm);
    }
    // Householder QR: reflectors v_k (stored separately) and R (p×p, column-major).
    let mut reflectors: Vec<(Vec<f64>, f64)> = Vec::with_capacity(p);
    for k in 0..p {
        let x = &a[k * n + k..(k + 1) * n];
        let xnorm = x.iter().map(|v| v * v).sum::<f64>().sqrt();
        let alpha = if x[0] >= 0.0 { -xnorm } else { xnorm };
        let mut v = x.to_vec();
        v[0] -= alpha;
        let vv: f64 = v.iter().map(|t| t * t).sum();
        if vv > 0.0 {
            for j in k..p {
                let col = &mut a[j * n + k..(j + 1) * n];
                let d: f64 = v.iter().zip(col.iter()).map(|(x, y)| x * y).sum();
                let f = 2.0 * d / vv;
                col.iter_mut().zip(&v).for_each(|(c, x)| *c -= f * x);
            }
        }
        reflectors.push((v, vv));
    }
    let mut r = vec![0.0; p * p];
    for j in 0..p {
        for i in 0..=j {
            r[j * p + i] = a[j * n + i];
        }
    }
    let sv = jacobi_singular_values(&mut r, p);
    let smax = sv.iter().cloned().fold(0.0, f64::max);
    let smin = sv.iter().cloned().fold(f64::INFINITY, f64::min);
    let sigma_ratio = if smax > 0.0 { smin / smax } else { 0.0 };
    if sigma_ratio.is_nan() || sigma_ratio < DEGENERACY_TOL {
        return SpanInfo {
            sigma_ratio: if sigma_ratio.is_nan() {
                0.0
            } else {
                sigma_ratio
            },
            degenerate: true,
            key: None,
        };
    }
    // y_k = Qᵀ p_k: apply the reflectors to each probe, keep the first p entries.
    let mut ys = Vec::with_capacity(PROBES);
    let mut norms = Vec::with_capacity(PROBES);
    for k in 0..PROBES {
        let mut x: Vec<f64> = (0..n).map(|i| probe(k, i)).collect();
        norms.push(x.iter().map(|t| t * t).sum::<f64>().sqrt());
        for (j, (v, vv)) in reflectors.iter().enumerate() {
            if *vv == 0.0 {
                continue;
            }
            let seg = &mut x[j..];
            let d: f64 = v.iter().zip(seg.iter()).map(|(a, b)| a * b).sum();
            let f = 2.0 * d / vv;
            seg.iter_mut().zip(v).for_each(|(s, a)| *s -= f * a);
        }
        x.truncate(p);
        ys.push(x);
    }
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    let mut feed = |x: u64| {
        for b in x.to_le_bytes() {
            h ^= b as u64;
            h = h.wrapping_mul(0x0000_0100_0000_01b3);
        }
    };
    feed(p as u64);
    for k in 0..PROBES {
        for l in k..PROBES {
            let g: f64 =
                ys[k].iter().zip(&ys[l]).map(|(a, b)| a * b).sum::<f64>() / (norms[k] * norms[l]);
            feed((g / SPAN_QUANTUM).round() as i64 as u64);
        }
    }
    SpanInfo {
        sigma_ratio,
        degenerate: false,
        key: Some(h),
    }
}

/// [`analyze_values`] for functions tabulated on a grid.
pub fn analyze(functions: &[&Function], grid: &Grid) -> SpanInfo {
    let m = functions.len();
    let mut values = Vec::with_capacity(grid.len() * m);
    for &z in grid.points() {
        values.extend(functions.iter().map(|f| f.eval(z)));
    }
    analyze_values(grid.len(), m, &values)
}

/// [`analyze`] for a [`Basis`].
pub fn analyze_basis(basis: &Basis, grid: &Grid) -> SpanInfo {
    let fs: Vec<&Function> = basis.functions().iter().collect();
    analyze(&fs, grid)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn small_colex_order() {
        let all: Vec<Vec<usize>> = (0..6).map(|i| index_to_subset(4, 2, i).unwrap()).collect();
        assert_eq!(
            all,
            vec![
                vec![0, 1],
                vec![0, 2],
                vec![1, 2],
                vec![0, 3],
                vec![1, 3],
                vec![2, 3]
            ]
        );
        assert!(index_to_subset(4, 2, 6).is_err());
    }

    #[test]
    fn binomials() {
        assert_eq!(binomial(37, 4), Some(66045));
        assert_eq!(binomial(5, 7), Some(0));
        assert_eq!(binomial(0, 0), Some(1));
        assert_eq!(binomial(1000, 8), None);
    }
}
