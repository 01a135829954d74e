use super::*;
use crate::Grid;

fn solver(n: usize, m: usize, f: impl FnMut(f64, &mut [f64])) -> FastSolver {
    FastSolver::new(GridTable::from_fn(&Grid::uniform(n).unwrap(), m, f).unwrap())
}

/// (z, z²) on {0, 1/4, 1/2, 3/4, 1}, b = (1/2, 5/16): G(z_f = 0.6) = 1/2 with support
/// ½δ(1/4) + ½δ(3/4), from the moments and from a distribution with those moments
/// (⅛δ(0) + ¾δ(1/2) + ⅛δ(1), mass ⅞ below z_f: the crossover must improve on it).
#[test]
fn known_optimum_from_moments_and_from_a_distribution() {
    let mut s = solver(5, 2, |z, o| (o[0], o[1]) = (z, z * z));
    let sol = s.solve(&[0.5, 0.3125], 0.6).unwrap();
    assert_eq!(sol.status, Status::Optimal);
    assert_eq!(sol.g, 0.5);
    assert_eq!(sol.support, vec![(0.25, 0.5), (0.75, 0.5)]);
    let d = s
        .solve_distribution(&[(0, 1.0), (2, 6.0), (4, 1.0)], 0.6)
        .unwrap();
    assert_eq!((d.status, d.g), (Status::Optimal, 0.5));
    assert_eq!(s.stats().hinted, 1);
    // Below every grid point, and above: G = 0 and G = 1.
    assert_eq!(s.solve(&[0.5, 0.3125], 0.0).unwrap().g, 0.0);
    assert_eq!(s.solve(&[0.5, 0.3125], 1.5).unwrap().g, 1.0);
}

/// The orthonormalised coordinates on {0, 1/2, 1} with (z, z²): orthonormal rows
/// (Σ_i a_i a_iᵀ = n I), and c = transform(b̄) = Σ_i w_i a_i for the distribution
/// w = (1/4, 1/2, 1/4) whose moments are b = (1/2, 3/8).
#[test]
fn orthonormal_coordinates_and_transformed_moments() {
    let s = solver(3, 2, |z, o| (o[0], o[1]) = (z, z * z));
    let o = &s.ortho;
    assert_eq!((o.r, o.kept.clone()), (3, vec![Some(0), Some(1), Some(2)]));
    for k in 0..3 {
        for l in 0..3 {
            let g: f64 = (0..3).map(|i| o.rows[i * 3 + k] * o.rows[i * 3 + l]).sum();
            assert!(
                (g - if k == l { 3.0 } else { 0.0 }).abs() < 1e-14,
                "{k} {l}: {g}"
            );
        }
    }
    let (mut u, mut c) = ([0.0; 3], [0.0; 3]);
    assert!(o.transform(&[0.5, 0.375], &mut u, &mut c));
    let w = [0.25, 0.5, 0.25];
    for k in 0..3 {
        let want: f64 = (0..3).map(|i| w[i] * o.rows[i * 3 + k]).sum();
        assert!((c[k] - want).abs() < 1e-14, "{c:?}");
    }
    assert!(o.inconsistency_ray(&[0.5, 0.375]).is_none());
    assert!(o.condition >= 1.0 && o.condition.is_finite());
    // max_i ‖a_i‖: a_i = √n Q_i, and Σ_i ‖a_i‖² = n·r.
    let norms: Vec<f64> = (0..3)
        .map(|i| {
            (0..3)
                .map(|k| o.rows[i * 3 + k].powi(2))
                .sum::<f64>()
                .sqrt()
        })
        .collect();
    assert_eq!(o.amax, norms.iter().cloned().fold(0.0, f64::max));
    assert!((norms.iter().map(|v| v * v).sum::<f64>() - 9.0).abs() < 1e-13);
}

/// (z, 2z) has rank 2 with the constant: the second moment is checked for consistency
/// (b₂ = 2b₁) instead of being a row of the LP.
#[test]
fn dependent_function_is_a_consistency_check() {
    let mut s = solver(9, 2, |z, o| (o[0], o[1]) = (z, 2.0 * z));
    assert_eq!(s.rank(), 2);
    // A single moment z̄ = 3/8 on a grid with z ≤ 1: G(z_f = 1/2) = 1/4 — the least mass
    // below 1/2 with mean 3/8 puts 3/4 at 1/2 and 1/4 at 0 (1/2 is not below z_f).
    let sol = s.solve(&[0.375, 0.75], 0.5).unwrap();
    assert_eq!((sol.status, sol.g), (Status::Optimal, 0.25));
    // Inconsistent (b₂ ≠ 2b₁): no distribution has these moments. The dependency
    // y = ±(e₂ − 2e₁) is the Farkas ray: y·ā_i = 0 on every grid point, y·b̄ = ∓0.05.
    let infeasible = s.stats().infeasible;
    let bad = s.solve(&[0.375, 0.7], 0.5).unwrap();
    assert_eq!(bad.status, Status::Infeasible);
    assert!(bad.g.is_nan() && bad.support.is_empty());
    assert_eq!(s.stats().infeasible, infeasible + 1);
    let y = s.ortho.inconsistency_ray(&[0.375, 0.7]).unwrap();
    for (got, want) in y.iter().zip([0.0, -2.0, 1.0]) {
        assert!((got - want).abs() < 1e-14, "{y:?}");
    }
    // Consistent to the tolerance: no ray, and the LP is solved on the kept rows.
    assert!(s.ortho.inconsistency_ray(&[0.375, 0.75 + 1e-12]).is_none());
    // An inconsistency far below the certificate's tolerance-widened moment space but
    // above the consistency check's: `failed` or `infeasible`, never an optimum.
    let near = s.solve(&[0.375, 0.75 + 3e-8], 0.5).unwrap();
    assert_ne!(near.status, Status::Optimal);
}

/// Another z_f for the same moments starts from the last optimal basis (primal feasible):
/// no phase 1; a reset solver answers bit for bit as a new one.
#[test]
fn same_moments_reuse_the_basis_and_reset_forgets_it() {
    let mut s = solver(257, 4, |z, o| {
        for (k, v) in o.iter_mut().enumerate() {
            *v = z.powi(k as i32 + 1);
        }
    });
    // 0.3δ(1/4) + 0.3δ(1/2) + 0.4δ(3/4), atoms on grid points.
    let b: Vec<f64> = (1..=4)
        .map(|k| 0.3 * 0.25f64.powi(k) + 0.3 * 0.5f64.powi(k) + 0.4 * 0.75f64.powi(k))
        .collect();
    let first = s.solve(&b, 0.6).unwrap();
    let phase1 = s.stats().phase1;
    let again = s.solve(&b, 0.2).unwrap();
    assert_eq!(
        s.stats().phase1,
        phase1,
        "the warm basis is primal feasible"
    );
    // The mixture itself has mass 0.6 below 0.6: an upper bound on G. Below every atom of
    // the first answer's support the bound is 0.
    assert!(first.g > 0.0 && first.g <= 0.6, "{first:?}");
    assert_eq!(again.g, 0.0, "{again:?}");
    s.reset();
    let mut fresh = solver(257, 4, |z, o| {
        for (k, v) in o.iter_mut().enumerate() {
            *v = z.powi(k as i32 + 1);
        }
    });
    assert_eq!(s.solve(&b, 0.5).unwrap(), fresh.solve(&b, 0.5).unwrap());
}
