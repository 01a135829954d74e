use super::*;
use crate::lp::GridTable;
use crate::Grid;

fn certifier(n: usize, f: impl FnMut(f64, &mut [f64]), m: usize) -> Certifier {
    let t = GridTable::from_fn(&Grid::uniform(n).unwrap(), m, f).unwrap();
    Certifier::new(&t, (0..=m).collect())
}

/// (z, z²) on {0, 1/4, 1/2, 3/4, 1}, b = (1/2, 5/16), z_f = 0.6: the optimum G = 1/2
/// (½δ(1/4) + ½δ(3/4)); from a cold start and from a feasible suboptimal basis.
#[test]
fn finds_the_known_optimum() {
    let mut c = certifier(5, |z, o| (o[0], o[1]) = (z, z * z), 2);
    let b = [0.5, 0.3125];
    for start in [None, Some(&[0usize, 2, 4][..])] {
        c.set_moments(&b);
        let mut s = ScaledSimplex::default();
        let Found::Optimal(basis) = s.solve(&c, 3, start) else {
            panic!("not optimal from {start:?}")
        };
        assert!(s.pivots > 0);
        assert_eq!(c.optimal(&b, 3, &basis).unwrap().g, 0.5, "{basis:?}");
    }
}

/// The same LP from the infeasible basis {0, 1/4, 1/2} (weights 1/2, −1, 3/2): the warm
/// phase 1 with the composite artificial −1·δ(1/4) in place of the point 1/4 reaches the
/// optimum G = 1/2 of the cold start in fewer pivots.
#[test]
fn warm_phase1_from_an_infeasible_basis_reaches_the_cold_optimum() {
    let mut c = certifier(5, |z, o| (o[0], o[1]) = (z, z * z), 2);
    let b = [0.5, 0.3125];
    c.set_moments(&b);
    let mut pivots = Vec::new();
    for start in [None, Some(&[0usize, 1, 2][..])] {
        let mut s = ScaledSimplex::default();
        let Found::Optimal(basis) = s.solve(&c, 3, start) else {
            panic!("not optimal from {start:?}")
        };
        let opt = c.optimal(&b, 3, &basis).unwrap();
        assert_eq!(opt.g, 0.5, "{basis:?}");
        assert_eq!(opt.support, vec![(0.25, 0.5), (0.75, 0.5)]);
        pivots.push(s.pivots);
    }
    assert_eq!(pivots, [5, 3], "cold and warm pivots");
}

/// Pivots through the eta file agree with refactorising at every pivot: (z, z², z³) on 65
/// points, the moments of ¼δ(1/8) + ½δ(1/2) + ¼δ(13/16) (exact in f64), z_f = 0.6, from
/// the all-artificial start. With at most 0, 3 and [`MAX_ETAS`] etas between
/// factorisations: every updated x and y within 1e-28 (relative to its largest entry) of a
/// fresh factorisation's, the same optimal basis {39, 10, 64, 9} after 14 pivots and the
/// same G = 0.3223894113549286.
#[test]
fn eta_file_matches_refactorising_at_every_pivot() {
    let mut c = certifier(65, |z, o| (o[0], o[1], o[2]) = (z, z * z, z * z * z), 3);
    let atoms = [(8u32, 0.25), (32, 0.5), (52, 0.25)];
    let b: Vec<f64> = (1..=3)
        .map(|k| {
            atoms
                .iter()
                .map(|&(i, w)| w * (i as f64 / 64.0).powi(k))
                .sum()
        })
        .collect();
    c.set_moments(&b);
    let mut runs = Vec::new();
    for max_etas in [0, 3, MAX_ETAS] {
        let mut s = ScaledSimplex {
            max_etas: Some(max_etas),
            check_updates: Some((0, 0.0)),
            ..Default::default()
        };
        let Found::Optimal(basis) = s.solve(&c, 39, None) else {
            panic!("not optimal with {max_etas} etas")
        };
        let (checks, worst) = s.check_updates.unwrap();
        assert!(worst <= 1e-28, "{max_etas} etas: {worst:e}");
        let g = c.optimal(&b, 39, &basis).unwrap().g;
        runs.push((basis, s.pivots, g, checks));
    }
    assert_eq!(runs[0].0, [39, 10, 64, 9]);
    assert_eq!(runs[0].1, 14);
    assert_eq!(runs[0].2, 0.3223894113549286);
    assert_eq!(runs[0].3, 0, "nothing updated without etas");
    assert!(runs[1].3 > 0 && runs[2].3 > 0, "{runs:?}");
    for run in &runs[1..] {
        assert_eq!(run.0, runs[0].0);
        assert_eq!(run.1, runs[0].1);
        assert_eq!(run.2, runs[0].2);
    }
}

/// (1/2, 1/5) has negative variance: phase 1 ends with a Farkas ray the certifier accepts.
#[test]
fn infeasible_moments_give_a_farkas_ray() {
    let mut c = certifier(5, |z, o| (o[0], o[1]) = (z, z * z), 2);
    let b = [0.5, 0.2];
    c.set_moments(&b);
    let Found::Infeasible(y) = ScaledSimplex::default().solve(&c, 3, None) else {
        panic!("expected a Farkas ray")
    };
    assert!(c.infeasible(&b, &y).unwrap() > 0.0);
}

/// At every pivot of both phases: the screened full pass, when it runs, picks the very
/// column of the scan over every column (so at every optimum neither finds an eligible
/// column), and every column partial pricing picks is non-basic with a double-double
/// reduced cost below −tol_i (its f64 d_i and e_i those of the full pass, bit for bit).
/// Flat windows, tight clusters, adjacent points, boundary moments and mixtures under
/// (z, z², z³, z⁴) on 1024 and 4096 points, z_f below, at, inside and above the support,
/// from the all-artificial start and from the support of a later problem (a feasible or
/// infeasible warm start).
#[test]
fn full_pass_matches_the_scan_and_partial_picks_are_eligible() {
    use crate::lp::corpus::{problem, Kind};
    use rand::SeedableRng;
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
    let mut checks = (0, 0);
    for n in [1024, 4096] {
        let t = GridTable::from_fn(&Grid::uniform(n).unwrap(), 4, |z, o| {
            (o[0], o[1], o[2], o[3]) = (z, z * z, z * z * z, z * z * z * z)
        })
        .unwrap();
        let mut c = Certifier::new(&t, (0..=4).collect());
        let z = t.grid().points();
        let mut s = ScaledSimplex {
            check_pricing: Some((0, 0)),
            ..Default::default()
        };
        let kinds = [
            Kind::Flat,
            Kind::Cluster,
            Kind::Adjacent,
            Kind::Boundary,
            Kind::Mixture,
        ];
        let mut last: Option<Vec<usize>> = None;
        for case in 0..30 {
            let p = problem(&mut rng, n, 4, kinds[case % kinds.len()]);
            let b = crate::lp::distribution_moments(&t, &p.dist).unwrap();
            c.set_moments(&b);
            for &zf in &p.zf {
                let kf = z.partition_point(|&v| v < zf);
                let warm = last.take();
                for start in [None, warm.as_deref()] {
                    if let Found::Optimal(basis) = s.solve(&c, kf, start) {
                        last = Some(basis);
                    }
                }
                last = last.or(warm);
            }
        }
        let (full, partial) = s.check_pricing.unwrap();
        checks.0 += full;
        checks.1 += partial;
    }
    assert!(
        checks.0 > 100 && checks.1 > 1000,
        "{checks:?} pivots checked"
    );
}

/// Partial pricing reaches the optimal value of full pricing: 400 problems (flat windows,
/// clusters, adjacent points, boundary moments and mixtures under (z, z², z³, z⁴) on 1024
/// and 4096 points, z_f uniform, cold starts) solved with and without it, each final
/// basis judged by the certifier as an escalation's ([`Certifier::improve`], up to 64
/// accurate pivots). Partial pricing certifies at least as many (397 of 400 each), and
/// where both are certified their G agree within 2 TOL_GAP (each is within TOL_GAP of its
/// dual bound).
#[test]
fn partial_pricing_reaches_the_optimal_value_of_full_pricing() {
    use crate::lp::certify::TOL_GAP;
    use crate::lp::corpus::{problem, Kind};
    use rand::{Rng, SeedableRng};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
    let kinds = [
        Kind::Flat,
        Kind::Flat,
        Kind::Cluster,
        Kind::Adjacent,
        Kind::Boundary,
        Kind::Mixture,
    ];
    let (mut both, mut certified) = (0, [0usize; 2]);
    let mut pivots = [0u64; 2];
    for n in [1024, 4096] {
        let t = GridTable::from_fn(&Grid::uniform(n).unwrap(), 4, |z, o| {
            (o[0], o[1], o[2], o[3]) = (z, z * z, z * z * z, z * z * z * z)
        })
        .unwrap();
        let mut c = Certifier::new(&t, (0..=4).collect());
        let mut solvers = [
            ScaledSimplex::default(),
            ScaledSimplex {
                full_pricing: true,
                ..Default::default()
            },
        ];
        for case in 0..200 {
            let p = problem(&mut rng, n, 4, kinds[case % kinds.len()]);
            let b = crate::lp::distribution_moments(&t, &p.dist).unwrap();
            let kf = rng.gen_range(1..n);
            let mut g = [None; 2];
            for (k, s) in solvers.iter_mut().enumerate() {
                c.set_moments(&b);
                let before = s.pivots;
                if let Found::Optimal(mut basis) = s.solve(&c, kf, None) {
                    g[k] = c.improve(&b, kf, &mut basis, 64).ok().map(|a| a.g);
                }
                pivots[k] += s.pivots - before;
            }
            for k in 0..2 {
                certified[k] += g[k].is_some() as usize;
            }
            if let [Some(gp), Some(gf)] = g {
                both += 1;
                assert!(
                    (gp - gf).abs() <= 2.0 * TOL_GAP,
                    "n = {n}, case {case}, kf = {kf}: {gp} against {gf}"
                );
            }
        }
    }
    eprintln!("certified {certified:?}, both {both}, pivots {pivots:?}");
    assert!(certified[0] >= certified[1], "{certified:?}");
    assert!(both >= 390, "{both} of 400 certified by both");
}

/// exp(40z) spans e⁴⁰ ≈ 2.4·10¹⁷ on [0, 1]: with z, the moments of ½δ(0) + ½δ(1) on 65
/// points leave only that distribution (the end points are the extreme values of both
/// functions' convex hull), so G at z_f = 1/2 is exactly 1/2.
#[test]
fn steep_exponential_rows_are_solved_in_scaled_coordinates() {
    let mut c = certifier(65, |z, o| (o[0], o[1]) = (z, (40.0 * z).exp()), 2);
    let b = [0.5, 0.5 * (1.0 + 40f64.exp())];
    c.set_moments(&b);
    let Found::Optimal(basis) = ScaledSimplex::default().solve(&c, 32, None) else {
        panic!("not optimal")
    };
    assert_eq!(c.optimal(&b, 32, &basis).unwrap().g, 0.5);
}
