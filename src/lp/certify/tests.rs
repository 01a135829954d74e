use super::*;
use crate::Grid;

/// (z, z²) on the grid {0, 1/4, 1/2, 3/4, 1}.
fn quadratic_table() -> GridTable {
    let grid = Grid::uniform(5).unwrap();
    GridTable::from_fn(&grid, 2, |z, o| (o[0], o[1]) = (z, z * z)).unwrap()
}

#[test]
fn scale_floor_exact_values() {
    // Sign-definite: min(1e-30 · max, smallest nonzero magnitude).
    assert_eq!(scale_floor(&[1.0, 2.0, 4.0]), SCALE_FLOOR * 4.0);
    assert_eq!(scale_floor(&[0.0, 1e-40, 1.0]), 1e-40);
    assert_eq!(scale_floor(&[-3.0, -1.0, 0.0]), SCALE_FLOOR * 3.0);
    // Sign-changing: CANCEL · max.
    assert_eq!(scale_floor(&[-1.0, 0.5, 2.0]), CANCEL * 2.0);
}

/// b = (1/2, 5/16), z_f = 0.6 (three grid points below): G = 1/2, attained by ½δ(1/4) +
/// ½δ(3/4). The basis {1/4, 1/2, 3/4} is optimal: its dual polynomial
/// q(z) = 1 − 8(z − 1/4)(z − 1/2) is 1 on {1/4, 1/2}, 0 at 3/4, q(0) = 0 ≤ 1, q(1) = −2 ≤ 0,
/// so L = E[q] = 1/2 = G.
#[test]
fn optimal_basis_certifies_with_its_exact_bound() {
    let t = quadratic_table();
    let mut c = Certifier::new(&t, vec![0, 1, 2]);
    let b = [0.5, 0.3125];
    let got = c.optimal(&b, 3, &[1, 2, 3]).unwrap();
    assert_eq!(got.g, 0.5);
    assert_eq!(got.support, vec![(0.25, 0.5), (0.75, 0.5)]);
    assert!(got.gap.abs() <= 1e-15 && got.residual <= 1e-15, "{got:?}");
    assert!(got.min_reduced >= -1e-15, "{got:?}");
}

/// The feasible basis {0, 1/2, 1} (weights 1/8, 3/4, 1/8, mass 7/8 below z_f) is not
/// optimal: its dual polynomial 1 − 2z(z − 1/2) is 9/8 at 1/4, a reduced cost of −1/8.
/// Accurate pivots from it reach the optimum 1/2.
#[test]
fn suboptimal_basis_is_refused_then_improved() {
    let t = quadratic_table();
    let mut c = Certifier::new(&t, vec![0, 1, 2]);
    let b = [0.5, 0.3125];
    let e = c.optimal(&b, 3, &[0, 2, 4]).unwrap_err();
    assert!(!e.is_empty());
    let mut basis = [0, 2, 4];
    let got = c.improve(&b, 3, &mut basis, 8).unwrap();
    assert_eq!(got.g, 0.5);
}

/// Stopping a check at the f64 reduced costs when they already bring the dual bound below
/// G − 1e-9 gives the verdict of the whole check: on 3 000 bases of neighbouring and
/// random grid points (z, …, z⁴ on 4096 points; moments of flat windows, tight clusters
/// and random mixtures; z_f inside and around the support), the same Ok or Err, and the
/// same certified answer, with and without the early stop; some checks stop early.
#[test]
fn early_stop_keeps_every_verdict() {
    use rand::{Rng, SeedableRng};
    let n = 4096;
    let grid = Grid::uniform(n).unwrap();
    let t = GridTable::from_fn(&grid, 4, |z, o| {
        let mut p = 1.0;
        for v in o.iter_mut() {
            p *= z;
            *v = p;
        }
    })
    .unwrap();
    let mut early = Certifier::new(&t, vec![0, 1, 2, 3, 4]);
    let mut full = early.clone();
    full.early = false;
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(21);
    let (mut ok, mut stopped) = (0, 0);
    for case in 0..3000 {
        let at = rng.gen_range(8..n - 16);
        let dist: Vec<(u32, f64)> = match case % 3 {
            0 => (at..at + rng.gen_range(2..5))
                .map(|i| (i as u32, rng.gen_range(0.05..1.0)))
                .collect(),
            1 => vec![(at as u32, 0.7), ((at + rng.gen_range(1..4)) as u32, 0.3)],
            _ => (0..rng.gen_range(1..6))
                .map(|_| (rng.gen_range(0..n as u32), rng.gen_range(0.05..1.0)))
                .collect(),
        };
        let b = crate::lp::distribution_moments(&t, &dist).unwrap();
        let mut basis: Vec<usize> = match case % 2 {
            0 => (0..5)
                .map(|k| at - 2 + k + rng.gen_range(0..2) * k)
                .collect(),
            _ => (0..5).map(|_| rng.gen_range(0..n)).collect(),
        };
        basis.sort_unstable();
        basis.dedup();
        if basis.len() < 5 {
            continue;
        }
        let kf = at + rng.gen_range(0..6) - 2;
        let got = early.optimal(&b, kf, &basis);
        let want = full.optimal(&b, kf, &basis);
        assert_eq!(got.is_ok(), want.is_ok(), "{case}: {got:?} {want:?}");
        if let (Ok(g), Ok(w)) = (&got, &want) {
            assert_eq!(g, w, "{case}");
            ok += 1;
        }
        stopped += usize::from(got.is_err() && early.duals_fresh != full.duals_fresh);
    }
    assert!(
        ok > 50 && stopped > 50,
        "{ok} certified, {stopped} stopped early"
    );
}

/// A distribution with no atom below z_f is its own optimum (G = 0, zero duals); one with
/// an atom below is refused.
#[test]
fn zero_mass_distribution() {
    let t = quadratic_table();
    let mut c = Certifier::new(&t, vec![0, 1, 2]);
    // ½δ(3/4) + ½δ(1): b = (7/8, 25/32).
    let b = [0.875, 0.78125];
    let got = c.zero_mass(&b, 3, &[(4, 1.0), (3, 1.0)]).unwrap();
    assert_eq!(got.g, 0.0);
    assert_eq!(got.support, vec![(0.75, 0.5), (1.0, 0.5)]);
    assert_eq!(
        c.zero_mass(&b, 3, &[(2, 1.0), (4, 1.0)]).unwrap_err(),
        "mass below z_f"
    );
    // Moments the distribution does not have.
    assert!(c
        .zero_mass(&[0.9, 0.78125], 3, &[(4, 1.0), (3, 1.0)])
        .is_err());
}

/// (1/2, 1/5) has negative variance: y = (1/4, −1, 1), i.e. (z − 1/2)² ≥ 0 on the grid
/// with E[(z − 1/2)²] = −1/20, is a Farkas ray with margin 1/20 (less the tolerance).
#[test]
fn farkas_ray_certifies_infeasibility() {
    let t = quadratic_table();
    let mut c = Certifier::new(&t, vec![0, 1, 2]);
    let margin = c.infeasible(&[0.5, 0.2], &[0.25, -1.0, 1.0]).unwrap();
    assert!((margin - 0.05).abs() < 1e-8, "{margin}");
    // Not a ray for feasible moments, nor of the wrong size.
    assert!(c.infeasible(&[0.5, 0.3125], &[0.25, -1.0, 1.0]).is_err());
    assert!(c.infeasible(&[0.5, 0.2], &[0.25, -1.0]).is_err());
}
