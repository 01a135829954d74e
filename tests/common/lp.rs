//! Checking an LP's answer independently of the solver: its support is a distribution on the
//! grid that reproduces the moments, and G is that distribution's mass below z_f.

use momentlab::lp::{GridTable, Solution, Status};

/// Tolerances of [`check_points`]: `mass` bounds |Σw − 1| and |G − mass below z_f|; `moment`
/// bounds each moment's error relative to its scale.
pub struct Tol {
    pub mass: f64,
    pub moment: f64,
}

/// The support `(z, w)` with value `g`: every point is a grid point (`row(z)` gives its basis
/// values, None off the grid), every weight is positive, the weights sum to 1, moment j is
/// `b[j]` within `tol.moment · scale[j]`, and `g` is the mass below `zf`. Err names the first
/// violation. NaN fails every comparison.
pub fn check_points(
    support: &[(f64, f64)],
    g: f64,
    b: &[f64],
    zf: f64,
    row: impl Fn(f64) -> Option<Vec<f64>>,
    scale: &[f64],
    tol: Tol,
) -> Result<(), String> {
    let (mut mass, mut below) = (0.0, 0.0);
    let mut mom = vec![0.0; b.len()];
    for &(z, w) in support {
        let r = row(z).ok_or(format!("support point {z} not on the grid"))?;
        if !positive(w) {
            return Err(format!("weight {w}"));
        }
        mass += w;
        if z < zf {
            below += w;
        }
        for (mj, v) in mom.iter_mut().zip(r) {
            *mj += w * v;
        }
    }
    if !within(mass - 1.0, tol.mass) {
        return Err(format!("mass {mass}"));
    }
    if !within(below - g, tol.mass) {
        return Err(format!("G {g} vs mass below z_f {below}"));
    }
    for j in 0..b.len() {
        if !within(mom[j] - b[j], tol.moment * scale[j]) {
            return Err(format!(
                "moment {j}: support gives {} want {} (scale {})",
                mom[j], b[j], scale[j]
            ));
        }
    }
    Ok(())
}

/// [`check_points`] for a solution on `table`'s grid: the solution is optimal, its support
/// points are grid points exactly, Σw and G hold to 1e-9, and moment j holds to
/// `moment_tol` times the largest |b_j| on the grid.
pub fn check_support(
    table: &GridTable,
    b: &[f64],
    zf: f64,
    sol: &Solution,
    moment_tol: f64,
) -> Result<(), String> {
    if sol.status != Status::Optimal {
        return Err(format!("not optimal ({:?})", sol.status));
    }
    let z = table.grid().points();
    let scale: Vec<f64> = (0..table.m())
        .map(|j| {
            (0..table.n())
                .map(|i| table.row(i)[j].abs())
                .fold(1e-300, f64::max)
        })
        .collect();
    let row = |zs: f64| {
        z.iter()
            .position(|&v| v == zs)
            .map(|i| table.row(i).to_vec())
    };
    let tol = Tol {
        mass: 1e-9,
        moment: moment_tol,
    };
    check_points(&sol.support, sol.g, b, zf, row, &scale, tol)
}

/// |err| ≤ tol; false for NaN.
fn within(err: f64, tol: f64) -> bool {
    err.abs() <= tol
}

/// w > 0; false for NaN.
fn positive(w: f64) -> bool {
    w > 0.0
}
