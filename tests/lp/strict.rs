//! Solver names: "fast-strict" (the fast solver's earlier name) is the fast solver, answer for
//! answer; an unknown name is an error naming the choices.

use momentlab::lp::{make_solver, GridTable, SolverKind};
use momentlab::Grid;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

#[test]
fn fast_strict_is_the_fast_solver() {
    let grid = Grid::uniform(257).unwrap();
    let table = GridTable::from_fn(&grid, 4, |z, o| {
        o[0] = z;
        o[1] = z * z;
        o[2] = z * z * z;
        o[3] = z * z * z * z;
    })
    .unwrap();
    let strict: SolverKind = "fast-strict".parse().unwrap();
    assert_eq!(strict, SolverKind::Fast);
    let mut fast = make_solver(SolverKind::Fast, table.clone());
    let mut strict = make_solver(strict, table.clone());
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    for _ in 0..2000 {
        let k = rng.gen_range(1..=5);
        let mut b = [0.0; 4];
        let mut wsum = 0.0;
        let atoms: Vec<(f64, f64)> = (0..k)
            .map(|_| {
                (
                    grid.points()[rng.gen_range(0..257)],
                    rng.gen_range(0.05..1.0),
                )
            })
            .collect();
        atoms.iter().for_each(|a| wsum += a.1);
        for &(z, w) in &atoms {
            for (j, bj) in b.iter_mut().enumerate() {
                *bj += w / wsum * z.powi(j as i32 + 1);
            }
        }
        let zf = rng.gen_range(0.0..1.0);
        let f = fast.solve(&b, zf).unwrap();
        let s = strict.solve(&b, zf).unwrap();
        assert_eq!(s.status, f.status);
        assert_eq!(
            s.g.to_bits(),
            f.g.to_bits(),
            "strict {} vs fast {}",
            s.g,
            f.g
        );
        assert_eq!(s.support, f.support);
    }
}

#[test]
fn unknown_solver_names_the_choices() {
    let e = "simplex".parse::<SolverKind>().err().unwrap().to_string();
    assert!(
        e.contains("fast") && e.contains("reference") && e.contains("simplex"),
        "{e}"
    );
}
