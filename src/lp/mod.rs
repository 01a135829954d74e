//! Algorithm 1 of Peters & Klein 2015 (Section 3.1): the discretized general moment problem.
//!
//! Given b(z_1..z_n) on a grid I, a moment vector b ∈ R^m and a fragment depth z_f,
//!
//! G(b, z_f) = min Σ_{z_i < z_f} w_i  s.t.  w ≥ 0, Σ w_i = 1, Σ w_i b(z_i) = b.
//!
//! Two solvers behind [`MomentSolver`]: [`ReferenceSolver`] (good_lp + microlp, the LP exactly
//! as stated) and [`FastSolver`] (certified; its answers carry a checked certificate, with an
//! exact simplex as the last resort). The public API is this file: the grid table, the solvers
//! ([`make_solver`]) and their trait, the answer and its status.
//!
//! # The fast solver's chain
//!
//! A problem goes down this chain until an answer is certified; each step is a folder or file:
//!
//! 1. `fast/`: a revised primal simplex on the whole grid in orthonormalised coordinates
//!    (`fast/simplex.rs`, its starts `fast/starts.rs` and `fast/recognise.rs`, the SIMD pricing
//!    kernels `fast/pricing/`);
//! 2. `fast/escalate/band.rs`: the same simplex on a window of the grid in the window's own
//!    coordinates;
//! 3. accurate pivots in the certifier's coordinates (`certify/improve.rs`);
//! 4. `fast/escalate/scaled/`: a revised simplex in double-double arithmetic on the LP scaled
//!    per problem;
//! 5. `fast/escalate/exact/`: an exact rational simplex.
//!
//! `certify/` judges every answer in the original coordinates (weights, the weak-duality bound
//! in `certify/bound.rs`, Farkas rays; its blocked row kernels in `certify/row_kernels/`).
//! What no step certifies is [`Status::Failed`] with the reasons. Shared numerics: `dense.rs`
//! (small LUs, double-double), `ortho.rs` (Gram–Schmidt of the table), `ratio.rs` (Harris'
//! ratio test), `cpu.rs` (CPU features). docs/lp.md maps every file.

#![warn(missing_docs)]

mod certify;
pub mod corpus;
mod cpu;
mod dense;
mod error;
mod fast;
mod ortho;
mod ratio;
mod reference;

pub use error::{Error, Result, SolverKind};
pub use fast::{FastSolver, FastStats};
pub use reference::ReferenceSolver;

use crate::Grid;

/// The pricing kernel the fast solver uses on this CPU ("avx512", "avx2" or "scalar"; the
/// environment variable `MOMENTLAB_PRICING` selects a supported one).
pub fn pricing_kernel() -> &'static str {
    fast::pricing::Kernel::detect().name()
}

/// The values b(z_i) of a basis on a grid: the constraint columns of Algorithm 1.
#[derive(Clone, Debug)]
pub struct GridTable {
    grid: Grid,
    m: usize,
    /// Row-major n × m: values[i*m + j] = b_j(z_i).
    values: Vec<f64>,
}

impl GridTable {
    /// Tabulate `f(z, out)` (writing the m values b(z)) at every grid point.
    pub fn from_fn(grid: &Grid, m: usize, mut f: impl FnMut(f64, &mut [f64])) -> Result<GridTable> {
        if m == 0 {
            return Err(Error::NoFunctions);
        }
        if m > MAX_FUNCTIONS {
            return Err(Error::TooManyFunctions { m });
        }
        let n = grid.len();
        if n.saturating_mul(m) > MAX_TABLE_VALUES {
            return Err(Error::TableTooLarge { n, m });
        }
        let mut values = vec![0.0; n * m];
        for (i, &z) in grid.points().iter().enumerate() {
            let row = &mut values[i * m..(i + 1) * m];
            f(z, row);
            if let Some(j) = row.iter().position(|v| !v.is_finite()) {
                return Err(Error::NotFinite { function: j + 1, z });
            }
        }
        Ok(GridTable {
            grid: grid.clone(),
            m,
            values,
        })
    }

    /// A table of any number of functions (a catalog tabulated once, from which LP tables are
    /// gathered by [`GridTable::columns`]); `values` row-major n × m, finite, checked by the
    /// caller. Only the size limit applies.
    pub(crate) fn wide(grid: &Grid, m: usize, values: Vec<f64>) -> Result<GridTable> {
        let n = grid.len();
        if m == 0 || values.len() != n * m {
            return Err(Error::TableShape {
                values: values.len(),
                n,
                m,
            });
        }
        if values.len() > MAX_TABLE_VALUES {
            return Err(Error::TableTooLarge { n, m });
        }
        Ok(GridTable {
            grid: grid.clone(),
            m,
            values,
        })
    }

    /// The LP table of the functions `cols` (indices into this table's functions): a gather of
    /// columns, with the limits of [`GridTable::from_fn`].
    pub fn columns(&self, cols: &[usize]) -> Result<GridTable> {
        if let Some(&c) = cols.iter().find(|&&c| c >= self.m) {
            return Err(Error::ColumnOutOfRange {
                index: c,
                m: self.m,
            });
        }
        let mut i = 0;
        GridTable::from_fn(&self.grid, cols.len(), |_, out| {
            let row = self.row(i);
            for (o, &c) in out.iter_mut().zip(cols) {
                *o = row[c];
            }
            i += 1;
        })
    }

    /// The grid I.
    pub fn grid(&self) -> &Grid {
        &self.grid
    }
    /// Number of basis functions m.
    pub fn m(&self) -> usize {
        self.m
    }
    /// Number of grid points n.
    pub fn n(&self) -> usize {
        self.grid.len()
    }
    /// b(z_i) as a slice of length m.
    pub fn row(&self, i: usize) -> &[f64] {
        &self.values[i * self.m..(i + 1) * self.m]
    }
    /// All values, row-major n × m.
    pub fn values(&self) -> &[f64] {
        &self.values
    }
}

/// Outcome of one LP.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Status {
    /// Certified: the support reproduces every moment to 1e-9 of its own magnitude and a dual
    /// bound matches G to 1e-9 ([`certify`]).
    Optimal,
    /// No distribution on the grid has these moments (certified by a Farkas ray for the fast
    /// solver).
    Infeasible,
    /// Neither could be certified (see [`Solution::reason`]); G is NaN.
    Failed,
}

/// Result of Algorithm 1 for one (b, z_f).
#[derive(Clone, Debug, PartialEq)]
pub struct Solution {
    /// Optimal, infeasible or failed.
    pub status: Status,
    /// The sharp lower bound G(b, z_f) (NaN when infeasible).
    pub g: f64,
    /// Support of a minimising distribution: (z_i, w_i) with w_i > 0, sorted by z.
    pub support: Vec<(f64, f64)>,
    /// Why the problem is `Failed` (one line); None otherwise.
    pub reason: Option<String>,
}

impl Solution {
    /// The answer for moments no distribution on the grid has.
    pub fn infeasible() -> Solution {
        Solution {
            status: Status::Infeasible,
            g: f64::NAN,
            support: Vec::new(),
            reason: None,
        }
    }

    /// An unsettled problem: G is NaN, `reason` says why.
    pub fn failed(reason: impl Into<String>) -> Solution {
        Solution {
            status: Status::Failed,
            g: f64::NAN,
            support: Vec::new(),
            reason: Some(reason.into()),
        }
    }
}

/// A solver for Algorithm 1 on a fixed [`GridTable`]. `&mut self` lets solvers keep warm-start
/// state between consecutive problems.
pub trait MomentSolver: Send {
    /// Solve for moments `b` (length m) and fragment depth `zf`.
    fn solve(&mut self, moments: &[f64], zf: f64) -> Result<Solution>;

    /// G for the moments of a distribution on the grid, `dist` = [(grid index, weight)]
    /// (weights ≥ 0, normalised by their sum): b = Σ w_i b(z_i), the filtered moments of a
    /// shadow-map kernel (Section 3.2). The default forms b and calls [`MomentSolver::solve`];
    /// a solver may instead use the distribution as a feasible start (no phase 1) and form the
    /// moments in its own, better-conditioned coordinates (Problem 1 is invariant under
    /// invertible affine maps of b).
    fn solve_distribution(&mut self, dist: &[(u32, f64)], zf: f64) -> Result<Solution> {
        let b = distribution_moments(self.table(), dist)?;
        self.solve(&b, zf)
    }

    /// The table the solver works on.
    fn table(&self) -> &GridTable;

    /// Forget any warm-start state: the answers that follow are bit for bit those of a new
    /// solver on the same table (so work split into chunks gives the same bits however the
    /// chunks are scheduled). Stateless solvers: nothing to do.
    fn reset(&mut self) {}
}

/// Largest basis size m: the dense kernels (src/lp/dense.rs) hold the r = m + 1 rows of the
/// LP's basis matrix in fixed arrays of 32.
pub const MAX_FUNCTIONS: usize = 31;

/// Largest grid table n·m (f64 values, 512 MiB), checked before it is allocated.
pub const MAX_TABLE_VALUES: usize = 1 << 26;

/// A solver of the given kind on `table` (a name is parsed by `str::parse::<SolverKind>`).
/// Problems nothing certifies come back `Failed`.
pub fn make_solver(kind: SolverKind, table: GridTable) -> Box<dyn MomentSolver> {
    match kind {
        SolverKind::Reference => Box::new(reference::ReferenceSolver::new(table)),
        SolverKind::Fast => Box::new(fast::FastSolver::new(table)),
    }
}

/// The one meaning of an unsettled LP (status `Failed`, or a solver error) everywhere G is
/// scored (the sweep, `evaluate`, the reports): the trivial bound G = 0 — every distribution
/// has mass ≥ 0 below z_f, so this claims nothing — counted per candidate and shown in the
/// results tables. Never NaN (which would drop the fragment and flatter the candidate).
pub const UNSETTLED_G: f64 = 0.0;

/// G of a settled answer; None when it is unsettled (see [`UNSETTLED_G`]). Infeasible
/// answers are settled (NaN: moments outside the moment space, e.g. after quantisation).
pub fn settled_g(sol: &Result<Solution>) -> Option<f64> {
    match sol {
        Ok(s) if s.status == Status::Optimal => Some(s.g),
        Ok(s) if s.status == Status::Infeasible => Some(f64::NAN),
        _ => None,
    }
}

/// Whether `sol`'s support lies on the grid and reproduces every moment to `tol` of that
/// moment's own scale σ_j = max(|b_j|, [`certify::scale_floor`]), the scale the certificates
/// use: how an answer that did not come with a certificate (the reference's) is judged before
/// it is compared.
pub fn support_reproduces(table: &GridTable, b: &[f64], sol: &Solution, tol: f64) -> bool {
    let z = table.grid().points();
    let mut mom = vec![0.0; table.m()];
    for &(zs, w) in &sol.support {
        let i = table.grid().nearest(zs);
        if z[i] != zs {
            return false;
        }
        for (mj, v) in mom.iter_mut().zip(table.row(i)) {
            *mj += w * v;
        }
    }
    (0..table.m()).all(|j| {
        let col: Vec<f64> = (0..table.n()).map(|i| table.row(i)[j]).collect();
        (mom[j] - b[j]).abs() <= tol * b[j].abs().max(certify::scale_floor(&col))
    })
}

/// b = Σ w_i b(z_i) / Σ w_i for a distribution [(grid index, weight)] on the table's grid.
pub fn distribution_moments(table: &GridTable, dist: &[(u32, f64)]) -> Result<Vec<f64>> {
    let (n, m) = (table.n(), table.m());
    let mut b = vec![0.0; m];
    let mut total = 0.0;
    for (k, &(i, w)) in dist.iter().enumerate() {
        let i = i as usize;
        if i >= n || !w.is_finite() || w < 0.0 {
            return Err(Error::DistributionEntry {
                entry: k,
                index: i,
                n,
                weight: w,
            });
        }
        total += w;
        for (bj, fj) in b.iter_mut().zip(table.row(i)) {
            *bj += w * fj;
        }
    }
    if total <= 0.0 || !total.is_finite() {
        return Err(Error::DistributionWeight);
    }
    b.iter_mut().for_each(|v| *v /= total);
    Ok(b)
}
