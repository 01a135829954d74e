//! Refinement and recovery of the weights at a basis: the accurate residual of the LP as stated
//! (double-double), iterative refinement against it, the least-squares polish of an optimal
//! basis, and the rescue of an ill-conditioned basis from a small support.

use super::linalg::{complete_basis, least_squares, norm};
use super::{FastSolver, Outcome, ART, TOL_P};
use crate::lp::dense::{two_prod, two_sum};

/// What [`FastSolver::refine_steps`] found.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Refined {
    /// Refined weights are a distribution (kept).
    Feasible,
    /// Refined weights negative, but the unrefined ones (kept) reproduce the moments to
    /// rounding: a numerically singular basis.
    Undetermined,
    /// Refined weights negative and the unrefined ones (kept) not accurate: the basis is not
    /// primal feasible.
    Infeasible,
}

/// Workspace of the least-squares solves on a support (polish and rescue): support indices,
/// its columns, their QR factors and the weights.
pub(super) struct LeastSquares {
    pub(super) sup: Vec<usize>,
    pub(super) a: Vec<f64>,
    pub(super) q: Vec<f64>,
    pub(super) r: Vec<f64>,
    pub(super) w: Vec<f64>,
}

impl FastSolver {
    /// Least squares on the basic positions `ls_sup[..k]`: c ≈ Σ w_a a_{B_t}. On success (w ≥ 0
    /// and residual at rounding level) x becomes w on those positions and 0 elsewhere
    /// (including the artificial).
    fn try_support(&mut self, k: usize) -> bool {
        let r = self.r;
        if k == 0 {
            return false;
        }
        for a in 0..k {
            let bt = self.basis[self.ls.sup[a]];
            self.ls.a[a * r..(a + 1) * r].copy_from_slice(&self.ortho.rows[bt * r..(bt + 1) * r]);
        }
        let w = &mut self.ls.w[..k];
        if !least_squares(
            &self.ls.a[..k * r],
            r,
            k,
            &self.c,
            &mut self.ls.q,
            &mut self.ls.r,
            w,
        ) {
            return false;
        }
        if w.iter().any(|&v| v < 0.0) {
            return false;
        }
        let mut res2 = 0.0;
        for kk in 0..r {
            let mut acc = self.c[kk];
            for a in 0..k {
                acc -= w[a] * self.ls.a[a * r + kk];
            }
            res2 += acc * acc;
        }
        if res2.sqrt() > 1e-12 * (1.0 + norm(&self.c)) {
            return false;
        }
        self.x.iter_mut().for_each(|v| *v = 0.0);
        for a in 0..k {
            self.x[self.ls.sup[a]] = w[a];
        }
        true
    }

    /// Accuracy polish at an optimal basis: the weights of an ill-conditioned degenerate basis
    /// are accurate to cond·ε only. Least squares on the clearly positive weights (> 1e-8) gives
    /// the same distribution accurately; any non-negative w on basic columns with B w = c is
    /// optimal (complementary slackness).
    pub(super) fn polish(&mut self) -> bool {
        let mut k = 0;
        for t in 0..self.r {
            if self.basis[t] != ART && self.x[t] > 1e-8 {
                self.ls.sup[k] = t;
                k += 1;
            }
        }
        self.try_support(k)
    }

    /// Rescue when the basic weights are unreliable (ill-conditioned basis of clustered grid
    /// points): find a small support among the basic columns, largest weights first, that
    /// reproduces c with non-negative weights; then complete it to a well-conditioned basis
    /// (greedy maximal volume) with zero weights on the added columns, and refactorise.
    pub(super) fn rescue(&mut self) -> bool {
        let r = self.r;
        // Basic positions of real columns with positive weight, by decreasing weight.
        let mut order: Vec<usize> = (0..r)
            .filter(|&t| self.basis[t] != ART && self.x[t] > 0.0)
            .collect();
        order.sort_by(|&a, &b| self.x[b].total_cmp(&self.x[a]));
        let mut found = 0;
        for k in 1..=order.len() {
            self.ls.sup[..k].copy_from_slice(&order[..k]);
            if self.try_support(k) {
                found = k;
                break;
            }
        }
        if found == 0 {
            return false;
        }
        let support: Vec<(usize, f64)> = order[..found]
            .iter()
            .map(|&t| (self.basis[t], self.x[t]))
            .collect();
        let cols: Vec<usize> = support.iter().map(|&(i, _)| i).collect();
        let Some(full) = complete_basis(&self.ortho.rows, self.n, r, &cols, &self.b0) else {
            return false;
        };
        self.mark_basic(false);
        self.basis.copy_from_slice(&full);
        self.mark_basic(true);
        if !self.refactor() {
            return false;
        }
        // The well-conditioned basis reproduces the support's weights; clamp rounding.
        if self.x.iter().any(|&v| v < -TOL_P) {
            return false;
        }
        for v in self.x.iter_mut() {
            *v = v.max(0.0);
        }
        true
    }

    /// Refinement of the weights against the LP as stated (full-rank tables, real columns
    /// only): the basic solution of a basis of neighbouring grid points (condition 1e6–1e9) is
    /// accurate to κ·ε only. Two steps of iterative refinement x += B̄⁻¹ ρ with the residual
    /// ρ = b̄ − B̄ x of the original system [1; b(z_i)] computed in double-double arithmetic
    /// (exact products, compensated sums) bring x to about ε; B̄⁻¹ ρ = B⁻¹ (√n R⁻ᵀ ρ) uses the
    /// basis inverse at hand. Returns None (x unchanged) when the steps do not converge or the
    /// basis holds the artificial column. A refined x with negative weights while the
    /// unrefined one reproduced the moments to 1e-12 (relative) means a numerically singular
    /// basis, whose weights are not determined: then the unrefined, valid x is kept.
    pub(super) fn refine_steps(&mut self) -> Option<Refined> {
        let (r, mm) = (self.r, self.m + 1);
        if r != mm || self.basis.contains(&ART) {
            return None;
        }
        self.x_backup.copy_from_slice(&self.x);
        let mut steps = [0.0f64; 2];
        let mut res0 = f64::NAN;
        for step in steps.iter_mut() {
            // lo_rhs = ρ (double-double residual rounded to f64).
            let res = self.residual_original();
            if res0.is_nan() {
                res0 = res;
            }
            // u = √n R⁻ᵀ ρ (every function kept), in the solver's coordinates.
            self.ortho.apply(&self.lo_rhs, &mut self.u);
            self.binv.apply(&self.u, &mut self.alpha);
            for t in 0..r {
                self.x[t] += self.alpha[t];
            }
            *step = self.alpha.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        }
        // Converging: the second correction much smaller than the first, or at rounding level.
        let converged = (steps[1] <= 0.25 * steps[0] || steps[1] <= 4.0 * f64::EPSILON)
            && self.x.iter().all(|v| v.is_finite());
        if !converged {
            self.x.copy_from_slice(&self.x_backup);
            return None;
        }
        if self.x.iter().all(|&v| v >= -TOL_P) {
            self.x.iter_mut().for_each(|v| *v = v.max(0.0));
            return Some(Refined::Feasible);
        }
        self.x.copy_from_slice(&self.x_backup);
        let valid = res0 <= 1e-12 && self.x.iter().all(|&v| v >= -TOL_P);
        Some(if valid {
            Refined::Undetermined
        } else {
            Refined::Infeasible
        })
    }

    /// At a phase-2 optimum: the weights refined against the LP as stated
    /// ([`Self::refine_steps`]). If they show that the basis is not primal feasible after all
    /// (its f64 weights were off by more than TOL_P), run again in accurate mode, where every
    /// basic solution is refined the same way.
    pub(super) fn finish_optimal(&mut self) -> Outcome {
        match self.refine_steps() {
            None | Some(Refined::Feasible) => {}
            Some(Refined::Undetermined) | Some(Refined::Infeasible) => {
                if !self.accurate {
                    self.accurate = true;
                    self.stats.accurate_retries += 1;
                    return Outcome::RetryAccurate;
                }
                self.stats.loose += 1;
            }
        }
        Outcome::Optimal
    }

    /// ρ = b̄ − Σ_t x_t [1; b(z_{B_t})] in double-double arithmetic, rounded into lo_rhs;
    /// returns max_j |ρ_j| / max_i |M_j(z_i)| (relative to the row scales).
    fn residual_original(&mut self) -> f64 {
        let mm = self.m + 1;
        let mut worst = 0.0f64;
        for j in 0..mm {
            let (mut hi, mut lo) = (if j == 0 { 1.0 } else { self.b_orig[j - 1] }, 0.0);
            for t in 0..self.r {
                let v = if j == 0 {
                    1.0
                } else {
                    self.table.row(self.basis[t])[j - 1]
                };
                let (p, pe) = two_prod(self.x[t], v);
                let (sum, se) = two_sum(hi, -p);
                hi = sum;
                lo += se - pe;
            }
            self.lo_rhs[j] = hi + lo;
            worst = worst.max(self.lo_rhs[j].abs() * self.oscale[j]);
        }
        worst
    }
}
