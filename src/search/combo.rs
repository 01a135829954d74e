//! Candidates as indices, using the catalog numbering of [`crate::basis::candidates`]
//! (combinatorial number system, colexicographic order: index = Σ_k C(c_k, k)), so indices
//! agree with `momentlab candidates` and stay valid when functions are appended to the catalog.

use crate::basis::candidates as bc;
use anyhow::{bail, Result};

/// Binomial coefficient C(n, k) (0 when k > n; saturates at u64::MAX).
pub fn binomial(n: usize, k: usize) -> u64 {
    bc::count(n, k)
}

/// The m-subset of {0..n} with index `index`.
pub fn combination(index: u64, n: usize, m: usize) -> Result<Vec<usize>> {
    if m == 0 {
        bail!("candidate size m must be positive");
    }
    bc::index_to_subset(n, m, index)
}

/// Inverse of [`combination`]: the index of a strictly increasing subset of {0..n}.
pub fn combination_index(c: &[usize], n: usize) -> Result<u64> {
    if c.is_empty() || c.windows(2).any(|w| w[0] >= w[1]) || *c.last().unwrap() >= n {
        bail!("not a strictly increasing subset of 0..{n}: {c:?}");
    }
    bc::subset_to_index(c)
}

/// All `(index, subset)` pairs in index order.
pub fn all_combinations(n: usize, m: usize) -> Vec<(u64, Vec<usize>)> {
    let mut out = Vec::with_capacity(binomial(n, m) as usize);
    if m == 0 || m > n {
        return out;
    }
    let mut c: Vec<usize> = (0..m).collect();
    let mut idx = 0u64;
    loop {
        out.push((idx, c.clone()));
        idx += 1;
        if !bc::next_subset(&mut c, n) {
            return out;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts_match_the_paper() {
        assert_eq!(binomial(37, 4), 66045);
        assert_eq!(binomial(37, 3), 7770);
        assert_eq!(binomial(37, 2), 666);
        assert_eq!(binomial(3, 5), 0);
    }

    #[test]
    fn rank_and_unrank_agree_with_enumeration() {
        for (n, m) in [(7, 1), (7, 3), (9, 4), (6, 6)] {
            let all = all_combinations(n, m);
            assert_eq!(all.len() as u64, binomial(n, m));
            for (i, c) in &all {
                assert_eq!(&combination(*i, n, m).unwrap(), c);
                assert_eq!(combination_index(c, n).unwrap(), *i);
            }
            // Colexicographic order: compare reversed subsets.
            assert!(all.windows(2).all(|w| {
                let a: Vec<_> = w[0].1.iter().rev().collect();
                let b: Vec<_> = w[1].1.iter().rev().collect();
                a < b
            }));
        }
        assert!(combination(66045, 37, 4).is_err());
        assert!(combination_index(&[3, 2], 5).is_err());
        assert!(combination_index(&[1, 5], 5).is_err());
    }
}
