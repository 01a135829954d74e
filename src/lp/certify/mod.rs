//! Certificates for the answers of Algorithm 1, checked in the ORIGINAL coordinates.
//!
//! Row j of the LP (j = 0: Σ w_i = 1; j ≥ 1: Σ w_i f_j(z_i) = b_j) is judged on its own scale
//! σ_j = max(|b̄_j|, 1e-30 · max_i |f_j(z_i)|) (σ_0 = 1), so a moment of 1e-25 must be
//! reproduced to 1e-34, not to 1e-9 of the function's range. The floor is lowered to the
//! smallest nonzero |f_j(z_i)| where that is smaller (exp(400z) spans 173 orders of magnitude:
//! its moments are judged on their own scale, not against 1e-30 · e^400); for a function that
//! changes sign it is 1e-5 · max_i |f_j(z_i)| (see [`CANCEL`]). (A moment whose terms cancel, a
//! sign-changing f_j with b_j ≈ 0, is judged against 1e-5 of the magnitude of its terms
//! instead, see [`CANCEL`]: f64 weights cannot resolve more.)
//!
//! * **optimal**: weights w ≥ 0 on a basis with |Σ_i w_i f_j(z_i) − b̄_j| ≤ 1e-9 σ_j for every
//!   row (residuals in double-double arithmetic), and duals y giving the weak-duality bound
//!   L = y·b̄ + min(0, min_i d_i), d_i = p_i − y·ā_i (p_i = [z_i < z_f]), with |G − L| ≤ 1e-9
//!   (or the tighter Σ_i u_i min(0, d_i) with u_i the bound on w_i from sign-definite rows):
//!   every distribution with exactly these moments has mass ≥ L ≥ G − 1e-9 below z_f. The d_i
//!   are computed in f64 and lowered by their rounding bound; the duals are double-double
//!   (y + y_lo). A check stops after the f64 pass when one point's u_i·(d_i + γe_i) already
//!   brings the bound below G − 1e-9. The support's residual ρ must not move the bound:
//!   |y·ρ| ≤ 1e-9, unless ρ is
//!   rounding-level (≤ 64 ε of the row's terms); then, when L > G + 1e-9 (huge duals near the
//!   boundary of the moment space), G must instead match L′ = L + y·ρ to 1e-9, the bound for
//!   the support's own moments b̄ + ρ, which equal b̄ at f64 resolution.
//! * **infeasible**: a Farkas ray y with y·b̄ < min_i y·ā_i − 1e-9 (|min_i y·ā_i| + Σ_j |y_j| σ_j):
//!   then no distribution reproduces the moments even to the tolerance above.
//!
//! Both solves (weights and duals) are done here from the basis alone, on the row-scaled basis
//! matrix (exact power-of-two scales) with iterative refinement on double-double residuals, so
//! the certificate does not trust the solver's own arithmetic.

#![allow(clippy::needless_range_loop)] // index-heavy dense linear algebra on r ≤ 13

mod bound;
mod improve;
pub(in crate::lp) mod row_kernels;

use super::dense::{inv_pow2, residual2, DdLu, Lu};
use super::ratio;
use super::GridTable;

/// Relative tolerance on every moment (against its row scale σ_j).
pub const TOL_MOMENT: f64 = 1e-9;
/// Largest accepted |G − L| between the answer and its dual lower bound.
pub const TOL_GAP: f64 = 1e-9;
/// σ_j ≥ SCALE_FLOOR · max_i |f_j(z_i)|: moments below this are judged absolutely.
pub const SCALE_FLOOR: f64 = 1e-30;
/// A moment that is a sum of terms of both signs cancelling to nearly 0 is judged against
/// CANCEL times the magnitude of its terms (f64 weights cannot resolve it more finely): the
/// residual must then be ≤ 1e-14 of Σ_i w_i |f_j(z_i)|. For a function that changes sign on
/// the grid the floor of σ_j is CANCEL · max_i |f_j(z_i)| (sin(4πz) at z = 1 is 4.9e-16, a
/// rounding error, not a scale).
pub const CANCEL: f64 = 1e-5;
/// Mass below z_f up to which the zero duals certify an answer (no grid pass; the gap is then
/// at most this, far inside [`TOL_GAP`]).
const ZERO_MASS: f64 = 1e-12;
/// Weights (≤ 1, the total mass) below this are rounding-level in the ratio test.
const TOL_WEIGHT: f64 = 1e-12;
/// Accurate pivots by Dantzig's rule before Bland's.
const BLAND_AFTER: usize = 60;
/// How many units of ε a support's residual may be for the bound of its own moments to stand
/// in for the bound of b̄ (see [`Certifier::optimal`]).
const ULPS: f64 = 64.0;
/// Pivot ratio of the f64 basis factorisation up to which its refined solves are taken as
/// accurate (a primal residual is then the basis's, not the arithmetic's).
const F64_ACCURATE: f64 = 1e8;
/// Points of a block needing a double-double reduced cost from which the whole block is
/// recomputed at once ([`row_kernels::reduced_dd_block`]).
const BLOCK_DD: usize = 3;
/// Rounding bound factor per term of a reduced cost (a few units of ε for r ≤ 13 terms).
const GAMMA: f64 = 16.0 * f64::EPSILON;

#[derive(Clone, Copy)]
enum Which {
    X,
    Y,
    Tmp,
}

/// An answer with its evidence.
#[derive(Clone, Debug, PartialEq)]
pub struct Certified {
    /// Mass of the certified distribution below z_f.
    pub g: f64,
    /// (z_i, w_i) with w_i > 0, sorted by z.
    pub support: Vec<(f64, f64)>,
    /// max_j |Σ w_i f_j(z_i) − b̄_j| / σ_j.
    pub residual: f64,
    /// G − L (L the dual lower bound).
    pub gap: f64,
    /// A lower bound on min(0, min_i d_i), the most negative reduced cost over the grid for
    /// the certificate's duals.
    pub min_reduced: f64,
}

/// Checks answers for one table; owns its workspace (no allocation per check except the
/// returned support).
#[derive(Clone, Debug)]
pub struct Certifier {
    n: usize,
    m: usize,
    /// The row kernels may use AVX-512 (detected once).
    avx512: bool,
    z: Vec<f64>,
    /// Column-major m × n: fcols[(j−1)·n + i] = f_j(z_i).
    fcols: Vec<f64>,
    /// max_i |f_j(z_i)| (j = 0: 1).
    fmax: Vec<f64>,
    /// Floor of σ_j: min(1e-30 max_i |f_j(z_i)|, min_i |f_j(z_i)| ≠ 0).
    floor: Vec<f64>,
    /// (row, column-major 1/f_j(z_i), 0 where f_j(z_i) = 0) of the sign-definite rows: the
    /// caps u_i without a division per grid point.
    finv: Vec<(usize, Vec<f64>)>,
    /// The duals y and reduced costs d belong to the basis last checked.
    duals_fresh: bool,
    /// A check stops at the f64 pass when that already shows the dual bound too low
    /// ([`Self::lower_bound`]); off only to test that the verdicts are the same.
    early: bool,
    /// The rows the bases are square on (function indices, 0 = the constant): the numerically
    /// independent ones. The others are checked through the residual only.
    rows: Vec<usize>,
    sigma: Vec<f64>,
    scale: Vec<f64>,
    bbar: Vec<f64>,
    a: Vec<f64>,
    lu: Lu,
    /// The same basis matrix in double-double, used when the f64 factorisation cannot
    /// certify (condition beyond 1/ε).
    ddlu: DdLu,
    precise: bool,
    /// Column scales K of the basis matrix (M = B̃ K is factorised).
    colscale: Vec<f64>,
    /// The last basis given to [`Self::optimal`] was factorised, and its weights reproduced
    /// the moments.
    factored: bool,
    primal_ok: bool,
    /// Bland's rule in [`Self::improve`] (after BLAND_AFTER steps: no cycling).
    bland: bool,
    x: Vec<f64>,
    /// x before clamping to ≥ 0.
    xraw: Vec<f64>,
    y: Vec<f64>,
    /// Low parts of the duals: y + ylo is the double-double dual vector (0 for Farkas rays).
    ylo: Vec<f64>,
    /// Rounding factor of the f64 reduced costs for the current duals: γ plus the relative
    /// size of ylo (the f64 pass leaves the low parts out).
    gamma: f64,
    tmp: Vec<f64>,
    d: Vec<f64>,
    e: Vec<f64>,
    /// Offsets in `fcols` of the function rows rows[1..].
    offs: Vec<usize>,
    /// First indices of the blocks of d where some d_i − γ e_i < 0, when `flagged_ok` (the
    /// last [`Self::reduced`] priced a cost vector): the only places a bound can go negative.
    flagged: Vec<usize>,
    flagged_ok: bool,
    /// −α and Σ|·| of a row of B⁻¹A over the grid (dual steps of [`Self::improve`]).
    ra: Vec<f64>,
    rm: Vec<f64>,
}

/// Whether f_j does not change sign on the grid.
fn sign_definite(col: &[f64]) -> bool {
    col.iter().all(|&v| v >= 0.0) || col.iter().all(|&v| v <= 0.0)
}

/// The floor of the scale σ_j = max(|b̄_j|, floor) on which moment j is judged, from the
/// function's grid values `col`: min([`SCALE_FLOOR`] · max_i |f_j(z_i)|, min_i |f_j(z_i)| ≠ 0)
/// for a sign-definite function, [`CANCEL`] · max_i |f_j(z_i)| for one that changes sign.
pub fn scale_floor(col: &[f64]) -> f64 {
    let fmax = col.iter().fold(0.0f64, |a, v| a.max(v.abs()));
    if sign_definite(col) {
        let fmin = col
            .iter()
            .filter(|v| **v != 0.0)
            .fold(f64::INFINITY, |a, v| a.min(v.abs()));
        (SCALE_FLOOR * fmax).min(fmin)
    } else {
        CANCEL * fmax
    }
}

impl Certifier {
    /// A certifier for `table` whose square bases use the function rows `rows` (0 = the
    /// constant, must be first; all of 0..=m when the functions are independent).
    pub fn new(table: &GridTable, rows: Vec<usize>) -> Certifier {
        let (n, m) = (table.n(), table.m());
        let mut fcols = vec![0.0; m * n];
        let mut fmax = vec![1.0; m + 1];
        let mut floor = vec![1.0; m + 1];
        let mut definite = vec![false; m + 1];
        for j in 1..=m {
            let col = &mut fcols[(j - 1) * n..j * n];
            for (i, v) in col.iter_mut().enumerate() {
                *v = table.row(i)[j - 1];
            }
            fmax[j] = col.iter().fold(0.0f64, |a, v| a.max(v.abs()));
            definite[j] = sign_definite(col);
            floor[j] = scale_floor(col);
        }
        let r = rows.len();
        let offs = rows[1..].iter().map(|&j| (j - 1) * n).collect();
        let finv = (1..=m)
            .filter(|&j| definite[j])
            .map(|j| {
                let col = &fcols[(j - 1) * n..j * n];
                let inv = col.iter().map(|&f| if f != 0.0 { 1.0 / f } else { 0.0 });
                (j, inv.collect())
            })
            .collect();
        Certifier {
            n,
            m,
            avx512: row_kernels::has_avx512(),
            finv,
            duals_fresh: false,
            z: table.grid().points().to_vec(),
            fcols,
            fmax,
            floor,
            rows,
            sigma: vec![1.0; m + 1],
            scale: vec![1.0; m + 1],
            bbar: vec![1.0; m + 1],
            a: vec![0.0; r * r],
            lu: Lu::default(),
            ddlu: DdLu::default(),
            precise: false,
            colscale: vec![1.0; r],
            factored: false,
            primal_ok: false,
            bland: false,
            x: vec![0.0; r],
            xraw: vec![0.0; r],
            y: vec![0.0; r],
            ylo: vec![0.0; r],
            gamma: GAMMA,
            tmp: vec![0.0; r],
            d: vec![0.0; n],
            e: vec![0.0; n],
            offs,
            flagged: Vec::new(),
            flagged_ok: false,
            early: true,
            ra: vec![0.0; n],
            rm: vec![0.0; n],
        }
    }

    /// Number of grid points.
    pub fn n(&self) -> usize {
        self.n
    }

    /// Number of basis functions m (rows 1..=m; row 0 is the constant).
    pub fn m(&self) -> usize {
        self.m
    }

    /// b̄_j of the moments last given (b̄_0 = 1).
    pub fn bbar(&self, j: usize) -> f64 {
        self.bbar[j]
    }

    /// The independent rows (function indices).
    pub fn rows(&self) -> &[usize] {
        &self.rows
    }

    /// The exact power-of-two row scales ≈ 1/σ_j for the moments last given.
    pub fn row_scales(&self) -> &[f64] {
        &self.scale
    }

    /// The values f_j(z_i) of function row j ≥ 1 over the grid; None for the constant row 0.
    pub fn function_row(&self, j: usize) -> Option<&[f64]> {
        (j > 0).then(|| &self.fcols[(j - 1) * self.n..j * self.n])
    }

    /// Entry of row j (0 = constant) at grid point i.
    #[inline]
    pub fn entry(&self, j: usize, i: usize) -> f64 {
        if j == 0 {
            1.0
        } else {
            self.fcols[(j - 1) * self.n + i]
        }
    }

    /// Set the moments b (length m): right-hand side b̄ = [1; b], σ_j and the row scales.
    pub fn set_moments(&mut self, b: &[f64]) {
        self.bbar[0] = 1.0;
        self.bbar[1..].copy_from_slice(&b[..self.m]);
        for j in 0..=self.m {
            let s = self.bbar[j].abs().max(self.floor[j]);
            self.sigma[j] = if s > 0.0 { s } else { f64::MIN_POSITIVE };
            self.scale[j] = inv_pow2(self.sigma[j]);
        }
    }

    /// Certify that `basis` (grid indices, one per independent row) is optimal for moments `b`
    /// and `kf` grid points below z_f; the reason when it is not.
    pub fn optimal(&mut self, b: &[f64], kf: usize, basis: &[usize]) -> Result<Certified, String> {
        self.precise = false;
        match self.check(b, kf, basis) {
            Ok(c) => Ok(c),
            // The weights miss the moments although the f64 solves are accurate (pivot ratio
            // ≤ 1e8, refined in double-double residuals): the basis is not primal feasible, in
            // any precision. (On the stacks and adversarial corpora the double-double retry
            // never certified such a basis.)
            Err(e) if self.factored && !self.primal_ok && self.lu.pivot_ratio() <= F64_ACCURATE => {
                Err(e)
            }
            Err(_) if basis.len() == self.rows.len() => {
                // Beyond f64 (or singular in f64): the same basis in double-double.
                self.precise = true;
                self.check(b, kf, basis)
            }
            Err(e) => Err(e),
        }
    }

    fn check(&mut self, b: &[f64], kf: usize, basis: &[usize]) -> Result<Certified, String> {
        self.duals_fresh = false;
        self.set_moments(b);
        let r = self.rows.len();
        self.factored = false;
        if basis.len() != r || basis.iter().any(|&i| i >= self.n) {
            return Err("basis of the wrong size".into());
        }
        for t in 0..r {
            let mut big = 0.0f64;
            for k in 0..r {
                let j = self.rows[k];
                let v = self.scale[j] * self.entry(j, basis[t]);
                self.a[k * r + t] = v;
                big = big.max(v.abs());
            }
            // Column equilibration (exact): M = B̃ K.
            self.colscale[t] = inv_pow2(big);
            for k in 0..r {
                self.a[k * r + t] *= self.colscale[t];
            }
        }
        self.factored = if self.precise {
            self.ddlu.factor(&self.a, r)
        } else {
            self.lu.factor(&self.a, r)
        };
        if !self.factored {
            return Err("singular final basis".into());
        }
        self.primal(basis);
        let mut residual = self.moment_residual(basis);
        if residual > TOL_MOMENT && self.xraw.iter().any(|&v| v < 0.0) {
            // A degenerate vertex: its zero weights came out ±κε, and clamping the negative
            // ones misses the moments. The positive support alone may reproduce them.
            if let Some(res) = self.primal_support(basis, residual) {
                residual = res;
            }
        }
        self.primal_ok = residual <= TOL_MOMENT;
        if !self.primal_ok {
            return Err(format!(
                "support reproduces the moments only to {residual:.1e} (relative)"
            ));
        }
        let g: f64 = (0..r).filter(|&t| basis[t] < kf).map(|t| self.x[t]).sum();
        if g <= ZERO_MASS {
            // No mass below z_f: the duals y = 0 certify it (d_i = p_i ≥ 0, L = 0 ≥ G − 1e-9),
            // with no pass over the grid.
            return Ok(self.certified(basis, g, residual, g, 0.0));
        }
        self.dual(basis, kf);
        let stop = if self.early {
            g - TOL_GAP
        } else {
            f64::NEG_INFINITY
        };
        let lower = self.lower_bound(kf, stop);
        let gap = g - lower;
        // The support reproduces b̄′ = b̄ + ρ, not b̄: its G moves the bound by y·ρ. Required:
        // either |y·ρ| ≤ 1e-9 (G is within 1e-9 of the sharp bound of b̄ itself), or ρ is
        // rounding-level (b̄′ and b̄ are the same moments at f64 resolution; near the boundary
        // of the moment space |y| reaches 1e9 and y·ρ exceeds 1e-9 there). In the latter case
        // G must match L or the bound for b̄′, L′ = L + y·ρ, to 1e-9.
        let (shift, ulp) = self.dual_shift(basis);
        let ok = gap <= TOL_GAP
            && (ulp || shift.abs() <= TOL_GAP)
            && (gap.abs() <= TOL_GAP || (ulp && (gap - shift).abs() <= TOL_GAP));
        if !ok || gap.is_nan() {
            return Err(format!("dual bound {lower:.12} does not match G = {g:.12}"));
        }
        let min_reduced = self.min_lower().min(0.0);
        Ok(self.certified(basis, g, residual, gap, min_reduced))
    }

    /// The certified answer of `basis` with the weights in `x`.
    fn certified(
        &self,
        basis: &[usize],
        g: f64,
        residual: f64,
        gap: f64,
        min_reduced: f64,
    ) -> Certified {
        let mut support: Vec<(f64, f64)> = (0..basis.len())
            .filter(|&t| self.x[t] > 0.0)
            .map(|t| (self.z[basis[t]], self.x[t]))
            .collect();
        support.sort_by(|a, b| a.0.total_cmp(&b.0));
        Certified {
            g: g.clamp(0.0, 1.0),
            support,
            residual,
            gap,
            min_reduced,
        }
    }

    /// Certify that a distribution [(grid index, weight)] with no positive weight below z_f
    /// (every such index ≥ `kf`) is optimal for moments `b`: G = 0, proven by the zero duals
    /// (d_i = p_i ≥ 0, L = 0), provided its weights, normalised to mass 1, reproduce every
    /// moment to [`TOL_MOMENT`] of its scale (double-double residuals). The support is the
    /// distribution itself, duplicates merged, sorted by z.
    pub fn zero_mass(
        &mut self,
        b: &[f64],
        kf: usize,
        dist: &[(u32, f64)],
    ) -> Result<Certified, String> {
        let total: f64 = dist.iter().map(|e| e.1).sum();
        let valid = |&(i, w): &(u32, f64)| (i as usize) < self.n && w.is_finite() && w >= 0.0;
        if !(total > 0.0 && total.is_finite() && dist.iter().all(valid)) {
            return Err("invalid distribution".into());
        }
        if dist.iter().any(|&(i, w)| w > 0.0 && (i as usize) < kf) {
            return Err("mass below z_f".into());
        }
        self.set_moments(b);
        let mut atoms: Vec<(usize, f64)> = dist
            .iter()
            .filter(|e| e.1 > 0.0)
            .map(|&(i, w)| (i as usize, w / total))
            .collect();
        atoms.sort_by_key(|a| a.0);
        atoms.dedup_by(|a, b| {
            let same = a.0 == b.0;
            if same {
                b.1 += a.1;
            }
            same
        });
        let residual = (0..=self.m)
            .map(|j| {
                let terms = atoms.iter().map(|&(i, w)| (self.entry(j, i), w));
                let mag: f64 = atoms
                    .iter()
                    .map(|&(i, w)| (self.entry(j, i) * w).abs())
                    .sum();
                residual2(self.bbar[j], terms).abs() / self.sigma[j].max(CANCEL * mag)
            })
            .fold(0.0, f64::max);
        // (NaN fails too.)
        if residual.is_nan() || residual > TOL_MOMENT {
            return Err(format!(
                "distribution reproduces the moments only to {residual:.1e} (relative)"
            ));
        }
        Ok(Certified {
            g: 0.0,
            support: atoms.iter().map(|&(i, w)| (self.z[i], w)).collect(),
            residual,
            gap: 0.0,
            min_reduced: 0.0,
        })
    }

    /// Certify that `y` (unscaled duals on the independent rows) is a Farkas ray for moments
    /// `b`: the margin by which the moments miss the (tolerance-widened) moment space.
    pub fn infeasible(&mut self, b: &[f64], y: &[f64]) -> Result<f64, String> {
        self.set_moments(b);
        let r = self.rows.len();
        if y.len() != r || y.iter().any(|v| !v.is_finite()) {
            return Err("Farkas ray of the wrong size or not finite".into());
        }
        self.ylo.iter_mut().for_each(|v| *v = 0.0);
        self.reduced(y, None);
        let lo = self.min_lower();
        let yb = -residual2(0.0, (0..r).map(|k| (y[k], self.bbar[self.rows[k]])));
        // The tolerance-widened moment space, on the widest scale a distribution could claim.
        let slack: f64 = (0..r)
            .map(|k| {
                let j = self.rows[k];
                y[k].abs() * self.sigma[j].max(CANCEL * self.fmax[j])
            })
            .sum();
        let bound = lo - TOL_MOMENT * (lo.abs() + slack);
        let margin = bound - yb;
        if margin > 1e-12 * (yb.abs() + bound.abs()) && margin.is_finite() {
            Ok(margin)
        } else {
            Err("no certified Farkas ray".into())
        }
    }

    /// Solve with the basis matrix (transposed if `t`) in place in one of the work vectors, in
    /// f64 or, in precise mode, in double-double.
    fn solve(&mut self, t: bool, which: Which) {
        let v = match which {
            Which::X => &mut self.x,
            Which::Y => &mut self.y,
            Which::Tmp => &mut self.tmp,
        };
        match (self.precise, t) {
            (false, false) => self.lu.solve(v),
            (false, true) => self.lu.solve_t(v),
            (true, false) => self.ddlu.solve(v),
            (true, true) => self.ddlu.solve_t(v),
        }
    }

    /// x = B̃⁻¹ b̃ on the row-scaled basis, refined three times on double-double residuals.
    fn primal(&mut self, basis: &[usize]) {
        let r = self.rows.len();
        for k in 0..r {
            let j = self.rows[k];
            self.x[k] = self.scale[j] * self.bbar[j];
        }
        self.solve(false, Which::X);
        for t in 0..r {
            self.x[t] *= self.colscale[t];
        }
        for _ in 0..3 {
            for k in 0..r {
                let j = self.rows[k];
                let terms = (0..r).map(|t| (self.entry(j, basis[t]), self.x[t]));
                self.tmp[k] = self.scale[j] * residual2(self.bbar[j], terms);
            }
            self.solve(false, Which::Tmp);
            let mut moved = false;
            for t in 0..r {
                let next = self.x[t] + self.colscale[t] * self.tmp[t];
                moved |= next != self.x[t];
                self.x[t] = next;
            }
            // x unchanged: the next pass would find the same residual and move nothing either.
            if !moved {
                break;
            }
        }
        self.xraw.copy_from_slice(&self.x);
        self.x.iter_mut().for_each(|v| *v = v.max(0.0));
    }

    /// Weights on the basis columns with a positive basic weight, by least squares on the
    /// row-scaled system (modified Gram–Schmidt, twice, then four refinements on double-double
    /// residuals), dropping columns whose weight comes out negative. Stores them in x (0 off
    /// the support) and returns the moment residual when it beats `than`; None otherwise.
    fn primal_support(&mut self, basis: &[usize], than: f64) -> Option<f64> {
        let r = self.rows.len();
        let mut keep: Vec<usize> = (0..r).filter(|&t| self.xraw[t] > 0.0).collect();
        while !keep.is_empty() {
            let x = self.least_squares(basis, &keep)?;
            if x.iter().all(|&v| v >= 0.0) {
                let saved = std::mem::replace(&mut self.x, vec![0.0; r]);
                for (&t, &v) in keep.iter().zip(&x) {
                    self.x[t] = v;
                }
                let res = self.moment_residual(basis);
                if res < than {
                    return Some(res);
                }
                self.x = saved;
                return None;
            }
            let before = keep.len();
            keep = keep
                .iter()
                .zip(&x)
                .filter(|(_, &v)| v > 0.0)
                .map(|(&t, _)| t)
                .collect();
            if keep.len() == before {
                return None;
            }
        }
        None
    }

    /// min ‖S(B_K x − b̄)‖ over the basis columns K (S the row scales), refined on
    /// double-double residuals; None if the columns are dependent in f64.
    fn least_squares(&self, basis: &[usize], keep: &[usize]) -> Option<Vec<f64>> {
        let (r, s) = (self.rows.len(), keep.len());
        let entry = |k: usize, c: usize| {
            let j = self.rows[k];
            self.scale[j] * self.entry(j, basis[keep[c]])
        };
        // Q (column-major r × s) and upper-triangular R (row-major s × s).
        let mut q = vec![0.0; r * s];
        let mut rm = vec![0.0; s * s];
        for c in 0..s {
            for k in 0..r {
                q[c * r + k] = entry(k, c);
            }
            let n0: f64 = q[c * r..(c + 1) * r]
                .iter()
                .map(|v| v * v)
                .sum::<f64>()
                .sqrt();
            for _pass in 0..2 {
                for p in 0..c {
                    let h: f64 = (0..r).map(|k| q[p * r + k] * q[c * r + k]).sum();
                    rm[p * s + c] += h;
                    for k in 0..r {
                        q[c * r + k] -= h * q[p * r + k];
                    }
                }
            }
            let nrm: f64 = q[c * r..(c + 1) * r]
                .iter()
                .map(|v| v * v)
                .sum::<f64>()
                .sqrt();
            if nrm.is_nan() || nrm <= 1e-14 * n0 {
                return None;
            }
            rm[c * s + c] = nrm;
            q[c * r..(c + 1) * r].iter_mut().for_each(|v| *v /= nrm);
        }
        let mut x = vec![0.0; s];
        let mut res = vec![0.0; r];
        for _ in 0..5 {
            for (k, out) in res.iter_mut().enumerate() {
                let j = self.rows[k];
                let terms = (0..s).map(|c| (self.entry(j, basis[keep[c]]), x[c]));
                *out = self.scale[j] * residual2(self.bbar[j], terms);
            }
            // dx = R⁻¹ Qᵀ res.
            let mut dx: Vec<f64> = (0..s)
                .map(|c| (0..r).map(|k| q[c * r + k] * res[k]).sum())
                .collect();
            for c in (0..s).rev() {
                let tail: f64 = (c + 1..s).map(|p| rm[c * s + p] * dx[p]).sum();
                dx[c] = (dx[c] - tail) / rm[c * s + c];
            }
            x.iter_mut().zip(&dx).for_each(|(x, d)| *x += d);
        }
        x.iter().all(|v| v.is_finite()).then_some(x)
    }

    /// max_j |Σ_t x_t f_j(z_{B_t}) − b̄_j| / max(σ_j, CANCEL · Σ_t x_t |f_j(z_{B_t})|) over
    /// every row (independent or not).
    fn moment_residual(&self, basis: &[usize]) -> f64 {
        let r = self.rows.len();
        (0..=self.m)
            .map(|j| {
                let terms = (0..r).map(|t| (self.entry(j, basis[t]), self.x[t]));
                let mag: f64 = (0..r)
                    .map(|t| (self.entry(j, basis[t]) * self.x[t]).abs())
                    .sum();
                residual2(self.bbar[j], terms).abs() / self.sigma[j].max(CANCEL * mag)
            })
            .fold(0.0, f64::max)
    }
}

#[cfg(test)]
mod tests;
