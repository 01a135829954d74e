//! Known answers for Algorithm 1 (fast solver): single Diracs, the Cantelli limit, bad input,
//! and independence of the start basis.

use momentlab::bench::instances::{
    mixture_moments, power_table, random_mixture, smooth_functions, table_of,
};
use momentlab::lp::FastSolver;
use momentlab::lp::{make_solver, MomentSolver, SolverKind, Status};
use momentlab::Grid;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

#[test]
fn single_dirac_gives_zero_or_one() {
    // Bases containing z and z² (zero variance pins the distribution to the Dirac).
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    let fns = smooth_functions();
    for n in [2usize, 5, 33, 257, 1024] {
        let grid = Grid::uniform(n).unwrap();
        for trial in 0..20usize {
            let m = rng.gen_range(2..=4);
            let mut pick = vec![fns[0], fns[1]];
            pick.extend((2..m).map(|k| fns[2 + (trial * 3 + k * 5) % (fns.len() - 2)]));
            let table = table_of(&grid, &pick).unwrap();
            let mut s = FastSolver::new(table.clone());
            let i = rng.gen_range(0..n);
            let zi = grid.points()[i];
            let b = mixture_moments(&table, &[(i, 1.0)]);
            // z_f at or below the Dirac: nothing strictly below z_f; above: all of it.
            for (zf, want) in [(zi, 0.0), (zi - 1e-9, 0.0), (zi + 1e-9, 1.0), (2.0, 1.0)] {
                let sol = s.solve(&b, zf).unwrap();
                assert_eq!(sol.status, Status::Optimal, "n {n} i {i}");
                assert!(
                    (sol.g - want).abs() < 1e-9,
                    "n {n} i {i} zf {zf}: {}",
                    sol.g
                );
            }
        }
    }
}

/// For b = (z, z²) with mean μ and variance σ², G approaches the one-tailed Chebyshev
/// (Cantelli) bound as the grid is refined: 0 for z_f ≤ μ, else (z_f−μ)²/(σ²+(z_f−μ)²)
/// (the optimum on R has its atoms at z_f and μ − σ²/(z_f − μ), both inside [0,1] here; for
/// z_f ≤ μ the bound 0 is attainable on [0,1] when (μ − z_f)(1 − μ) ≥ σ²).
#[test]
fn cantelli_limit_with_shrinking_error() {
    let (mu, var) = (0.5013, 0.0101);
    let cantelli = |zf: f64| {
        if zf <= mu {
            0.0
        } else {
            (zf - mu).powi(2) / (var + (zf - mu).powi(2))
        }
    };
    let zfs = [0.3, 0.45, 0.6207, 0.7003, 0.9];
    let mut errors = Vec::new();
    for n in [11usize, 101, 1001, 10001] {
        let grid = Grid::uniform(n).unwrap();
        let mut s = FastSolver::new(power_table(&grid, 2).unwrap());
        let b = [mu, var + mu * mu];
        let mut worst: f64 = 0.0;
        for &zf in &zfs {
            let sol = s.solve(&b, zf).unwrap();
            assert_eq!(sol.status, Status::Optimal);
            // The grid restricts the distributions: never below the bound on R.
            assert!(sol.g >= cantelli(zf) - 1e-9, "n {n} zf {zf}: {}", sol.g);
            worst = worst.max(sol.g - cantelli(zf));
        }
        eprintln!("n = {n}: max G − Cantelli = {worst:e}");
        errors.push(worst);
    }
    for w in errors.windows(2) {
        assert!(w[1] < w[0], "error does not shrink: {errors:?}");
    }
    assert!(errors[3] < 1e-3, "{errors:?}");
}

#[test]
fn bad_input_is_an_error_not_a_panic() {
    let grid = Grid::uniform(16).unwrap();
    let mut s = make_solver(SolverKind::Fast, power_table(&grid, 3).unwrap());
    assert!(s.solve(&[0.5, 0.3], 0.5).is_err());
    assert!(s.solve(&[0.5, f64::NAN, 0.1], 0.5).is_err());
    assert!(s.solve(&[0.5, f64::INFINITY, 0.1], 0.5).is_err());
    assert!(s.solve(&[0.5, 0.3, 0.2], f64::NAN).is_err());
    // Out-of-range but finite moments are simply infeasible.
    let sol = s.solve(&[5.0, 0.3, 0.2], 0.5).unwrap();
    assert_eq!(sol.status, Status::Infeasible);
    assert!("nope".parse::<SolverKind>().is_err());
    let mut f = FastSolver::new(power_table(&grid, 3).unwrap());
    assert!(f.set_warm_basis(&[0, 1]).is_err());
    assert!(f.set_warm_basis(&[0, 1, 1, 2]).is_err());
    assert!(f.set_warm_basis(&[0, 1, 2, 99]).is_err());
}

/// Any start basis (random, possibly infeasible or ill-conditioned) gives the same G as a
/// cold start.
#[test]
fn result_is_independent_of_the_start_basis() {
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    let mut count = 0;
    for _ in 0..60 {
        let n = [16usize, 64, 256][rng.gen_range(0..3)];
        let m = rng.gen_range(1..=6);
        let grid = Grid::uniform(n).unwrap();
        let table = power_table(&grid, m).unwrap();
        let mut cold = FastSolver::new(table.clone());
        cold.set_warm_start(false);
        let mut any = FastSolver::new(table.clone());
        for _ in 0..10 {
            let k = rng.gen_range(1..=6);
            let mix = random_mixture(&mut rng, n, k);
            let b = mixture_moments(&table, &mix);
            let zf = grid.points()[rng.gen_range(0..n)];
            let mut start: Vec<usize> = Vec::new();
            while start.len() < m + 1 {
                let i = rng.gen_range(0..n);
                if !start.contains(&i) {
                    start.push(i);
                }
            }
            any.set_warm_basis(&start).unwrap();
            let a = any.solve(&b, zf).unwrap();
            let c = cold.solve(&b, zf).unwrap();
            let bound = 10.0 * any.last_error_bound().max(cold.last_error_bound());
            assert!(
                (a.g - c.g).abs() <= 1e-9_f64.max(bound),
                "n {n} m {m} start {start:?} mix {mix:?} zf {zf}: {} vs {}",
                a.g,
                c.g
            );
            count += 1;
        }
    }
    assert_eq!(count, 600);
}
