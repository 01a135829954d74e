//! The last resort of Algorithm 1: a primal simplex in exact integer arithmetic on the LP
//! exactly as given (the f64 grid table and the f64 moments), for the problems no basis
//! certifies in floating point.
//!
//! Those are ill-posed at f64 resolution (power bases of degree ≥ 8 on clusters and flat
//! receivers): the sharp bound moves by up to 1e-2 while the moments move by 1e-9, so no
//! tolerance-based certificate can settle them. The exact LP has one answer, and this module
//! finds it with its certificate: an optimal basis whose weights reproduce b̄ exactly and
//! whose reduced costs are exactly ≥ 0 (gap 0), or a Farkas ray y with y·ā_i ≤ 0 for every
//! grid point and y·b̄ > 0 (no distribution on the grid has exactly these moments).
//!
//! Every f64 is an integer times a power of two, so row j scaled by 2^(−E_j) (E_j the
//! smallest exponent in the row and b̄_j) is an integer row; scaling rows does not change
//! the LP. The basis inverse is kept fraction-free, adj = D·B⁻¹ with D = ±det B, and updated
//! per pivot with exact divisions (adj′_i = (α_p adj_i − α_i adj_p)/D, D′ = α_p, α = adj·a_q).
//! Reduced costs are priced in double-double with a rounding bound and decided exactly
//! wherever the bound leaves their sign open. The start is the escalation's last basis (usually
//! exactly optimal already, or a few dual pivots away), else the distribution's support; phase
//! 1, with one artificial column (the negative part of the start's solution), is the last step.

#![allow(clippy::needless_range_loop)] // exact dense linear algebra on r ≤ 13

use crate::lp::certify::Certifier;
use crate::lp::dense::Dd;
use num_bigint::{BigInt, Sign};
use num_integer::Integer;
use num_traits::{Signed, ToPrimitive, Zero};

/// Primal pivots per phase before the exact simplex gives up.
const MAX_PIVOTS: usize = 400;
/// Dual pivots tried before phase 1.
const MAX_DUAL_PIVOTS: usize = 16;
/// Per row of a dot product, the relative error bound (of Σ_k |v_k ā_ki|) of an f64 dot
/// product against the double-double one of the same values ([`ExactSimplex::dots_f64`]):
/// 4ε per term covers γ_r, the dropped low parts and the rounding of the bounds themselves.
const F64_DOT_BOUND: f64 = 4.0 * f64::EPSILON;
/// Largest number of rows handled (the work grows as r³ in numbers of r·(53 + span) bits).
const MAX_ROWS: usize = 24;

/// What the exact simplex found.
#[derive(Clone, Debug, PartialEq)]
pub(in crate::lp::fast) enum ExactAnswer {
    /// An exactly optimal basis: `g` and the weights are the exact values rounded to f64.
    Optimal {
        /// The basis (grid indices).
        basis: Vec<usize>,
        /// G rounded to f64.
        g: f64,
        /// (grid index, weight) of the positive weights.
        weights: Vec<(usize, f64)>,
    },
    /// Exactly infeasible, with the Farkas ray y (per row, as f64) of phase 1.
    Infeasible(Vec<f64>),
    /// Not settled (singular start, pivot cap, dependent rows): why.
    Failed(String),
}

/// `v` as (odd integer, exponent): v = m·2^e exactly (None for 0).
fn split(v: f64) -> Option<(i64, i32)> {
    if v == 0.0 {
        return None;
    }
    let bits = v.to_bits();
    let exp = ((bits >> 52) & 0x7ff) as i32;
    let frac = (bits & ((1u64 << 52) - 1)) as i64;
    let (mut m, mut e) = if exp == 0 {
        (frac, -1074)
    } else {
        (frac | (1i64 << 52), exp - 1075)
    };
    let tz = m.trailing_zeros() as i32;
    m >>= tz;
    e += tz;
    Some((if v < 0.0 { -m } else { m }, e))
}

/// v·2^(−shift) as an integer (exact: shift ≤ the exponent of v).
fn to_int(v: f64, shift: i32) -> BigInt {
    match split(v) {
        None => BigInt::zero(),
        Some((m, e)) => BigInt::from(m) << ((e - shift) as usize),
    }
}

/// p/q rounded to f64 (to within one unit in the last place; q ≠ 0).
pub(super) fn ratio_f64(p: &BigInt, q: &BigInt) -> f64 {
    if p.is_zero() {
        return 0.0;
    }
    let neg = (p.sign() == Sign::Minus) != (q.sign() == Sign::Minus);
    let (pa, qa) = (p.abs(), q.abs());
    // Quotient with 64–65 significant bits, then the power of two.
    let k = pa.bits() as i64 - qa.bits() as i64 - 65;
    let quot = if k >= 0 {
        &pa / (&qa << (k as usize))
    } else {
        (&pa << ((-k) as usize)) / &qa
    };
    let v = ldexp(quot.to_f64().unwrap_or(f64::INFINITY), k);
    if neg {
        -v
    } else {
        v
    }
}

/// x·2^k without intermediate overflow.
fn ldexp(mut x: f64, mut k: i64) -> f64 {
    while k > 1000 {
        x *= 2f64.powi(1000);
        k -= 1000;
    }
    while k < -1000 {
        x *= 2f64.powi(-1000);
        k += 1000;
    }
    x * 2f64.powi(k as i32)
}

/// Fraction-free Gauss–Jordan (Bareiss) on [M | I]: (adj, D) with M·adj = D·I and D = ±det M;
/// None when M is singular. `m` is row-major r × r.
pub(super) fn adjugate(m: &[BigInt], r: usize) -> Option<(Vec<BigInt>, BigInt)> {
    let w = 2 * r;
    let mut a = vec![BigInt::zero(); r * w];
    for i in 0..r {
        for j in 0..r {
            a[i * w + j] = m[i * r + j].clone();
        }
        a[i * w + r + i] = BigInt::from(1);
    }
    let mut prev = BigInt::from(1);
    for k in 0..r {
        let p = (k..r).find(|&i| !a[i * w + k].is_zero())?;
        if p != k {
            for j in 0..w {
                a.swap(p * w + j, k * w + j);
            }
        }
        let piv = a[k * w + k].clone();
        for i in (0..r).filter(|&i| i != k) {
            let f = a[i * w + k].clone();
            for j in 0..w {
                let (v, rem) = (&piv * &a[i * w + j] - &f * &a[k * w + j]).div_rem(&prev);
                if !rem.is_zero() {
                    return None;
                }
                a[i * w + j] = v;
            }
        }
        prev = piv;
    }
    // Every diagonal entry is now D = ±det M; the right half is D·M⁻¹.
    let d = a[0].clone();
    let adj = (0..r)
        .flat_map(|i| a[i * w + r..(i + 1) * w].to_vec())
        .collect();
    (0..r).all(|i| a[i * w + i] == d).then_some((adj, d))
}

/// The exact simplex on one problem (the moments last given to the certifier).
pub(in crate::lp::fast) struct ExactSimplex<'a> {
    cert: &'a Certifier,
    n: usize,
    r: usize,
    /// Row exponents E_j: row j of the integer LP is row j of the f64 LP times 2^(−E_j).
    shift: Vec<i32>,
    b: Vec<BigInt>,
    /// Grid indices, or n for the artificial column.
    basis: Vec<usize>,
    art: Vec<BigInt>,
    /// adj = D·B⁻¹ (row-major r × r).
    adj: Vec<BigInt>,
    d: BigInt,
    /// adj·b̄: the basic weights times D.
    x: Vec<BigInt>,
    /// 1 for the grid points below z_f (phase 2), or for the artificial (phase 1).
    kf: usize,
    phase1: bool,
    /// Pivots over the solver's lifetime.
    pub pivots: usize,
}

impl<'a> ExactSimplex<'a> {
    /// The integer LP for the certifier's table with kf grid points below z_f. Its right-hand
    /// side is the moments last given to the certifier ([`Certifier::set_moments`]), or, with
    /// `dist` = [(grid index, weight)], the exact moments of that distribution: Σ w_i ā_i / Σ w_i
    /// in rationals, not rounded to f64 (every row scaled by Σ w_i). None when the certifier's
    /// square bases do not use every row (then the exact LP is not the one its bases describe).
    pub(in crate::lp::fast) fn new(
        cert: &'a Certifier,
        kf: usize,
        dist: Option<&[(u32, f64)]>,
    ) -> Option<ExactSimplex<'a>> {
        let (n, m) = (cert.n(), cert.m());
        let r = m + 1;
        if cert.rows().len() != r || r > MAX_ROWS {
            return None;
        }
        let mut shift = vec![0i32; r];
        for j in 0..r {
            let mut e = match dist {
                Some(_) => i32::MAX,
                None => split(cert.bbar(j)).map_or(i32::MAX, |s| s.1),
            };
            for i in 0..n {
                if let Some((_, ei)) = split(cert.entry(j, i)) {
                    e = e.min(ei);
                }
            }
            shift[j] = if e == i32::MAX { 0 } else { e };
        }
        let b = match dist {
            None => (0..r).map(|j| to_int(cert.bbar(j), shift[j])).collect(),
            Some(dist) => {
                let ew = dist.iter().filter_map(|e| split(e.1)).map(|s| s.1).min()?;
                let mut b = vec![BigInt::zero(); r];
                for &(i, w) in dist {
                    if w < 0.0 || !w.is_finite() || i as usize >= n {
                        return None;
                    }
                    let w = to_int(w, ew);
                    for (j, bj) in b.iter_mut().enumerate() {
                        *bj += &w * to_int(cert.entry(j, i as usize), shift[j]);
                    }
                }
                b
            }
        };
        Some(ExactSimplex {
            cert,
            n,
            r,
            shift,
            b,
            basis: Vec::new(),
            art: Vec::new(),
            adj: Vec::new(),
            d: BigInt::zero(),
            x: Vec::new(),
            kf,
            phase1: false,
            pivots: 0,
        })
    }

    /// Integer column of grid point i (or of the artificial, i = n).
    fn column(&self, i: usize) -> Vec<BigInt> {
        if i == self.n {
            return self.art.clone();
        }
        (0..self.r)
            .map(|j| to_int(self.cert.entry(j, i), self.shift[j]))
            .collect()
    }

    fn cost(&self, i: usize) -> bool {
        if self.phase1 {
            i == self.n
        } else {
            i < self.kf
        }
    }

    /// adj·v.
    fn times_adj(&self, v: &[BigInt]) -> Vec<BigInt> {
        let r = self.r;
        (0..r)
            .map(|t| (0..r).map(|k| &self.adj[t * r + k] * &v[k]).sum())
            .collect()
    }

    /// Factorise `start` (grid indices, one per row); false when it is singular.
    fn load(&mut self, start: &[usize]) -> bool {
        let r = self.r;
        if start.len() != r || start.iter().any(|&i| i >= self.n) {
            return false;
        }
        self.basis = start.to_vec();
        let cols: Vec<Vec<BigInt>> = start.iter().map(|&i| self.column(i)).collect();
        let bm: Vec<BigInt> = (0..r * r).map(|e| cols[e % r][e / r].clone()).collect();
        let Some((adj, d)) = adjugate(&bm, r) else {
            return false;
        };
        self.adj = adj;
        self.d = d;
        self.x = self.times_adj(&self.b);
        true
    }

    /// Solve from the first of `starts` (bases: grid indices, one per row) that is primal
    /// feasible; else from the first nonsingular one, made feasible by dual pivots or, failing
    /// those, by phase 1.
    pub(in crate::lp::fast) fn solve(&mut self, starts: &[&[usize]]) -> ExactAnswer {
        match self.feasible_start(starts) {
            Ok(true) => match self.run() {
                Ok(()) => self.optimal(),
                Err(e) => ExactAnswer::Failed(e),
            },
            Ok(false) => ExactAnswer::Infeasible(self.duals().iter().map(|y| y.0).collect()),
            Err(e) => ExactAnswer::Failed(e),
        }
    }

    /// A primal feasible basis loaded (true), or phase 1 proved the moments infeasible
    /// (false, the phase-1 basis loaded). Each start in turn is taken as it is when feasible,
    /// else after dual pivots; phase 1 runs from the first nonsingular start.
    fn feasible_start(&mut self, starts: &[&[usize]]) -> Result<bool, String> {
        let mut first = None;
        for b in starts {
            if !self.load(b) {
                continue;
            }
            first = first.or(Some(b));
            if self.dual_phase()? {
                return Ok(true);
            }
        }
        let first = first.ok_or("exact simplex: no nonsingular start basis")?;
        self.load(first);
        self.phase_one()?;
        Ok(!self.phase1)
    }

    /// Basic weight t is negative (x_t/D < 0).
    fn negative(&self, t: usize) -> bool {
        !self.x[t].is_zero() && (self.x[t].sign() != self.d.sign())
    }

    /// Phase 1 with one artificial column g = D·Σ_{x_t<0} x_t a_t (sign-adjusted so that its
    /// weight 1/|D| is positive) in place of the first negative basic column; minimises that
    /// weight. Leaves `phase1` set iff the minimum is positive (infeasible).
    fn phase_one(&mut self) -> Result<(), String> {
        let r = self.r;
        let neg: Vec<usize> = (0..r).filter(|&t| self.negative(t)).collect();
        let Some(&p) = neg.first() else {
            return Ok(());
        };
        let mut g = vec![BigInt::zero(); r];
        for &t in &neg {
            let col = self.column(self.basis[t]);
            for k in 0..r {
                g[k] += &self.x[t] * &col[k];
            }
        }
        if self.d.is_negative() {
            g.iter_mut().for_each(|v| *v = -&*v);
        }
        self.art = g;
        let alpha = self.times_adj(&self.art);
        self.pivot(p, self.n, &alpha)?;
        self.phase1 = true;
        self.run()?;
        let t = self.basis.iter().position(|&i| i == self.n);
        match t {
            Some(t) if !self.x[t].is_zero() => Ok(()),
            Some(t) => {
                // Feasible, the artificial basic at 0: exchange it for any column with a
                // nonzero entry in its row (a degenerate pivot).
                let row: Vec<BigInt> = self.adj[t * r..(t + 1) * r].to_vec();
                let q = (0..self.n)
                    .filter(|i| !self.basis.contains(i))
                    .find(|&i| {
                        let c = self.column(i);
                        !(0..r).map(|k| &row[k] * &c[k]).sum::<BigInt>().is_zero()
                    })
                    .ok_or("exact simplex: the artificial cannot leave the basis")?;
                let alpha = self.times_adj(&self.column(q));
                self.pivot(t, q, &alpha)?;
                self.phase1 = false;
                Ok(())
            }
            None => {
                self.phase1 = false;
                Ok(())
            }
        }
    }

    /// Exchange basic row p for column q (α = adj·a_q). Every division is exact (checked).
    fn pivot(&mut self, p: usize, q: usize, alpha: &[BigInt]) -> Result<(), String> {
        let r = self.r;
        let ap = alpha[p].clone();
        let exact = |v: BigInt, d: &BigInt| -> Result<BigInt, String> {
            let (q, rem) = v.div_rem(d);
            if rem.is_zero() {
                Ok(q)
            } else {
                Err("exact simplex: inexact division (internal error)".into())
            }
        };
        for i in (0..r).filter(|&i| i != p) {
            for k in 0..r {
                let mut v = &ap * &self.adj[i * r + k];
                if !alpha[i].is_zero() {
                    v -= &alpha[i] * &self.adj[p * r + k];
                }
                self.adj[i * r + k] = exact(v, &self.d)?;
            }
            let mut v = &ap * &self.x[i];
            if !alpha[i].is_zero() {
                v -= &alpha[i] * &self.x[p];
            }
            self.x[i] = exact(v, &self.d)?;
        }
        self.d = ap;
        self.basis[p] = q;
        self.pivots += 1;
        Ok(())
    }

    /// The dual numerators Y = c_Bᵀ adj (y = Y/D).
    fn dual_numerators(&self) -> Vec<BigInt> {
        let r = self.r;
        let mut y = vec![BigInt::zero(); r];
        for t in 0..r {
            if self.cost(self.basis[t]) {
                for k in 0..r {
                    y[k] += &self.adj[t * r + k];
                }
            }
        }
        y
    }

    /// num/D·2^(−E_k) (a dual or basis-inverse entry of row k in the original rows) as a
    /// double-double number.
    fn dd_ratio(&self, num: &BigInt, k: usize) -> Dd {
        let d = &self.d;
        let hi = ratio_f64(num, d);
        // lo = (num − hi·D)/D, with hi = m·2^e exactly.
        let lo = match split(hi) {
            None => 0.0,
            Some((m, e)) if e >= 0 => ratio_f64(&(num - ((d * m) << e as usize)), d),
            Some((m, e)) => {
                let s = (-e) as usize;
                ratio_f64(&((num << s) - d * m), &(d << s))
            }
        };
        let sh = -(self.shift[k] as i64);
        Dd(ldexp(hi, sh), ldexp(lo, sh))
    }

    /// The duals in the original (unscaled) rows, as double-double numbers.
    fn duals(&self) -> Vec<Dd> {
        let y = self.dual_numerators();
        (0..self.r).map(|k| self.dd_ratio(&y[k], k)).collect()
    }

    /// v·a_i in double-double (v per original row), and Σ_k |v_k a_ki|.
    fn dot(&self, v: &[Dd], i: usize) -> (Dd, f64) {
        let mut s = Dd::from(0.0);
        let mut mag = 0.0;
        for (k, vk) in v.iter().enumerate() {
            let t = vk.mul(Dd::from(self.cert.entry(k, i)));
            s = s.add(t);
            mag += t.0.abs();
        }
        (s, mag)
    }

    /// v·ā_i and Σ_k |v_k ā_ki| in f64 for every grid point i (v per original row), into
    /// `dot` and `mag`. Against the double-double [`Self::dot`] of the values whose high parts
    /// are v: |fl(v·ā_i) − v·ā_i| ≤ γ_r Σ_k |v_k ā_ki| (γ_r = rε/(1 − rε)), and the low parts
    /// move the sum by at most ε/2 of the same magnitude; [`F64_DOT_BOUND`] covers both.
    fn dots_f64(&self, v: &[f64], dot: &mut Vec<f64>, mag: &mut Vec<f64>) {
        dot.clear();
        dot.resize(self.n, v[0]);
        mag.clear();
        mag.resize(self.n, v[0].abs());
        for (k, &vk) in v.iter().enumerate().skip(1) {
            let row = self.cert.function_row(k).expect("rows 1.. are functions");
            for ((d, m), &e) in dot.iter_mut().zip(mag.iter_mut()).zip(row) {
                let t = vk * e;
                *d += t;
                *m += t.abs();
            }
        }
    }

    /// The leaving row: the most negative basic weight (None when the basis is feasible).
    fn most_negative(&self) -> Option<usize> {
        (0..self.r).filter(|&t| self.negative(t)).min_by(|&a, &b| {
            ratio_f64(&self.x[a], &self.d).total_cmp(&ratio_f64(&self.x[b], &self.d))
        })
    }

    /// Dual simplex pivots from a basis whose weights are (slightly) negative: the most
    /// negative weight leaves, the column of the smallest ratio d_i/|α_i| over α_i < 0 (row of
    /// B⁻¹A, both in double-double; see [`Self::dual_entering`]) enters. True once the basis
    /// is primal feasible; false when no pivot is found within the budget (the caller then
    /// tries the next start, and finally phase 1). The ratio test only steers: optimality is
    /// decided exactly by the primal phase afterwards.
    fn dual_phase(&mut self) -> Result<bool, String> {
        for _ in 0..MAX_DUAL_PIVOTS {
            let Some(p) = self.most_negative() else {
                return Ok(true);
            };
            let Some(q) = self.dual_entering(p) else {
                return Ok(false);
            };
            let alpha = self.times_adj(&self.column(q));
            if alpha[p].is_zero() || alpha[p].sign() == self.d.sign() {
                return Ok(false);
            }
            self.pivot(p, q, &alpha)?;
        }
        Ok(false)
    }

    /// The entering column of a dual pivot on row p: the first grid index of the least ratio
    /// ρ_i = max(d_i, 0)/(−α_i) over the non-basic columns with α_i < −10⁻²⁰ Σ_k |ρ_k ā_ki|
    /// (α_i = (row p of B⁻¹)·ā_i and d_i = c_i − y·ā_i formed in double-double, ρ_i rounded to
    /// f64), as [`Self::dual_entering_dd`] defines it. Every column is first bounded in f64
    /// ([`Self::dots_f64`]): α_i ∈ [α̃_i − δ_α, α̃_i + δ_α], d_i ∈ [d̃_i − δ_d, d̃_i + δ_d], hence
    /// ρ_i ∈ [lo_i, hi_i]. A column with α̃_i − δ_α ≥ 0 cannot enter; H = min hi_i over the
    /// columns certain to qualify bounds the least ratio, so only the columns with lo_i ≤ H
    /// (and those whose f64 values are not finite) are formed in double-double, in grid
    /// order, with the same comparisons: the same column enters.
    fn dual_entering(&self, p: usize) -> Option<usize> {
        let (r, n) = (self.r, self.n);
        let y = self.duals();
        let row: Vec<Dd> = (0..r)
            .map(|k| self.dd_ratio(&self.adj[p * r + k], k))
            .collect();
        let hi_parts = |v: &[Dd]| v.iter().map(|e| e.0).collect::<Vec<f64>>();
        let (mut af, mut am, mut yf, mut ym) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
        self.dots_f64(&hi_parts(&row), &mut af, &mut am);
        self.dots_f64(&hi_parts(&y), &mut yf, &mut ym);
        let mut basic = vec![false; n];
        self.basis
            .iter()
            .filter(|&&i| i < n)
            .for_each(|&i| basic[i] = true);
        let (rel, eps) = (F64_DOT_BOUND * (r as f64 + 4.0), f64::EPSILON);
        // lo_i, or NaN for a column that cannot enter, −∞ for one the f64 values cannot bound.
        let mut lo = vec![f64::NAN; n];
        let mut h = f64::INFINITY;
        for i in (0..n).filter(|&i| !basic[i]) {
            let c = if self.cost(i) { 1.0 } else { 0.0 };
            let (a, d) = (af[i], c - yf[i]);
            if !(a.is_finite() && d.is_finite() && am[i] < 1e300 && ym[i] < 1e300) {
                lo[i] = f64::NEG_INFINITY;
                continue;
            }
            let da = rel * am[i] + 1e-300;
            if a - da >= 0.0 {
                continue;
            }
            let dd = rel * (ym[i] + c) + 1e-300;
            lo[i] = (d - dd).max(0.0) / (-a + da) * (1.0 - 8.0 * eps);
            let den = -a - da;
            if den > 2e-20 * am[i] {
                h = h.min((d + dd).max(0.0) / den * (1.0 + 8.0 * eps));
            }
        }
        let mut best: Option<(usize, f64)> = None;
        for i in (0..n).filter(|&i| lo[i] <= h) {
            let (a, amag) = self.dot(&row, i);
            if a.0 >= -1e-20 * amag {
                continue;
            }
            let (yd, _) = self.dot(&y, i);
            let d = (if self.cost(i) { 1.0 } else { 0.0 }) - yd.0 - yd.1;
            let ratio = d.max(0.0) / -a.0;
            if best.is_none_or(|(_, b)| ratio < b) {
                best = Some((i, ratio));
            }
        }
        best.map(|e| e.0)
    }

    /// [`Self::dual_entering`] by its definition: every non-basic column in double-double.
    #[cfg(test)]
    fn dual_entering_dd(&self, p: usize) -> Option<usize> {
        let r = self.r;
        let y = self.duals();
        let row: Vec<Dd> = (0..r)
            .map(|k| self.dd_ratio(&self.adj[p * r + k], k))
            .collect();
        let mut best: Option<(usize, f64)> = None;
        for i in (0..self.n).filter(|i| !self.basis.contains(i)) {
            let (a, amag) = self.dot(&row, i);
            if a.0 >= -1e-20 * amag {
                continue;
            }
            let (yd, _) = self.dot(&y, i);
            let d = (if self.cost(i) { 1.0 } else { 0.0 }) - yd.0 - yd.1;
            let ratio = d.max(0.0) / -a.0;
            if best.is_none_or(|(_, b)| ratio < b) {
                best = Some((i, ratio));
            }
        }
        best.map(|e| e.0)
    }

    /// Exact sign of the reduced cost c_i − y·a_i (D·d_i = c_i D − Y·a_i).
    fn reduced_negative(&self, i: usize, y: &[BigInt]) -> bool {
        let col = self.column(i);
        let mut v: BigInt = if self.cost(i) {
            self.d.clone()
        } else {
            BigInt::zero()
        };
        for k in 0..self.r {
            v -= &y[k] * &col[k];
        }
        !v.is_zero() && v.sign() != self.d.sign()
    }

    /// Columns whose reduced cost may be negative, most negative first (Dantzig's rule). The
    /// reduced costs are computed in double-double from the duals rounded to double-double
    /// (relative error ≤ 2ε² each): a column is left out only when its reduced cost exceeds
    /// that rounding bound, i.e. is certainly positive; the order is only a guide, the exact
    /// test decides. The columns whose f64 reduced cost exceeds the bound by more than its f64
    /// error ([`ExactSimplex::dots_f64`]) are left out without the double-double product.
    fn candidates(&self) -> Vec<usize> {
        let y = self.duals();
        let bound = 16.0 * (self.r as f64 + 4.0) * f64::EPSILON * f64::EPSILON;
        let (mut yf, mut ym) = (Vec::new(), Vec::new());
        self.dots_f64(
            &y.iter().map(|e| e.0).collect::<Vec<f64>>(),
            &mut yf,
            &mut ym,
        );
        let rel = F64_DOT_BOUND * (self.r as f64 + 4.0);
        let mut out: Vec<(usize, f64)> = Vec::new();
        for i in (0..self.n).filter(|i| !self.basis.contains(i)) {
            let c = if self.cost(i) { 1.0 } else { 0.0 };
            // f64 first (see `dots_f64`): a reduced cost above the bound by more than the f64
            // error is above it in double-double too.
            let s = c - yf[i];
            if s.is_finite()
                && ym[i] < 1e300
                && s - rel * (ym[i] + c) > bound * (ym[i] * (1.0 + 1e-10) + c) + 1e-300
            {
                continue;
            }
            let (yd, mag) = self.dot(&y, i);
            let s = Dd::from(c).add(yd.neg());
            if !s.0.is_finite() || s.0 <= bound * (mag + c) + 1e-300 {
                out.push((i, s.0));
            }
        }
        out.sort_by(|a, b| a.1.total_cmp(&b.1));
        out.into_iter().map(|e| e.0).collect()
    }

    /// Primal simplex from a feasible basis until no reduced cost is negative. Dantzig's rule
    /// with Bland's tie-break in the ratio test; degenerate pivots could in principle cycle,
    /// which the pivot cap turns into `Failed` (never a wrong answer). Bland's entering rule
    /// is not used: on these LPs it slides a zero-weight atom one grid point per pivot.
    fn run(&mut self) -> Result<(), String> {
        let cap = self.pivots + MAX_PIVOTS;
        loop {
            if self.pivots >= cap {
                return Err(format!(
                    "exact simplex: no optimum after {MAX_PIVOTS} pivots"
                ));
            }
            let y = self.dual_numerators();
            let Some(q) = self
                .candidates()
                .into_iter()
                .find(|&i| self.reduced_negative(i, &y))
            else {
                return Ok(());
            };
            let alpha = self.times_adj(&self.column(q));
            let p = self
                .ratio_test(&alpha)
                .ok_or("exact simplex: unbounded (the constant row is missing)")?;
            self.pivot(p, q, &alpha)?;
        }
    }

    /// The leaving row: the smallest ratio x_t/α_t over α_t/D > 0, ties to the artificial and
    /// then the smallest grid index (Bland).
    fn ratio_test(&self, alpha: &[BigInt]) -> Option<usize> {
        let mut best: Option<usize> = None;
        for t in 0..self.r {
            if alpha[t].is_zero() || alpha[t].sign() != self.d.sign() {
                continue;
            }
            best = match best {
                None => Some(t),
                Some(s) => {
                    // x_t/α_t vs x_s/α_s, both with α of D's sign: α_t·α_s > 0.
                    let lhs = &self.x[t] * &alpha[s];
                    let rhs = &self.x[s] * &alpha[t];
                    let key = |u: usize| {
                        if self.basis[u] == self.n {
                            0
                        } else {
                            self.basis[u] + 1
                        }
                    };
                    if lhs < rhs || (lhs == rhs && key(t) < key(s)) {
                        Some(t)
                    } else {
                        Some(s)
                    }
                }
            };
        }
        best
    }

    /// The basic solution, normalised by its total mass b̄_0 (1, or Σ w_i of a distribution).
    fn optimal(&self) -> ExactAnswer {
        let den = &self.d * &self.b[0];
        let mut num = BigInt::zero();
        let mut weights = Vec::new();
        for t in 0..self.r {
            let i = self.basis[t];
            if self.x[t].is_zero() {
                continue;
            }
            if i < self.kf {
                num += &self.x[t];
            }
            weights.push((i, ratio_f64(&self.x[t], &den)));
        }
        weights.sort_by_key(|e| e.0);
        ExactAnswer::Optimal {
            basis: self.basis.clone(),
            g: ratio_f64(&num, &den),
            weights,
        }
    }
}

#[cfg(test)]
pub(in crate::lp::fast) mod tests;
