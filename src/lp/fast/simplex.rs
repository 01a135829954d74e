//! The revised primal simplex loop: basis factorisation and basic solution, duals, the
//! iteration (pricing, optimality checks of either phase, Harris ratio test, pivot), degenerate
//! perturbation, and the bounded "refactorise, else rescue, else fail" recovery.

use super::linalg::norm;
use super::price::price_bland;
use super::{
    FastSolver, Outcome, ART, DEGENERATE_LIMIT, MAX_COND, REFACTOR_EVERY, TOL_D, TOL_INF, TOL_P,
    TOL_PIV, TOL_P_LOOSE,
};
use crate::lp::fast::pricing::dantzig::price;
use crate::lp::ratio::harris;

/// Phase-2 cost (mass below z_f) taken as zero: the run ends there.
const ZERO_COST: f64 = 1e-13;
/// Largest condition (‖B‖_F‖B⁻¹‖_F of the last factorisation) of a start basis from which
/// phase 1 is set up by a pivot update instead of a factorisation. The update skips the
/// refinement of the weights; on flat windows, whose warm bases hold pairs of neighbouring grid
/// points (cond 1e6–1e9), that changes which ill-posed windows settle (moments corpus,
/// n = 1024: 11 failed instead of 8 without this bound, the same 8 with it).
const EXCHANGE_COND: f64 = 1e4;
/// Rescues ([`FastSolver::rescue`]) allowed per run.
const MAX_RESCUES: usize = 3;
/// Phase 1 ends as soon as the artificial's weight x_a satisfies x_a‖d‖ ≤ this · (1 + ‖c‖):
/// dropping it then changes B x by no more than rounding, and the phase-1 objective x_a ≥ 0 is
/// at its least value, whatever the reduced costs say.
const ART_ZERO: f64 = 1e-14;

/// The state of one simplex run ([`FastSolver::run`]) between iterations.
struct Run {
    /// Number of grid points below z_f.
    kf: usize,
    /// Bland's rule throughout.
    bland_always: bool,
    /// Phase 1: the artificial column is in the basis, at `art_pos`, with norm `art_norm`.
    phase1: bool,
    art_pos: usize,
    art_norm: f64,
    /// ‖c‖ at the start (scale of the infeasibility test).
    c_norm: f64,
    /// Pivots since the last refactorisation.
    since_refactor: usize,
    /// Consecutive degenerate pivots.
    degenerate: usize,
    /// The current basis was refactorised at this optimum (the pricing pass used fresh duals).
    verified: bool,
    /// Rescues so far.
    rescues: usize,
    /// c is perturbed (see [`FastSolver::perturb`]).
    perturbed: bool,
    /// The column that left the basis at the last pivot (usize::MAX: none yet).
    last_left: usize,
}

impl Run {
    /// The state at the start of a run with `kf` grid points below z_f.
    fn new(kf: usize, bland_always: bool) -> Run {
        Run {
            kf,
            bland_always,
            phase1: false,
            art_pos: 0,
            art_norm: 0.0,
            c_norm: 0.0,
            since_refactor: 0,
            degenerate: 0,
            verified: false,
            rescues: 0,
            perturbed: false,
            last_left: usize::MAX,
        }
    }
}

/// How an iteration of [`FastSolver::run`] ends early.
enum Jump {
    /// Go on with the next iteration.
    Next,
    /// The run ends with this outcome.
    End(Outcome),
}

impl FastSolver {
    /// Recompute the basis inverse from scratch (Gauss–Jordan, partial pivoting) and
    /// x = B⁻¹ c. False if the basis is numerically singular.
    pub(super) fn refactor(&mut self) -> bool {
        let ok = self.factor();
        if ok {
            self.basic_solution();
        }
        ok
    }

    /// Basis inverse only (see [`Self::refactor`]); false if numerically singular.
    pub(super) fn factor(&mut self) -> bool {
        let (r, rows, art) = (self.r, &self.ortho.rows, &self.art);
        let column = |i: usize| {
            if i == ART {
                &art[..]
            } else {
                &rows[i * r..(i + 1) * r]
            }
        };
        // Numerically singular for our purposes: weights from such a basis carry errors of
        // cond·ε > 1e-4; the caller rebuilds a well-conditioned basis instead.
        self.binv.factor(&self.basis, column, ART, MAX_COND)
    }

    /// x = B⁻¹ c with two steps of iterative refinement.
    fn basic_solution(&mut self) {
        let r = self.r;
        {
            self.binv.apply(&self.c, &mut self.x);
            // Two steps of iterative refinement: x += B⁻¹ (c − B x). The explicit inverse of an
            // ill-conditioned basis (neighbouring grid points) is accurate to cond·ε only.
            for _ in 0..2 {
                for k in 0..r {
                    self.alpha[k] = self.c[k];
                }
                for t in 0..r {
                    let xt = self.x[t];
                    let bt = self.basis[t];
                    let col = if bt == ART {
                        &self.art[..]
                    } else {
                        &self.ortho.rows[bt * r..(bt + 1) * r]
                    };
                    for (ak, ck) in self.alpha.iter_mut().zip(col) {
                        *ak -= ck * xt;
                    }
                }
                // self.y is free here as scratch.
                self.binv.apply(&self.alpha, &mut self.y);
                for t in 0..r {
                    self.x[t] += self.y[t];
                }
            }
        }
        if self.accurate && self.c == self.c0 {
            // Accurate mode (see `finish_optimal`): against the LP as stated.
            let _ = self.refine_steps();
        }
    }

    /// y = c_Bᵀ B⁻¹ for costs cost(B_t).
    fn duals(&mut self, phase1: bool, kf: usize) {
        let r = self.r;
        self.y.iter_mut().for_each(|v| *v = 0.0);
        for t in 0..r {
            let bt = self.basis[t];
            let cost = if phase1 {
                (bt == ART) as u8 as f64
            } else {
                (bt < kf) as u8 as f64
            };
            if cost != 0.0 {
                let row = &self.binv.inv[t * r..(t + 1) * r];
                for (yk, bk) in self.y.iter_mut().zip(row) {
                    *yk += cost * bk;
                }
            }
        }
    }

    /// One simplex run from `self.basis`. `kf` = number of grid points below z_f.
    pub(super) fn run(&mut self, kf: usize, bland_always: bool) -> Outcome {
        if std::mem::take(&mut self.crossed) {
            // Straight from the crossover: B⁻¹ and x = B⁻¹c are up to date.
        } else if self.binv.is_fresh_for(&self.basis) {
            // B⁻¹ is still the fresh factorisation of this basis (the warm start after a
            // problem that ended on it): only the weights are new.
            self.basic_solution();
        } else if !self.refactor() {
            return Outcome::Failed;
        }
        let mut st = Run::new(kf, bland_always);
        if !self.start_phase1(&mut st) {
            return Outcome::Failed;
        }
        st.c_norm = norm(&self.c);
        let cap = 200 + 20 * self.r + self.n / 16;
        for _iter in 0..cap {
            if let Err(Jump::End(outcome)) = self.iteration(&mut st) {
                return outcome;
            }
        }
        Outcome::Failed
    }

    /// Phase 1 set-up with a single artificial column: d = −Σ_{x_t<0} a_{B_t} replaces the most
    /// negative basic weight x_s (nothing to do when the start is primal feasible). From a
    /// start whose last factorisation had cond_F ≤ [`EXCHANGE_COND`] by a pivot update of B⁻¹
    /// (the pivot element is −1), else by a fresh factorisation; false if that is singular.
    fn start_phase1(&mut self, st: &mut Run) -> bool {
        let r = self.r;
        let mut worst = None;
        let mut worst_v = -TOL_P;
        for t in 0..r {
            if self.x[t] < worst_v {
                worst_v = self.x[t];
                worst = Some(t);
            }
        }
        let Some(ts) = worst else {
            return true;
        };
        self.stats.phase1 += 1;
        self.art.iter_mut().for_each(|v| *v = 0.0);
        for t in 0..r {
            if self.x[t] < -TOL_P {
                let bt = self.basis[t];
                for k in 0..r {
                    self.art[k] -= self.ortho.rows[bt * r + k];
                }
            }
        }
        st.art_norm = norm(&self.art);
        st.art_pos = ts;
        st.phase1 = true;
        if self.binv.cond.is_nan() || self.binv.cond > EXCHANGE_COND {
            // An ill-conditioned start (flat windows: pairs of neighbouring grid points):
            // the basis with the artificial is factorised afresh and its weights refined.
            self.set_basic(self.basis[ts], false);
            self.basis[ts] = ART;
            return self.refactor();
        }
        // The exchange as a pivot, without refactorisation: B⁻¹d = −Σ_{x_t<0} e_t, so the
        // pivot element is −1 and the step θ = x_s/(−1) = −x_s; the other negative weights
        // become x_t − x_s ≥ 0 (x_s the most negative), the artificial's weight −x_s.
        let theta = -self.x[ts];
        for t in 0..r {
            self.alpha[t] = if self.x[t] < -TOL_P { -1.0 } else { 0.0 };
        }
        self.binv.pivot(&self.alpha, ts);
        for t in 0..r {
            self.x[t] -= theta * self.alpha[t];
        }
        self.x[ts] = theta;
        self.set_basic(self.basis[ts], false);
        self.basis[ts] = ART;
        true
    }

    /// One iteration of [`Self::run`]: periodic refactorisation, pricing, and either the
    /// optimality checks of the current phase or a ratio test and pivot.
    fn iteration(&mut self, st: &mut Run) -> Result<(), Jump> {
        if st.since_refactor >= REFACTOR_EVERY {
            // A numerically singular basis (clustered grid points) is rebuilt well-conditioned
            // around the current weights.
            self.refactor_or_rescue(st)?;
        }
        if st.degenerate >= DEGENERATE_LIMIT && !st.perturbed {
            self.perturb(st);
        }
        if self.partial_optimum && !st.phase1 && !st.perturbed && self.no_mass_below(st.kf) {
            // Cost 0 is the least possible: optimal whatever the reduced costs say (the
            // certificate's zero duals prove it, see `solve_inner`).
            self.full_pass_skipped = true;
            return self.at_optimum(st, 0.0);
        }
        if st.phase1 && !st.perturbed && self.artificial_at_zero(st) {
            // Phase 1 is optimal: its objective x_a ≥ 0 has reached 0. Pricing on would only
            // take degenerate pivots at x_a = 0 (boundary moments, such as those of one or
            // two grid atoms, whose only representation phase 1 has just found).
            self.stats.phase1_at_zero += 1;
            self.duals(true, st.kf);
            return self.drive_out_artificial(st);
        }
        let bland = st.bland_always || st.degenerate >= DEGENERATE_LIMIT;
        let (q, dq) = self.price_step(st, bland)?;
        if dq >= -TOL_D {
            return self.at_optimum(st, dq);
        }
        if q == st.last_left && !st.phase1 && !st.perturbed {
            // Right after a pivot the leaving column's reduced cost is −d_q/α_l > 0: its
            // return is rounding in the duals of an ill-conditioned basis (a tight cluster at
            // n = 4096 otherwise ping-pongs until the iteration cap). The certificate, with
            // duals refined in double-double, decides instead (see `solve_inner`).
            self.stats.ping_pong += 1;
            self.full_pass_skipped = true;
            return self.at_optimum(st, 0.0);
        }
        st.verified = false;
        self.load_alpha(q);
        let l = self.ratio_test(bland).ok_or(Jump::End(Outcome::Failed))?;
        self.pivot_step(st, l, q, dq);
        Ok(())
    }

    /// Phase 1 has reached its least objective: the artificial's weight x_a is zero to
    /// rounding, x_a‖d‖ ≤ [`ART_ZERO`] (1 + ‖c‖) (never the case outside phase 1).
    fn artificial_at_zero(&self, st: &Run) -> bool {
        st.phase1 && self.x[st.art_pos].max(0.0) * st.art_norm <= ART_ZERO * (1.0 + st.c_norm)
    }

    /// The basic solution is feasible and puts no mass below z_f (grid points 0..kf).
    fn no_mass_below(&self, kf: usize) -> bool {
        let mut below = 0.0;
        for t in 0..self.r {
            if self.x[t] < -TOL_P {
                return false;
            }
            if self.basis[t] < kf {
                below += self.x[t].max(0.0);
            }
        }
        below <= ZERO_COST
    }

    /// Refactorise, else rescue (at most `MAX_RESCUES` per run), else fail. After a rescue the
    /// run goes on in phase 2 from the rescued basis with the next iteration.
    fn refactor_or_rescue(&mut self, st: &mut Run) -> Result<(), Jump> {
        if self.refactor() {
            st.since_refactor = 0;
            return Ok(());
        }
        self.rescue_or(st, Outcome::Failed)
    }

    /// Rescue (at most `MAX_RESCUES` per run; then `Jump::Next`), else end the run with
    /// `outcome`.
    fn rescue_or(&mut self, st: &mut Run, outcome: Outcome) -> Result<(), Jump> {
        if self.try_rescue(st) {
            Err(Jump::Next)
        } else {
            Err(Jump::End(outcome))
        }
    }

    /// [`Self::rescue`] if the run has rescues left; on success the run state is that of a
    /// fresh phase-2 factorisation.
    fn try_rescue(&mut self, st: &mut Run) -> bool {
        if st.rescues < MAX_RESCUES && self.rescue() {
            st.rescues += 1;
            st.phase1 = false;
            st.since_refactor = 0;
            st.verified = false;
            return true;
        }
        false
    }

    /// Stalling on a degenerate vertex (moments on the boundary of the moment space): perturb
    /// c = B x into c + B δ with small distinct δ_t > 0, which makes the vertex non-degenerate;
    /// the true c is restored at the optimum.
    fn perturb(&mut self, st: &mut Run) {
        let r = self.r;
        for t in 0..r {
            let bt = self.basis[t];
            if bt == ART {
                continue; // never feed the artificial: c stays feasible iff it was
            }
            let dt = 1e-7 * (1.0 + t as f64 / r as f64);
            self.x[t] += dt;
            for k in 0..r {
                self.c[k] += dt * self.ortho.rows[bt * r + k];
            }
        }
        st.perturbed = true;
        st.degenerate = 0;
        self.stats.perturbations += 1;
    }

    /// Duals and the entering column (q, d_q): partial pricing first; a full pass (after a
    /// fresh factorisation) or Bland's rule when it finds nothing.
    fn price_step(&mut self, st: &mut Run, bland: bool) -> Result<(usize, f64), Jump> {
        let (n, r) = (self.n, self.r);
        self.duals(st.phase1, st.kf);
        let kf_eff = if st.phase1 { 0 } else { st.kf };
        let partial = if bland || self.pricing.stride <= 1 {
            (usize::MAX, 0.0)
        } else {
            self.price_partial(kf_eff)
        };
        if partial.0 == usize::MAX && !bland && self.partial_optimum && !st.phase1 && !st.perturbed
        {
            // The certificate will price every column (see `solve_inner`).
            self.full_pass_skipped = true;
            return Ok((usize::MAX, 0.0));
        }
        if partial.0 == usize::MAX {
            self.full_pass_skipped = false;
        }
        if partial.0 == usize::MAX && !bland && !st.verified && st.since_refactor > 0 {
            // About to prove optimality with a full pass: refactorise first, so that the
            // pass prices with fresh duals (the updated ones of an ill-conditioned basis
            // can be off by far more than the tolerance, and a pass with them would have
            // to be repeated).
            self.yold.copy_from_slice(&self.y);
            self.xold.copy_from_slice(&self.x);
            self.refactor_or_rescue(st)?;
            st.verified = true;
            self.duals(st.phase1, st.kf);
        }
        if partial.0 == usize::MAX {
            self.stats.full_pricing += 1;
        }
        let (q, dq) = if partial.0 != usize::MAX {
            partial
        } else if bland {
            price_bland(
                &self.pricing.fine,
                n,
                r,
                &self.y,
                kf_eff,
                &self.basis,
                &mut self.s,
            )
        } else {
            self.price_full(kf_eff)
        };
        if partial.0 == usize::MAX && dq < -TOL_D {
            self.stats.partial_misses += 1;
        }
        Ok((q, dq))
    }

    /// No entering column (d_q ≥ −TOL_D): verify with a fresh factorisation, then end phase 1,
    /// restore perturbed moments, or settle the phase-2 optimum.
    fn at_optimum(&mut self, st: &mut Run, dq: f64) -> Result<(), Jump> {
        if self.full_pass_skipped
            && !st.phase1
            && !st.perturbed
            && self.x.iter().all(|&v| v >= -TOL_P)
        {
            // The certificate factorises, refines and prices on its own (see `solve_inner`);
            // should it fail, the run resumes from this basis with the full pass and the
            // verification, polish and refinement below.
            return Err(Jump::End(Outcome::Optimal));
        }
        if !st.verified && st.since_refactor > 0 {
            self.verify_optimum(st, dq)?;
        }
        if st.phase1 {
            return self.end_phase1(st);
        }
        if st.perturbed {
            // Restore the true moments at this (dual-feasible) basis and continue.
            self.c.copy_from_slice(&self.c0);
            st.perturbed = false;
            st.verified = false;
            return self.refactor_or_rescue(st);
        }
        let outcome = self.phase2_optimum(st)?;
        Err(Jump::End(outcome))
    }

    /// Refactorise at an apparent optimum. If the fresh duals moved so little that no reduced
    /// cost can have crossed the tolerance, the pricing pass stands (`Ok`); otherwise price
    /// again (`Jump::Next`).
    fn verify_optimum(&mut self, st: &mut Run, dq: f64) -> Result<(), Jump> {
        self.yold.copy_from_slice(&self.y);
        self.xold.copy_from_slice(&self.x);
        self.refactor_or_rescue(st)?;
        st.verified = true;
        self.duals(st.phase1, st.kf);
        let dy: f64 = self
            .y
            .iter()
            .zip(&self.yold)
            .map(|(a, b)| (a - b) * (a - b))
            .sum::<f64>()
            .sqrt();
        if dy * self.ortho.amax > 0.5 * TOL_D || dq < -0.5 * TOL_D {
            return Err(Jump::Next);
        }
        Ok(())
    }

    /// Phase-1 optimum: infeasible moments if the artificial keeps a positive weight (decided on
    /// the true moments, after a rescue if one is left), else drive the artificial out.
    fn end_phase1(&mut self, st: &mut Run) -> Result<(), Jump> {
        let xa = self.x[st.art_pos].max(0.0);
        let positive = xa * st.art_norm > TOL_INF * (1.0 + st.c_norm);
        if positive && st.perturbed {
            // Decide feasibility on the true moments.
            self.c.copy_from_slice(&self.c0);
            st.perturbed = false;
            st.verified = false;
            if !self.refactor() {
                return Err(Jump::End(Outcome::Failed));
            }
            st.since_refactor = 0;
            return Ok(());
        }
        if positive {
            return self.rescue_or(st, Outcome::Infeasible);
        }
        self.drive_out_artificial(st)
    }

    /// Feasible: drive the (zero) artificial out of the basis. With the phase-1 duals
    /// (y = row art_pos of B⁻¹), s = row art_pos of B⁻¹A; pick the largest pivot element.
    fn drive_out_artificial(&mut self, st: &mut Run) -> Result<(), Jump> {
        let (n, r) = (self.n, self.r);
        price(
            &self.pricing.fine,
            n,
            r,
            &self.y,
            0,
            &self.basis,
            &mut self.s,
        );
        let Some(j) = first_largest_abs(&self.s[..n], TOL_PIV) else {
            return Err(Jump::End(Outcome::Failed));
        };
        self.x[st.art_pos] = 0.0;
        self.load_alpha(j);
        self.pivot(st.art_pos, j, 0.0);
        st.since_refactor += 1;
        st.phase1 = false;
        st.verified = false;
        Ok(())
    }

    /// Phase 2 optimum. Any non-negative w on the basic columns with B w = c is optimal too
    /// (complementary slackness); prefer the well-conditioned one on the clearly positive
    /// weights, else the basic solution if it is feasible. `Outcome::Retry` when the weights
    /// stay infeasible; the run goes on (`Jump::Next`) after a rescue.
    fn phase2_optimum(&mut self, st: &mut Run) -> Result<Outcome, Jump> {
        if self.x.iter().all(|&v| v >= -TOL_P) {
            // With every weight clearly positive the least squares of the polish is
            // the square system the refined basic solution already solved.
            if self.x.iter().any(|&v| v <= 1e-8) {
                self.polish();
            }
            return Ok(self.finish_optimal());
        }
        if self.polish() {
            return Ok(self.finish_optimal());
        }
        if self.try_rescue(st) {
            return Err(Jump::Next);
        }
        // The updated weights drifted on an ill-conditioned basis: rebuild from the
        // weights before the refactorisation (validated by least squares in rescue).
        if st.rescues < MAX_RESCUES {
            self.x.copy_from_slice(&self.xold);
            if self.try_rescue(st) {
                return Err(Jump::Next);
            }
            if !self.refactor() {
                return Ok(Outcome::Failed);
            }
        }
        if self.x.iter().all(|&v| v >= -TOL_P_LOOSE) {
            // Dual feasible and primal feasible to 1e-9: as good as the data allow
            // on this degenerate, ill-conditioned basis.
            self.stats.loose += 1;
            return Ok(Outcome::Optimal);
        }
        Ok(Outcome::Retry)
    }

    /// Ratio test ([`crate::lp::ratio::harris`]: Harris's two passes, the largest pivot among
    /// the near-minimal ratios; Bland: the smallest basis index) for the entering column in
    /// `alpha`: the leaving basis position, None for an unbounded direction (impossible for
    /// this LP, whose objective is ≥ 0: numerical trouble).
    fn ratio_test(&self, bland: bool) -> Option<usize> {
        let keys = bland.then_some(&self.basis[..]);
        harris(&self.x, &self.alpha, TOL_PIV, TOL_P, keys)
    }

    /// Pivot column q into basis position l (reduced cost dq), counting degenerate steps;
    /// phase 1 ends when the artificial leaves.
    fn pivot_step(&mut self, st: &mut Run, l: usize, q: usize, dq: f64) {
        let theta = (self.x[l].max(0.0) / self.alpha[l]).max(0.0);
        if theta * (-dq) <= 1e-14 {
            st.degenerate += 1;
            self.stats.degenerate_pivots += 1;
        } else {
            st.degenerate = 0;
        }
        let leaving = self.basis[l];
        st.last_left = leaving;
        self.pivot(l, q, theta);
        self.stats.pivots += 1;
        if st.phase1 {
            self.stats.phase1_pivots += 1;
        }
        st.since_refactor += 1;
        if st.phase1 && leaving == ART {
            st.phase1 = false;
        }
    }

    /// alpha = B⁻¹ a_j.
    pub(super) fn load_alpha(&mut self, j: usize) {
        let r = self.r;
        self.binv
            .apply(&self.ortho.rows[j * r..(j + 1) * r], &mut self.alpha);
    }

    /// Exchange basis position l for column q with step theta (alpha already loaded).
    fn pivot(&mut self, l: usize, q: usize, theta: f64) {
        for t in 0..self.r {
            self.x[t] -= theta * self.alpha[t];
        }
        self.x[l] = theta;
        self.exchange(l, q);
    }

    /// Basis change only: column q replaces position l in B⁻¹ (alpha = B⁻¹ a_q loaded).
    pub(super) fn exchange(&mut self, l: usize, q: usize) {
        self.binv.pivot(&self.alpha, l);
        if self.basis[l] != ART {
            self.set_basic(self.basis[l], false);
        }
        self.set_basic(q, true);
        self.basis[l] = q;
    }

    /// Set the basic flags of the current basis' real columns.
    pub(super) fn mark_basic(&mut self, on: bool) {
        for t in 0..self.r {
            let bt = self.basis[t];
            if bt != ART {
                self.set_basic(bt, on);
            }
        }
    }
}

/// The first index of the largest |s_i| above `floor` (None when no |s_i| exceeds it; NaN
/// entries never qualify): the maximum by branch-free compares in eight independent lanes
/// (which vectorise), then the first entry attaining it.
fn first_largest_abs(s: &[f64], floor: f64) -> Option<usize> {
    const L: usize = 8;
    let mut lanes = [floor; L];
    let chunks = s.chunks_exact(L);
    let tail = chunks.remainder();
    for c in chunks {
        for (m, v) in lanes.iter_mut().zip(c) {
            let a = v.abs();
            *m = if a > *m { a } else { *m };
        }
    }
    let top = lanes
        .iter()
        .chain(tail.iter())
        .fold(floor, |m, v| if v.abs() > m { v.abs() } else { m });
    if top > floor {
        s.iter().position(|v| v.abs() == top)
    } else {
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lp::GridTable;
    use crate::Grid;

    /// The first largest |s_i| above the floor: ties to the first, NaN and entries at the
    /// floor never taken; the same index as a running strict maximum over random vectors.
    #[test]
    fn first_largest_abs_takes_the_first_of_the_largest() {
        assert_eq!(first_largest_abs(&[0.5, -2.0, 2.0, 1.0], 1e-9), Some(1));
        assert_eq!(first_largest_abs(&[f64::NAN, -3.0, 3.0], 1e-9), Some(1));
        assert_eq!(first_largest_abs(&[1e-9, -1e-9, 0.0], 1e-9), None);
        assert_eq!(first_largest_abs(&[], 1e-9), None);
        let mut x = 0.37f64;
        for len in 1..200 {
            let s: Vec<f64> = (0..len)
                .map(|_| {
                    x = (x * 3.7 + 0.13).fract();
                    ((x * 8.0).round() - 4.0) * 0.25
                })
                .collect();
            let mut want = None;
            let mut best = 1e-9;
            for (i, v) in s.iter().enumerate() {
                if v.abs() > best {
                    best = v.abs();
                    want = Some(i);
                }
            }
            assert_eq!(first_largest_abs(&s, 1e-9), want, "{s:?}");
        }
    }

    /// The moments of two grid atoms, ¼δ(z_a) + ¾δ(z_{a+5}), lie on the boundary of the moment
    /// space (m = 4): the only representation is the pair itself, so phase 1 must reach it
    /// exactly, and from there on (artificial weight 0) it ends instead of pricing on. Power
    /// basis m = 4 on n = 257 points, pairs at every eighth grid point, each from the previous
    /// answer's basis: G(z_f) = ¼[z_a < z_f] + ¾[z_{a+5} < z_f], with the pair as the support.
    #[test]
    fn phase1_ends_when_the_artificial_reaches_zero() {
        use crate::lp::{MomentSolver, Status};
        let grid = Grid::uniform(257).unwrap();
        let table = GridTable::from_fn(&grid, 4, |z, o| {
            for (k, v) in o.iter_mut().enumerate() {
                *v = z.powi(k as i32 + 1);
            }
        })
        .unwrap();
        let z = grid.points().to_vec();
        let mut s = FastSolver::new(table);
        for a in (3..250).step_by(8) {
            let e = a + 5;
            let b: Vec<f64> = (1..=4)
                .map(|k| 0.25 * z[a].powi(k) + 0.75 * z[e].powi(k))
                .collect();
            for zf in [z[a] - 0.001, z[a] + 0.001, z[e] + 0.001] {
                let sol = s.solve(&b, zf).unwrap();
                assert_eq!(sol.status, Status::Optimal);
                let want = 0.25 * (z[a] < zf) as u8 as f64 + 0.75 * (z[e] < zf) as u8 as f64;
                assert!(
                    (sol.g - want).abs() <= 1e-12,
                    "pair {a}, z_f {zf}: {}",
                    sol.g
                );
                // The support: the pair, degenerate columns at rounding level.
                let heavy: Vec<_> = sol.support.iter().filter(|p| p.1 > 1e-12).collect();
                assert_eq!(heavy.len(), 2, "pair {a}: {heavy:?}");
                assert!(
                    (heavy[0].0, heavy[1].0) == (z[a], z[e]),
                    "pair {a}: {heavy:?}"
                );
                assert!((heavy[0].1 - 0.25).abs() < 1e-12 && (heavy[1].1 - 0.75).abs() < 1e-12);
            }
        }
        let st = s.stats();
        assert!(st.phase1 > 0 && st.phase1_at_zero > 0, "{st:?}");
        assert_eq!((st.escalations, st.failed, st.single_atom), (0, 0, 0));
    }

    /// The phase-1 set-up by one exchange equals a fresh factorisation of the basis with the
    /// artificial. (z, z², z³) on the grid {i/8}, basis z = 0, 1/4, 1/2, 3/4 and the moments of
    /// δ(1): x = B⁻¹c are the Lagrange weights of z = 1 on those nodes, (−1, 4, −6, 4). The
    /// artificial d = −(a_0 + a_2) replaces the most negative (position 2) with weight 6; the
    /// other negative becomes −1 + 6 = 5.
    #[test]
    fn phase1_setup_by_exchange_matches_a_fresh_factorisation() {
        let grid = Grid::uniform(9).unwrap();
        let table = GridTable::from_fn(&grid, 3, |z, o| {
            (o[0], o[1], o[2]) = (z, z * z, z * z * z);
        })
        .unwrap();
        let mut s = FastSolver::new(table);
        s.mark_basic(false);
        s.basis.copy_from_slice(&[0, 2, 4, 6]);
        s.mark_basic(true);
        assert!(s.ortho.transform(&[1.0, 1.0, 1.0], &mut s.u, &mut s.c));
        assert!(s.refactor());
        assert!(s.binv.cond <= EXCHANGE_COND, "{}", s.binv.cond);
        for (x, want) in s.x.iter().zip([-1.0, 4.0, -6.0, 4.0]) {
            assert!((x - want).abs() < 1e-12, "{:?}", s.x);
        }
        let mut st = Run::new(0, false);
        assert!(s.start_phase1(&mut st));
        assert!(st.phase1 && st.art_pos == 2);
        assert_eq!(s.basis, [0, 2, ART, 6]);
        assert!(!s.pricing.is_basic[4] && s.pricing.is_basic[0]);
        assert!(!s.binv.is_fresh_for(&s.basis), "updated, not factorised");
        let want = [5.0, 4.0, 6.0, 4.0];
        for (x, w) in s.x.iter().zip(want) {
            assert!((x - w).abs() < 1e-12, "{:?}", s.x);
        }
        // The updated inverse against a fresh factorisation of [a_0 a_2 d a_6].
        let updated = s.binv.inv.clone();
        assert!(s.refactor());
        for (u, f) in updated.iter().zip(&s.binv.inv) {
            assert!(
                (u - f).abs() < 1e-12 * (1.0 + f.abs()),
                "{updated:?} vs {:?}",
                s.binv.inv
            );
        }
        for (x, w) in s.x.iter().zip(want) {
            assert!((x - w).abs() < 1e-12, "{:?}", s.x);
        }
        // A feasible start (δ(1/4), x = e_1) needs no artificial.
        assert!(s
            .ortho
            .transform(&[0.25, 0.0625, 0.015625], &mut s.u, &mut s.c));
        s.mark_basic(false);
        s.basis.copy_from_slice(&[0, 2, 4, 6]);
        s.mark_basic(true);
        assert!(s.refactor());
        let mut st = Run {
            phase1: false,
            ..st
        };
        assert!(s.start_phase1(&mut st));
        assert!(!st.phase1 && s.basis == [0, 2, 4, 6]);
    }
}
