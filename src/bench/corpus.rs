//! The adversarial corpus of Algorithm 1 problems (deterministic for a seed), used by the tests
//! (tests/lp/contract.rs) and by `momentlab bench lp --corpus adversarial`.
//!
//! Every problem is the moment vector of a known distribution on the grid (so it is feasible
//! and its own mass below z_f bounds G from above), chosen where solvers break:
//! * flat receivers: 9×9 Gaussian windows (σ = 2.4) over a plane spanning 0–3 grid steps,
//!   30 % with an occluder edge, depths snapped to the grid;
//! * 1–3 adjacent grid points (also at the ends of the grid);
//! * tight clusters (0.99 / 0.01 at 1–3 grid steps) with z_f below, inside and above;
//! * boundary moment vectors (≤ m/2 Diracs) and random mixtures;
//!
//! on the power bases m = 1…12, every catalog function alone, exp(c·z) for |c| ≤ 80 (and 400)
//! alone, exp(80(z−1)) (ESM's c = 80), the paper's bases (MSM z…z⁴, TMSM's trigonometric
//! basis, EVSM's exponentials) and mixed bases with exp(±40z), at n = 256…8192.

//!
//! The problem kinds and generators live in [`crate::lp::corpus`]; this module adds the
//! adversarial set of bases, which needs the catalog.

use crate::basis::Catalog;
use crate::lp::GridTable;
use crate::Grid;
use anyhow::{Context, Result};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

pub use crate::lp::corpus::{
    from_windows, mass_below, moments_groups, problem, Group, Kind, Problem, KINDS,
};

/// The adversarial corpus with `per_kind` problems of every kind for every table. `large`
/// adds the n = 4096 and 8192 tables.
pub fn adversarial(per_kind: usize, large: bool, seed: u64) -> Result<Vec<Group>> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let catalog = Catalog::embedded();
    let mut specs: Vec<(Vec<String>, usize)> = Vec::new();
    let power = |m: usize| -> Vec<String> {
        (1..=m)
            .map(|k| if k == 1 { "z".into() } else { format!("z^{k}") })
            .collect()
    };
    let ns: &[usize] = if large {
        &[256, 1024, 4096, 8192]
    } else {
        &[256, 1024]
    };
    for &n in ns {
        specs.push((power(4), n));
    }
    for m in (1..=12).filter(|&m| m != 4) {
        specs.push((power(m), 1024));
    }
    for c in [-80.0, -40.0, -20.0, -5.0, 5.0, 20.0, 40.0, 80.0, 400.0] {
        specs.push((vec![format!("exp({c}*z)")], 1024));
    }
    specs.push((vec!["exp(80*(z-1))".into()], 1024));
    specs.push((vec!["exp(80*(z-1))".into()], 4096));
    for f in catalog.functions() {
        specs.push((vec![f.formula().to_string()], 1024));
    }
    let paper: [&[&str]; 5] = [
        &["sin(2*pi*z)", "cos(2*pi*z)", "sin(4*pi*z)", "cos(4*pi*z)"],
        &["exp(40*z)", "exp(80*z)", "-exp(-40*z)", "exp(-80*z)"],
        &["exp(40*z)", "-exp(-40*z)"],
        &["z", "z^2", "z^3", "exp(-40*z)"],
        &["z", "z^2", "exp(40*z)", "exp(-40*z)"],
    ];
    for b in paper {
        specs.push((b.iter().map(|s| s.to_string()).collect(), 1024));
    }
    let mut out = Vec::new();
    for (basis, n) in specs {
        let grid = Grid::uniform(n)?;
        let table = table_for(&catalog, &grid, &basis)?;
        let m = basis.len();
        for kind in KINDS {
            let problems = (0..per_kind)
                .map(|_| problem(&mut rng, n, m, kind))
                .collect();
            out.push(Group {
                name: format!("{} @ {n}: {kind:?}", basis.join(", ")),
                basis: basis.clone(),
                table: table.clone(),
                problems,
            });
        }
    }
    Ok(out)
}

/// Tabulate formulas (catalog names or formulas) on `grid`.
pub fn table_for(catalog: &Catalog, grid: &Grid, basis: &[String]) -> Result<GridTable> {
    let fns = basis
        .iter()
        .map(|s| catalog.resolve(s))
        .collect::<Result<Vec<_>>>()
        .context("corpus basis")?;
    Ok(GridTable::from_fn(grid, fns.len(), |z, out| {
        for (o, f) in out.iter_mut().zip(&fns) {
            *o = f.eval(z);
        }
    })?)
}
