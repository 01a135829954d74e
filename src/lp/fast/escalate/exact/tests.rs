use super::*;
use crate::lp::GridTable;
use crate::Grid;
use num_rational::BigRational;
use rand::{Rng, SeedableRng};

/// Exact solution of the square system M v = rhs (rational Gaussian elimination).
pub(in crate::lp) fn solve_q(
    mut m: Vec<Vec<BigRational>>,
    mut rhs: Vec<BigRational>,
) -> Option<Vec<BigRational>> {
    let r = rhs.len();
    for c in 0..r {
        let p = (c..r).find(|&i| !m[i][c].is_zero())?;
        m.swap(c, p);
        rhs.swap(c, p);
        for i in (0..r).filter(|&i| i != c) {
            let f = &m[i][c] / &m[c][c];
            for k in c..r {
                let v = &f * &m[c][k];
                m[i][k] -= v;
            }
            let v = &f * &rhs[c];
            rhs[i] -= v;
        }
    }
    Some((0..r).map(|i| &rhs[i] / &m[i][i]).collect())
}

/// The exact optimum by enumerating every basis (vertex enumeration): min over the
/// nonsingular bases with x ≥ 0 of Σ_{i<kf} x_i; None when none is feasible.
fn brute(cert: &Certifier, b: &[BigRational], kf: usize) -> Option<BigRational> {
    let (n, r) = (cert.n(), cert.m() + 1);
    let q = |v: f64| BigRational::from_float(v).unwrap();
    let mut best: Option<BigRational> = None;
    let mut idx: Vec<usize> = (0..r).collect();
    loop {
        let m = (0..r)
            .map(|j| idx.iter().map(|&i| q(cert.entry(j, i))).collect())
            .collect();
        if let Some(x) = solve_q(m, b.to_vec()) {
            if x.iter().all(|v| !v.is_negative()) {
                let g: BigRational = (0..r).filter(|&t| idx[t] < kf).map(|t| x[t].clone()).sum();
                if best.as_ref().is_none_or(|v| g < *v) {
                    best = Some(g);
                }
            }
        }
        // Next r-subset of 0..n in lexicographic order.
        let Some(t) = (0..r).rev().find(|&t| idx[t] < n - r + t) else {
            return best;
        };
        idx[t] += 1;
        for u in t + 1..r {
            idx[u] = idx[u - 1] + 1;
        }
    }
}

/// Writes the m function values at z.
type Basis = fn(f64, &mut [f64]);

/// g is the exact value v rounded to f64 (within one unit in the last place).
fn close(g: f64, v: &BigRational) -> bool {
    let w = v.to_f64().unwrap();
    (g - w).abs() <= f64::EPSILON * w.abs()
}

/// A table of the functions `f` (at most 3) on a uniform grid of n points.
fn table(n: usize, f: Basis, m: usize) -> (GridTable, Certifier) {
    let t = GridTable::from_fn(&Grid::uniform(n).unwrap(), m, f).unwrap();
    let c = Certifier::new(&t, (0..=m).collect());
    (t, c)
}

/// Against vertex enumeration on small grids: power and steep exponential bases, random
/// distributions of 1–5 atoms (boundary moments among them), from f64 moments (which
/// may be exactly infeasible) and from the exact moments of the distribution.
#[test]
fn exact_simplex_matches_vertex_enumeration() {
    let bases: [(Basis, usize); 3] = [
        (|z, o| (o[0], o[1], o[2]) = (z, z * z, z * z * z), 3),
        (
            |z, o| (o[0], o[1]) = ((40.0 * z).exp(), (-40.0 * z).exp()),
            2,
        ),
        (|z, o| (o[0], o[1]) = ((80.0 * (z - 1.0)).exp(), z), 2),
    ];
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
    let (mut optimal, mut infeasible) = (0, 0);
    for (f, m) in bases {
        let n = 10;
        let (tab, mut cert) = table(n, f, m);
        for _ in 0..30 {
            let atoms = rng.gen_range(1..=5);
            let dist: Vec<(u32, f64)> = (0..atoms)
                .map(|_| (rng.gen_range(0..n as u32), rng.gen_range(0.01..1.0)))
                .collect();
            let kf = rng.gen_range(0..=n);
            let moments = crate::lp::distribution_moments(&tab, &dist).unwrap();
            cert.set_moments(&moments);
            let q = |v: f64| BigRational::from_float(v).unwrap();
            // f64 moments.
            let bq: Vec<BigRational> = (0..=m).map(|j| q(cert.bbar(j))).collect();
            let want = brute(&cert, &bq, kf);
            let got = ExactSimplex::new(&cert, kf, None)
                .unwrap()
                .solve(&[&[0, n / 2, n - 1, 1][..=m]]);
            match (&want, &got) {
                (Some(w), ExactAnswer::Optimal { g, weights, .. }) => {
                    assert!(close(*g, w), "{dist:?} kf {kf}: {g} vs {w}");
                    let mass: f64 = weights.iter().map(|e| e.1).sum();
                    assert!((mass - 1.0).abs() < 1e-14);
                    optimal += 1;
                }
                (None, ExactAnswer::Infeasible(_)) => infeasible += 1,
                _ => panic!("{dist:?} kf {kf}: {want:?} vs {got:?}"),
            }
            // Exact moments of the distribution: always feasible.
            let total: BigRational = dist.iter().map(|e| q(e.1)).sum();
            let bq: Vec<BigRational> = (0..=m)
                .map(|j| {
                    let s: BigRational = dist
                        .iter()
                        .map(|&(i, w)| q(w) * q(cert.entry(j, i as usize)))
                        .sum();
                    s / &total
                })
                .collect();
            let want = brute(&cert, &bq, kf).expect("a distribution is feasible");
            let got = ExactSimplex::new(&cert, kf, Some(&dist))
                .unwrap()
                .solve(&[&[0, n / 2, n - 1, 1][..=m]]);
            match got {
                ExactAnswer::Optimal { g, .. } => assert!(close(g, &want), "{g} vs {want}"),
                other => panic!("{dist:?} kf {kf}: {other:?}"),
            }
        }
    }
    assert!(
        optimal > 50 && infeasible > 0,
        "{optimal} optimal, {infeasible} infeasible"
    );
}

/// The f64 pre-filter of the dual ratio test picks the very column the double-double
/// scan over every column picks, at every dual pivot from several starts: flat windows
/// (the ill-posed escalations), tight clusters and single atoms under (z, z², z³, z⁴) on
/// 1024 points, from f64 moments and from the exact moments of the distribution, z_f on
/// an atom, inside and outside the support.
#[test]
fn prefiltered_dual_ratio_test_matches_the_double_double_scan() {
    let n = 1024;
    let (tab, mut cert) = table(
        n,
        |z, o| (o[0], o[1], o[2], o[3]) = (z, z * z, z * z * z, z * z * z * z),
        4,
    );
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
    let (mut steps, mut feasible) = (0, 0);
    for case in 0..24 {
        let dist: Vec<(u32, f64)> = match case % 3 {
            0 => {
                let (a, w) = (rng.gen_range(0..n - 64), rng.gen_range(2..64));
                (a..a + w).map(|i| (i as u32, 1.0)).collect()
            }
            1 => {
                let a = rng.gen_range(0..n - 2) as u32;
                vec![(a, 0.5), (a + 1, 0.3), (a + 2, 0.2)]
            }
            _ => vec![(rng.gen_range(0..n) as u32, 1.0)],
        };
        let kf = match case % 4 {
            0 => dist[0].0 as usize,
            1 => 0,
            2 => n,
            _ => rng.gen_range(0..=n),
        };
        let moments = crate::lp::distribution_moments(&tab, &dist).unwrap();
        cert.set_moments(&moments);
        let spread: Vec<usize> = (0..5).map(|t| t * (n - 1) / 4).collect();
        let mut random: Vec<usize> = Vec::new();
        while random.len() < 5 {
            let i = rng.gen_range(0..n);
            if !random.contains(&i) {
                random.push(i);
            }
        }
        for exact_moments in [false, true] {
            let d = exact_moments.then_some(&dist[..]);
            for start in [&spread, &random] {
                let mut ex = ExactSimplex::new(&cert, kf, d).unwrap();
                assert!(ex.load(start));
                for _ in 0..100 {
                    let Some(p) = ex.most_negative() else {
                        feasible += 1;
                        break;
                    };
                    let q = ex.dual_entering(p);
                    assert_eq!(
                        q,
                        ex.dual_entering_dd(p),
                        "case {case} basis {:?}",
                        ex.basis
                    );
                    steps += 1;
                    let Some(q) = q else { break };
                    let alpha = ex.times_adj(&ex.column(q));
                    if alpha[p].is_zero() || alpha[p].sign() == ex.d.sign() {
                        break;
                    }
                    ex.pivot(p, q, &alpha).unwrap();
                }
            }
        }
    }
    assert!(
        steps > 200 && feasible > 20,
        "{steps} steps, {feasible} feasible"
    );
}

/// Flat windows under (z, z², z³, z⁴) on 1024 points, from f64 moments: the exact
/// optimum does not depend on the path to it (the starts in three orders, each made
/// feasible by the bounded dual phase or by phase 1), bit for bit.
#[test]
fn exact_optimum_does_not_depend_on_the_start() {
    let n = 1024;
    let (tab, mut cert) = table(
        n,
        |z, o| (o[0], o[1], o[2], o[3]) = (z, z * z, z * z * z, z * z * z * z),
        4,
    );
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
    let mut optimal = 0;
    for _ in 0..6 {
        let (a, w) = (rng.gen_range(0..n - 200), rng.gen_range(20..200));
        let dist: Vec<(u32, f64)> = (a..a + w).map(|i| (i as u32, 1.0)).collect();
        let kf = rng.gen_range(a..a + w);
        let moments = crate::lp::distribution_moments(&tab, &dist).unwrap();
        cert.set_moments(&moments);
        let spread: Vec<usize> = (0..5).map(|t| t * (n - 1) / 4).collect();
        let near: Vec<usize> = (0..5).map(|t| a + t * w / 5).collect();
        let low: Vec<usize> = (0..5).collect();
        let orders: [&[&[usize]]; 3] = [&[&spread, &near], &[&near, &spread], &[&low]];
        let answers: Vec<ExactAnswer> = orders
            .iter()
            .map(|starts| ExactSimplex::new(&cert, kf, None).unwrap().solve(starts))
            .collect();
        let g = |e: &ExactAnswer| match e {
            ExactAnswer::Optimal { g, .. } => Some(*g),
            _ => None,
        };
        assert!(
            answers.iter().all(|e| g(e) == g(&answers[0])),
            "{answers:?}"
        );
        optimal += g(&answers[0]).is_some() as usize;
    }
    assert!(optimal >= 3, "{optimal} optimal");
}

#[test]
fn split_and_ratio_are_exact_on_simple_values() {
    assert_eq!(split(1.0), Some((1, 0)));
    assert_eq!(split(-0.75), Some((-3, -2)));
    assert_eq!(split(5e-324), Some((1, -1074)));
    assert_eq!(to_int(0.375, -3), BigInt::from(3));
    assert_eq!(ratio_f64(&BigInt::from(1), &BigInt::from(3)), 1.0 / 3.0);
    assert_eq!(ratio_f64(&BigInt::from(-22), &BigInt::from(7)), -22.0 / 7.0);
    let big = BigInt::from(1) << 3000usize;
    assert_eq!(ratio_f64(&big, &(&big * 4)), 0.25);
}

#[test]
fn adjugate_satisfies_its_identity() {
    let r = 4;
    // A matrix needing a row swap (zero leading entry).
    let v: Vec<i64> = vec![0, 2, -1, 3, 4, 1, 0, -2, 1, 1, 1, 1, 5, -3, 2, 0];
    let m: Vec<BigInt> = v.iter().map(|&x| BigInt::from(x)).collect();
    let (adj, d) = adjugate(&m, r).unwrap();
    for i in 0..r {
        for j in 0..r {
            let s: BigInt = (0..r).map(|k| &m[i * r + k] * &adj[k * r + j]).sum();
            let want = if i == j { d.clone() } else { BigInt::zero() };
            assert_eq!(s, want);
        }
    }
    assert!(!d.is_zero());
    let sing: Vec<BigInt> = [1, 2, 2, 4].iter().map(|&x| BigInt::from(x)).collect();
    assert!(adjugate(&sing, 2).is_none());
}
