//! Candidates: the colex bijection (exhaustive for N = 37, m = 1..4), degeneracy against an
//! independent Gram-matrix eigenvalue computation, and span signatures.

use momentlab::basis::candidates::{
    analyze, analyze_values, check_m, count, index_to_subset, next_subset, subset_to_index,
    DEGENERACY_TOL,
};
use momentlab::basis::{Catalog, Function};
use momentlab::Grid;
use rand::seq::index::sample;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::collections::{HashMap, HashSet};

#[test]
fn counts() {
    assert_eq!(count(37, 4), 66045);
    assert_eq!(count(37, 1), 37);
    assert_eq!(count(37, 8), 38_608_020);
    assert_eq!(count(3, 4), 0);
    assert!(check_m(37, 0).is_err());
    assert!(check_m(37, 9).is_err());
    assert!(check_m(3, 4).is_err());
    assert!(check_m(37, 8).is_ok());
}

#[test]
fn exhaustive_bijection_n37() {
    let n = 37;
    for m in 1..=4 {
        let total = count(n, m);
        let mut prev: Option<Vec<usize>> = None;
        for i in 0..total {
            let s = index_to_subset(n, m, i).unwrap();
            assert_eq!(s.len(), m);
            assert!(s.windows(2).all(|w| w[0] < w[1]) && s[m - 1] < n, "{s:?}");
            assert_eq!(subset_to_index(&s).unwrap(), i);
            if let Some(mut p) = prev.take() {
                assert!(next_subset(&mut p, n));
                assert_eq!(p, s, "successor of index {}", i - 1);
            }
            prev = Some(s);
        }
        assert!(
            !next_subset(&mut prev.unwrap(), n),
            "last subset has no successor"
        );
        assert!(index_to_subset(n, m, total).is_err());
    }
    // Independent enumeration: all 4-subsets by nested loops map onto 0..C(37,4) exactly.
    let mut seen = vec![false; count(n, 4) as usize];
    for a in 0..n {
        for b in a + 1..n {
            for c in b + 1..n {
                for d in c + 1..n {
                    let i = subset_to_index(&[d, b, a, c]).unwrap() as usize;
                    assert!(!seen[i], "index {i} hit twice");
                    seen[i] = true;
                }
            }
        }
    }
    assert!(seen.iter().all(|&s| s));
}

#[test]
fn random_roundtrips_up_to_m8_and_append_stability() {
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    for _ in 0..5000 {
        let n = rng.gen_range(8..300);
        let m = rng.gen_range(1..=8);
        let mut s = sample(&mut rng, n, m).into_vec();
        s.sort_unstable();
        let i = subset_to_index(&s).unwrap();
        assert!(i < count(n, m));
        assert_eq!(index_to_subset(n, m, i).unwrap(), s);
        // Appending functions to the catalog keeps the index.
        let bigger = n + rng.gen_range(1..50);
        assert_eq!(index_to_subset(bigger, m, i).unwrap(), s);
    }
    assert!(subset_to_index(&[1, 1]).is_err());
}

fn f(s: &str) -> Function {
    Function::parse(s).unwrap()
}

#[test]
fn degenerate_candidates() {
    let g = Grid::uniform(1024).unwrap();
    for set in [
        vec!["z", "1-z"],
        vec!["z", "z^2", "(1-z)^2"],
        vec!["3"],
        vec!["z", "2z+1"],
        vec!["sin(2πz)", "cos(2πz)", "sin(2πz+1)"],
        vec!["exp(z)", "exp(z+1)"],
    ] {
        let fs: Vec<Function> = set.iter().map(|s| f(s)).collect();
        let refs: Vec<&Function> = fs.iter().collect();
        let info = analyze(&refs, &g);
        assert!(info.degenerate, "{set:?}: {info:?}");
        assert_eq!(info.key, None);
    }
    // Too few grid points for m + 1 columns.
    let fs = [f("z"), f("z^2"), f("z^3")];
    let refs: Vec<&Function> = fs.iter().collect();
    assert!(analyze(&refs, &Grid::uniform(3).unwrap()).degenerate);
    assert!(!analyze(&refs, &Grid::uniform(4).unwrap()).degenerate);
    // The MSM and TMSM bases are fine.
    let c = Catalog::embedded();
    for set in [
        ["z", "z^2", "z^3", "z^4"],
        ["sin(2πz)", "cos(2πz)", "sin(4πz)", "cos(4πz)"],
    ] {
        let fs: Vec<Function> = set.iter().map(|s| c.resolve(s).unwrap()).collect();
        let refs: Vec<&Function> = fs.iter().collect();
        let info = analyze(&refs, &g);
        assert!(!info.degenerate && info.key.is_some(), "{set:?}: {info:?}");
    }
}

/// σ_min/σ_max of the column-normalised [1, B] from the eigenvalues of its Gram matrix
/// (cyclic Jacobi eigenvalue method): independent of the QR + one-sided Jacobi path.
fn gram_sigma_ratio(n: usize, m: usize, values: &[f64]) -> f64 {
    let p = m + 1;
    let col = |j: usize, i: usize| if j == 0 { 1.0 } else { values[i * m + j - 1] };
    let norms: Vec<f64> = (0..p)
        .map(|j| (0..n).map(|i| col(j, i).powi(2)).sum::<f64>().sqrt())
        .collect();
    let mut a = vec![vec![0.0; p]; p];
    for (j, row) in a.iter_mut().enumerate() {
        for (k, v) in row.iter_mut().enumerate() {
            *v = (0..n).map(|i| col(j, i) * col(k, i)).sum::<f64>() / (norms[j] * norms[k]);
        }
    }
    for _ in 0..100 {
        let off: f64 = (0..p)
            .flat_map(|i| (0..p).filter(move |&j| j != i).map(move |j| (i, j)))
            .map(|(i, j)| a[i][j] * a[i][j])
            .sum();
        if off < 1e-30 {
            break;
        }
        for i in 0..p {
            for j in i + 1..p {
                if a[i][j] == 0.0 {
                    continue;
                }
                let theta = (a[j][j] - a[i][i]) / (2.0 * a[i][j]);
                let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
                let c = 1.0 / (t * t + 1.0).sqrt();
                let s = t * c;
                for row in a.iter_mut() {
                    let (x, y) = (row[i], row[j]);
                    row[i] = c * x - s * y;
                    row[j] = s * x + c * y;
                }
                let (ri, rj) = (a[i].clone(), a[j].clone());
                for k in 0..p {
                    a[i][k] = c * ri[k] - s * rj[k];
                    a[j][k] = s * ri[k] + c * rj[k];
                }
            }
        }
    }
    let ev: Vec<f64> = (0..p).map(|i| a[i][i]).collect();
    let max = ev.iter().cloned().fold(f64::MIN, f64::max);
    let min = ev.iter().cloned().fold(f64::MAX, f64::min);
    (min.max(0.0) / max).sqrt()
}

fn table(fs: &[&Function], grid: &Grid) -> Vec<f64> {
    grid.points()
        .iter()
        .flat_map(|&z| fs.iter().map(move |f| f.eval(z)))
        .collect()
}

#[test]
fn sigma_ratio_matches_gram_eigenvalues() {
    let c = Catalog::embedded();
    let g = Grid::uniform(257).unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    let mut checked = 0;
    for _ in 0..1500 {
        let m = rng.gen_range(1..=5);
        let idx = sample(&mut rng, c.len(), m).into_vec();
        let fs: Vec<&Function> = idx.iter().map(|&i| &c.functions()[i]).collect();
        let vals = table(&fs, &g);
        let info = analyze_values(g.len(), m, &vals);
        let want = gram_sigma_ratio(g.len(), m, &vals);
        // The Gram route squares the condition number: trust it only above ~1e-5.
        if want > 1e-5 {
            assert!(
                (info.sigma_ratio - want).abs() <= 1e-6 * want,
                "{:?}: {} vs {want}",
                fs.iter().map(|f| f.name()).collect::<Vec<_>>(),
                info.sigma_ratio
            );
            assert!(!info.degenerate);
            checked += 1;
        }
    }
    assert!(checked > 1000, "{checked}");
}

#[test]
fn near_dependence_threshold() {
    // b_3 = 0.3 + 0.7 b_1 − 1.1 b_2 + ε·r(z): degenerate for ε ≪ tol, not for ε ≫ tol.
    let g = Grid::uniform(1024).unwrap();
    let (b1, b2, r) = (f("exp(-5z)"), f("sin(3πz)"), f("z^(1/3)"));
    for (eps, want) in [(0.0, true), (1e-13, true), (1e-6, false), (1e-3, false)] {
        let vals: Vec<f64> = g
            .points()
            .iter()
            .flat_map(|&z| {
                let (x, y) = (b1.eval(z), b2.eval(z));
                [x, y, 0.3 + 0.7 * x - 1.1 * y + eps * r.eval(z)]
            })
            .collect();
        let info = analyze_values(g.len(), 3, &vals);
        assert_eq!(
            info.degenerate, want,
            "eps {eps}: {info:?} (tol {DEGENERACY_TOL})"
        );
    }
}

#[test]
fn equal_spans_share_a_key_and_different_spans_do_not() {
    let g = Grid::uniform(1024).unwrap();
    let key = |set: &[&str]| {
        let fs: Vec<Function> = set.iter().map(|s| f(s)).collect();
        let refs: Vec<&Function> = fs.iter().collect();
        analyze(&refs, &g).key.unwrap()
    };
    assert_eq!(key(&["z", "z^2"]), key(&["z", "(1-z)^2"]));
    assert_eq!(key(&["z", "z^2"]), key(&["z^2", "z"]));
    assert_eq!(
        key(&["sin(2πz)", "cos(2πz)"]),
        key(&["sin(2πz + 0.7)", "2cos(2πz - 1) + 5"])
    );
    assert_ne!(key(&["z", "z^2"]), key(&["z", "z^3"]));
    assert_ne!(key(&["z", "z^2"]), key(&["z", "z^2", "z^3"]));

    // Random invertible affine remixes of random catalog candidates keep the key; the keys of
    // distinct candidates are distinct.
    let c = Catalog::embedded();
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    let mut by_key: HashMap<u64, Vec<usize>> = HashMap::new();
    let mut distinct = HashSet::new();
    for _ in 0..1500 {
        let m = rng.gen_range(1..=6);
        let mut idx = sample(&mut rng, c.len(), m).into_vec();
        idx.sort_unstable();
        let fs: Vec<&Function> = idx.iter().map(|&i| &c.functions()[i]).collect();
        let vals = table(&fs, &g);
        let info = analyze_values(g.len(), m, &vals);
        let Some(k) = info.key else { continue };
        // B' = B·M + 1·cᵀ with M = I + E, |E_ij| < 0.5/m (diagonally dominant, so
        // cond(M) ≤ 3), c random. Only well-conditioned candidates: remixing an
        // ill-conditioned one may legitimately push it across the degeneracy tolerance.
        if info.sigma_ratio < 1e-6 {
            continue;
        }
        let e = 0.5 / m as f64;
        let mm: Vec<f64> = (0..m * m)
            .map(|t| (t % (m + 1) == 0) as u8 as f64 + rng.gen_range(-e..e))
            .collect();
        let cc: Vec<f64> = (0..m).map(|_| rng.gen_range(-2.0..2.0)).collect();
        // Columns are scaled to unit RMS first so that exp(40z) does not swamp the mix.
        let rms: Vec<f64> = (0..m)
            .map(|j| {
                ((0..g.len()).map(|i| vals[i * m + j].powi(2)).sum::<f64>() / g.len() as f64).sqrt()
            })
            .collect();
        let mixed: Vec<f64> = (0..g.len())
            .flat_map(|i| {
                let row: Vec<f64> = (0..m).map(|l| vals[i * m + l] / rms[l]).collect();
                (0..m)
                    .map(|j| cc[j] + (0..m).map(|l| row[l] * mm[l * m + j]).sum::<f64>())
                    .collect::<Vec<_>>()
            })
            .collect();
        let info2 = analyze_values(g.len(), m, &mixed);
        assert_eq!(info2.key, Some(k), "{idx:?} remixed: {info:?} -> {info2:?}");
        if distinct.insert(idx.clone()) {
            by_key.entry(k).or_default().push(distinct.len());
        }
    }
    assert!(
        by_key.values().all(|v| v.len() == 1),
        "distinct candidates share a key"
    );
    assert!(by_key.len() > 1000);
}
