//! The escalation solver: a textbook revised simplex on the LP scaled per problem, for the
//! answers the fast solver cannot certify (functions spanning many orders of magnitude such as
//! exp(80(z−1)), bases that are numerically singular in the orthonormalised coordinates).
//!
//! Every row j is scaled by an exact power of two s_j ≈ 1/σ_j (σ_j the row's own magnitude,
//! see [`crate::lp::certify`]) and then every column i by an exact power of two κ_i ≈ 1/max_j |s_j ā_ji|:
//! the LP min Σ (p_i κ_i) v_i s.t. Σ (s ∘ ā_i κ_i) v_i = s ∘ b̄, v ≥ 0 has entries in (−2, 2) and
//! w_i = κ_i v_i. A weight of 1e-24 on a column with entries 1e24 (a steep exponential near its
//! peak, under a moment of 1e-25) is an ordinary number here. Phase 1 uses one artificial per
//! row; the final basis (or the Farkas ray of phase 1) is judged by the certifier, not trusted.
//!
//! All linear algebra is in double-double arithmetic (an LU of the r × r basis, r ≤ 13, and
//! the eta file of the pivots since, [`DdEtaLu`]): the bases of neighbouring grid points under
//! a power basis (flat receivers, tight clusters) have condition 1e12–1e20, beyond f64 but far
//! inside the ~1e-32 of double-double. The basis is refactorised after [`MAX_ETAS`] pivots,
//! after a pivot α_l below [`ETA_PIVOT`] max_i |α_i|, and before unboundedness is accepted.
//! Reduced costs d_i = c_i − y·a_i are computed in f64 with their rounding bound
//! and recomputed in double-double where the bound leaves the sign of d_i + tol open: the duals
//! of such bases reach 1e8 and cancel.
//!
//! Pricing is partial first (grids of [`PARTIAL_MIN_N`] points or more): the least eligible
//! reduced cost over a subset enters — the coarse subgrid of every s-th column
//! (s = max(2, ⌊√(n/2)⌋)), the neighbours of the basic columns and of z_f, and the fine window
//! around the best of these — with eligibility decided column by column as in the full pass.
//! Only where the subset holds no eligible column does Dantzig's full pass run: it forms the f64
//! reduced costs and screens them in one pass with a bound common to all columns; the
//! per-column bound and the comparisons follow only where the least reduced cost can lie (the
//! same column as the scan over every column). A phase therefore ends only on a full pass
//! that finds no eligible column, and Bland's rule (after [`DEGENERATE_LIMIT`] degenerate
//! pivots in a row) always takes the scan over every column.

#![allow(clippy::needless_range_loop)] // index-heavy dense linear algebra on r ≤ 13

mod pricing;

use crate::lp::certify::row_kernels;
use crate::lp::certify::Certifier;
use crate::lp::dense::{inv_pow2, Dd, DdEtaLu};
use crate::lp::ratio;

const TOL_D: f64 = 1e-11;
const TOL_PIV: f64 = 1e-10;
const HARRIS: f64 = 1e-12;
const TOL_ART: f64 = 1e-10;
const DEGENERATE_LIMIT: usize = 50;
/// Pivots kept in the eta file before the basis is factorised afresh.
const MAX_ETAS: usize = 8;
/// A pivot enters the eta file only when |α_l| ≥ ETA_PIVOT · max_i |α_i| (a smaller one
/// amplifies the error of α by up to max_i |α_i| / |α_l| in every later solve; the basis is
/// factorised afresh instead).
const ETA_PIVOT: f64 = 1e-8;
/// Grids from this size on are priced partially first ([`ScaledSimplex::price_partial`]).
const PARTIAL_MIN_N: usize = 64;
/// Columns on either side of a basic column and of z_f that partial pricing examines.
const NEIGHBOURS: usize = 3;

/// What the scaled simplex found (to be certified by the caller).
#[derive(Clone, Debug, PartialEq)]
pub(in crate::lp::fast) enum Found {
    /// An optimal basis (grid indices, one per independent row).
    Optimal(Vec<usize>),
    /// Phase 1 ended with positive artificials: a Farkas ray (unscaled, per independent row).
    Infeasible(Vec<f64>),
    /// Numerical trouble or the iteration cap.
    Failed(&'static str),
}

/// A start basis as loaded by [`ScaledSimplex::try_start`].
enum Start {
    Singular,
    Feasible,
    Infeasible,
}

/// Workspace of the scaled simplex (reused between problems of one table).
#[derive(Clone, Debug, Default)]
pub(in crate::lp::fast) struct ScaledSimplex {
    n: usize,
    r: usize,
    /// Scaled entries row by row: arow[k·n + i] (the pricing kernel's layout).
    arow: Vec<f64>,
    /// Column scales (exact powers of two).
    kappa: Vec<f64>,
    /// Eligibility tolerance of each column, TOL_D · min(1, κ_i).
    tol: Vec<f64>,
    /// Reduced costs of every column and their magnitudes (pricing workspace).
    d: Vec<f64>,
    e: Vec<f64>,
    /// max_i |a_ki| per row k.
    amax: Vec<f64>,
    /// Blocks flagged by the pricing's screening pass.
    flagged: Vec<(usize, f64)>,
    /// Coarse stride of partial pricing (1: every pivot priced by the full pass).
    stride: usize,
    /// The coarse subgrid of partial pricing (every `stride`-th column and the last): its
    /// grid indices, its scaled entries row by row (acoarse[k·nc + j] = a_k,coarse[j]), costs,
    /// and the reduced costs and magnitudes of a pass over it.
    coarse: Vec<usize>,
    acoarse: Vec<f64>,
    ccoarse: Vec<f64>,
    dcoarse: Vec<f64>,
    ecoarse: Vec<f64>,
    /// Column ranges [lo, hi) of partial pricing's neighbourhoods (workspace).
    ranges: Vec<(usize, usize)>,
    /// The grid columns' costs in the current phase (κ_i below kf in phase 2, else 0) and
    /// their maximum.
    cost: Vec<f64>,
    cmax: f64,
    /// The row kernels may use AVX-512.
    avx512: bool,
    rhs: Vec<f64>,
    /// The composite artificial column n + r of a warm phase 1 ([`Self::composite_phase1`]).
    comp: Vec<f64>,
    /// Basis: grid indices, n + k for the artificial of row k, n + r for the composite one.
    basis: Vec<usize>,
    is_basic: Vec<bool>,
    sign: Vec<f64>,
    /// The basic solution x = B⁻¹ b̂ in double-double and rounded.
    xdd: Vec<Dd>,
    x: Vec<f64>,
    /// Duals in double-double.
    y: Vec<Dd>,
    /// Their high parts (the f64 pricing pass).
    yhi: Vec<f64>,
    /// α = B⁻¹ a_q of the entering column in double-double and rounded.
    alpha_dd: Vec<Dd>,
    alpha: Vec<f64>,
    col: Vec<f64>,
    /// Row-major basis matrix.
    bm: Vec<f64>,
    lu: DdEtaLu,
    /// Pivots over the solver's lifetime.
    pub pivots: u64,
    /// Check every full pass against [`Self::price_scan`] and every column partial pricing
    /// picks against its double-double reduced cost, counting (full passes, partial picks).
    #[cfg(test)]
    check_pricing: Option<(usize, usize)>,
    /// Price every pivot by the full pass.
    #[cfg(test)]
    full_pricing: bool,
    /// Eta file length before refactorisation instead of [`MAX_ETAS`].
    #[cfg(test)]
    max_etas: Option<usize>,
    /// Compare the updated x and y with those of a fresh factorisation at every pivot: the
    /// number of comparisons and the largest relative difference.
    #[cfg(test)]
    check_updates: Option<(usize, f64)>,
}

impl ScaledSimplex {
    /// Solve for the moments last given to `cert` ([`Certifier::set_moments`]) with `kf` grid
    /// points below z_f. A nonsingular `start` is phase 2's start when it is primal feasible,
    /// else phase 1's ([`Self::composite_phase1`]); otherwise phase 1 starts from one
    /// artificial per row.
    pub(in crate::lp::fast) fn solve(
        &mut self,
        cert: &Certifier,
        kf: usize,
        start: Option<&[usize]>,
    ) -> Found {
        self.setup(cert);
        let warm = match start.map(|s| self.try_start(s)) {
            Some(Start::Feasible) => true,
            Some(Start::Infeasible) => self.composite_phase1(),
            _ => false,
        };
        if !warm {
            self.artificial_start();
            if let Err(e) = self.iterate(kf, true) {
                return Found::Failed(e);
            }
            let infeas: f64 = (0..self.r)
                .filter(|&t| self.basis[t] >= self.n)
                .map(|t| self.x[t].max(0.0))
                .sum();
            if infeas > TOL_ART {
                return Found::Infeasible(self.farkas(cert));
            }
            if let Err(e) = self.drive_out_artificials() {
                return Found::Failed(e);
            }
        }
        match self.iterate(kf, false) {
            Ok(()) => Found::Optimal(self.grid_basis()),
            Err(e) => Found::Failed(e),
        }
    }

    /// The final basis with any remaining (zero-level) artificial replaced by an unused grid
    /// column of weight 0 (the certifier's accurate pivots take it from there).
    fn grid_basis(&self) -> Vec<usize> {
        let mut out = self.basis.clone();
        let mut next = 0;
        for t in 0..self.r {
            if out[t] >= self.n {
                while self.is_basic[next] || out.contains(&next) {
                    next += 1;
                }
                out[t] = next;
            }
        }
        out
    }

    /// Scaled rows, column scales and right-hand side for the current moments: row by row
    /// (vectorised passes over the grid), κ_i from the exponent of max_k |s_k ā_ki| ≥ 1 (the
    /// constant row is 1 after scaling).
    fn setup(&mut self, cert: &Certifier) {
        let rows = cert.rows();
        let (r, n) = (rows.len(), cert.n());
        self.n = n;
        self.r = r;
        self.arow.resize(n * r, 0.0);
        self.kappa.resize(n, 1.0);
        self.d.resize(n, 0.0);
        self.tol.resize(n, 0.0);
        self.e.resize(n, 0.0);
        self.avx512 = row_kernels::has_avx512();
        self.stride = if n >= PARTIAL_MIN_N {
            ((n as f64 / 2.0).sqrt() as usize).max(2)
        } else {
            1
        };
        #[cfg(test)]
        if self.full_pricing {
            self.stride = 1;
        }
        let s = cert.row_scales();
        // e holds max_k |s_k ā_ki| while the rows are filled.
        self.e.fill(0.0);
        for (k, &j) in rows.iter().enumerate() {
            let row = &mut self.arow[k * n..(k + 1) * n];
            match cert.function_row(j) {
                Some(f) => row.iter_mut().zip(f).for_each(|(a, &v)| *a = s[j] * v),
                None => row.fill(s[j]),
            }
            self.e
                .iter_mut()
                .zip(row.iter())
                .for_each(|(m, a)| *m = m.max(a.abs()));
        }
        for (kap, &big) in self.kappa.iter_mut().zip(&self.e) {
            *kap = inv_pow2(big);
        }
        for k in 0..r {
            let row = &mut self.arow[k * n..(k + 1) * n];
            row.iter_mut()
                .zip(&self.kappa)
                .for_each(|(a, &kap)| *a *= kap);
        }
        self.coarse.clear();
        if self.stride > 1 {
            self.coarse.extend((0..n).step_by(self.stride));
            if self.coarse.last() != Some(&(n - 1)) {
                self.coarse.push(n - 1);
            }
        }
        let nc = self.coarse.len();
        self.acoarse.clear();
        for k in 0..r {
            let row = &self.arow[k * n..(k + 1) * n];
            self.acoarse.extend(self.coarse.iter().map(|&i| row[i]));
        }
        self.dcoarse.resize(nc, 0.0);
        self.ecoarse.resize(nc, 0.0);
        self.amax.clear();
        for k in 0..r {
            let row = &self.arow[k * n..(k + 1) * n];
            self.amax
                .push(row.iter().fold(0.0f64, |m, a| m.max(a.abs())));
        }
        for (t, &kap) in self.tol.iter_mut().zip(&self.kappa) {
            *t = TOL_D * kap.min(1.0);
        }
        self.rhs.clear();
        self.rhs.extend(rows.iter().map(|&j| s[j] * cert.bbar(j)));
        self.basis.resize(r, 0);
        self.is_basic.clear();
        self.is_basic.resize(n + r + 1, false);
        self.sign.clear();
        self.sign
            .extend(self.rhs.iter().map(|&v| if v < 0.0 { -1.0 } else { 1.0 }));
        self.bm.resize(r * r, 0.0);
        self.y.resize(r, Dd::default());
        self.xdd.resize(r, Dd::default());
        self.alpha_dd.resize(r, Dd::default());
        for v in [&mut self.x, &mut self.alpha, &mut self.col] {
            v.resize(r, 0.0);
        }
    }

    /// Scaled entry of row k at grid point i.
    #[inline]
    fn a(&self, k: usize, i: usize) -> f64 {
        self.arow[k * self.n + i]
    }

    /// Column q (grid index, artificial n + k of row k, or the composite artificial n + r)
    /// into self.col.
    fn load(&mut self, q: usize) {
        let r = self.r;
        if q == self.n + r {
            self.col.copy_from_slice(&self.comp);
        } else if q >= self.n {
            self.col.iter_mut().for_each(|v| *v = 0.0);
            self.col[q - self.n] = self.sign[q - self.n];
        } else {
            for k in 0..r {
                self.col[k] = self.a(k, q);
            }
        }
    }

    fn cost(&self, q: usize, kf: usize, phase1: bool) -> f64 {
        match (phase1, q >= self.n) {
            (true, art) => art as u8 as f64,
            (false, true) => 0.0,
            (false, false) => (q < kf) as u8 as f64 * self.kappa[q],
        }
    }

    /// LU of the basis from scratch (an empty eta file) and x = B⁻¹ b̂; false if singular.
    fn factor(&mut self) -> bool {
        let r = self.r;
        for t in 0..r {
            self.load(self.basis[t]);
            for k in 0..r {
                self.bm[k * r + t] = self.col[k];
            }
        }
        if !self.lu.factor(&self.bm, r) {
            return false;
        }
        for (x, &b) in self.xdd.iter_mut().zip(&self.rhs) {
            *x = Dd::from(b);
        }
        self.lu.ftran(&mut self.xdd);
        self.round_x()
    }

    /// x rounded from its double-double value; false if not finite.
    fn round_x(&mut self) -> bool {
        for (x, v) in self.x.iter_mut().zip(&self.xdd) {
            *x = v.0 + v.1;
        }
        self.x.iter().all(|v| v.is_finite())
    }

    /// After the entering column replaced position l (α in self.alpha_dd): the pivot's eta
    /// F = I + (α − e_l) e_lᵀ joins the eta file and x ← F⁻¹x, the new basis' solution
    /// (x_l / α_l at l, x_i − α_i x_l / α_l elsewhere). False when the basis is to be
    /// factorised afresh instead: the eta file is full, or |α_l| < ETA_PIVOT max_i |α_i|.
    fn update(&mut self, l: usize) -> bool {
        #[cfg(test)]
        let max_etas = self.max_etas.unwrap_or(MAX_ETAS);
        #[cfg(not(test))]
        let max_etas = MAX_ETAS;
        let amax = self.alpha.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        // False for a NaN α as well.
        let large = self.alpha[l].abs() >= ETA_PIVOT * amax;
        if self.lu.etas() >= max_etas || !large {
            return false;
        }
        self.lu.push(&self.alpha_dd, l);
        self.lu.ftran_last(&mut self.xdd);
        self.round_x()
    }

    fn set_basis(&mut self, basis: &[usize]) {
        for &b in &self.basis {
            self.is_basic[b] = false;
        }
        self.basis.copy_from_slice(basis);
        for &b in basis {
            self.is_basic[b] = true;
        }
    }

    /// Load a given basis of grid columns and its basic solution x = B⁻¹ b̂.
    fn try_start(&mut self, start: &[usize]) -> Start {
        if start.len() != self.r || start.iter().any(|&i| i >= self.n) {
            return Start::Singular;
        }
        self.is_basic.iter_mut().for_each(|b| *b = false);
        self.basis.copy_from_slice(start);
        self.set_basis(start);
        if !self.factor() {
            Start::Singular
        } else if self.x.iter().all(|&v| v >= -HARRIS) {
            Start::Feasible
        } else {
            Start::Infeasible
        }
    }

    /// Phase 1 from a nonsingular start basis B with some x_t = (B⁻¹ b̂)_t < 0 (loaded by
    /// [`Self::try_start`]), with one artificial column instead of one per row: the negative
    /// part a = Σ_{x_t<0} x_t B_t of the basic solution. Then b̂ = Σ_{x_t>0} x_t B_t + 1·a, so
    /// the basis with a in place of the most negative x_l is nonsingular (B⁻¹a = x⁻, whose
    /// entry l is x_l ≠ 0, and |x⁻_t / x_l| ≤ 1) and primal feasible: weights x_t ≥ 0 where
    /// x_t > 0, zero on the other negative columns, 1 on a. Phase 1 minimises the weight of a.
    /// True when it reaches a primal feasible basis without artificials at a positive level;
    /// false (numerical trouble, or a remaining weight on a) leaves the cold start to decide,
    /// so that `Infeasible` always comes from the all-artificial phase 1 and its Farkas ray.
    fn composite_phase1(&mut self) -> bool {
        let (n, r) = (self.n, self.r);
        let Some(l) = (0..r).min_by(|&s, &t| self.x[s].total_cmp(&self.x[t])) else {
            return false;
        };
        self.comp.clear();
        self.comp.resize(r, 0.0);
        for t in 0..r {
            let w = self.x[t];
            if w < 0.0 {
                for k in 0..r {
                    self.comp[k] += w * self.a(k, self.basis[t]);
                }
            }
        }
        self.is_basic[self.basis[l]] = false;
        self.basis[l] = n + r;
        self.is_basic[n + r] = true;
        if self.iterate(0, true).is_err() {
            return false;
        }
        let size: f64 = self.comp.iter().map(|v| v.abs()).sum();
        let left: f64 = (0..r)
            .filter(|&t| self.basis[t] >= n)
            .map(|t| self.x[t].max(0.0))
            .sum::<f64>()
            * size;
        left <= TOL_ART && self.drive_out_artificials().is_ok()
    }

    fn artificial_start(&mut self) {
        self.is_basic.iter_mut().for_each(|b| *b = false);
        let arts: Vec<usize> = (0..self.r).map(|k| self.n + k).collect();
        self.set_basis(&arts);
        let ok = self.factor();
        debug_assert!(ok);
    }

    /// Simplex iterations to optimality of the phase's costs: the basis is factorised at the
    /// start and then updated by [`Self::update`], or factorised afresh where that declines.
    /// Optimality is read from the updated duals (the caller's certificate judges the final
    /// basis from scratch); an unbounded ray only from a fresh factorisation (with a
    /// non-empty eta file the basis is factorised and priced again).
    fn iterate(&mut self, kf: usize, phase1: bool) -> Result<(), &'static str> {
        let k = if phase1 { 0 } else { kf.min(self.n) };
        self.cost.clear();
        self.cost.extend_from_slice(&self.kappa[..k]);
        self.cost.resize(self.n, 0.0);
        self.cmax = self.cost.iter().fold(0.0, |m, &c| c.max(m));
        self.ccoarse.clear();
        self.ccoarse
            .extend(self.coarse.iter().map(|&i| self.cost[i]));
        let cap = 50 * self.n + 1000;
        let (mut degenerate, mut bland) = (0, false);
        // The factors and x are those of the current basis.
        let mut current = false;
        for _ in 0..cap {
            if !current && !self.factor() {
                return Err("singular basis in the scaled simplex");
            }
            self.duals(kf, phase1);
            #[cfg(test)]
            self.check_update(kf, phase1);
            let Some(q) = self.price(kf, phase1, bland) else {
                return Ok(());
            };
            self.entering(q);
            let Some(l) = self.ratio(bland, phase1) else {
                if self.lu.etas() > 0 {
                    current = false;
                    continue;
                }
                return Err("unbounded ray in the scaled simplex");
            };
            let theta = (self.x[l] / self.alpha[l]).max(0.0);
            degenerate = if theta == 0.0 { degenerate + 1 } else { 0 };
            bland |= degenerate > DEGENERATE_LIMIT;
            self.replace(l, q);
            current = self.update(l);
        }
        Err("iteration cap of the scaled simplex")
    }

    /// α = B⁻¹ a_q for column q.
    fn entering(&mut self, q: usize) {
        self.load(q);
        for (a, &v) in self.alpha_dd.iter_mut().zip(&self.col) {
            *a = Dd::from(v);
        }
        self.lu.ftran(&mut self.alpha_dd);
        for (a, v) in self.alpha.iter_mut().zip(&self.alpha_dd) {
            *a = v.0 + v.1;
        }
    }

    /// Duals y = B⁻ᵀ c_B in double-double.
    fn duals(&mut self, kf: usize, phase1: bool) {
        for t in 0..self.r {
            self.y[t] = Dd::from(self.cost(self.basis[t], kf, phase1));
        }
        self.lu.btran(&mut self.y);
    }

    /// With an eta file: x and y against those of a fresh factorisation of the basis, the
    /// largest difference relative to max_t |x_t| (resp. max_t |y_t|) kept in check_updates.
    #[cfg(test)]
    fn check_update(&mut self, kf: usize, phase1: bool) {
        let Some((checks, worst)) = self.check_updates else {
            return;
        };
        if self.lu.etas() == 0 {
            return;
        }
        let r = self.r;
        let mut fresh = DdEtaLu::default();
        assert!(fresh.factor(&self.bm_of_basis(), r));
        let mut x: Vec<Dd> = self.rhs.iter().map(|&b| Dd::from(b)).collect();
        fresh.ftran(&mut x);
        let mut y: Vec<Dd> = (0..r)
            .map(|t| Dd::from(self.cost(self.basis[t], kf, phase1)))
            .collect();
        fresh.btran(&mut y);
        let rel = |upd: &[Dd], ref_: &[Dd]| {
            let scale = ref_.iter().fold(0.0f64, |m, v| m.max(v.0.abs()));
            let diff = upd
                .iter()
                .zip(ref_)
                .fold(0.0f64, |m, (u, v)| m.max(u.add(v.neg()).0.abs()));
            if scale == 0.0 {
                diff
            } else {
                diff / scale
            }
        };
        let worst = worst.max(rel(&self.xdd, &x)).max(rel(&self.y, &y));
        self.check_updates = Some((checks + 1, worst));
    }

    /// The basis matrix, row-major.
    #[cfg(test)]
    fn bm_of_basis(&mut self) -> Vec<f64> {
        let r = self.r;
        let mut bm = vec![0.0; r * r];
        for t in 0..r {
            self.load(self.basis[t]);
            for k in 0..r {
                bm[k * r + t] = self.col[k];
            }
        }
        bm
    }

    /// d_q = c_q − y·a_q in double-double (where the f64 value's rounding bound leaves the
    /// comparison with −tol open).
    fn reduced_dd(&self, q: usize, c: f64) -> f64 {
        let r = self.r;
        let mut acc = Dd::from(c);
        for k in 0..r {
            acc = acc.add(self.y[k].mul(Dd::from(self.a(k, q))).neg());
        }
        acc.0 + acc.1
    }

    /// Leaving position: Harris' two passes ([`ratio::harris`]), the largest pivot among the
    /// near-minimal ratios (Bland: the smallest basis index).
    fn ratio(&self, bland: bool, phase1: bool) -> Option<usize> {
        let r = self.r;
        let amax = self.alpha.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        let tol = TOL_PIV * amax.max(1.0);
        // In phase 2 a zero-level artificial left in the basis must not become positive: it
        // blocks.
        if !phase1 {
            if let Some(t) = (0..r).find(|&t| self.basis[t] >= self.n && self.alpha[t].abs() > tol)
            {
                return Some(t);
            }
        }
        let keys = bland.then_some(&self.basis[..]);
        ratio::harris(&self.x, &self.alpha, tol, HARRIS, keys)
    }

    /// Column q replaces the basic column at position l (the next factorisation recomputes x).
    fn replace(&mut self, l: usize, q: usize) {
        self.is_basic[self.basis[l]] = false;
        self.basis[l] = q;
        self.is_basic[q] = true;
        self.pivots += 1;
    }

    /// Pivot the zero-level artificials of a feasible phase-1 optimum out of the basis.
    fn drive_out_artificials(&mut self) -> Result<(), &'static str> {
        let r = self.r;
        for l in 0..r {
            if self.basis[l] < self.n {
                continue;
            }
            if !self.factor() {
                return Err("singular basis after phase 1");
            }
            // Row l of B⁻¹.
            let mut e = vec![Dd::default(); r];
            e[l] = Dd::from(1.0);
            self.lu.btran(&mut e);
            let row: Vec<f64> = e.iter().map(|v| v.0 + v.1).collect();
            let mut best = (None, 1e-9);
            for i in 0..self.n {
                if self.is_basic[i] {
                    continue;
                }
                let v: f64 = (0..r).map(|k| row[k] * self.a(k, i)).sum();
                if v.abs() > best.1 {
                    best = (Some(i), v.abs());
                }
            }
            // None: a redundant row (at this precision): the artificial stays, blocking at 0.
            if let Some(q) = best.0 {
                self.replace(l, q);
            }
        }
        if !self.factor() {
            return Err("singular basis after phase 1");
        }
        self.x.iter_mut().for_each(|v| *v = v.max(0.0));
        Ok(())
    }

    /// Farkas ray from the phase-1 duals: −y in the original (unscaled) rows.
    fn farkas(&self, cert: &Certifier) -> Vec<f64> {
        let s = cert.row_scales();
        cert.rows()
            .iter()
            .enumerate()
            .map(|(k, &j)| -(self.y[k].0 + self.y[k].1) * s[j])
            .collect()
    }
}

#[cfg(test)]
mod tests;
