//! LP candidates as a Technique: the "lp:" registry arm, Algorithm 1 through the evaluator
//! against an independently tabulated reference LP, infeasible → NaN.

use momentlab::basis::Catalog;
use momentlab::lp::{GridTable, MomentSolver, ReferenceSolver, SolverKind, Status};
use momentlab::technique::lp_candidate::LpCandidate;
use momentlab::technique::{by_name, Technique};
use momentlab::Grid;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

#[test]
fn registry_arm_parses_specs() {
    let t = by_name("lp:z,z^2").unwrap();
    assert_eq!(t.name(), "lp[z,z^2]");
    assert_eq!(t.moment_count(), 2);
    assert_eq!(t.bits_per_texel(), 64);
    assert_eq!(t.depth_grid().unwrap().len(), 1024);
    let mut out = [0.0; 2];
    t.basis(0.5, &mut out);
    assert_eq!(out, [0.5, 0.25]);

    let t = by_name("lp: z , tanh(10(z-0.5)), 1/(1+3z)").unwrap();
    assert_eq!(t.name(), "lp[z,tanh(10(z-0.5)),1/(1+3z)]");
    let mut out = [0.0; 3];
    t.basis(0.25, &mut out);
    assert!((out[1] - (-2.5f64).tanh()).abs() < 1e-15 && (out[2] - 1.0 / 1.75).abs() < 1e-15);

    // The solver: the certified fast one.
    let c = LpCandidate::from_spec("z,z^2").unwrap();
    assert_eq!(c.solver_kind(), SolverKind::Fast);

    for (spec, want) in [
        ("lp:", "empty function name"),
        ("lp:z,,z^2", "empty function name"),
        ("lp:z,blorp", "'blorp' is not in the catalog"),
        ("lp:z,log(z)", "not finite on [0,1]"),
        ("lp:z,sin(z", "expected ')'"),
    ] {
        let e = match by_name(spec) {
            Ok(t) => panic!("{spec} accepted as {}", t.name()),
            Err(e) => format!("{e:#}"),
        };
        assert!(e.contains(want), "{spec}: {e}");
        assert!(!e.contains('\n'));
    }
}

#[test]
fn evaluator_is_algorithm_1() {
    let n = 33;
    let grid = Grid::uniform(n).unwrap();
    let c = Catalog::embedded();
    let names = ["z", "exp(-5z)", "sin(2πz)"];
    let basis = c.basis(&names).unwrap();
    let cand = LpCandidate::new(basis, grid.clone(), SolverKind::Reference).unwrap();
    assert_eq!(cand.depth_grid().unwrap(), &grid);
    assert!("nope".parse::<SolverKind>().is_err());

    // Independent tabulation of the same functions with std math.
    let b = |z: f64| [z, (-5.0 * z).exp(), (2.0 * std::f64::consts::PI * z).sin()];
    let table = GridTable::from_fn(&grid, 3, |z, o| o.copy_from_slice(&b(z))).unwrap();
    let mut oracle = ReferenceSolver::new(table);
    let mut ev = cand.evaluator();
    let mut rng = ChaCha8Rng::seed_from_u64(9);
    for _ in 0..60 {
        let k = rng.gen_range(1..=4);
        let mut m = [0.0; 3];
        let mut lo = 1.0f64;
        for _ in 0..k {
            let z = rng.gen_range(0..n) as f64 / (n - 1) as f64;
            let v = b(z);
            lo = lo.min(z);
            for j in 0..3 {
                m[j] += v[j] / k as f64;
            }
        }
        let zf = match rng.gen_range(0..3) {
            0 => rng.gen_range(0.0..1.0),
            1 => lo,
            _ => rng.gen_range(0..n) as f64 / (n - 1) as f64,
        };
        let g = ev.shadow(&m, zf);
        let want = oracle.solve(&m, zf).unwrap();
        assert_eq!(want.status, Status::Optimal);
        assert!(
            (g - want.g).abs() < 1e-9,
            "{m:?} zf {zf}: {g} vs {}",
            want.g
        );
        assert!((0.0..=1.0).contains(&g));
        if zf <= lo {
            assert!(g.abs() < 1e-9, "nothing below the lowest Dirac: {g}");
        }
    }
    // A single Dirac: 0 at or above z_f, 1 below.
    let z0 = 8.0 / 32.0;
    assert!(ev.shadow(&b(z0), z0).abs() < 1e-9);
    assert!((ev.shadow(&b(z0), z0 + 1e-3) - 1.0).abs() < 1e-9);
    // Infeasible moments (z outside [0,1]) → NaN.
    assert!(ev.shadow(&b(1.5), 0.5).is_nan());
    assert!(ev.shadow(&[0.5, 0.5, 2.0], 0.5).is_nan());
}

/// The registry's candidate (fast solver once merged, 1024 points) against the reference LP.
#[test]
fn registry_candidate_matches_reference() {
    let t = by_name("lp:z,z^2,z^3,z^4").unwrap();
    let grid = t.depth_grid().unwrap().clone();
    let n = grid.len();
    let table = GridTable::from_fn(&grid, 4, |z, o| {
        for (j, v) in o.iter_mut().enumerate() {
            *v = z.powi(j as i32 + 1);
        }
    })
    .unwrap();
    let mut oracle = ReferenceSolver::new(table);
    let mut ev = t.evaluator();
    let mut rng = ChaCha8Rng::seed_from_u64(21);
    for _ in 0..12 {
        let k = rng.gen_range(1..=4);
        let mut m = [0.0; 4];
        for _ in 0..k {
            let z = rng.gen_range(0..n) as f64 / (n - 1) as f64;
            let mut out = [0.0; 4];
            t.basis(z, &mut out);
            for j in 0..4 {
                m[j] += out[j] / k as f64;
            }
        }
        let zf = rng.gen_range(0.0..1.0);
        let (g, want) = (ev.shadow(&m, zf), oracle.solve(&m, zf).unwrap().g);
        assert!((g - want).abs() < 1e-7, "{m:?} zf {zf}: {g} vs {want}");
    }
}
