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
//!   is checked for consistency instead; an inconsistent one is `Infeasible` when the
//!   dependency, as a Farkas ray over every row, certifies it (`inconsistency_ray`).
//! * **Simplex.** An explicit (m+1)×(m+1) basis inverse, Dantzig pricing (partial: a coarse
//!   subgrid, the neighbours of z_f and of the support, the fine window around the best) with
//!   the blocked SIMD kernels of [`pricing`] (greatest improvement on the coarse
//!   subgrid when the column found has a reduced cost below −1, see [`pricing::greatest`]), a
//!   Harris-style ratio test, Bland's rule
//!   after repeated degenerate pivots, a refactorisation every 16 pivots. When partial pricing
//!   finds no entering column in phase 2, the certificate ([`super::certify`]) prices every
//!   grid point with refined duals in the original coordinates: that proves optimality (no
//!   reduced cost below −1e-10, the same as a full pass). Only when it does not is the run
//!   resumed with the full pricing pass (after a refactorisation) and the usual verification.
//! * **Phase 1** uses a single artificial column: from any start basis B with x = B⁻¹c, the
//!   artificial d = −Σ_{x_t<0} a_{B_t} replaces the most negative basic variable, which makes the
//!   basis feasible; phase 1 then minimises the artificial's weight and ends as soon as it is
//!   zero (to rounding). Moments are infeasible when that weight stays positive.
//! * **Warm start.** The optimal basis of the previous problem is the start basis of the next one:
//!   when the moments are unchanged (only z_f moves) it is primal feasible and phase 2 starts
//!   at once; otherwise phase 1 starts from a nearby basis.
//! * **Start from the moments alone** ([`recognise`]). Moments of one grid point, or of two
//!   under a power basis (Prony's method), are the boundary of the moment space and those
//!   points their only representation: with no atom below z_f they are the answer, otherwise
//!   they and their neighbours towards z_f start the run (five rows; with more, the crossover
//!   from the atoms). Interior moments under z, …, z⁴ start from the grid points around the
//!   canonical representation through z_f (Algorithm 3). Moments close to one grid point's
//!   column (a cluster, as under a flat receiver) go first to a short band around it, solved
//!   in coordinates local to the band and certified on the whole grid ([`band`]).
//! * **Start from a known distribution** ([`MomentSolver::solve_distribution`], the pipeline's
//!   case: the moments are those of a kernel's depth distribution). The moments are formed in
//!   the orthonormalised coordinates, c = Σ w_i a_i, and the distribution itself is a feasible
//!   point: a crossover turns it into a basic feasible solution of no greater cost (the first
//!   grid point at or above z_f and the last grid point, which the optimum nearly always holds,
//!   and the support columns of greatest volume as the basis, every other support point
//!   pushed to weight 0 or into the basis by one ratio test), so phase 1 is skipped. A
//!   distribution with no atom below z_f is the answer itself (G = 0), and a basic solution
//!   with no mass below z_f ends phase 2: the zero duals certify both.
//! * **Accuracy.** The final weights are refined against the LP as stated (residual of the
//!   original system in double-double arithmetic); weights that turn out infeasible trigger a
//!   rerun in accurate mode (see `finish_optimal`).
//! * **Band solves** ([`band`]). Where the whole grid cannot resolve a steep function
//!   (exp(40z) spans 10^17), the LP restricted to a band of the grid around the window is solved
//!   in the band's own coordinates and its basis certified on the whole grid; on a steep table,
//!   where that basis does not certify, it starts the whole-grid run (a basis of the whole LP
//!   whose weights solve it) in place of the crossover.
//! * **Robustness.** An iteration cap with a cold restart (Bland's rule throughout), then the
//!   scaled double-double simplex ([`escalate::scaled`]) and the exact simplex ([`escalate::exact`]);
//!   what none of them certifies is `Failed` with the reason. Never an endless loop.

#![allow(clippy::needless_range_loop)] // index-heavy dense linear algebra on r ≤ 9

mod escalate;
mod linalg;
mod ortho;
mod price;
pub(super) mod pricing;
mod recognise;
mod refine;
mod simplex;
mod starts;

use super::certify::{Certified, Certifier};
use super::{Error, GridTable, MomentSolver, Result, Solution, Status};
use escalate::band;
use escalate::scaled::ScaledSimplex;
use linalg::max_volume_rows;
use ortho::{orthonormalise, Ortho};
use pricing::ColumnTable;

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
/// Relative tolerance of the consistency check of a dependent function's moment.
const TOL_DEP: f64 = 1e-8;
/// Largest condition number (Frobenius) of a basis accepted at refactorisation.
const MAX_COND: f64 = 1e12;
/// Accurate pivots ([`Certifier::improve`]) tried on a basis that does not certify.
const IMPROVE_STEPS: usize = 4;
/// Accurate pivots from the scaled simplex's basis, the last chance before `failed`.
const FINAL_IMPROVE_STEPS: usize = 64;
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
    /// Problems escalated to the scaled simplex ([`escalate::scaled`]): the fast answer was not
    /// certified, or the fast runs did not converge, or phase 1 called them infeasible.
    pub escalations: u64,
    /// Problems returned as `Failed` (nothing certified either verdict).
    pub failed: u64,
    /// Problems handed to the exact simplex ([`escalate::exact`]) after the scaled simplex.
    pub exact: u64,
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
    /// Solves given a distribution with no atom below z_f: G = 0 with that distribution as
    /// the support, certified by the zero duals (no simplex).
    pub zero_mass: u64,
    /// Crossover pivots (start distribution → basic feasible solution).
    pub crossover_pivots: u64,
    /// Optima whose weights, refined against the LP as stated, were infeasible: solved again
    /// with every basic solution refined.
    pub accurate_retries: u64,
    /// Optima reached by partial pricing alone whose certificate failed: the simplex resumed
    /// from that basis with the full pricing pass.
    pub resumed: u64,
    /// Runs ended because the column that had just left the basis would re-enter (rounding
    /// in the duals of an ill-conditioned basis): the certificate decides.
    pub ping_pong: u64,
    /// Solves on a band of the grid around the window ([`band`]: steep functions resolved in
    /// the band's own coordinates): every distribution start on a steep table, elsewhere the
    /// answers the whole-grid run could not certify.
    pub band_solves: u64,
    /// Of which certified on the whole grid (as they stand or after accurate pivots): no
    /// escalation.
    pub band_certified: u64,
    /// Phase-1 runs ended as soon as the artificial's weight reached zero (to rounding),
    /// before pricing found no entering column.
    pub phase1_at_zero: u64,
    /// Solves given moments only that are those of a single grid point (its column equals
    /// the transformed moments).
    pub single_atom: u64,
    /// Solves given moments only that are those of two grid points under a power basis
    /// (recognised by Prony's method): started from that pair.
    pub two_atoms: u64,
    /// Solves given moments only started from a basis built from the moments
    /// ([`recognise`]: boundary atoms, or the canonical representation through z_f).
    pub moments_starts: u64,
    /// Solves given moments only that are close to one grid point's column (a cluster):
    /// solved first on a short band of the grid around that point ([`band`]).
    pub clusters: u64,
    /// Of which certified on the whole grid.
    pub cluster_certified: u64,
}

/// Index of the artificial column in a basis.
const ART: usize = usize::MAX;

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
    /// The orthonormalised coordinates of the table (columns a_i, R, kept functions).
    ortho: Ortho,
    /// Well-conditioned cold-start basis.
    b0: Vec<usize>,
    /// Rounding-error bound on the weights of the last solve.
    last_bound: f64,
    /// The crossover has just left a basic feasible solution with its (updated) inverse.
    crossed: bool,
    /// The warm start carried from one problem to the next.
    warm: starts::WarmStart,
    stats: FastStats,
    /// Checks every answer in the original coordinates.
    cert: Certifier,
    /// The escalation solver.
    scaled: ScaledSimplex,
    /// The exactly optimal basis of the last answer from the exact simplex, if the last
    /// answer came from it.
    last_exact: Option<Vec<usize>>,
    // Workspace (no allocation per solve).
    c: Vec<f64>,
    u: Vec<f64>,
    basis: Vec<usize>,
    /// B⁻¹ of `basis`, by factorisation and pivot updates.
    binv: linalg::BasisInverse,
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
    /// Phase 2 may end when partial pricing finds no entering column, leaving the full
    /// pricing pass to the certificate's reduced costs over every grid point (per solve).
    partial_optimum: bool,
    /// The last "no entering column" came from partial pricing alone (no full pass).
    full_pass_skipped: bool,
    x_backup: Vec<f64>,
    /// Duals and weights before the last verification refactorisation.
    yold: Vec<f64>,
    xold: Vec<f64>,
    /// The column tables and the partial-pricing state.
    pricing: price::Pricing,
    /// Least-squares workspace of the polish and the rescue.
    ls: refine::LeastSquares,
    /// 1 / max_i |M_j(z_i)|: row equilibration of the original system.
    oscale: Vec<f64>,
    lo_rhs: Vec<f64>,
    /// Crossover workspace.
    cross: starts::Crossover,
    /// The starts from moments alone ([`recognise`]).
    recognise: recognise::Recognise,
    /// Fast solvers on bands of the grid, for windows the whole-grid run cannot certify.
    bands: band::Bands,
}

impl FastSolver {
    /// Prepare the solver for `table` (orthonormalisation and cold-start basis; O(n m²)).
    pub fn new(table: GridTable) -> FastSolver {
        let (ortho, cols) = orthonormalise(&table);
        FastSolver::with_coordinates(table, ortho, cols)
    }

    /// The solver for `table` in the coordinates `ortho` (columns `cols`, column-major).
    fn with_coordinates(table: GridTable, ortho: Ortho, cols: Vec<f64>) -> FastSolver {
        let n = table.n();
        let m = table.m();
        let mm = m + 1;
        let r = ortho.r;
        let b0 = max_volume_rows(&ortho.rows, n, r);
        let fine = ColumnTable::new(r, n, |k, i| cols[k * n + i]);
        let recognise = recognise::Recognise::new(&table, &cols, r);
        let cert_rows: Vec<usize> = (0..mm).filter(|&j| ortho.kept[j].is_some()).collect();
        let oscale = ortho
            .fscale
            .iter()
            .map(|&f| if f > 0.0 { 1.0 / f } else { 1.0 })
            .collect();
        let mut solver = FastSolver {
            n,
            m,
            r,
            ortho,
            b0,
            last_bound: 0.0,
            crossed: false,
            warm: starts::WarmStart {
                basis: None,
                last_c: vec![f64::NAN; r],
                on: true,
            },
            stats: FastStats::default(),
            cert: Certifier::new(&table, cert_rows),
            scaled: ScaledSimplex::default(),
            last_exact: None,
            c: vec![0.0; r],
            u: vec![0.0; r],
            basis: vec![0; r],
            binv: linalg::BasisInverse::new(r),
            x: vec![0.0; r],
            y: vec![0.0; r],
            alpha: vec![0.0; r],
            art: vec![0.0; r],
            s: vec![0.0; n],
            c0: vec![0.0; r],
            b_orig: vec![0.0; m],
            accurate: false,
            partial_optimum: false,
            full_pass_skipped: false,
            x_backup: vec![0.0; r],
            yold: vec![0.0; r],
            xold: vec![0.0; r],
            pricing: price::Pricing {
                is_basic: vec![false; n],
                stride: 1,
                fine,
                coarse: ColumnTable::default(),
                coarse_idx: Vec::new(),
                coarse_pos: vec![u32::MAX; n],
            },
            recognise,
            ls: refine::LeastSquares {
                sup: vec![0; r],
                a: vec![0.0; r * r],
                q: vec![0.0; r * r],
                r: vec![0.0; r * r],
                w: vec![0.0; r],
            },
            oscale,
            lo_rhs: vec![0.0; mm],
            table,
            cross: starts::Crossover {
                v: vec![0.0; r],
                ..Default::default()
            },
            bands: band::Bands {
                on: true,
                first: false,
                ..Default::default()
            },
        };
        solver.bands.first = band::is_steep(&solver.table);
        solver.set_partial_pricing(true);
        solver
    }

    /// Enable or disable warm start from the previous optimal basis (on by default).
    pub fn set_warm_start(&mut self, on: bool) {
        self.warm.on = on;
        if !on {
            self.warm.basis = None;
        }
    }

    /// The exactly optimal basis (grid indices, one per row 0..=m) when the last answer came
    /// from the exact simplex ([`escalate::exact`]); None otherwise. For independent checks.
    pub fn last_exact_basis(&self) -> Option<&[usize]> {
        self.last_exact.as_deref()
    }

    /// The basis the next solve starts from (grid indices), if any.
    pub fn warm_basis(&self) -> Option<&[usize]> {
        self.warm.basis.as_deref()
    }

    /// Start the next solve from `basis` (rank() distinct grid indices), e.g. to test that any
    /// start basis gives the same answer. Invalid bases are rejected.
    pub fn set_warm_basis(&mut self, basis: &[usize]) -> Result<()> {
        if basis.len() != self.r {
            return Err(Error::WarmBasisSize {
                expected: self.r,
                got: basis.len(),
            });
        }
        for (k, &i) in basis.iter().enumerate() {
            if i >= self.n || basis[..k].contains(&i) {
                return Err(Error::WarmBasisIndex { index: i });
            }
        }
        self.warm.on = true;
        self.warm.basis = Some(basis.to_vec());
        self.warm.last_c.iter_mut().for_each(|v| *v = f64::NAN);
        Ok(())
    }

    /// What the solver carries from one problem to the next (the last optimal basis and its
    /// moments), to time a stretch of problems repeatedly from the same state.
    pub(crate) fn warm_state(&self) -> (Option<Vec<usize>>, Vec<f64>) {
        (self.warm.basis.clone(), self.warm.last_c.clone())
    }

    /// Restore a [`Self::warm_state`].
    pub(crate) fn restore_warm_state(&mut self, state: &(Option<Vec<usize>>, Vec<f64>)) {
        self.warm.basis.clone_from(&state.0);
        self.warm.last_c.copy_from_slice(&state.1);
    }

    /// Enable or disable partial pricing (coarse subgrid first; on by default for n ≥ 64).
    pub fn set_partial_pricing(&mut self, on: bool) {
        let n = self.n;
        self.pricing.stride = if on && n >= 64 {
            ((n as f64 / 2.0).sqrt() as usize).max(2)
        } else {
            1
        };
        self.pricing.coarse_idx = (0..n).step_by(self.pricing.stride).collect();
        if self.pricing.coarse_idx.last() != Some(&(n - 1)) {
            self.pricing.coarse_idx.push(n - 1);
        }
        self.pricing
            .coarse_pos
            .iter_mut()
            .for_each(|v| *v = u32::MAX);
        for (c, &i) in self.pricing.coarse_idx.iter().enumerate() {
            self.pricing.coarse_pos[i] = c as u32;
        }
        let (fine, idx) = (&self.pricing.fine, &self.pricing.coarse_idx);
        self.pricing.coarse = ColumnTable::new(self.r, idx.len(), |k, j| fine.entry(k, idx[j]));
        for i in 0..n {
            if self.pricing.is_basic[i] {
                self.set_basic(i, true);
            }
        }
    }

    /// Enable or disable band solves (on by default): an uncertified whole-grid optimum is
    /// solved again on a band of the grid around the window before escalation ([`band`]).
    pub fn set_band_solves(&mut self, on: bool) {
        self.bands.on = on;
    }

    /// Forget the warm-start basis.
    pub fn reset(&mut self) {
        self.bands.reset();
        self.warm.basis = None;
        self.warm.last_c.iter_mut().for_each(|v| *v = f64::NAN);
    }

    /// Numerical rank of [1, b_1, …, b_m] on the grid (m+1 unless functions are dependent).
    pub fn rank(&self) -> usize {
        self.r
    }

    /// Condition number (Frobenius) of the n × (m+1) matrix [1, b_1(z), …, b_m(z)] on the grid.
    /// Above ~1e8 the candidate is numerically rank-deficient for double precision.
    pub fn condition(&self) -> f64 {
        self.ortho.condition
    }

    /// A first-order bound on how far the weights (and G) of the last optimal solve can move
    /// when the moments are perturbed at the rounding level: ε · cond(M) · ‖B⁻¹‖_F · (1 + ‖c‖)
    /// for the final basis B. Where this exceeds ~1e-10, G is not determined to 1e-9 by the
    /// double-precision moments (clustered support on a fine grid), for any solver.
    pub fn last_error_bound(&self) -> f64 {
        self.last_bound
    }

    /// Counters over the solver's lifetime.
    pub fn stats(&self) -> FastStats {
        self.stats
    }

    /// The table the solver works on.
    pub fn table(&self) -> &GridTable {
        &self.table
    }
}

impl MomentSolver for FastSolver {
    fn solve(&mut self, moments: &[f64], zf: f64) -> Result<Solution> {
        self.solve_inner(moments, zf, None, false)
    }

    fn table(&self) -> &GridTable {
        &self.table
    }

    fn reset(&mut self) {
        FastSolver::reset(self)
    }

    /// Moments in the orthonormalised coordinates straight from the distribution,
    /// c = Σ w_i a_i / Σ w_i (no cancellation however badly scaled the functions are), and the
    /// distribution itself as the phase-1-free start (see [`FastSolver::crossover`]).
    fn solve_distribution(&mut self, dist: &[(u32, f64)], zf: f64) -> Result<Solution> {
        // Validates the distribution; the moments in the original coordinates serve the
        // reference fallback.
        let moments = super::distribution_moments(&self.table, dist)?;
        self.distribution_coordinates(dist);
        self.solve_inner(&moments, zf, Some(dist), true)
    }
}

impl FastSolver {
    /// c = Σ w_i a_i / Σ w_i: the moments of the distribution `dist` (grid index, weight) in the
    /// orthonormalised coordinates, summed term by term (no cancellation).
    fn distribution_coordinates(&mut self, dist: &[(u32, f64)]) {
        let r = self.r;
        let mut total = 0.0;
        self.c.iter_mut().for_each(|v| *v = 0.0);
        for &(i, w) in dist {
            let i = i as usize;
            total += w;
            for (ck, ak) in self.c.iter_mut().zip(&self.ortho.rows[i * r..(i + 1) * r]) {
                *ck += w * ak;
            }
        }
        self.c.iter_mut().for_each(|v| *v /= total);
    }
}

/// The fast solver's own verdict, kept for when nothing certifies.
enum Legacy {
    /// An optimal basis that did not certify, and why.
    Answer(Vec<usize>, String),
    Infeasible,
    /// The simplex did not converge from any start.
    NoConvergence,
}

impl Legacy {
    /// Why this verdict is not an answer (for the reason of a `Failed` solution).
    fn reason(&self) -> String {
        match self {
            Legacy::Answer(_, why) => format!("fast optimum not certified ({why})"),
            Legacy::Infeasible => {
                "phase 1 found no feasible point, but no Farkas ray certifies it".into()
            }
            Legacy::NoConvergence => "the simplex did not converge".into(),
        }
    }
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
        self.check_problem(moments, zf)?;
        self.stats.solves += 1;
        self.last_exact = None;
        self.accurate = false;
        self.b_orig.copy_from_slice(moments);
        let kf = self.table.grid().points().partition_point(|&z| z < zf);
        let transformed = c_given || self.ortho.transform(moments, &mut self.u, &mut self.c);
        // Moments of one grid point, or of two under a power basis, have those points as their
        // only representation: the distribution, as if given.
        let moments_only = hint.is_none() && transformed;
        // The grid point whose column is nearest the moments: a single atom's, or a cluster's
        // centre.
        let nearest = moments_only.then(|| self.nearest_column()).flatten();
        let atoms = if moments_only {
            self.boundary_atoms(moments, nearest)
        } else {
            None
        };
        let hint = hint.or(atoms.as_ref().map(|(a, k)| &a[..*k]));
        if let Some(dist) = hint.filter(|d| d.iter().all(|&(i, w)| i as usize >= kf || w <= 0.0)) {
            // No atom below z_f: the distribution itself has the least possible mass, 0.
            if let Ok(c) = self.cert.zero_mass(moments, kf, dist) {
                self.stats.zero_mass += 1;
                return Ok(certified(c));
            }
        }
        self.bands.tried = false;
        self.bands.failed = None;
        if let Some(dist) = hint.filter(|_| self.bands.first && c_given) {
            // A steep table: the band first (see [`band`]), certified on the whole grid.
            self.c0.copy_from_slice(&self.c);
            if let Some(c) = self.band_certified(moments, kf, zf, dist, true) {
                return Ok(certified(c));
            }
        }
        if let Some((center, _)) = nearest.filter(|&(_, gap)| gap <= band::CLUSTER_GAP) {
            if atoms.is_none() {
                self.c0.copy_from_slice(&self.c);
                if let Some(c) = self.cluster_certified(moments, kf, zf, center) {
                    return Ok(certified(c));
                }
            }
        }
        let mut verdict = if transformed {
            self.c0.copy_from_slice(&self.c);
            self.partial_optimum = true;
            self.full_pass_skipped = false;
            // From the moments alone: a start basis built from them, not the crossover.
            let given = moments_only && self.moments_start(moments, kf, hint);
            self.stats.moments_starts += given as u64;
            self.attempts(kf, hint.filter(|_| !given), given)
        } else {
            // A dependent function's moment contradicts the others: its dependency is the
            // Farkas ray, checked on every row (the usual certifier holds the kept rows only).
            if let Some(y) = self.ortho.inconsistency_ray(moments) {
                let mut all = Certifier::new(&self.table, (0..=self.m).collect());
                if all.infeasible(moments, &y).is_ok() {
                    self.stats.infeasible += 1;
                    return Ok(Solution::infeasible());
                }
            }
            Verdict::Infeasible
        };
        self.partial_optimum = false;
        if matches!(verdict, Verdict::Optimal) && self.full_pass_skipped {
            // Partial pricing ended phase 2: the certificate prices every grid point (in the
            // original coordinates, with refined duals) and so stands in for the full pass.
            // As strict as that pass: no reduced cost below −TOL_D (the reduced costs do not
            // depend on the coordinates).
            match self.cert.optimal(moments, kf, &self.basis) {
                Ok(c) if c.min_reduced >= -TOL_D => {
                    self.remember_optimal();
                    return Ok(certified(c));
                }
                _ => {}
            }
            self.stats.resumed += 1;
            verdict = self.resume(kf);
        }
        let legacy = match self.certify_fast(verdict, moments, kf, zf, hint) {
            Ok(sol) => return Ok(sol),
            Err(legacy) => legacy,
        };
        // The scaled simplex starts from the uncertified optimum, else from the fast
        // simplex's last basis when it holds grid columns only (a warm phase 1 if infeasible).
        let start = match &legacy {
            Legacy::Answer(b, _) => Some(b.clone()),
            _ if self.basis.iter().all(|&i| i < self.n) => Some(self.basis.clone()),
            _ => None,
        };
        let sol = self.escalate(moments, kf, start.as_deref(), hint);
        if sol.status != Status::Failed {
            return Ok(sol);
        }
        // Nothing certified: `Failed` with the reason (never an uncertified `optimal`).
        self.stats.failed += 1;
        let escalation = sol.reason.unwrap_or_default();
        Ok(Solution::failed(format!(
            "{}; {escalation}",
            legacy.reason()
        )))
    }

    /// A one-line error for malformed moments or z_f, before any work.
    fn check_problem(&self, moments: &[f64], zf: f64) -> Result<()> {
        if moments.len() != self.m {
            return Err(Error::MomentCount {
                expected: self.m,
                got: moments.len(),
            });
        }
        if let Some(j) = moments.iter().position(|v| !v.is_finite()) {
            return Err(Error::MomentNotFinite {
                index: j + 1,
                value: moments[j],
            });
        }
        if zf.is_nan() {
            return Err(Error::ZfNaN);
        }
        Ok(())
    }

    /// The fast solver's verdict certified (`Ok`): its optimal basis as it stands or after
    /// accurate pivots, else the support of the start distribution after accurate pivots.
    /// Otherwise the verdict to escalate (`Err`).
    fn certify_fast(
        &mut self,
        verdict: Verdict,
        moments: &[f64],
        kf: usize,
        zf: f64,
        hint: Option<&[(u32, f64)]>,
    ) -> Result<Solution, Legacy> {
        let legacy = match verdict {
            Verdict::Optimal => {
                let fast_basis = self.basis.clone();
                match self.cert.optimal(moments, kf, &fast_basis) {
                    Ok(c) => {
                        self.remember_optimal();
                        return Ok(certified(c));
                    }
                    Err(e) => Legacy::Answer(fast_basis, e),
                }
            }
            Verdict::Infeasible => Legacy::Infeasible,
            Verdict::Failed => Legacy::NoConvergence,
        };
        // The same LP on a band of the grid around the window (steep functions), certified on
        // the whole grid, with accurate pivots from it where columns outside the band enter.
        if let Some(c) = hint.and_then(|h| self.band_certified(moments, kf, zf, h, false)) {
            return Ok(certified(c));
        }
        if let Legacy::Answer(fast_basis, why) = &legacy {
            let mut basis = fast_basis.clone();
            let found =
                self.cert
                    .improve_checked(moments, kf, &mut basis, IMPROVE_STEPS, why.clone());
            if let Ok(c) = found {
                self.stats.improved += 1;
                self.remember_certified(&basis);
                return Ok(certified(c));
            }
        }
        // A start distribution with at most r atoms is itself a basic feasible solution: the
        // accurate pivots from it never leave the feasible set.
        if let Some(mut basis) = hint.and_then(|h| self.support_basis(h)) {
            if let Ok(c) = self.cert.improve(moments, kf, &mut basis, IMPROVE_STEPS) {
                self.stats.improved += 1;
                self.remember_certified(&basis);
                return Ok(certified(c));
            }
        }
        Err(legacy)
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

#[cfg(test)]
mod tests;
