//! Candidates as indices: candidate k is the k-th m-subset {c_1 < … < c_m} of {0, …, N−1} in
//! lexicographic order (so for N = 37, m = 4 the indices run 0..66045 = C(37,4)).

use anyhow::{bail, Result};

/// Binomial coefficient C(n, k) (0 when k > n); exact for the sizes used here.
pub fn binomial(n: usize, k: usize) -> u64 {
    if k > n {
        return 0;
    }
    let k = k.min(n - k);
    let mut r: u128 = 1;
    for i in 0..k {
        r = r * (n - i) as u128 / (i + 1) as u128;
    }
    r as u64
}

/// The `index`-th m-subset of {0..n} in lexicographic order.
pub fn combination(index: u64, n: usize, m: usize) -> Result<Vec<usize>> {
    let total = binomial(n, m);
    if m == 0 || index >= total {
        bail!("candidate index {index} out of range (C({n},{m}) = {total})");
    }
    let mut rest = index;
    let mut out = Vec::with_capacity(m);
    let mut v = 0;
    for p in 0..m {
        loop {
            // Number of subsets whose p-th element is v (the remaining m-p-1 from above v).
            let count = binomial(n - v - 1, m - p - 1);
            if rest < count {
                break;
            }
            rest -= count;
            v += 1;
        }
        out.push(v);
        v += 1;
    }
    Ok(out)
}

/// Inverse of [`combination`]: the index of a strictly increasing subset of {0..n}.
pub fn combination_index(c: &[usize], n: usize) -> Result<u64> {
    if c.is_empty() || c.windows(2).any(|w| w[0] >= w[1]) || *c.last().unwrap() >= n {
        bail!("not a strictly increasing subset of 0..{n}: {c:?}");
    }
    let m = c.len();
    let mut idx = 0u64;
    let mut start = 0;
    for (p, &cp) in c.iter().enumerate() {
        for v in start..cp {
            idx += binomial(n - v - 1, m - p - 1);
        }
        start = cp + 1;
    }
    Ok(idx)
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
        // Advance to the next subset in lexicographic order.
        let mut p = m;
        while p > 0 && c[p - 1] == n - m + (p - 1) {
            p -= 1;
        }
        if p == 0 {
            return out;
        }
        c[p - 1] += 1;
        for q in p..m {
            c[q] = c[q - 1] + 1;
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
            // Lexicographic order.
            assert!(all.windows(2).all(|w| w[0].1 < w[1].1));
        }
        assert!(combination(66045, 37, 4).is_err());
        assert!(combination_index(&[3, 2], 5).is_err());
        assert!(combination_index(&[1, 5], 5).is_err());
    }
}
