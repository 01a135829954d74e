//! LP candidates: Algorithm 1 of Peters & Klein 2015 (Section 3.1) with any basis, as a
//! [`Technique`]. G(b, z_f) = min Σ_{z_i < z_f} w_i s.t. w ≥ 0, Σ w_i = 1, Σ w_i b(z_i) = b on
//! a fixed grid I. Moments with no representing distribution on I give NaN.

use super::{Evaluator, Technique};
use crate::basis::{split_list, Basis, Catalog};
use crate::lp::{self, make_solver, GridTable, MomentSolver, SolverKind};
use crate::Grid;
use anyhow::{bail, Context, Result};

/// Default grid size of "lp:…" techniques (uniform points on [0,1]).
pub const DEFAULT_GRID_POINTS: usize = crate::grid::DEFAULT_POINTS;

/// Algorithm 1 with a given basis, grid and LP solver ("fast" or "reference").
pub struct LpCandidate {
    basis: Basis,
    grid: Grid,
    solver_kind: SolverKind,
    table: GridTable,
}

impl LpCandidate {
    /// Tabulates the basis on the grid; `solver_kind` solves its LPs.
    pub fn new(basis: Basis, grid: Grid, solver_kind: SolverKind) -> Result<LpCandidate> {
        if basis.is_empty() {
            bail!("LP candidate: need at least one basis function");
        }
        let m = basis.len();
        let table = GridTable::from_fn(&grid, m, |z, out| basis.eval(z, out))
            .with_context(|| format!("LP candidate [{}]", basis.names().join(",")))?;
        Ok(LpCandidate {
            basis,
            grid,
            solver_kind,
            table,
        })
    }

    /// "f1,f2,…" (commas inside parentheses do not split) resolved in the embedded catalog, on
    /// [`DEFAULT_GRID_POINTS`] uniform points, with the fast solver.
    pub fn from_spec(list: &str) -> Result<LpCandidate> {
        Self::from_spec_on(list, DEFAULT_GRID_POINTS)
    }

    /// [`LpCandidate::from_spec`] on `n` uniform points.
    pub fn from_spec_on(list: &str, n: usize) -> Result<LpCandidate> {
        let names = split_list(list);
        if names.iter().any(|n| n.is_empty()) {
            bail!("LP candidate 'lp:{list}': empty function name");
        }
        let basis = Catalog::embedded()
            .basis(&names)
            .with_context(|| format!("LP candidate 'lp:{list}'"))?;
        let grid = Grid::uniform(n)?;
        LpCandidate::new(basis, grid, SolverKind::Fast)
    }

    /// The LP solver.
    pub fn solver_kind(&self) -> SolverKind {
        self.solver_kind
    }

    /// The basis tabulated on the grid, as the solver reads it.
    pub fn table(&self) -> &GridTable {
        &self.table
    }

    /// The basis b_1, …, b_m.
    pub fn basis_functions(&self) -> &Basis {
        &self.basis
    }
}

/// One solver per evaluator: warm-start state stays per thread.
struct LpEvaluator {
    solver: Option<Box<dyn MomentSolver>>,
    unsettled: usize,
}

impl Evaluator for LpEvaluator {
    /// G(b, z_f); NaN when the moments are infeasible on the grid; the trivial bound
    /// [`lp::UNSETTLED_G`] (counted) when the solver settles neither.
    fn shadow(&mut self, moments: &[f64], zf: f64) -> f64 {
        let settled = self
            .solver
            .as_mut()
            .and_then(|s| lp::settled_g(&s.solve(moments, zf)));
        settled.unwrap_or_else(|| {
            self.unsettled += 1;
            lp::UNSETTLED_G
        })
    }
    fn unsettled(&self) -> usize {
        self.unsettled
    }
    fn reset(&mut self) {
        if let Some(s) = self.solver.as_mut() {
            s.reset();
        }
    }
}

impl Technique for LpCandidate {
    fn name(&self) -> String {
        format!("lp[{}]", self.basis.names().join(","))
    }
    fn moment_count(&self) -> usize {
        self.basis.len()
    }
    fn basis(&self, z: f64, out: &mut [f64]) {
        self.basis.eval(z, out)
    }
    fn depth_grid(&self) -> Option<&Grid> {
        Some(&self.grid)
    }
    fn evaluator(&self) -> Box<dyn Evaluator + '_> {
        Box::new(LpEvaluator {
            solver: Some(make_solver(self.solver_kind, self.table.clone())),
            unsettled: 0,
        })
    }
}
