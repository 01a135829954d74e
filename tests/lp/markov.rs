//! `lp:exp(80*(z-1))` (ESM's function as an LP candidate) on every fragment of a rendered view:
//! the sharp bound on the grid lies pointwise between Markov's bound (the closed-form `esm`,
//! sharp on I = R, so weaker on [0,1]) and the true CDF F_Z(z_f). Before the certificates the
//! LP answered G = 0 "optimal" on exactly these inputs (31.9 % error against ESM's
//! 9.9 %).

use momentlab::basis::Catalog;
use momentlab::bench::corpus::table_for;
use momentlab::lp::FastSolver;
use momentlab::lp::{MomentSolver, Status};
use momentlab::metrics::windows::stacks_corpus;
use momentlab::technique::esm::esm;
use momentlab::Grid;

#[test]
fn steep_exponential_lp_lies_between_markov_and_the_cdf() {
    let stacks = momentlab::render::default_dataset(48).unwrap();
    let view = &stacks[..1];
    // Every fragment of the view (the sampler keeps all when asked for more than there are).
    let windows = stacks_corpus(view, usize::MAX / 4, 1).unwrap();
    let all: usize = view.iter().map(|s| s.fragment_count()).sum();
    assert!(
        windows.zfs.len() >= all * 9 / 10,
        "{} of {all}",
        windows.zfs.len()
    );
    let grid = Grid::uniform(1024).unwrap();
    let table = table_for(&Catalog::embedded(), &grid, &["exp(80*(z-1))".to_string()]).unwrap();
    let mut solver = FastSolver::new(table.clone());
    let (mut below_markov, mut above_cdf, mut strict) = (0, 0, 0);
    for (w, &zf) in windows.dists.iter().zip(&windows.zfs) {
        // The window's distribution snapped to the grid (as the pipeline does for LP candidates).
        let atoms: Vec<(f64, f64)> = w
            .iter()
            .map(|&(z, wt)| (grid.points()[grid.nearest(z)], wt))
            .collect();
        let total: f64 = atoms.iter().map(|a| a.1).sum();
        let b: f64 = atoms
            .iter()
            .map(|&(z, wt)| wt * (80.0 * (z - 1.0)).exp())
            .sum::<f64>()
            / total;
        let cdf: f64 = atoms.iter().filter(|a| a.0 < zf).map(|a| a.1).sum::<f64>() / total;
        let markov = esm(b * 80f64.exp(), zf, 80.0).max(0.0);
        let sol = solver.solve(&[b], zf).unwrap();
        assert_eq!(
            sol.status,
            Status::Optimal,
            "b {b:e} zf {zf}: {:?}",
            sol.reason
        );
        below_markov += (sol.g < markov - 1e-9) as usize;
        above_cdf += (sol.g > cdf + 1e-9) as usize;
        strict += (sol.g > markov + 1e-6) as usize;
    }
    let n = windows.zfs.len();
    eprintln!("{n} fragments: LP above Markov by > 1e-6 on {strict}");
    assert_eq!(
        below_markov, 0,
        "LP below Markov's bound on {below_markov} of {n}"
    );
    assert_eq!(above_cdf, 0, "LP above F_Z on {above_cdf} of {n}");
}
