//! The fast solver for Algorithm 1 (Peters & Klein 2015, Section 3.1): a revised primal simplex
//! specialised to m+1 ≤ 9 dense equality rows and up to ~10^4 columns.
//!
//! The LP is min p·w s.t. Ā w = b̄, w ≥ 0 with p_i = [z_i < z_f], Ā = [1; b(z_i)], b̄ = [1; b].
//!
//! * **Orthonormalisation.** The feasible set {w ≥ 0 : Ā w = b̄} is unchanged when both Ā and b̄
//!   are multiplied by the same invertible matrix. Once per table the n × (m+1) matrix
//!   M = [1, b_1(z), …, b_m(z)] is factorised M = Q R by modified Gram–Schmidt with
//!   reorthogonalisation; the solver works with the columns a_i = √n · Q_{i,·} (row i of Q, scaled
//!   so that the first coordinate is 1 and every coordinate has RMS 1 over the grid) and moment
//!   vectors c = √n · R^{-T} b̄. This keeps bases such as exp(20z) next to z numerically sane.
//!   Numerically dependent functions (relative residual < 1e-10) are dropped and their moment
//!   is checked for consistency instead.
//! * **Simplex.** An explicit (m+1)×(m+1) basis inverse, Dantzig pricing (partial: a coarse
//!   subgrid, the neighbours of z_f and of the support, the fine window around the best; a full
//!   pass proves optimality) with the blocked SIMD kernels of [`super::pricing`], a Harris-style
//!   ratio test, Bland's rule after repeated degenerate pivots, a refactorisation every 16
//!   pivots and before the optimality-proving pass.
//! * **Phase 1** uses a single artificial column: from any start basis B with x = B⁻¹c, the
//!   artificial d = −Σ_{x_t<0} a_{B_t} replaces the most negative basic variable, which makes the
//!   basis feasible; phase 1 then minimises the artificial's weight. Moments are infeasible when
//!   that weight stays positive.
//! * **Warm start.** The optimal basis of the previous problem is the start basis of the next one:
//!   when the moments are unchanged (only z_f moves) it is primal feasible and phase 2 starts
//!   at once; otherwise phase 1 starts from a nearby basis.
//! * **Start from a known distribution** ([`MomentSolver::solve_distribution`], the pipeline's
//!   case: the moments are those of a kernel's depth distribution). The moments are formed in
//!   the orthonormalised coordinates, c = Σ w_i a_i, and the distribution itself is a feasible
//!   point: a crossover turns it into a basic feasible solution of no greater cost (support
//!   columns of greatest volume as the basis, every other support point pushed to weight 0 or
//!   into the basis by one ratio test), so phase 1 is skipped.
//! * **Accuracy.** The final weights are refined against the LP as stated (residual of the
//!   original system in double-double arithmetic); weights that turn out infeasible trigger a
//!   rerun in accurate mode (see `finish_optimal`).
//! * **Robustness.** An iteration cap with a cold restart (Bland's rule throughout), and as the
//!   last resort the reference solver (counted in [`FastStats::fallbacks`]); never an endless loop.

#![allow(clippy::needless_range_loop)] // index-heavy dense linear algebra on r ≤ 9

use super::certify::{Certified, Certifier};
use super::dense::{two_prod, two_sum};
use super::pricing::ColumnTable;
use super::reference::ReferenceSolver;
use super::scaled::{Found, ScaledSimplex};
use super::{GridTable, MomentSolver, Solution, Status};
use anyhow::{bail, Result};

/// Primal feasibility tolerance on weights (which sum to 1).
const TOL_P: f64 = 1e-10;
/// Primal feasibility accepted at a dual-feasible basis when nothing better is found.
const TOL_P_LOOSE: f64 = 1e-9;
/// Optimality tolerance on reduced costs (costs are 0 or 1, columns have RMS 1).
const TOL_D: f64 = 1e-10;
/// Smallest admissible pivot element.
const TOL_PIV: f64 = 1e-9;
/// Residual of the phase-1 optimum above which the moments are declared infeasible.
const TOL_INF: f64 = 1e-9;
/// Relative residual below which a basis function counts as dependent on the previous ones.
const TOL_RANK: f64 = 1e-10;
/// Relative tolerance of the consistency check of a dependent function's moment.
const TOL_DEP: f64 = 1e-8;
/// Largest condition number (Frobenius) of a basis accepted at refactorisation.
const MAX_COND: f64 = 1e12;
/// Accurate pivots ([`Certifier::improve`]) tried on a basis that does not certify.
const IMPROVE_STEPS: usize = 4;
/// Pivots between refactorisations of the basis inverse.
const REFACTOR_EVERY: usize = 16;
/// Consecutive degenerate pivots after which Bland's rule takes over.
const DEGENERATE_LIMIT: usize = 20;

/// Counters over the lifetime of a [`FastSolver`] (for benchmarks and tests).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct FastStats {
    /// Problems solved.
    pub solves: u64,
    /// Simplex pivots (both phases).
    pub pivots: u64,
    /// Of which in phase 1.
    pub phase1_pivots: u64,
    /// Of which degenerate (step 0).
    pub degenerate_pivots: u64,
    /// Runs that perturbed the moments to leave a degenerate vertex.
    pub perturbations: u64,
    /// Full pricing passes (partial pricing found nothing, or Bland's rule).
    pub full_pricing: u64,
    /// Of which found an entering column that partial pricing missed.
    pub partial_misses: u64,
    /// Problems that needed phase 1 (start basis not primal feasible).
    pub phase1: u64,
    /// Problems reported infeasible.
    pub infeasible: u64,
    /// Optimal bases accepted with weights down to −1e-9 (clamped to 0): degenerate,
    /// ill-conditioned final bases where neither polish nor rescue reached rounding level.
    pub loose: u64,
    /// Cold restarts after an iteration cap, a singular basis or a failed verification.
    pub restarts: u64,
    /// Problems handed to the reference solver after everything else failed.
    pub fallbacks: u64,
    /// Problems escalated to the scaled simplex ([`super::scaled`]): the fast answer was not
    /// certified, or the fast runs did not converge, or phase 1 called them infeasible.
    pub escalations: u64,
    /// Problems returned as `Failed` (nothing settled them and the reference fallback is off).
    pub failed: u64,
    /// Fast optima that certified only after accurate pivots ([`Certifier::improve`]).
    pub improved: u64,
    /// Solves started from a given distribution ([`MomentSolver::solve_distribution`]) by the
    /// crossover.
    pub hinted: u64,
    /// Solves given a distribution whose moments equal the last solved problem's (another
    /// fragment depth for the same texel): started from that problem's optimal basis, which
    /// is primal feasible, instead of the crossover.
    pub same_moments: u64,
    /// Of which the start could not be turned into a basis (the usual start was used).
    pub hint_rejected: u64,
    /// Crossover pivots (start distribution → basic feasible solution).
    pub crossover_pivots: u64,
    /// Optima whose weights, refined against the LP as stated, were infeasible: solved again
    /// with every basic solution refined.
    pub accurate_retries: u64,
}

/// Index of the artificial column in a basis.
const ART: usize = usize::MAX;

/// What [`FastSolver::refine_steps`] found.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Refined {
    /// Refined weights are a distribution (kept).
    Feasible,
    /// Refined weights negative, but the unrefined ones (kept) reproduce the moments to
    /// rounding: a numerically singular basis.
    Undetermined,
    /// Refined weights negative and the unrefined ones (kept) not accurate: the basis is not
    /// primal feasible.
    Infeasible,
}

enum Outcome {
    Optimal,
    Infeasible,
    /// Numerical trouble or the iteration cap: retry from a cold basis.
    Failed,
    /// The final basis is slightly primal infeasible after refactorisation: run again from it.
    Retry,
    /// An optimum whose weights are not reliable (see `finish_optimal`): run again from it in
    /// accurate mode; the current weights stand if that run fails.
    RetryAccurate,
}

/// Fast exact solver for Algorithm 1; see the module documentation.
pub struct FastSolver {
    table: GridTable,
    n: usize,
    m: usize,
    /// Numerical rank of [1, b_1..b_m] on the grid (= number of rows of the transformed LP).
    r: usize,
    /// Transformed columns, row-major: rows[i*r + k] = a_i[k].
    rows: Vec<f64>,
    /// For function j (0 = constant): coefficients R[k][j], k < r, at rcoef[j*r + k].
    rcoef: Vec<f64>,
    /// For function j: its position among the kept (independent) functions, if kept.
    kept: Vec<Option<usize>>,
    /// For function j: max |M_j| over the grid (scale of the consistency check).
    fscale: Vec<f64>,
    /// Well-conditioned cold-start basis.
    b0: Vec<usize>,
    /// cond_F of [1, b_1..b_m] on the grid (via R).
    condition: f64,
    /// Rounding-error bound on the weights of the last solve.
    last_bound: f64,
    /// The basis of the last successful factorisation, and whether `binv` is still exactly
    /// that factorisation (no pivot since, no artificial column).
    factored: Vec<usize>,
    factored_ok: bool,
    /// Last optimal basis (warm start), if any, and the transformed moments it was optimal for.
    warm_basis: Option<Vec<usize>>,
    last_c: Vec<f64>,
    warm: bool,
    stats: FastStats,
    /// Checks every answer in the original coordinates.
    cert: Certifier,
    /// The escalation solver.
    scaled: ScaledSimplex,
    fallback: Option<ReferenceSolver>,
    /// Hand problems nothing else settles to the reference solver (default) or report them
    /// `Failed`.
    use_fallback: bool,
    // Workspace (no allocation per solve).
    c: Vec<f64>,
    u: Vec<f64>,
    basis: Vec<usize>,
    binv: Vec<f64>,
    bmat: Vec<f64>,
    x: Vec<f64>,
    y: Vec<f64>,
    alpha: Vec<f64>,
    art: Vec<f64>,
    s: Vec<f64>,
    /// The transformed moments of the current problem (c may be perturbed during a run).
    c0: Vec<f64>,
    /// The moments of the current problem as given.
    b_orig: Vec<f64>,
    /// Refine every basic solution against the LP as stated (set when an optimum's weights
    /// turned out infeasible on refinement; per solve).
    accurate: bool,
    x_backup: Vec<f64>,
    /// Duals and weights before the last verification refactorisation.
    yold: Vec<f64>,
    xold: Vec<f64>,
    /// max_i ‖a_i‖₂.
    amax: f64,
    /// is_basic[i]: grid column i is in the basis.
    is_basic: Vec<bool>,
    /// Coarse stride of partial pricing (1 = always full pricing).
    stride: usize,
    /// The columns in pricing blocks (all of them, and the coarse subgrid of partial pricing:
    /// every `stride`-th point and the last one, at grid indices `coarse_idx`).
    fine: ColumnTable,
    coarse: ColumnTable,
    coarse_idx: Vec<usize>,
    ls_sup: Vec<usize>,
    ls_a: Vec<f64>,
    ls_q: Vec<f64>,
    ls_r: Vec<f64>,
    ls_w: Vec<f64>,
    /// 1 / max_i |M_j(z_i)|: row equilibration of the original system.
    oscale: Vec<f64>,
    lo_rhs: Vec<f64>,
    /// Crossover workspace: the start distribution, residuals, orthonormal directions and
    /// basis positions of its support points.
    hint: Vec<(usize, f64)>,
    hint_res: Vec<f64>,
    hint_u: Vec<f64>,
    hint_pos: Vec<usize>,
}

impl FastSolver {
    /// Prepare the solver for `table` (orthonormalisation and cold-start basis; O(n m²)).
    pub fn new(table: GridTable) -> FastSolver {
        let n = table.n();
        let m = table.m();
        let mm = m + 1;
        // Columns of M = [1, b_1..b_m] on the grid.
        let mut q: Vec<Vec<f64>> = Vec::with_capacity(mm);
        let mut rcoef_full = vec![0.0; mm * mm];
        let mut kept = vec![None; mm];
        let mut fscale = vec![0.0; mm];
        for j in 0..mm {
            let mut v: Vec<f64> = if j == 0 {
                vec![1.0; n]
            } else {
                (0..n).map(|i| table.row(i)[j - 1]).collect()
            };
            fscale[j] = v.iter().fold(0.0f64, |a, &b| a.max(b.abs()));
            // Work on v·2^-e (exact) so that ‖v‖² cannot overflow (exp(400z) reaches 1e173).
            let unit = super::dense::inv_pow2(fscale[j]);
            v.iter_mut().for_each(|x| *x *= unit);
            let norm0 = norm(&v);
            let coef = &mut rcoef_full[j * mm..(j + 1) * mm];
            for _pass in 0..2 {
                for (k, qk) in q.iter().enumerate() {
                    let h = dot(qk, &v);
                    coef[k] += h;
                    for (vi, qi) in v.iter_mut().zip(qk) {
                        *vi -= h * qi;
                    }
                }
            }
            let nv = norm(&v);
            if norm0 > 0.0 && nv > TOL_RANK * norm0 {
                coef[q.len()] = nv;
                kept[j] = Some(q.len());
                for vi in v.iter_mut() {
                    *vi /= nv;
                }
                q.push(v);
            }
            // R's column of the unscaled function.
            coef.iter_mut().for_each(|c| *c /= unit);
        }
        let r = q.len();
        let sn = (n as f64).sqrt();
        let mut cols = vec![0.0; r * n];
        let mut rows = vec![0.0; n * r];
        for (k, qk) in q.iter().enumerate() {
            for i in 0..n {
                let a = sn * qk[i];
                cols[k * n + i] = a;
                rows[i * r + k] = a;
            }
        }
        let mut rcoef = vec![0.0; mm * r];
        for j in 0..mm {
            rcoef[j * r..(j + 1) * r].copy_from_slice(&rcoef_full[j * mm..j * mm + r]);
        }
        let b0 = max_volume_rows(&rows, n, r);
        let amax = (0..n)
            .map(|i| norm(&rows[i * r..(i + 1) * r]))
            .fold(0.0, f64::max);
        // cond_F(R) over the kept functions (= condition of M on the grid).
        let condition = {
            let mut rk = vec![0.0; r * r];
            let mut t = 0;
            for j in 0..mm {
                if let Some(tj) = kept[j] {
                    for k in 0..r {
                        rk[k * r + tj] = rcoef[j * r + k];
                    }
                    t += 1;
                }
            }
            debug_assert_eq!(t, r);
            let nr = norm(&rk);
            let mut inv = vec![0.0; r * r];
            if invert(&mut rk, &mut inv, r) {
                nr * norm(&inv)
            } else {
                f64::INFINITY
            }
        };
        let fine = ColumnTable::new(r, n, |k, i| cols[k * n + i]);
        let cert_rows: Vec<usize> = (0..mm).filter(|&j| kept[j].is_some()).collect();
        let mut solver = FastSolver {
            n,
            m,
            r,
            rows,
            rcoef,
            kept,
            b0,
            condition,
            last_bound: 0.0,
            factored: vec![usize::MAX; r],
            factored_ok: false,
            warm_basis: None,
            last_c: vec![f64::NAN; r],
            warm: true,
            stats: FastStats::default(),
            cert: Certifier::new(&table, cert_rows),
            scaled: ScaledSimplex::default(),
            fallback: None,
            use_fallback: false,
            c: vec![0.0; r],
            u: vec![0.0; r],
            basis: vec![0; r],
            binv: vec![0.0; r * r],
            bmat: vec![0.0; r * r],
            x: vec![0.0; r],
            y: vec![0.0; r],
            alpha: vec![0.0; r],
            art: vec![0.0; r],
            s: vec![0.0; n],
            c0: vec![0.0; r],
            b_orig: vec![0.0; m],
            accurate: false,
            x_backup: vec![0.0; r],
            yold: vec![0.0; r],
            xold: vec![0.0; r],
            amax,
            is_basic: vec![false; n],
            stride: 1,
            fine,
            coarse: ColumnTable::default(),
            coarse_idx: Vec::new(),
            ls_sup: vec![0; r],
            ls_a: vec![0.0; r * r],
            ls_q: vec![0.0; r * r],
            ls_r: vec![0.0; r * r],
            ls_w: vec![0.0; r],
            oscale: fscale
                .iter()
                .map(|&f| if f > 0.0 { 1.0 / f } else { 1.0 })
                .collect(),
            lo_rhs: vec![0.0; mm],
            fscale,
            table,
            hint: Vec::new(),
            hint_res: Vec::new(),
            hint_u: Vec::new(),
            hint_pos: Vec::new(),
        };
        solver.set_partial_pricing(true);
        solver
    }

    /// Enable or disable warm start from the previous optimal basis (on by default).
    /// Whether problems that neither the fast runs nor the scaled simplex settle are also given
    /// to the reference solver, whose support is then certified like any other basis (off by
    /// default: the reference is an oracle for the tests, not a rescue). Without a certificate
    /// the answer is `Failed` either way.
    pub fn set_reference_fallback(&mut self, on: bool) {
        self.use_fallback = on;
    }

    pub fn set_warm_start(&mut self, on: bool) {
        self.warm = on;
        if !on {
            self.warm_basis = None;
        }
    }

    /// The basis the next solve starts from (grid indices), if any.
    pub fn warm_basis(&self) -> Option<&[usize]> {
        self.warm_basis.as_deref()
    }

    /// Start the next solve from `basis` (rank() distinct grid indices), e.g. to test that any
    /// start basis gives the same answer. Invalid bases are rejected.
    pub fn set_warm_basis(&mut self, basis: &[usize]) -> Result<()> {
        if basis.len() != self.r {
            bail!("basis: expected {} indices, got {}", self.r, basis.len());
        }
        for (k, &i) in basis.iter().enumerate() {
            if i >= self.n || basis[..k].contains(&i) {
                bail!("basis: index {i} out of range or repeated");
            }
        }
        self.warm = true;
        self.warm_basis = Some(basis.to_vec());
        self.last_c.iter_mut().for_each(|v| *v = f64::NAN);
        Ok(())
    }

    /// Enable or disable partial pricing (coarse subgrid first; on by default for n ≥ 64).
    pub fn set_partial_pricing(&mut self, on: bool) {
        let n = self.n;
        self.stride = if on && n >= 64 {
            ((n as f64 / 2.0).sqrt() as usize).max(2)
        } else {
            1
        };
        self.coarse_idx = (0..n).step_by(self.stride).collect();
        if self.coarse_idx.last() != Some(&(n - 1)) {
            self.coarse_idx.push(n - 1);
        }
        let (fine, idx) = (&self.fine, &self.coarse_idx);
        self.coarse = ColumnTable::new(self.r, idx.len(), |k, j| fine.entry(k, idx[j]));
        for i in 0..n {
            if self.is_basic[i] {
                self.set_basic(i, true);
            }
        }
    }

    /// Forget the warm-start basis.
    pub fn reset(&mut self) {
        self.warm_basis = None;
        self.last_c.iter_mut().for_each(|v| *v = f64::NAN);
    }

    /// Numerical rank of [1, b_1, …, b_m] on the grid (m+1 unless functions are dependent).
    pub fn rank(&self) -> usize {
        self.r
    }

    /// Condition number (Frobenius) of the n × (m+1) matrix [1, b_1(z), …, b_m(z)] on the grid.
    /// Above ~1e8 the candidate is numerically rank-deficient for double precision.
    pub fn condition(&self) -> f64 {
        self.condition
    }

    /// A first-order bound on how far the weights (and G) of the last optimal solve can move
    /// when the moments are perturbed at the rounding level: ε · cond(M) · ‖B⁻¹‖_F · (1 + ‖c‖)
    /// for the final basis B. Where this exceeds ~1e-10, G is not determined to 1e-9 by the
    /// double-precision moments (clustered support on a fine grid), for any solver.
    pub fn last_error_bound(&self) -> f64 {
        self.last_bound
    }

    pub fn stats(&self) -> FastStats {
        self.stats
    }

    pub fn table(&self) -> &GridTable {
        &self.table
    }

    /// Transform b̄ = [1, b] to c = √n R^{-T} b̄; false if a dependent function's moment is
    /// inconsistent (then no distribution on the grid has these moments).
    fn transform(&mut self, moments: &[f64]) -> bool {
        let r = self.r;
        let mut done = 0usize;
        for j in 0..=self.m {
            let bj = if j == 0 { 1.0 } else { moments[j - 1] };
            let coef = &self.rcoef[j * r..(j + 1) * r];
            let mut acc = bj;
            for k in 0..done {
                acc -= coef[k] * self.u[k];
            }
            match self.kept[j] {
                Some(t) => {
                    self.u[t] = acc / coef[t];
                    done = t + 1;
                }
                None => {
                    let scale = self.fscale[j].max(bj.abs()).max(1e-300);
                    if acc.abs() > TOL_DEP * scale {
                        return false;
                    }
                }
            }
        }
        let sn = (self.n as f64).sqrt();
        for k in 0..r {
            self.c[k] = sn * self.u[k];
        }
        true
    }

    /// Column i of the transformed LP (i == ART: the artificial column).
    #[inline]
    fn column(&self, i: usize) -> &[f64] {
        if i == ART {
            &self.art
        } else {
            &self.rows[i * self.r..(i + 1) * self.r]
        }
    }

    /// Recompute the basis inverse from scratch (Gauss–Jordan, partial pivoting) and
    /// x = B⁻¹ c. False if the basis is numerically singular.
    fn refactor(&mut self) -> bool {
        let ok = self.factor();
        if ok {
            self.basic_solution();
        }
        ok
    }

    /// Basis inverse only (see [`Self::refactor`]); false if numerically singular.
    fn factor(&mut self) -> bool {
        let r = self.r;
        // bmat[k][t] = a_{B_t}[k]
        for t in 0..r {
            let bt = self.basis[t];
            for k in 0..r {
                let v = self.column(bt)[k];
                self.bmat[k * r + t] = v;
            }
        }
        let bnorm = norm(&self.bmat);
        // Numerically singular for our purposes: weights from such a basis carry errors of
        // cond·ε > 1e-4; the caller rebuilds a well-conditioned basis instead.
        let ok = invert(&mut self.bmat, &mut self.binv, r) && bnorm * norm(&self.binv) < MAX_COND;
        self.factored.copy_from_slice(&self.basis);
        self.factored_ok = ok && !self.basis.contains(&ART);
        ok
    }

    /// x = B⁻¹ c with two steps of iterative refinement.
    fn basic_solution(&mut self) {
        let r = self.r;
        {
            mat_vec(&self.binv, &self.c, &mut self.x, r);
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
                        &self.rows[bt * r..(bt + 1) * r]
                    };
                    for (ak, ck) in self.alpha.iter_mut().zip(col) {
                        *ak -= ck * xt;
                    }
                }
                // self.y is free here as scratch.
                mat_vec(&self.binv, &self.alpha, &mut self.y, r);
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
                let row = &self.binv[t * r..(t + 1) * r];
                for (yk, bk) in self.y.iter_mut().zip(row) {
                    *yk += cost * bk;
                }
            }
        }
    }

    /// One simplex run from `self.basis`. `kf` = number of grid points below z_f.
    fn run(&mut self, kf: usize, bland_always: bool) -> Outcome {
        let r = self.r;
        let n = self.n;
        if self.factored_ok && self.basis == self.factored {
            // B⁻¹ is still the fresh factorisation of this basis (the warm start after a
            // problem that ended on it): only the weights are new.
            self.basic_solution();
        } else if !self.refactor() {
            return Outcome::Failed;
        }
        let mut phase1 = false;
        let mut art_pos = 0usize;
        let mut art_norm = 0.0;
        // Phase 1 set-up with a single artificial column.
        {
            let mut worst = None;
            let mut worst_v = -TOL_P;
            for t in 0..r {
                if self.x[t] < worst_v {
                    worst_v = self.x[t];
                    worst = Some(t);
                }
            }
            if let Some(ts) = worst {
                self.stats.phase1 += 1;
                self.art.iter_mut().for_each(|v| *v = 0.0);
                for t in 0..r {
                    if self.x[t] < -TOL_P {
                        let bt = self.basis[t];
                        for k in 0..r {
                            self.art[k] -= self.rows[bt * r + k];
                        }
                    }
                }
                art_norm = norm(&self.art);
                self.set_basic(self.basis[ts], false);
                self.basis[ts] = ART;
                art_pos = ts;
                phase1 = true;
                if !self.refactor() {
                    return Outcome::Failed;
                }
            }
        }
        let c_norm = norm(&self.c);
        let cap = 200 + 20 * r + n / 16;
        let mut since_refactor = 0usize;
        let mut degenerate = 0usize;
        let mut verified = false;
        let mut rescues = 0;
        let mut perturbed = false;
        for _iter in 0..cap {
            if since_refactor >= REFACTOR_EVERY {
                if !self.refactor() {
                    // Numerically singular basis (clustered grid points): rebuild a
                    // well-conditioned one around the current weights.
                    if rescues < 3 && self.rescue() {
                        rescues += 1;
                        phase1 = false;
                        since_refactor = 0;
                        verified = false;
                        continue;
                    }
                    return Outcome::Failed;
                }
                since_refactor = 0;
            }
            if degenerate >= DEGENERATE_LIMIT && !perturbed {
                // Stalling on a degenerate vertex (moments on the boundary of the moment
                // space): perturb c = B x into c + B δ with small distinct δ_t > 0, which makes
                // the vertex non-degenerate; the true c is restored at the optimum.
                for t in 0..r {
                    let bt = self.basis[t];
                    if bt == ART {
                        continue; // never feed the artificial: c stays feasible iff it was
                    }
                    let dt = 1e-7 * (1.0 + t as f64 / r as f64);
                    self.x[t] += dt;
                    for k in 0..r {
                        self.c[k] += dt * self.rows[bt * r + k];
                    }
                }
                perturbed = true;
                degenerate = 0;
                self.stats.perturbations += 1;
            }
            let bland = bland_always || degenerate >= DEGENERATE_LIMIT;
            self.duals(phase1, kf);
            let kf_eff = if phase1 { 0 } else { kf };
            let partial = if bland || self.stride <= 1 {
                (usize::MAX, 0.0)
            } else {
                self.price_partial(kf_eff)
            };
            if partial.0 == usize::MAX && !bland && !verified && since_refactor > 0 {
                // About to prove optimality with a full pass: refactorise first, so that the
                // pass prices with fresh duals (the updated ones of an ill-conditioned basis
                // can be off by far more than the tolerance, and a pass with them would have
                // to be repeated).
                self.yold.copy_from_slice(&self.y);
                self.xold.copy_from_slice(&self.x);
                if !self.refactor() {
                    if rescues < 3 && self.rescue() {
                        rescues += 1;
                        phase1 = false;
                        since_refactor = 0;
                        continue;
                    }
                    return Outcome::Failed;
                }
                since_refactor = 0;
                verified = true;
                self.duals(phase1, kf);
            }
            if partial.0 == usize::MAX {
                self.stats.full_pricing += 1;
            }
            let (q, dq) = if partial.0 != usize::MAX {
                partial
            } else if bland {
                price_bland(&self.fine, n, r, &self.y, kf_eff, &self.basis, &mut self.s)
            } else {
                self.price_full(kf_eff)
            };
            if partial.0 == usize::MAX && dq < -TOL_D {
                self.stats.partial_misses += 1;
            }
            if dq >= -TOL_D {
                // Optimal for the current phase: verify with a fresh factorisation first.
                if !verified && since_refactor > 0 {
                    self.yold.copy_from_slice(&self.y);
                    self.xold.copy_from_slice(&self.x);
                    if !self.refactor() {
                        if rescues < 3 && self.rescue() {
                            rescues += 1;
                            phase1 = false;
                            since_refactor = 0;
                            verified = false;
                            continue;
                        }
                        return Outcome::Failed;
                    }
                    since_refactor = 0;
                    verified = true;
                    // If the fresh duals moved so little that no reduced cost can have crossed
                    // the tolerance, the pricing pass stands; otherwise price again.
                    self.duals(phase1, kf);
                    let dy: f64 = self
                        .y
                        .iter()
                        .zip(&self.yold)
                        .map(|(a, b)| (a - b) * (a - b))
                        .sum::<f64>()
                        .sqrt();
                    if dy * self.amax > 0.5 * TOL_D || dq < -0.5 * TOL_D {
                        continue;
                    }
                }
                if phase1 {
                    let xa = self.x[art_pos].max(0.0);
                    if xa * art_norm > TOL_INF * (1.0 + c_norm) && perturbed {
                        // Decide feasibility on the true moments.
                        self.c.copy_from_slice(&self.c0);
                        perturbed = false;
                        verified = false;
                        if !self.refactor() {
                            return Outcome::Failed;
                        }
                        since_refactor = 0;
                        continue;
                    }
                    if xa * art_norm > TOL_INF * (1.0 + c_norm) {
                        if rescues < 3 && self.rescue() {
                            rescues += 1;
                            phase1 = false;
                            since_refactor = 0;
                            verified = false;
                            continue;
                        }
                        return Outcome::Infeasible;
                    }
                    // Feasible: drive the (zero) artificial out of the basis. With the phase-1
                    // duals, s = row art_pos of B⁻¹A; pick the largest pivot element.
                    price(&self.fine, n, r, &self.y, 0, &self.basis, &mut self.s);
                    let mut best = None;
                    let mut best_v = TOL_PIV;
                    for i in 0..n {
                        let v = self.s[i].abs();
                        if v > best_v {
                            best_v = v;
                            best = Some(i);
                        }
                    }
                    let Some(j) = best else {
                        return Outcome::Failed;
                    };
                    self.x[art_pos] = 0.0;
                    self.load_alpha(j);
                    self.pivot(art_pos, j, 0.0);
                    since_refactor += 1;
                    phase1 = false;
                    verified = false;
                    continue;
                }
                if perturbed {
                    // Restore the true moments at this (dual-feasible) basis and continue.
                    self.c.copy_from_slice(&self.c0);
                    perturbed = false;
                    verified = false;
                    if !self.refactor() {
                        if rescues < 3 && self.rescue() {
                            rescues += 1;
                            since_refactor = 0;
                            continue;
                        }
                        return Outcome::Failed;
                    }
                    since_refactor = 0;
                    continue;
                }
                // Phase 2 optimum. Any non-negative w on the basic columns with B w = c is
                // optimal too (complementary slackness); prefer the well-conditioned one on the
                // clearly positive weights, else the basic solution if it is feasible.
                if self.x.iter().all(|&v| v >= -TOL_P) {
                    // With every weight clearly positive the least squares of the polish is
                    // the square system the refined basic solution already solved.
                    if self.x.iter().any(|&v| v <= 1e-8) {
                        self.polish();
                    }
                    return self.finish_optimal();
                }
                if self.polish() {
                    return self.finish_optimal();
                }
                if rescues < 3 && self.rescue() {
                    rescues += 1;
                    since_refactor = 0;
                    verified = false;
                    continue;
                }
                // The updated weights drifted on an ill-conditioned basis: rebuild from the
                // weights before the refactorisation (validated by least squares in rescue).
                if rescues < 3 {
                    self.x.copy_from_slice(&self.xold);
                    if self.rescue() {
                        rescues += 1;
                        since_refactor = 0;
                        verified = false;
                        continue;
                    }
                    if !self.refactor() {
                        return Outcome::Failed;
                    }
                }
                if self.x.iter().all(|&v| v >= -TOL_P_LOOSE) {
                    // Dual feasible and primal feasible to 1e-9: as good as the data allow
                    // on this degenerate, ill-conditioned basis.
                    self.stats.loose += 1;
                    return Outcome::Optimal;
                }
                return Outcome::Retry;
            }
            verified = false;
            self.load_alpha(q);
            // Ratio test (Harris two-pass; Bland: smallest basis index among ties).
            let mut theta_max = f64::INFINITY;
            for t in 0..r {
                let a = self.alpha[t];
                if a > TOL_PIV {
                    let v = (self.x[t].max(0.0) + TOL_P) / a;
                    if v < theta_max {
                        theta_max = v;
                    }
                }
            }
            if !theta_max.is_finite() {
                // Unbounded direction: impossible for this LP (objective ≥ 0); numerical.
                return Outcome::Failed;
            }
            let mut l = usize::MAX;
            let mut best = 0.0;
            for t in 0..r {
                let a = self.alpha[t];
                if a > TOL_PIV && self.x[t].max(0.0) / a <= theta_max {
                    let better = if bland {
                        l == usize::MAX || self.basis[t] < self.basis[l]
                    } else {
                        a > best
                    };
                    if better {
                        best = a;
                        l = t;
                    }
                }
            }
            let theta = (self.x[l].max(0.0) / self.alpha[l]).max(0.0);
            if theta * (-dq) <= 1e-14 {
                degenerate += 1;
                self.stats.degenerate_pivots += 1;
            } else {
                degenerate = 0;
            }
            let leaving = self.basis[l];
            self.pivot(l, q, theta);
            self.stats.pivots += 1;
            if phase1 {
                self.stats.phase1_pivots += 1;
            }
            since_refactor += 1;
            if phase1 && leaving == ART {
                phase1 = false;
            }
        }
        Outcome::Failed
    }

    /// Least squares on the basic positions `ls_sup[..k]`: c ≈ Σ w_a a_{B_t}. On success (w ≥ 0
    /// and residual at rounding level) x becomes w on those positions and 0 elsewhere
    /// (including the artificial).
    fn try_support(&mut self, k: usize) -> bool {
        let r = self.r;
        if k == 0 {
            return false;
        }
        for a in 0..k {
            let bt = self.basis[self.ls_sup[a]];
            self.ls_a[a * r..(a + 1) * r].copy_from_slice(&self.rows[bt * r..(bt + 1) * r]);
        }
        let w = &mut self.ls_w[..k];
        if !least_squares(
            &self.ls_a[..k * r],
            r,
            k,
            &self.c,
            &mut self.ls_q,
            &mut self.ls_r,
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
                acc -= w[a] * self.ls_a[a * r + kk];
            }
            res2 += acc * acc;
        }
        if res2.sqrt() > 1e-12 * (1.0 + norm(&self.c)) {
            return false;
        }
        self.x.iter_mut().for_each(|v| *v = 0.0);
        for a in 0..k {
            self.x[self.ls_sup[a]] = w[a];
        }
        true
    }

    /// Accuracy polish at an optimal basis: the weights of an ill-conditioned degenerate basis
    /// are accurate to cond·ε only. Least squares on the clearly positive weights (> 1e-8) gives
    /// the same distribution accurately; any non-negative w on basic columns with B w = c is
    /// optimal (complementary slackness).
    fn polish(&mut self) -> bool {
        let mut k = 0;
        for t in 0..self.r {
            if self.basis[t] != ART && self.x[t] > 1e-8 {
                self.ls_sup[k] = t;
                k += 1;
            }
        }
        self.try_support(k)
    }

    /// Rescue when the basic weights are unreliable (ill-conditioned basis of clustered grid
    /// points): find a small support among the basic columns, largest weights first, that
    /// reproduces c with non-negative weights; then complete it to a well-conditioned basis
    /// (greedy maximal volume) with zero weights on the added columns, and refactorise.
    fn rescue(&mut self) -> bool {
        let r = self.r;
        // Basic positions of real columns with positive weight, by decreasing weight.
        let mut order: Vec<usize> = (0..r)
            .filter(|&t| self.basis[t] != ART && self.x[t] > 0.0)
            .collect();
        order.sort_by(|&a, &b| self.x[b].total_cmp(&self.x[a]));
        let mut found = 0;
        for k in 1..=order.len() {
            self.ls_sup[..k].copy_from_slice(&order[..k]);
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
        let Some(full) = complete_basis(&self.rows, self.n, r, &cols) else {
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

    /// Set the basic flags of the current basis' real columns.
    fn mark_basic(&mut self, on: bool) {
        for t in 0..self.r {
            let bt = self.basis[t];
            if bt != ART {
                self.set_basic(bt, on);
            }
        }
    }

    /// Partial pricing: reduced costs on a coarse subgrid (every `stride`-th point and the last
    /// one), next to z_f and next to the current support points, then on the whole fine window
    /// between the coarse neighbours of the best of these. Reduced costs are smooth in z on
    /// either side of z_f, so this usually finds a good entering column at a fraction of a full
    /// pass. Returns (usize::MAX, −TOL_D) when it finds no negative reduced cost (then a full
    /// pass decides).
    fn price_partial(&self, kf: usize) -> (usize, f64) {
        let (n, r, st) = (self.n, self.r, self.stride);
        let y = &self.y[..r];
        let none = (usize::MAX, -TOL_D);
        // Coarse subgrid.
        let coarse = &self.coarse;
        // Coarse points below kf: j·st < kf for the regular ones, and the extra last point
        // n − 1 only when kf = n.
        let nc = self.coarse_idx.len();
        let regular = if (nc - 1) * st == n - 1 { nc } else { nc - 1 };
        let csplit = kf.div_ceil(st).min(regular) + (regular < nc && kf == n) as usize;
        debug_assert_eq!(csplit, self.coarse_idx.partition_point(|&i| i < kf));
        let cb = coarse.scan(y, csplit, 0, coarse.blocks(), none);
        let mut best = if cb.0 == usize::MAX {
            none
        } else {
            (self.coarse_idx[cb.0], cb.1)
        };
        // Narrow dips of the reduced cost appear next to the current support points and at
        // the step at z_f: scan a few neighbours of each (whole blocks, overlaps merged).
        const W: usize = 3;
        let mut ranges = [(0usize, 0usize); 10];
        let mut nr = 0;
        ranges[nr] = self.fine.block_range(kf.saturating_sub(W), kf + W);
        nr += 1;
        for &bt in &self.basis {
            if bt != ART && nr < ranges.len() {
                ranges[nr] = self.fine.block_range(bt.saturating_sub(W), bt + W + 1);
                nr += 1;
            }
        }
        // Support points come in neighbouring pairs: scan each distinct block range once.
        let mut distinct = 0;
        for a in 0..nr {
            if !ranges[..distinct].contains(&ranges[a]) {
                ranges[distinct] = ranges[a];
                distinct += 1;
            }
        }
        best = self.fine.scan_ranges(y, kf, &ranges[..distinct], best);
        if best.0 == usize::MAX {
            return best;
        }
        // The reduced cost is smooth between coarse points: the minimum of the whole fine
        // window around the best point is the entering column.
        let c = best.0;
        let window = self
            .fine
            .block_range(c.saturating_sub(st - 1), (c + st).min(n));
        self.scan_fine(y, kf, window, best)
    }

    /// Full pricing: the non-basic column with the lowest reduced cost, or (usize::MAX, 0) when
    /// none is below −TOL_D / 4 (basic columns, whose reduced cost is 0 up to rounding, then
    /// never come out lowest).
    fn price_full(&self, kf: usize) -> (usize, f64) {
        let y = &self.y[..self.r];
        let got = self.scan_fine(y, kf, (0, self.fine.blocks()), (usize::MAX, -0.25 * TOL_D));
        if got.0 == usize::MAX {
            (usize::MAX, 0.0)
        } else {
            got
        }
    }

    /// [`ColumnTable::scan`] of the fine table over a block range (basic columns excluded).
    fn scan_fine(
        &self,
        y: &[f64],
        kf: usize,
        (blo, bhi): (usize, usize),
        best: (usize, f64),
    ) -> (usize, f64) {
        self.fine.scan(y, kf, blo, bhi, best)
    }

    /// Mark grid column i basic (excluded from pricing) or not.
    fn set_basic(&mut self, i: usize, on: bool) {
        self.is_basic[i] = on;
        self.fine.set_excluded(i, on);
        let st = self.stride;
        let nc = self.coarse_idx.len();
        if i.is_multiple_of(st) {
            self.coarse.set_excluded(i / st, on);
        } else if i == self.n - 1 {
            self.coarse.set_excluded(nc - 1, on);
        }
    }

    /// alpha = B⁻¹ a_j.
    fn load_alpha(&mut self, j: usize) {
        let r = self.r;
        let col = &self.rows[j * r..(j + 1) * r];
        mat_vec(&self.binv, col, &mut self.alpha, r);
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
    fn exchange(&mut self, l: usize, q: usize) {
        let r = self.r;
        let al = self.alpha[l];
        for k in 0..r {
            self.binv[l * r + k] /= al;
        }
        for t in 0..r {
            if t != l {
                let f = self.alpha[t];
                if f != 0.0 {
                    for k in 0..r {
                        self.binv[t * r + k] -= f * self.binv[l * r + k];
                    }
                }
            }
        }
        self.factored_ok = false;
        if self.basis[l] != ART {
            self.set_basic(self.basis[l], false);
        }
        self.set_basic(q, true);
        self.basis[l] = q;
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
    fn refine_steps(&mut self) -> Option<Refined> {
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
            // u = √n R⁻ᵀ ρ (forward substitution, every function kept).
            for j in 0..mm {
                let coef = &self.rcoef[j * r..(j + 1) * r];
                let mut acc = self.lo_rhs[j];
                for k in 0..j {
                    acc -= coef[k] * self.u[k];
                }
                self.u[j] = acc / coef[j];
            }
            let sn = (self.n as f64).sqrt();
            for k in 0..r {
                self.u[k] *= sn;
            }
            mat_vec(&self.binv, &self.u, &mut self.alpha, r);
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
    fn finish_optimal(&mut self) -> Outcome {
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

    /// Crossover from a known distribution `start` = [(grid index, weight)] with these moments
    /// (e.g. the filtered depth distribution of a kernel) to a basis whose basic solution is
    /// feasible and costs no more. The basis is the support columns of greatest volume (greedy
    /// Gram–Schmidt), completed from the cold-start basis; every other support point is then
    /// pushed out, to weight 0 or into the basis, in the direction that does not increase
    /// Σ_{z_i<z_f} w_i (one ratio test and exchange each). This replaces phase 1. False when
    /// the start is unusable (then the caller starts as usual); `run` re-verifies feasibility
    /// from the true moments in any case, so a wrong start cannot change the answer.
    fn crossover(&mut self, start: &[(u32, f64)], kf: usize) -> bool {
        let (n, r) = (self.n, self.r);
        self.stats.hinted += 1;
        self.hint.clear();
        for &(i, w) in start {
            let i = i as usize;
            if i >= n || !w.is_finite() || w < 0.0 {
                return false;
            }
            if w > 0.0 {
                self.hint.push((i, w));
            }
        }
        let s = self.hint.len();
        if s == 0 {
            return false;
        }
        // Greedy maximal volume among the support columns: residuals after projecting out the
        // chosen ones (modified Gram–Schmidt on copies).
        self.hint_res.clear();
        for &(i, _) in &self.hint {
            self.hint_res
                .extend_from_slice(&self.rows[i * r..(i + 1) * r]);
        }
        self.hint_u.clear();
        self.mark_basic(false);
        let mut chosen = 0usize;
        // hint_pos[k]: basis position of support point k, or usize::MAX (superbasic).
        self.hint_pos.clear();
        self.hint_pos.resize(s, usize::MAX);
        while chosen < r {
            let mut best = usize::MAX;
            let mut best_v = 0.0;
            for k in 0..s {
                if self.hint_pos[k] != usize::MAX {
                    continue;
                }
                let v = dot(
                    &self.hint_res[k * r..(k + 1) * r],
                    &self.hint_res[k * r..(k + 1) * r],
                );
                if v > best_v {
                    best_v = v;
                    best = k;
                }
            }
            // Relative to the column norm (RMS 1 over the grid, first coordinate 1).
            if best == usize::MAX || best_v.sqrt() < 1e-5 {
                break;
            }
            let inv = 1.0 / best_v.sqrt();
            let u: Vec<f64> = self.hint_res[best * r..(best + 1) * r]
                .iter()
                .map(|v| v * inv)
                .collect();
            for k in 0..s {
                if self.hint_pos[k] == usize::MAX && k != best {
                    let row = &mut self.hint_res[k * r..(k + 1) * r];
                    let h = dot(row, &u);
                    for (a, b) in row.iter_mut().zip(&u) {
                        *a -= h * b;
                    }
                }
            }
            self.hint_u.extend_from_slice(&u);
            self.hint_pos[best] = chosen;
            self.basis[chosen] = self.hint[best].0;
            self.x[chosen] = self.hint[best].1;
            chosen += 1;
        }
        // Complete from the cold-start basis (which spans R^r).
        let mut t0 = 0;
        while chosen < r && t0 < r {
            let i = self.b0[t0];
            t0 += 1;
            if self.basis[..chosen].contains(&i) {
                continue;
            }
            let mut v = self.rows[i * r..(i + 1) * r].to_vec();
            let n0 = norm(&v);
            for _pass in 0..2 {
                for u in self.hint_u.chunks(r) {
                    let h = dot(&v, u);
                    for (a, b) in v.iter_mut().zip(u) {
                        *a -= h * b;
                    }
                }
            }
            let nv = norm(&v);
            if nv <= 1e-5 * n0 {
                continue;
            }
            v.iter_mut().for_each(|a| *a /= nv);
            self.hint_u.extend_from_slice(&v);
            self.basis[chosen] = i;
            self.x[chosen] = 0.0;
            chosen += 1;
        }
        if chosen < r {
            return false;
        }
        self.mark_basic(true);
        if !self.factor() {
            return false;
        }
        // Push every superbasic support point out of the interior.
        let mut since = 0usize;
        for k in 0..s {
            if self.hint_pos[k] != usize::MAX {
                continue;
            }
            let (j, w) = self.hint[k];
            if self.is_basic[j] {
                // A completion column of the cold basis is also in the support: give it the
                // weight (same column, same point of the feasible set).
                let Some(t) = self.basis.iter().position(|&b| b == j) else {
                    return false;
                };
                self.x[t] += w;
                continue;
            }
            self.load_alpha(j);
            let mut dj = (j < kf) as u8 as f64;
            for t in 0..r {
                if self.basis[t] < kf {
                    dj -= self.alpha[t];
                }
            }
            const PIV: f64 = 1e-8;
            // Decreasing w_j moves the basic weights by +t·α; increasing by −t·α.
            let mut decrease = dj >= 0.0;
            if !decrease && !self.alpha[..r].iter().any(|&a| a > PIV) {
                decrease = true;
            }
            let (step, l) = if decrease {
                let mut step = w;
                let mut l = usize::MAX;
                for t in 0..r {
                    let a = self.alpha[t];
                    if a < -PIV {
                        let v = self.x[t].max(0.0) / -a;
                        if v < step {
                            step = v;
                            l = t;
                        }
                    }
                }
                (step, l)
            } else {
                let mut step = f64::INFINITY;
                let mut l = usize::MAX;
                for t in 0..r {
                    let a = self.alpha[t];
                    if a > PIV {
                        let v = self.x[t].max(0.0) / a;
                        if v < step {
                            step = v;
                            l = t;
                        }
                    }
                }
                (step, l)
            };
            let sign = if decrease { 1.0 } else { -1.0 };
            for t in 0..r {
                self.x[t] += sign * step * self.alpha[t];
            }
            if l != usize::MAX {
                let wl = if decrease { w - step } else { w + step };
                self.exchange(l, j);
                self.x[l] = wl;
                self.stats.crossover_pivots += 1;
                since += 1;
                if since >= REFACTOR_EVERY {
                    if !self.factor() {
                        return false;
                    }
                    since = 0;
                }
            }
        }
        true
    }
}

impl MomentSolver for FastSolver {
    fn solve(&mut self, moments: &[f64], zf: f64) -> Result<Solution> {
        self.solve_inner(moments, zf, None, false)
    }

    fn table(&self) -> &GridTable {
        &self.table
    }

    /// Moments in the orthonormalised coordinates straight from the distribution,
    /// c = Σ w_i a_i / Σ w_i (no cancellation however badly scaled the functions are), and the
    /// distribution itself as the phase-1-free start (see [`FastSolver::crossover`]).
    fn solve_distribution(&mut self, dist: &[(u32, f64)], zf: f64) -> Result<Solution> {
        // Validates the distribution; the moments in the original coordinates serve the
        // reference fallback.
        let moments = super::distribution_moments(&self.table, dist)?;
        let r = self.r;
        let mut total = 0.0;
        self.c.iter_mut().for_each(|v| *v = 0.0);
        for &(i, w) in dist {
            let i = i as usize;
            total += w;
            for (ck, ak) in self.c.iter_mut().zip(&self.rows[i * r..(i + 1) * r]) {
                *ck += w * ak;
            }
        }
        self.c.iter_mut().for_each(|v| *v /= total);
        self.solve_inner(&moments, zf, Some(dist), true)
    }
}

/// The fast solver's own verdict, kept for when nothing certifies.
enum Legacy {
    Answer(Vec<usize>),
    Infeasible,
    Reference,
}

/// What the simplex attempts of [`FastSolver::attempts`] ended with.
enum Verdict {
    /// `self.basis` is optimal as far as the fast solver can tell (to be certified).
    Optimal,
    /// Phase 1 left the artificial positive (to be confirmed by a Farkas ray).
    Infeasible,
    /// No convergence from any start.
    Failed,
}

impl FastSolver {
    /// The contract ([`super::certify`]): a fast answer is returned only with its certificate;
    /// otherwise the problem is escalated to the scaled simplex, whose answer is certified the
    /// same way; what neither settles is `Failed` with the reason.
    fn solve_inner(
        &mut self,
        moments: &[f64],
        zf: f64,
        hint: Option<&[(u32, f64)]>,
        c_given: bool,
    ) -> Result<Solution> {
        if moments.len() != self.m {
            bail!("expected {} moments, got {}", self.m, moments.len());
        }
        if let Some(j) = moments.iter().position(|v| !v.is_finite()) {
            bail!("moment {} is not finite ({})", j + 1, moments[j]);
        }
        if zf.is_nan() {
            bail!("z_f is NaN");
        }
        self.stats.solves += 1;
        self.accurate = false;
        self.b_orig.copy_from_slice(moments);
        let kf = self.table.grid().points().partition_point(|&z| z < zf);
        let verdict = if c_given || self.transform(moments) {
            self.c0.copy_from_slice(&self.c);
            self.attempts(kf, hint)
        } else {
            Verdict::Infeasible
        };
        // The fast solver's verdict: its basis is certified, improved or escalated below.
        let mut why = String::new();
        let legacy = match verdict {
            Verdict::Optimal => {
                self.remember_optimal();
                let fast_basis = self.basis.clone();
                match self.cert.optimal(moments, kf, &fast_basis) {
                    Ok(c) => return Ok(certified(c)),
                    Err(e) => {
                        why = e;
                        Legacy::Answer(fast_basis)
                    }
                }
            }
            Verdict::Infeasible => Legacy::Infeasible,
            Verdict::Failed => Legacy::Reference,
        };
        if let Legacy::Answer(fast_basis) = &legacy {
            let mut basis = fast_basis.clone();
            if let Ok(c) = self.cert.improve(moments, kf, &mut basis, IMPROVE_STEPS) {
                self.stats.improved += 1;
                return Ok(certified(c));
            }
        }
        // A start distribution with at most r atoms is itself a basic feasible solution: the
        // accurate pivots from it never leave the feasible set.
        if let Some(mut basis) = hint.and_then(|h| self.support_basis(h)) {
            if let Ok(c) = self.cert.improve(moments, kf, &mut basis, IMPROVE_STEPS) {
                self.stats.improved += 1;
                return Ok(certified(c));
            }
        }
        let start = match &legacy {
            Legacy::Answer(b) => Some(b.clone()),
            _ => None,
        };
        let sol = self.escalate(moments, kf, start.as_deref());
        if sol.status != Status::Failed {
            return Ok(sol);
        }
        // Nothing certified: `Failed` with the reason (never an uncertified `optimal`). The
        // reference, when enabled, is one more source of a basis to certify, not a rescue.
        self.stats.failed += 1;
        let fast = match &legacy {
            Legacy::Answer(..) => format!("fast optimum not certified ({why})"),
            Legacy::Infeasible => {
                "phase 1 found no feasible point, but no Farkas ray certifies it".into()
            }
            Legacy::Reference => "the simplex did not converge".into(),
        };
        let escalation = sol.reason.unwrap_or_default();
        if self.use_fallback {
            if let Some(c) = self.reference_certified(moments, zf, kf) {
                self.stats.failed -= 1;
                self.stats.fallbacks += 1;
                return Ok(c);
            }
        }
        Ok(Solution::failed(format!("{fast}; {escalation}")))
    }

    /// The reference's answer, if its support (completed to a basis) certifies.
    fn reference_certified(&mut self, moments: &[f64], zf: f64, kf: usize) -> Option<Solution> {
        let table = &self.table;
        let fb = self
            .fallback
            .get_or_insert_with(|| ReferenceSolver::new(table.clone()));
        let sol = fb.solve(moments, zf).ok()?;
        if sol.status == Status::Infeasible {
            return None;
        }
        let grid = self.table.grid();
        let dist: Vec<(u32, f64)> = sol
            .support
            .iter()
            .map(|&(z, w)| (grid.nearest(z) as u32, w))
            .collect();
        let mut basis = self.support_basis(&dist)?;
        let c = self
            .cert
            .improve(moments, kf, &mut basis, IMPROVE_STEPS)
            .ok()?;
        Some(certified(c))
    }

    /// The scaled simplex on the problem, from `start` if given; its answer certified.
    fn escalate(&mut self, moments: &[f64], kf: usize, start: Option<&[usize]>) -> Solution {
        self.stats.escalations += 1;
        self.last_c.iter_mut().for_each(|v| *v = f64::NAN);
        self.cert.set_moments(moments);
        let pivots = self.scaled.pivots;
        let found = self.scaled.solve(&self.cert, kf, start);
        self.stats.pivots += self.scaled.pivots - pivots;
        let sol = match found {
            Found::Optimal(mut basis) => {
                match self.cert.improve(moments, kf, &mut basis, IMPROVE_STEPS) {
                    Ok(c) => certified(c),
                    Err(e) => {
                        Solution::failed(format!("scaled simplex optimum not certified: {e}"))
                    }
                }
            }
            Found::Infeasible(y) => match self.cert.infeasible(moments, &y) {
                Ok(_) => Solution::infeasible(),
                Err(e) => Solution::failed(format!("phase 1 infeasible, but {e}")),
            },
            Found::Failed(e) => Solution::failed(e),
        };
        if sol.status == Status::Infeasible {
            self.stats.infeasible += 1;
        }
        sol
    }

    /// The support of a distribution with at most r atoms, completed to r columns from the
    /// cold-start basis (None for larger supports).
    fn support_basis(&self, dist: &[(u32, f64)]) -> Option<Vec<usize>> {
        let mut basis: Vec<usize> = Vec::with_capacity(self.r);
        for &(i, w) in dist {
            let i = i as usize;
            if w > 0.0 && !basis.contains(&i) {
                if basis.len() == self.r {
                    return None;
                }
                basis.push(i);
            }
        }
        let rows = &self.rows;
        complete_basis(rows, self.n, self.r, &basis)
    }

    /// After a certified fast optimum: its basis is the next warm start.
    fn remember_optimal(&mut self) {
        self.last_bound = f64::EPSILON * self.condition * norm(&self.binv) * (1.0 + norm(&self.c));
        if self.warm {
            match &mut self.warm_basis {
                Some(wb) => wb.copy_from_slice(&self.basis),
                None => self.warm_basis = Some(self.basis.clone()),
            }
            self.last_c.copy_from_slice(&self.c0);
        }
    }

    /// Simplex runs from the hint, warm or cold bases, retrying after numerical trouble
    /// (two cold runs, the second with Bland's rule throughout).
    fn attempts(&mut self, kf: usize, hint: Option<&[(u32, f64)]>) -> Verdict {
        #[derive(Clone, Copy)]
        enum Start {
            Hint,
            Warm,
            Cold,
            Current,
        }
        let warm_or_cold = if self.warm && self.warm_basis.is_some() {
            Start::Warm
        } else {
            Start::Cold
        };
        // The same moments as the last solved problem (another fragment depth for the same
        // texel): its optimal basis is primal feasible here, a better start than the crossover.
        let same_moments = matches!(warm_or_cold, Start::Warm) && self.last_c == self.c0;
        if hint.is_some() && same_moments {
            self.stats.same_moments += 1;
        }
        let mut start = if hint.is_some() && !same_moments {
            Start::Hint
        } else {
            warm_or_cold
        };
        let mut cold_runs = 0;
        let mut stash: Option<Vec<usize>> = None;
        for _attempt in 0..6 {
            if let Start::Hint = start {
                self.c.copy_from_slice(&self.c0);
                if !self.crossover(hint.unwrap_or(&[]), kf) {
                    // Unusable start (numerically dependent support): the usual way.
                    self.stats.hint_rejected += 1;
                    start = warm_or_cold;
                }
            }
            match start {
                Start::Hint | Start::Current => {}
                Start::Warm => {
                    self.mark_basic(false);
                    let wb = self.warm_basis.as_ref().expect("warm basis");
                    self.basis.copy_from_slice(wb);
                    self.mark_basic(true);
                }
                Start::Cold => {
                    self.mark_basic(false);
                    self.basis.copy_from_slice(&self.b0);
                    self.mark_basic(true);
                    cold_runs += 1;
                }
            }
            // The second cold run uses Bland's rule throughout.
            self.c.copy_from_slice(&self.c0);
            match self.run(kf, cold_runs >= 2) {
                Outcome::RetryAccurate => {
                    self.stats.restarts += 1;
                    // The answer to certify if the accurate run fails.
                    stash = Some(self.basis.clone());
                    start = Start::Current;
                }
                Outcome::Optimal => return Verdict::Optimal,
                Outcome::Infeasible => return Verdict::Infeasible,
                Outcome::Retry => {
                    self.stats.restarts += 1;
                    start = Start::Current;
                }
                Outcome::Failed => {
                    self.stats.restarts += 1;
                    if cold_runs >= 2 || stash.is_some() {
                        break;
                    }
                    start = if matches!(start, Start::Hint) {
                        warm_or_cold
                    } else {
                        Start::Cold
                    };
                }
            }
        }
        match stash {
            Some(basis) => {
                self.stats.loose += 1;
                self.mark_basic(false);
                self.basis.copy_from_slice(&basis);
                self.mark_basic(true);
                Verdict::Optimal
            }
            None => Verdict::Failed,
        }
    }
}

/// The solution of a certified answer.
fn certified(c: Certified) -> Solution {
    Solution {
        status: Status::Optimal,
        g: c.g,
        support: c.support,
        reason: None,
    }
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

fn norm(a: &[f64]) -> f64 {
    dot(a, a).sqrt()
}

/// out = A v for row-major r × r A.
#[inline]
fn mat_vec(a: &[f64], v: &[f64], out: &mut [f64], r: usize) {
    for t in 0..r {
        out[t] = dot(&a[t * r..(t + 1) * r], &v[..r]);
    }
}

/// Invert the r × r row-major matrix `a` (destroyed) into `inv`; false if singular.
fn invert(a: &mut [f64], inv: &mut [f64], r: usize) -> bool {
    // Specialised for the row count (loops unrolled at compile time).
    match r {
        1 => invert_r::<1>(a, inv, r),
        2 => invert_r::<2>(a, inv, r),
        3 => invert_r::<3>(a, inv, r),
        4 => invert_r::<4>(a, inv, r),
        5 => invert_r::<5>(a, inv, r),
        6 => invert_r::<6>(a, inv, r),
        7 => invert_r::<7>(a, inv, r),
        8 => invert_r::<8>(a, inv, r),
        9 => invert_r::<9>(a, inv, r),
        _ => invert_r::<0>(a, inv, r),
    }
}

/// Gauss–Jordan with partial pivoting for r = R (R = 0: any r).
#[inline(always)]
fn invert_r<const R: usize>(a: &mut [f64], inv: &mut [f64], r: usize) -> bool {
    let r = if R > 0 { R } else { r };
    let (a, inv) = (&mut a[..r * r], &mut inv[..r * r]);
    inv.iter_mut().for_each(|v| *v = 0.0);
    for t in 0..r {
        inv[t * r + t] = 1.0;
    }
    for col in 0..r {
        let mut p = col;
        let mut pv = a[col * r + col].abs();
        for row in col + 1..r {
            let v = a[row * r + col].abs();
            if v > pv {
                pv = v;
                p = row;
            }
        }
        if pv < 1e-12 || !pv.is_finite() {
            return false;
        }
        if p != col {
            for k in 0..r {
                a.swap(p * r + k, col * r + k);
                inv.swap(p * r + k, col * r + k);
            }
        }
        let d = a[col * r + col];
        for k in 0..r {
            a[col * r + k] /= d;
            inv[col * r + k] /= d;
        }
        for row in 0..r {
            if row != col {
                let f = a[row * r + col];
                if f != 0.0 {
                    for k in 0..r {
                        a[row * r + k] -= f * a[col * r + k];
                        inv[row * r + k] -= f * inv[col * r + k];
                    }
                }
            }
        }
    }
    true
}

/// Least squares min ‖A w − c‖ for the column-major r × k matrix `a` (k ≤ r) by modified
/// Gram–Schmidt with reorthogonalisation, using the scratch `q` (r·k) and `rm` (k·k); false if
/// the columns are numerically dependent.
fn least_squares(
    a: &[f64],
    r: usize,
    k: usize,
    c: &[f64],
    q: &mut [f64],
    rm: &mut [f64],
    w: &mut [f64],
) -> bool {
    rm[..k * k].iter_mut().for_each(|v| *v = 0.0);
    for j in 0..k {
        let (done, rest) = q.split_at_mut(j * r);
        let v = &mut rest[..r];
        v.copy_from_slice(&a[j * r..(j + 1) * r]);
        let n0 = norm(v);
        for _pass in 0..2 {
            for i in 0..j {
                let qi = &done[i * r..(i + 1) * r];
                let h = dot(qi, v);
                rm[i * k + j] += h;
                for (vv, qq) in v.iter_mut().zip(qi) {
                    *vv -= h * qq;
                }
            }
        }
        let nv = norm(v);
        if nv.is_nan() || nv <= 1e-13 * n0 {
            return false;
        }
        rm[j * k + j] = nv;
        let inv = 1.0 / nv;
        v.iter_mut().for_each(|x| *x *= inv);
    }
    for j in 0..k {
        w[j] = dot(&q[j * r..(j + 1) * r], &c[..r]);
    }
    for j in (0..k).rev() {
        let mut acc = w[j];
        for l in j + 1..k {
            acc -= rm[j * k + l] * w[l];
        }
        w[j] = acc / rm[j * k + j];
    }
    true
}

/// Complete the grid columns `cols` (independent) to a basis of r columns by greedily adding the
/// column with the largest component orthogonal to the span so far; None if that fails.
fn complete_basis(rows: &[f64], n: usize, r: usize, cols: &[usize]) -> Option<Vec<usize>> {
    let mut basis: Vec<usize> = cols.to_vec();
    let mut q: Vec<Vec<f64>> = Vec::with_capacity(r);
    let add = |v: &[f64], q: &mut Vec<Vec<f64>>| -> bool {
        let mut v = v.to_vec();
        let n0 = norm(&v);
        for _ in 0..2 {
            for qi in q.iter() {
                let h = dot(qi, &v);
                for (a, b) in v.iter_mut().zip(qi) {
                    *a -= h * b;
                }
            }
        }
        let nv = norm(&v);
        if nv.is_nan() || nv <= 1e-10 * n0 {
            return false;
        }
        v.iter_mut().for_each(|a| *a /= nv);
        q.push(v);
        true
    };
    for &i in cols {
        if !add(&rows[i * r..(i + 1) * r], &mut q) {
            return None;
        }
    }
    while basis.len() < r {
        let mut best = None;
        let mut best_v = 0.0;
        for i in 0..n {
            if basis.contains(&i) {
                continue;
            }
            let row = &rows[i * r..(i + 1) * r];
            let mut res = dot(row, row);
            for qi in &q {
                let h = dot(qi, row);
                res -= h * h;
            }
            if res > best_v {
                best_v = res;
                best = Some(i);
            }
        }
        let i = best?;
        if !add(&rows[i * r..(i + 1) * r], &mut q) {
            return None;
        }
        basis.push(i);
    }
    Some(basis)
}

/// r rows of the row-major n × r matrix with (greedily) maximal volume: a well-conditioned
/// cold-start basis.
fn max_volume_rows(rows: &[f64], n: usize, r: usize) -> Vec<usize> {
    let mut res = rows.to_vec();
    let mut chosen = Vec::with_capacity(r);
    for _ in 0..r {
        let mut best = 0usize;
        let mut best_v = -1.0;
        for i in 0..n {
            if chosen.contains(&i) {
                continue;
            }
            let v = norm(&res[i * r..(i + 1) * r]);
            if v > best_v {
                best_v = v;
                best = i;
            }
        }
        chosen.push(best);
        let pivot: Vec<f64> = res[best * r..(best + 1) * r].to_vec();
        let pn = norm(&pivot);
        if pn == 0.0 {
            continue;
        }
        let unit: Vec<f64> = pivot.iter().map(|v| v / pn).collect();
        for i in 0..n {
            let row = &mut res[i * r..(i + 1) * r];
            let h = dot(row, &unit);
            for (a, u) in row.iter_mut().zip(&unit) {
                *a -= h * u;
            }
        }
    }
    chosen
}

/// Dantzig pricing: s_i = y·a_i for every column; returns the column with the most negative
/// reduced cost d_i = [i < kf] − s_i and that reduced cost.
/// Basic columns are excluded (their reduced cost is 0 in exact arithmetic).
fn price(
    table: &ColumnTable,
    n: usize,
    r: usize,
    y: &[f64],
    kf: usize,
    basis: &[usize],
    s: &mut [f64],
) -> (usize, f64) {
    #[cfg(target_arch = "x86_64")]
    {
        if std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma")
        {
            // SAFETY: the CPU supports the features enabled on `price_avx2`.
            return unsafe { price_avx2(table, n, r, y, kf, basis, s) };
        }
    }
    price_generic::<false>(table, n, r, y, kf, basis, s)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
unsafe fn price_avx2(
    table: &ColumnTable,
    n: usize,
    r: usize,
    y: &[f64],
    kf: usize,
    basis: &[usize],
    s: &mut [f64],
) -> (usize, f64) {
    price_generic::<true>(table, n, r, y, kf, basis, s)
}

#[inline(always)]
fn price_generic<const FMA: bool>(
    table: &ColumnTable,
    n: usize,
    r: usize,
    y: &[f64],
    kf: usize,
    basis: &[usize],
    s: &mut [f64],
) -> (usize, f64) {
    let (cols, ld) = table.rows();
    let s = &mut s[..n];
    let y0 = y[0];
    for (si, &c) in s.iter_mut().zip(&cols[..n]) {
        *si = y0 * c;
    }
    for k in 1..r {
        let yk = y[k];
        for (si, &c) in s.iter_mut().zip(&cols[k * ld..k * ld + n]) {
            *si = if FMA {
                yk.mul_add(c, *si)
            } else {
                yk * c + *si
            };
        }
    }
    for &bt in basis {
        if bt < n {
            s[bt] = if bt < kf { 1.0 } else { 0.0 };
        }
    }
    let (il, sl) = argmax(&s[..kf]);
    let (ir, sr) = argmax(&s[kf..]);
    let dl = 1.0 - sl;
    let dr = -sr;
    if dl <= dr {
        (il, dl)
    } else {
        (kf + ir, dr)
    }
}

/// Index and value of the maximum (first among equals; (0, −∞) when empty).
#[inline(always)]
fn argmax(s: &[f64]) -> (usize, f64) {
    const L: usize = 8;
    let mut bv = [f64::NEG_INFINITY; L];
    let mut bi = [0usize; L];
    let chunks = s.len() / L;
    for c in 0..chunks {
        let base = c * L;
        let ch = &s[base..base + L];
        for l in 0..L {
            if ch[l] > bv[l] {
                bv[l] = ch[l];
                bi[l] = base + l;
            }
        }
    }
    for (i, &v) in s.iter().enumerate().skip(chunks * L) {
        let l = i % L;
        if v > bv[l] {
            bv[l] = v;
            bi[l] = i;
        }
    }
    let mut best = (0usize, f64::NEG_INFINITY);
    for l in 0..L {
        if bv[l] > best.1 || (bv[l] == best.1 && bi[l] < best.0) {
            best = (bi[l], bv[l]);
        }
    }
    best
}

/// Bland's rule: the first column with a negative reduced cost (after computing s).
fn price_bland(
    table: &ColumnTable,
    n: usize,
    r: usize,
    y: &[f64],
    kf: usize,
    basis: &[usize],
    s: &mut [f64],
) -> (usize, f64) {
    let (iq, dq) = price(table, n, r, y, kf, basis, s);
    if dq >= -TOL_D {
        return (iq, dq);
    }
    for (i, &si) in s[..n].iter().enumerate() {
        let d = if i < kf { 1.0 - si } else { -si };
        if d < -TOL_D {
            return (i, d);
        }
    }
    (iq, dq)
}
