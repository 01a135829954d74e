//! The reference solver: Algorithm 1 handed verbatim to good_lp's pure-Rust microlp backend.

use super::{GridTable, MomentSolver, Solution, Status};
use anyhow::{bail, Result};
use good_lp::{
    constraint, microlp, variable, variables, Expression, ResolutionError, Solution as _,
    SolverModel, Variable,
};

/// Algorithm 1 through a general-purpose LP solver. Slow (milliseconds per LP) but
/// independent of our own code: the oracle for the fast solver.
pub struct ReferenceSolver {
    table: GridTable,
}

impl ReferenceSolver {
    pub fn new(table: GridTable) -> ReferenceSolver {
        ReferenceSolver { table }
    }
}

impl MomentSolver for ReferenceSolver {
    fn solve(&mut self, moments: &[f64], zf: f64) -> Result<Solution> {
        let t = &self.table;
        let (n, m) = (t.n(), t.m());
        if moments.len() != m {
            bail!("expected {m} moments, got {}", moments.len());
        }
        let mut vars = variables!();
        let w: Vec<Variable> = (0..n).map(|_| vars.add(variable().min(0.0))).collect();
        let z = t.grid().points();
        let objective: Expression = w
            .iter()
            .zip(z)
            .filter(|(_, &zi)| zi < zf)
            .map(|(v, _)| *v)
            .sum();
        let mut model = vars.minimise(objective.clone()).using(microlp);
        let total: Expression = w.iter().copied().sum();
        model = model.with(constraint!(total == 1.0));
        for (j, &bj) in moments.iter().enumerate() {
            let e: Expression = w.iter().enumerate().map(|(i, v)| t.row(i)[j] * *v).sum();
            model = model.with(constraint!(e == bj));
        }
        match model.solve() {
            Ok(sol) => {
                let support: Vec<(f64, f64)> = w
                    .iter()
                    .zip(z)
                    .map(|(v, &zi)| (zi, sol.value(*v)))
                    .filter(|&(_, wi)| wi > 1e-12)
                    .collect();
                let g = w
                    .iter()
                    .zip(z)
                    .filter(|(_, &zi)| zi < zf)
                    .map(|(v, _)| sol.value(*v))
                    .sum::<f64>()
                    .clamp(0.0, 1.0);
                Ok(Solution {
                    status: Status::Optimal,
                    g,
                    support,
                })
            }
            Err(ResolutionError::Infeasible) => Ok(Solution::infeasible()),
            Err(e) => bail!("reference LP solver failed: {e}"),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Grid;

    fn msm_table(n: usize) -> GridTable {
        GridTable::from_fn(&Grid::uniform(n).unwrap(), 2, |z, o| {
            o[0] = z;
            o[1] = z * z;
        })
        .unwrap()
    }

    #[test]
    fn single_dirac_gives_zero_or_one() {
        let mut s = ReferenceSolver::new(msm_table(11));
        let z0 = 0.3;
        let b = [z0, z0 * z0];
        assert!(s.solve(&b, 0.2).unwrap().g.abs() < 1e-9);
        assert!((s.solve(&b, 0.5).unwrap().g - 1.0).abs() < 1e-9);
    }

    #[test]
    fn impossible_moments_are_infeasible() {
        let mut s = ReferenceSolver::new(msm_table(11));
        // Variance would be negative: E[z^2] < E[z]^2.
        let sol = s.solve(&[0.5, 0.1], 0.4).unwrap();
        assert_eq!(sol.status, Status::Infeasible);
    }
}
