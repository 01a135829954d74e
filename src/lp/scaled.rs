//! The escalation solver: a textbook revised simplex on the LP scaled per problem, for the
//! answers the fast solver cannot certify (functions spanning many orders of magnitude such as
//! exp(80(z−1)), bases that are numerically singular in the orthonormalised coordinates).
//!
//! Every row j is scaled by an exact power of two s_j ≈ 1/σ_j (σ_j the row's own magnitude,
//! see [`super::certify`]) and then every column i by an exact power of two κ_i ≈ 1/max_j |s_j ā_ji|:
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

use super::certify::Certifier;
use super::dense::{inv_pow2, Dd, DdEtaLu};
use super::ratio;
use super::row_kernels;

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
pub enum Found {
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
pub struct ScaledSimplex {
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
    pub fn solve(&mut self, cert: &Certifier, kf: usize, start: Option<&[usize]>) -> Found {
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

    /// Entering column: an eligible column of [`Self::price_partial`] where it finds one,
    /// else the full pass of [`Self::price_full`] (Bland's rule always takes the full pass).
    /// None only from the full pass: no non-basic column is eligible, the phase's optimum.
    fn price(&mut self, kf: usize, phase1: bool, bland: bool) -> Option<usize> {
        self.yhi.clear();
        self.yhi.extend(self.y.iter().map(|y| y.0));
        if !bland {
            if let Some(q) = self.price_partial(kf, phase1) {
                #[cfg(test)]
                self.check_partial(q, kf, phase1);
                return Some(q);
            }
        }
        let q = self.price_full(kf, phase1, bland);
        #[cfg(test)]
        self.check_full(q, kf, phase1, bland);
        q
    }

    /// Partial pricing: an eligible column of a subset, the least v_i (see
    /// [`Self::price_full`]) among the columns that [`Self::consider`] examines there like
    /// the full pass (those whose f64 d_i leaves room for eligibility, d_i + tol_i ≤ γ e_i, and
    /// for a value below the best so far, d_i − γ e_i < best). The subset: the coarse subgrid
    /// (every `stride`-th column and the last), the [`NEIGHBOURS`] columns on either side of
    /// every basic grid column and, in phase 2, of the cost step at z_f (whole blocks), then
    /// the fine window between the coarse neighbours of the best of these. The reduced cost
    /// is smooth in z on either side of z_f, and a flat window's support is a narrow cluster,
    /// so the subset usually holds a good entering column at a fraction of the full pass.
    /// None when it holds no eligible column (or partial pricing is off, stride 1).
    fn price_partial(&mut self, kf: usize, phase1: bool) -> Option<usize> {
        let (n, st) = (self.n, self.stride);
        if st <= 1 {
            return None;
        }
        let factor = self.rounding_factor();
        let mut best = (None, 0.0);
        self.reduced_coarse();
        for j in 0..self.coarse.len() {
            let (i, d, e) = (self.coarse[j], self.dcoarse[j], self.ecoarse[j]);
            if d + self.tol[i] <= factor * e && d - factor * e < best.1 {
                (self.d[i], self.e[i]) = (d, e);
                self.consider(i, kf, phase1, factor, &mut best);
            }
        }
        let mut ranges = std::mem::take(&mut self.ranges);
        ranges.clear();
        let block = |lo: usize, hi: usize| {
            let b = row_kernels::BLOCK;
            (lo / b * b, (hi.div_ceil(b) * b).min(n))
        };
        ranges.extend(
            self.basis
                .iter()
                .filter(|&&b| b < n)
                .map(|&b| block(b.saturating_sub(NEIGHBOURS), b + NEIGHBOURS + 1)),
        );
        let k = if phase1 { 0 } else { kf.min(n) };
        if 0 < k && k < n {
            ranges.push(block(k - NEIGHBOURS.min(k), k + NEIGHBOURS));
        }
        // Overlapping ranges (neighbouring support points) merged: each column once.
        ranges.sort_unstable();
        let mut merged: Option<(usize, usize)> = None;
        for &(lo, hi) in ranges.iter().chain(std::iter::once(&(n, n))) {
            match merged {
                Some((mlo, mhi)) if lo <= mhi => merged = Some((mlo, mhi.max(hi))),
                _ => {
                    if let Some((mlo, mhi)) = merged {
                        self.consider_range(mlo, mhi, kf, phase1, factor, &mut best);
                    }
                    merged = Some((lo, hi));
                }
            }
        }
        self.ranges = ranges;
        let c = best.0?;
        let (lo, hi) = block(c.saturating_sub(st - 1), c + st);
        self.consider_range(lo, hi, kf, phase1, factor, &mut best);
        best.0
    }

    /// Reduced costs of the columns lo..hi, those that may be eligible and beat `best` within
    /// the rounding bound examined by [`Self::consider`].
    fn consider_range(
        &mut self,
        lo: usize,
        hi: usize,
        kf: usize,
        phase1: bool,
        factor: f64,
        best: &mut (Option<usize>, f64),
    ) {
        self.reduced_range(lo, hi);
        for i in lo..hi {
            let (d, e) = (self.d[i], self.e[i]);
            if d + self.tol[i] <= factor * e && d - factor * e < best.1 {
                self.consider(i, kf, phase1, factor, best);
            }
        }
    }

    /// d_i = c_i − y·a_i and e_i = c_i + Σ_k |y_k a_ki| in f64 from the duals' high parts for the
    /// columns lo..hi, with the operations of [`row_kernels::sub_rows_abs`] in the same order
    /// (the same bits as the full pass).
    fn reduced_range(&mut self, lo: usize, hi: usize) {
        const B: usize = row_kernels::BLOCK;
        let n = self.n;
        let mut lo = lo;
        while lo + B <= hi {
            let mut db: [f64; B] = self.cost[lo..lo + B].try_into().unwrap();
            let mut eb = db;
            for (k, &y) in self.yhi.iter().enumerate() {
                let f: &[f64; B] = self.arow[k * n + lo..k * n + lo + B].try_into().unwrap();
                for t in 0..B {
                    let v = y * f[t];
                    db[t] -= v;
                    eb[t] += v.abs();
                }
            }
            self.d[lo..lo + B].copy_from_slice(&db);
            self.e[lo..lo + B].copy_from_slice(&eb);
            lo += B;
        }
        for i in lo..hi {
            let (mut d, mut e) = (self.cost[i], self.cost[i]);
            for (k, &y) in self.yhi.iter().enumerate() {
                let v = y * self.arow[k * n + i];
                d -= v;
                e += v.abs();
            }
            (self.d[i], self.e[i]) = (d, e);
        }
    }

    /// [`Self::reduced_range`] on the coarse subgrid, into dcoarse and ecoarse (the same bits).
    fn reduced_coarse(&mut self) {
        let nc = self.coarse.len();
        self.dcoarse.copy_from_slice(&self.ccoarse);
        self.ecoarse.copy_from_slice(&self.ccoarse);
        for (k, &y) in self.yhi.iter().enumerate() {
            let row = &self.acoarse[k * nc..(k + 1) * nc];
            for ((d, e), &a) in self.dcoarse.iter_mut().zip(&mut self.ecoarse).zip(row) {
                let v = y * a;
                *d -= v;
                *e += v.abs();
            }
        }
    }

    /// A column of partial pricing is non-basic, its double-double reduced cost is below
    /// −tol_q, and its f64 d_q and e_q are those of the full pass bit for bit.
    #[cfg(test)]
    fn check_partial(&mut self, q: usize, kf: usize, phase1: bool) {
        let Some((_, partial)) = self.check_pricing.as_mut() else {
            return;
        };
        *partial += 1;
        assert!(q < self.n && !self.is_basic[q], "column {q}");
        let d = self.reduced_dd(q, self.cost(q, kf, phase1));
        assert!(d < -self.tol[q], "column {q}: d = {d:e}");
        let (dq, eq) = (self.d[q], self.e[q]);
        self.reduced_f64(kf, phase1);
        assert_eq!(
            (dq.to_bits(), eq.to_bits()),
            (self.d[q].to_bits(), self.e[q].to_bits())
        );
    }

    /// The full pass picks the column of the scan over every column.
    #[cfg(test)]
    fn check_full(&mut self, q: Option<usize>, kf: usize, phase1: bool, bland: bool) {
        let Some((full, _)) = self.check_pricing.as_mut() else {
            return;
        };
        *full += 1;
        self.reduced_f64(kf, phase1);
        let scan = self.price_scan(kf, phase1, bland);
        assert_eq!(q, scan, "basis {:?}", self.basis);
    }

    /// The full pass: the entering column by Dantzig's rule, or Bland's first improving index,
    /// over every column: among the non-basic columns with v_i < −tol_i, the first index of
    /// the least v_i, where v_i is d_i = c_i − y·a_i formed in f64 when its rounding bound
    /// γ e_i (γ = 4(r+2)ε, e_i = |c_i| + Σ_k |y_k a_ki|) settles the sign of d_i + tol_i, and
    /// d_i formed in double-double otherwise: the scan over every column of
    /// [`Self::price_scan`], which Bland's rule (after a run of degenerate pivots) takes as it
    /// is.
    ///
    /// Dantzig's rule examines few columns, with the same comparisons in index order, so the
    /// same column enters. The f64 d_i of every column come from one vectorised pass;
    /// E = (max c_i + Σ_k |y_k| max_i |a_ki|)(1 + 2⁻⁴⁰) ≥ e_i for every i (also as computed in
    /// f64). Every v_i ≥ d_i − 2γ e_i, and U = min(0, min d_i over d_i + tol_i < −γE) is a
    /// value v_j of an eligible column j or the bound 0 every eligible value lies below, so
    /// the least value is attained only where d_i − 2γ e_i ≤ U and d_i + tol_i ≤ γ e_i. The
    /// blocks where no d_i + tol_i ≤ γE, or where min d_i − 2γE > U, hold no such column
    /// ([`row_kernels::price_screen`], one pass forming d and screening it); e_i is formed in
    /// the others alone, bit for bit as in the scan.
    fn price_full(&mut self, kf: usize, phase1: bool, bland: bool) -> Option<usize> {
        let (n, r) = (self.n, self.r);
        let bound = (0..r).fold(self.cmax, |a, j| a + self.yhi[j].abs() * self.amax[j]);
        let big_e = bound * (1.0 + f64::powi(2.0, -40));
        if bland || !big_e.is_finite() {
            self.reduced_f64(kf, phase1);
            return self.price_scan(kf, phase1, bland);
        }
        let factor = self.rounding_factor();
        let (g, wide) = (factor * big_e, 2.0 * factor);
        // A basic column neither bounds U nor flags its block: its threshold is +∞ for the pass.
        let mut saved = [0.0; 32];
        for (t, &b) in self.basis.iter().enumerate() {
            if b < n {
                saved[t] = std::mem::replace(&mut self.tol[b], f64::INFINITY);
            }
        }
        let mut flagged = std::mem::take(&mut self.flagged);
        let u = row_kernels::price_screen(
            &mut self.d,
            &self.cost,
            &self.yhi,
            &self.arow,
            &self.tol,
            g,
            &mut flagged,
            self.avx512,
        )
        .min(0.0);
        for (t, &b) in self.basis.iter().enumerate() {
            if b < n {
                self.tol[b] = saved[t];
            }
        }
        let mut best = (None, 0.0);
        for &(lo, low) in &flagged {
            if low - 2.0 * g > u {
                continue;
            }
            let hi = (lo + row_kernels::BLOCK).min(n);
            self.magnitudes(lo, hi);
            for i in lo..hi {
                let (d, e) = (self.d[i], self.e[i]);
                if d - wide * e <= u && d + self.tol[i] <= factor * e {
                    self.consider(i, kf, phase1, factor, &mut best);
                }
            }
        }
        self.flagged = flagged;
        best.0
    }

    /// e_i = c_i + Σ_k |y_k a_ki| for the columns lo..hi, with the operations of
    /// [`row_kernels::sub_rows_abs`] in the same order (the same bits).
    fn magnitudes(&mut self, lo: usize, hi: usize) {
        let n = self.n;
        self.e[lo..hi].copy_from_slice(&self.cost[lo..hi]);
        for (j, &y) in self.yhi.iter().enumerate() {
            let row = &self.arow[j * n + lo..j * n + hi];
            for (e, &a) in self.e[lo..hi].iter_mut().zip(row) {
                *e += (y * a).abs();
            }
        }
    }

    /// γ = 4(r+2)ε: |d_i − d_i^dd| ≤ γ e_i for the f64 reduced cost d_i of [`Self::reduced_f64`]
    /// (the f64 dot product's γ_{r+1} e_i and the duals' low parts, ≤ ε/2 e_i, with room for
    /// the rounding of e_i itself).
    fn rounding_factor(&self) -> f64 {
        4.0 * (self.r as f64 + 2.0) * f64::EPSILON
    }

    /// d_i = c_i − y·a_i and e_i = |c_i| + Σ_k |y_k a_ki| in f64 from the duals' high parts for
    /// every column (one vectorised pass per row).
    fn reduced_f64(&mut self, kf: usize, phase1: bool) {
        let n = self.n;
        let k = if phase1 { 0 } else { kf.min(n) };
        self.d[..k].copy_from_slice(&self.kappa[..k]);
        self.e[..k].copy_from_slice(&self.kappa[..k]);
        self.d[k..].fill(0.0);
        self.e[k..].fill(0.0);
        self.yhi.clear();
        self.yhi.extend(self.y.iter().map(|y| y.0));
        row_kernels::sub_rows_abs(&mut self.d, &mut self.e, &self.yhi, &self.arow, self.avx512);
    }

    /// One column of the scan: v_i (see [`Self::price`]) replaces `best` when it is below
    /// −tol_i and strictly below best's value. Eligible when the reduced cost is below −TOL_D in
    /// scaled or in original units (d_i = d̃_i / κ_i: a large column's weight moves G by its
    /// unscaled value). True when column i is eligible.
    fn consider(
        &self,
        i: usize,
        kf: usize,
        phase1: bool,
        factor: f64,
        best: &mut (Option<usize>, f64),
    ) -> bool {
        if self.is_basic[i] {
            return false;
        }
        let tol = self.tol[i];
        let mut d = self.d[i];
        if (d + tol).abs() <= factor * self.e[i] {
            d = self.reduced_dd(i, self.cost(i, kf, phase1));
        }
        let eligible = d < -tol;
        if eligible && d < best.1 {
            *best = (Some(i), d);
        }
        eligible
    }

    /// The entering column by the scan over every column (blocks where no d_i + tol_i can be
    /// negative within γ e_i skipped), from d and e of [`Self::reduced_f64`] (to be called
    /// first); with `bland` the first eligible column.
    fn price_scan(&self, kf: usize, phase1: bool, bland: bool) -> Option<usize> {
        let n = self.n;
        let factor = self.rounding_factor();
        let mut best = (None, 0.0);
        for lo in (0..n).step_by(row_kernels::BLOCK) {
            let hi = (lo + row_kernels::BLOCK).min(n);
            // No column of the block can be eligible: d_i + tol_i > factor · e_i everywhere.
            if !row_kernels::any_below_shifted(
                &self.d[lo..hi],
                &self.tol[lo..hi],
                &self.e[lo..hi],
                factor,
            ) {
                continue;
            }
            for i in lo..hi {
                if self.consider(i, kf, phase1, factor, &mut best) && bland {
                    return Some(i);
                }
            }
        }
        best.0
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
mod tests {
    use super::*;
    use crate::lp::GridTable;
    use crate::Grid;

    fn certifier(n: usize, f: impl FnMut(f64, &mut [f64]), m: usize) -> Certifier {
        let t = GridTable::from_fn(&Grid::uniform(n).unwrap(), m, f).unwrap();
        Certifier::new(&t, (0..=m).collect())
    }

    /// (z, z²) on {0, 1/4, 1/2, 3/4, 1}, b = (1/2, 5/16), z_f = 0.6: the optimum G = 1/2
    /// (½δ(1/4) + ½δ(3/4)); from a cold start and from a feasible suboptimal basis.
    #[test]
    fn finds_the_known_optimum() {
        let mut c = certifier(5, |z, o| (o[0], o[1]) = (z, z * z), 2);
        let b = [0.5, 0.3125];
        for start in [None, Some(&[0usize, 2, 4][..])] {
            c.set_moments(&b);
            let mut s = ScaledSimplex::default();
            let Found::Optimal(basis) = s.solve(&c, 3, start) else {
                panic!("not optimal from {start:?}")
            };
            assert!(s.pivots > 0);
            assert_eq!(c.optimal(&b, 3, &basis).unwrap().g, 0.5, "{basis:?}");
        }
    }

    /// The same LP from the infeasible basis {0, 1/4, 1/2} (weights 1/2, −1, 3/2): the warm
    /// phase 1 with the composite artificial −1·δ(1/4) in place of the point 1/4 reaches the
    /// optimum G = 1/2 of the cold start in fewer pivots.
    #[test]
    fn warm_phase1_from_an_infeasible_basis_reaches_the_cold_optimum() {
        let mut c = certifier(5, |z, o| (o[0], o[1]) = (z, z * z), 2);
        let b = [0.5, 0.3125];
        c.set_moments(&b);
        let mut pivots = Vec::new();
        for start in [None, Some(&[0usize, 1, 2][..])] {
            let mut s = ScaledSimplex::default();
            let Found::Optimal(basis) = s.solve(&c, 3, start) else {
                panic!("not optimal from {start:?}")
            };
            let opt = c.optimal(&b, 3, &basis).unwrap();
            assert_eq!(opt.g, 0.5, "{basis:?}");
            assert_eq!(opt.support, vec![(0.25, 0.5), (0.75, 0.5)]);
            pivots.push(s.pivots);
        }
        assert_eq!(pivots, [5, 3], "cold and warm pivots");
    }

    /// Pivots through the eta file agree with refactorising at every pivot: (z, z², z³) on 65
    /// points, the moments of ¼δ(1/8) + ½δ(1/2) + ¼δ(13/16) (exact in f64), z_f = 0.6, from
    /// the all-artificial start. With at most 0, 3 and [`MAX_ETAS`] etas between
    /// factorisations: every updated x and y within 1e-28 (relative to its largest entry) of a
    /// fresh factorisation's, the same optimal basis {39, 10, 64, 9} after 14 pivots and the
    /// same G = 0.3223894113549286.
    #[test]
    fn eta_file_matches_refactorising_at_every_pivot() {
        let mut c = certifier(65, |z, o| (o[0], o[1], o[2]) = (z, z * z, z * z * z), 3);
        let atoms = [(8u32, 0.25), (32, 0.5), (52, 0.25)];
        let b: Vec<f64> = (1..=3)
            .map(|k| {
                atoms
                    .iter()
                    .map(|&(i, w)| w * (i as f64 / 64.0).powi(k))
                    .sum()
            })
            .collect();
        c.set_moments(&b);
        let mut runs = Vec::new();
        for max_etas in [0, 3, MAX_ETAS] {
            let mut s = ScaledSimplex {
                max_etas: Some(max_etas),
                check_updates: Some((0, 0.0)),
                ..Default::default()
            };
            let Found::Optimal(basis) = s.solve(&c, 39, None) else {
                panic!("not optimal with {max_etas} etas")
            };
            let (checks, worst) = s.check_updates.unwrap();
            assert!(worst <= 1e-28, "{max_etas} etas: {worst:e}");
            let g = c.optimal(&b, 39, &basis).unwrap().g;
            runs.push((basis, s.pivots, g, checks));
        }
        assert_eq!(runs[0].0, [39, 10, 64, 9]);
        assert_eq!(runs[0].1, 14);
        assert_eq!(runs[0].2, 0.3223894113549286);
        assert_eq!(runs[0].3, 0, "nothing updated without etas");
        assert!(runs[1].3 > 0 && runs[2].3 > 0, "{runs:?}");
        for run in &runs[1..] {
            assert_eq!(run.0, runs[0].0);
            assert_eq!(run.1, runs[0].1);
            assert_eq!(run.2, runs[0].2);
        }
    }

    /// (1/2, 1/5) has negative variance: phase 1 ends with a Farkas ray the certifier accepts.
    #[test]
    fn infeasible_moments_give_a_farkas_ray() {
        let mut c = certifier(5, |z, o| (o[0], o[1]) = (z, z * z), 2);
        let b = [0.5, 0.2];
        c.set_moments(&b);
        let Found::Infeasible(y) = ScaledSimplex::default().solve(&c, 3, None) else {
            panic!("expected a Farkas ray")
        };
        assert!(c.infeasible(&b, &y).unwrap() > 0.0);
    }

    /// At every pivot of both phases: the screened full pass, when it runs, picks the very
    /// column of the scan over every column (so at every optimum neither finds an eligible
    /// column), and every column partial pricing picks is non-basic with a double-double
    /// reduced cost below −tol_i (its f64 d_i and e_i those of the full pass, bit for bit).
    /// Flat windows, tight clusters, adjacent points, boundary moments and mixtures under
    /// (z, z², z³, z⁴) on 1024 and 4096 points, z_f below, at, inside and above the support,
    /// from the all-artificial start and from the support of a later problem (a feasible or
    /// infeasible warm start).
    #[test]
    fn full_pass_matches_the_scan_and_partial_picks_are_eligible() {
        use crate::bench::corpus::{problem, Kind};
        use rand::SeedableRng;
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
        let mut checks = (0, 0);
        for n in [1024, 4096] {
            let t = GridTable::from_fn(&Grid::uniform(n).unwrap(), 4, |z, o| {
                (o[0], o[1], o[2], o[3]) = (z, z * z, z * z * z, z * z * z * z)
            })
            .unwrap();
            let mut c = Certifier::new(&t, (0..=4).collect());
            let z = t.grid().points();
            let mut s = ScaledSimplex {
                check_pricing: Some((0, 0)),
                ..Default::default()
            };
            let kinds = [
                Kind::Flat,
                Kind::Cluster,
                Kind::Adjacent,
                Kind::Boundary,
                Kind::Mixture,
            ];
            let mut last: Option<Vec<usize>> = None;
            for case in 0..30 {
                let p = problem(&mut rng, n, 4, kinds[case % kinds.len()]);
                let b = crate::lp::distribution_moments(&t, &p.dist).unwrap();
                c.set_moments(&b);
                for &zf in &p.zf {
                    let kf = z.partition_point(|&v| v < zf);
                    let warm = last.take();
                    for start in [None, warm.as_deref()] {
                        if let Found::Optimal(basis) = s.solve(&c, kf, start) {
                            last = Some(basis);
                        }
                    }
                    last = last.or(warm);
                }
            }
            let (full, partial) = s.check_pricing.unwrap();
            checks.0 += full;
            checks.1 += partial;
        }
        assert!(
            checks.0 > 100 && checks.1 > 1000,
            "{checks:?} pivots checked"
        );
    }

    /// Partial pricing reaches the optimal value of full pricing: 400 problems (flat windows,
    /// clusters, adjacent points, boundary moments and mixtures under (z, z², z³, z⁴) on 1024
    /// and 4096 points, z_f uniform, cold starts) solved with and without it, each final
    /// basis judged by the certifier as an escalation's ([`Certifier::improve`], up to 64
    /// accurate pivots). Partial pricing certifies at least as many (397 of 400 each), and
    /// where both are certified their G agree within 2 TOL_GAP (each is within TOL_GAP of its
    /// dual bound).
    #[test]
    fn partial_pricing_reaches_the_optimal_value_of_full_pricing() {
        use crate::bench::corpus::{problem, Kind};
        use crate::lp::certify::TOL_GAP;
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
        let kinds = [
            Kind::Flat,
            Kind::Flat,
            Kind::Cluster,
            Kind::Adjacent,
            Kind::Boundary,
            Kind::Mixture,
        ];
        let (mut both, mut certified) = (0, [0usize; 2]);
        let mut pivots = [0u64; 2];
        for n in [1024, 4096] {
            let t = GridTable::from_fn(&Grid::uniform(n).unwrap(), 4, |z, o| {
                (o[0], o[1], o[2], o[3]) = (z, z * z, z * z * z, z * z * z * z)
            })
            .unwrap();
            let mut c = Certifier::new(&t, (0..=4).collect());
            let mut solvers = [
                ScaledSimplex::default(),
                ScaledSimplex {
                    full_pricing: true,
                    ..Default::default()
                },
            ];
            for case in 0..200 {
                let p = problem(&mut rng, n, 4, kinds[case % kinds.len()]);
                let b = crate::lp::distribution_moments(&t, &p.dist).unwrap();
                let kf = rng.gen_range(1..n);
                let mut g = [None; 2];
                for (k, s) in solvers.iter_mut().enumerate() {
                    c.set_moments(&b);
                    let before = s.pivots;
                    if let Found::Optimal(mut basis) = s.solve(&c, kf, None) {
                        g[k] = c.improve(&b, kf, &mut basis, 64).ok().map(|a| a.g);
                    }
                    pivots[k] += s.pivots - before;
                }
                for k in 0..2 {
                    certified[k] += g[k].is_some() as usize;
                }
                if let [Some(gp), Some(gf)] = g {
                    both += 1;
                    assert!(
                        (gp - gf).abs() <= 2.0 * TOL_GAP,
                        "n = {n}, case {case}, kf = {kf}: {gp} against {gf}"
                    );
                }
            }
        }
        eprintln!("certified {certified:?}, both {both}, pivots {pivots:?}");
        assert!(certified[0] >= certified[1], "{certified:?}");
        assert!(both >= 390, "{both} of 400 certified by both");
    }

    /// exp(40z) spans e⁴⁰ ≈ 2.4·10¹⁷ on [0, 1]: with z, the moments of ½δ(0) + ½δ(1) on 65
    /// points leave only that distribution (the end points are the extreme values of both
    /// functions' convex hull), so G at z_f = 1/2 is exactly 1/2.
    #[test]
    fn steep_exponential_rows_are_solved_in_scaled_coordinates() {
        let mut c = certifier(65, |z, o| (o[0], o[1]) = (z, (40.0 * z).exp()), 2);
        let b = [0.5, 0.5 * (1.0 + 40f64.exp())];
        c.set_moments(&b);
        let Found::Optimal(basis) = ScaledSimplex::default().solve(&c, 32, None) else {
            panic!("not optimal")
        };
        assert_eq!(c.optimal(&b, 32, &basis).unwrap().g, 0.5);
    }
}
