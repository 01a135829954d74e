//! The escalation chain of the fast solver, for what its whole-grid run could not certify:
//!
//! 1. [`band`]: the fast simplex on a window of the grid, in coordinates of that window (steep
//!    functions, clusters of neighbouring grid points), its basis certified on the whole grid;
//! 2. accurate pivots in the certifier's coordinates ([`crate::lp::certify`]);
//! 3. [`scaled`]: a revised simplex in double-double arithmetic on the LP scaled per problem
//!    (rows and columns by exact powers of two);
//! 4. [`exact`]: an exact rational simplex from the last bases tried.
//!
//! Every answer is certified the same way; what none of them settles is `Failed` with the
//! reasons of each step.

pub(super) mod band;
pub(super) mod exact;
pub(super) mod scaled;

use super::{certified, FastSolver, FINAL_IMPROVE_STEPS};
use crate::lp::{Solution, Status};
use exact::{ExactAnswer, ExactSimplex};
use scaled::Found;

impl FastSolver {
    /// The scaled simplex on the problem, from `start` if given; its answer certified. What
    /// that leaves unsettled goes to the exact simplex ([`super::exact`]) from the last basis
    /// tried.
    pub(super) fn escalate(
        &mut self,
        moments: &[f64],
        kf: usize,
        start: Option<&[usize]>,
        dist: Option<&[(u32, f64)]>,
    ) -> Solution {
        self.stats.escalations += 1;
        self.warm.last_c.iter_mut().for_each(|v| *v = f64::NAN);
        self.cert.set_moments(moments);
        let pivots = self.scaled.pivots;
        let found = self.scaled.solve(&self.cert, kf, start);
        self.stats.pivots += self.scaled.pivots - pivots;
        let (sol, last) = match found {
            Found::Optimal(mut basis) => {
                match self
                    .cert
                    .improve(moments, kf, &mut basis, FINAL_IMPROVE_STEPS)
                {
                    Ok(c) => (certified(c), None),
                    Err(e) => (
                        Solution::failed(format!("scaled simplex optimum not certified: {e}")),
                        Some(basis),
                    ),
                }
            }
            Found::Infeasible(y) => match self.cert.infeasible(moments, &y) {
                Ok(_) => (Solution::infeasible(), None),
                Err(e) => (
                    Solution::failed(format!("phase 1 infeasible, but {e}")),
                    None,
                ),
            },
            Found::Failed(e) => (Solution::failed(e), None),
        };
        let sol = if sol.status == Status::Failed {
            match self.exact(moments, kf, [last, start.map(<[usize]>::to_vec)], dist) {
                Some(ex) if ex.status == Status::Failed => Solution::failed(format!(
                    "{}; {}",
                    sol.reason.unwrap_or_default(),
                    ex.reason.unwrap_or_default()
                )),
                Some(ex) => ex,
                None => sol,
            }
        } else {
            sol
        };
        if sol.status == Status::Infeasible {
            self.stats.infeasible += 1;
        }
        sol
    }

    /// The exact simplex on the exact moments of `dist` when given (else on `moments`). Its
    /// starts: the last basis the escalation tried (usually exactly optimal already, or a few
    /// dual pivots away), the distribution's atoms completed by that basis's columns (feasible,
    /// with duals close to that basis's), the distribution's support, the fast solver's basis,
    /// evenly spaced grid points. None when the exact LP does not apply (dependent rows).
    pub(super) fn exact(
        &mut self,
        moments: &[f64],
        kf: usize,
        [last, fast]: [Option<Vec<usize>>; 2],
        dist: Option<&[(u32, f64)]>,
    ) -> Option<Solution> {
        let (n, r) = (self.table.n(), self.table.m() + 1);
        let mixed = dist
            .zip(last.as_deref())
            .and_then(|(h, l)| mixed_basis(h, l));
        let support = dist.and_then(|h| self.support_basis(h));
        let spread = Some((0..r).map(|t| t * (n - 1) / (r - 1).max(1)).collect());
        let from: Vec<Vec<usize>> = [last, mixed, support, fast, spread]
            .into_iter()
            .flatten()
            .collect();
        let from: Vec<&[usize]> = from.iter().map(Vec::as_slice).collect();
        self.cert.set_moments(moments);
        let mut ex = ExactSimplex::new(&self.cert, kf, dist)?;
        self.stats.exact += 1;
        let answer = ex.solve(&from);
        self.stats.pivots += ex.pivots as u64;
        let z = self.table.grid().points();
        match answer {
            ExactAnswer::Optimal { g, weights, basis } => {
                let support = weights.iter().map(|&(i, w)| (z[i], w)).collect();
                self.last_exact = Some(basis);
                Some(Solution {
                    status: Status::Optimal,
                    g: g.clamp(0.0, 1.0),
                    support,
                    reason: None,
                })
            }
            // The exact ray proves that no distribution has exactly these moments; the answer
            // `infeasible` also promises that none reproduces them to the tolerance
            // ([`super::certify`]), which the same ray must show.
            ExactAnswer::Infeasible(y) => {
                let y: Vec<f64> = y.iter().map(|v| -v).collect();
                Some(match self.cert.infeasible(moments, &y) {
                    Ok(_) => Solution::infeasible(),
                    Err(_) => Solution::failed(
                        "ill-posed at f64 resolution: exactly outside the moment space \
                         (Farkas ray), but within 1e-9 of it; solve from the distribution \
                         for the exact answer",
                    ),
                })
            }
            ExactAnswer::Failed(e) => Some(Solution::failed(e)),
        }
    }
}

/// The atoms of `dist` (at most |last| of them) completed by columns of `last`: a basis
/// (if nonsingular) whose basic solution is the distribution itself.
fn mixed_basis(dist: &[(u32, f64)], last: &[usize]) -> Option<Vec<usize>> {
    let mut basis: Vec<usize> = Vec::with_capacity(last.len());
    for &(i, w) in dist {
        let i = i as usize;
        if w > 0.0 && !basis.contains(&i) {
            if basis.len() == last.len() {
                return None;
            }
            basis.push(i);
        }
    }
    for &i in last {
        if basis.len() < last.len() && !basis.contains(&i) {
            basis.push(i);
        }
    }
    Some(basis)
}
