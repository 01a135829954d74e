//! The weak-duality bound of a certificate: the duals of the row-scaled basis, the reduced
//! costs d_i = p_i − y·ā_i over the grid with their rounding bounds e_i (f64 in blocks, with
//! double-double rechecks where a block is close), and L = y·b̄ + min(0, min_i d_i) lowered by
//! the rounding bound.

use super::*;

impl Certifier {
    /// Duals ỹ of the row-scaled basis: B̃ᵀ ỹ = p_B, refined twice; stored unscaled in y.
    pub(super) fn dual(&mut self, basis: &[usize], kf: usize) {
        let r = self.rows.len();
        // Mᵀ ỹ = K p_B (M = B̃ K).
        // Taken out for the closure below (no copy) and put back at the end.
        let colscale = std::mem::take(&mut self.colscale);
        let cost = |t: usize| (basis[t] < kf) as u8 as f64 * colscale[t];
        for t in 0..r {
            self.y[t] = cost(t);
        }
        self.solve(true, Which::Y);
        for step in 0..3 {
            for t in 0..r {
                let terms = (0..r).map(|k| (self.a[k * r + t], self.y[k]));
                self.tmp[t] = residual2(cost(t), terms);
            }
            self.solve(true, Which::Tmp);
            // The last correction is kept apart: y + ylo in double-double. Near the boundary of
            // the moment space |y| reaches 1e9, and the f64 y alone leaves reduced costs of
            // ε|y| ≈ 1e-7 on the basis columns. A correction that leaves y unchanged would be
            // found again by the next passes: it is the low part at once.
            let still = step < 2 && (0..r).all(|k| self.y[k] + self.tmp[k] == self.y[k]);
            if step == 2 || still {
                self.ylo[..r].copy_from_slice(&self.tmp[..r]);
                break;
            }
            for k in 0..r {
                self.y[k] += self.tmp[k];
            }
        }
        for k in 0..r {
            self.y[k] *= self.scale[self.rows[k]];
            self.ylo[k] *= self.scale[self.rows[k]];
        }
        self.colscale = colscale;
    }

    /// (y·ρ, whether every ρ_k is rounding-level) with ρ_k = Σ_t x_t ā_{j_k}(z_{B_t}) − b̄_{j_k}
    /// the support's residual on each independent row (double-double) and y + y_lo the
    /// unscaled duals. Rounding-level: |ρ_k| ≤ [`ULPS`] ε (|b̄_j| + Σ_t |x_t ā_jt|), so b̄ + ρ is
    /// indistinguishable from b̄ in f64.
    pub(super) fn dual_shift(&self, basis: &[usize]) -> (f64, bool) {
        let r = self.rows.len();
        let (mut shift, mut ulp) = (0.0, true);
        for k in 0..r {
            let j = self.rows[k];
            let terms = (0..r).map(|t| (self.entry(j, basis[t]), self.x[t]));
            let rho = -residual2(self.bbar[j], terms);
            let mag: f64 = self.bbar[j].abs()
                + (0..r)
                    .map(|t| (self.entry(j, basis[t]) * self.x[t]).abs())
                    .sum::<f64>();
            ulp &= rho.abs() <= ULPS * f64::EPSILON * mag;
            shift += (self.y[k] + self.ylo[k]) * rho;
        }
        (shift, ulp)
    }

    /// L = y·b̄ + min(0, min_i d_i) for the duals in y; or, as soon as the f64 reduced costs
    /// show L < `stop` (some u_i·(d_i + γ e_i) alone brings the bound below it), an upper
    /// bound on L below `stop`, without the double-double pass (the duals are then not kept
    /// as fresh).
    pub(super) fn lower_bound(&mut self, kf: usize, stop: f64) -> f64 {
        let r = self.rows.len();
        let y = std::mem::take(&mut self.y);
        let bb = |k: usize| self.bbar[self.rows[k]];
        let terms = (0..r)
            .map(|k| (y[k], bb(k)))
            .chain((0..r).map(|k| (self.ylo[k], bb(k))));
        let yb = -residual2(0.0, terms);
        let rest = self.reduced_until(&y, Some(kf), stop - yb);
        self.y = y;
        if let Some(upper) = rest {
            return yb + upper;
        }
        self.duals_fresh = true;
        yb + self.min_lower().min(0.0).max(self.capped_lower())
    }

    /// Σ_i u_i min(0, d_i − γ e_i) with u_i = min(1, min_j b_j / f_j(z_i)) over the rows whose
    /// function does not change sign (every exactly feasible w has w_i ≤ u_i): a lower bound on
    /// Σ_i w_i d_i that stays tight where huge columns (a steep exponential near its peak) can
    /// only carry tiny weights.
    pub(super) fn capped_lower(&self) -> f64 {
        debug_assert!(self.flagged_ok);
        let mut sum = 0.0;
        for (lo, hi) in self.flagged_blocks() {
            for (i, v) in row_kernels::below(&self.d[lo..hi], &self.e[lo..hi], self.gamma) {
                sum += self.cap(lo + i) * v;
            }
        }
        sum
    }

    /// d_i = p_i − y·ā_i (p = 0 when `kf` is None) and the magnitudes e_i = |p_i| + Σ|y_j ā_ji|.
    pub(super) fn reduced(&mut self, y: &[f64], kf: Option<usize>) {
        self.reduced_until(y, kf, f64::NEG_INFINITY);
    }

    /// [`Self::reduced`], unless the f64 pass already shows a point i with
    /// u_i·(d_i + γ e_i) < `stop` < 0 (an upper bound on its term of either lower bound on
    /// Σ_i w_i d_i): then that value, with d left in f64 (no double-double recheck).
    pub(super) fn reduced_until(&mut self, y: &[f64], kf: Option<usize>, stop: f64) -> Option<f64> {
        let n = self.n;
        let ylo = &self.ylo;
        // |ylo_k| ≤ τ |y_k|: the f64 pass below (high parts only) is within (γ + τ) e_i.
        let tau = y.iter().zip(ylo).fold(0.0f64, |t, (h, l)| {
            if *l == 0.0 {
                t
            } else if *h == 0.0 {
                f64::INFINITY
            } else {
                t.max((l / h).abs())
            }
        });
        self.gamma = GAMMA + 2.0 * tau;
        // Farkas: d holds y·ā_i (the sign is flipped at the end).
        let k = kf.unwrap_or(0).min(n);
        let (d, e, flagged) = (&mut self.d, &mut self.e, &mut self.flagged);
        let (fcols, offs) = (&self.fcols, &self.offs);
        let (ys, gamma) = (&y[1..], self.gamma);
        // e_i ≤ E = 1 + |y₀| + Σ_k |y_k| max_i |f_k(z_i)| (with room for rounding): e is only
        // needed where d_i < γ E. The Farkas check reads e everywhere.
        let ebound = kf.map(|_| {
            let rows = &self.rows[1..];
            let sum: f64 = ys
                .iter()
                .zip(rows)
                .map(|(y, &j)| y.abs() * self.fmax[j])
                .sum();
            (1.0 + y[0].abs() + sum) * (1.0 + 1e-9)
        });
        row_kernels::reduced_costs(
            d,
            e,
            (k, y[0]),
            ys,
            fcols,
            offs,
            (gamma, ebound),
            flagged,
            self.avx512,
        );
        self.flagged_ok = kf.is_some();
        if let Some(upper) = self.clearly_below(stop) {
            return Some(upper);
        }
        self.recheck(y, k);
        if kf.is_none() {
            self.d.iter_mut().for_each(|v| *v = -*v);
        }
        None
    }

    /// After the f64 pass (`flagged_ok`): u_i·(d_i + γ e_i) at the point of least
    /// d_i + γ e_i, if that is below `stop` < 0.
    pub(super) fn clearly_below(&self, stop: f64) -> Option<f64> {
        if stop.is_nan() || stop >= 0.0 || !self.flagged_ok {
            return None;
        }
        let (mut at, mut least) = (usize::MAX, 0.0f64);
        for (lo, hi) in self.flagged_blocks() {
            for i in lo..hi {
                let high = self.d[i] + self.gamma * self.e[i];
                if high < least {
                    (at, least) = (i, high);
                }
            }
        }
        let upper = (at != usize::MAX).then(|| self.cap(at) * least)?;
        (upper < stop).then_some(upper)
    }

    /// In the flagged blocks, where the f64 rounding bound could hide a negative value: d_i
    /// in double-double (error ≤ 2ε|d| + O(ε²) e; the huge duals of clustered bases cancel to
    /// 1e-7 in f64), with the bound e_i shrunk to match. A block with [`BLOCK_DD`] or more such
    /// points is recomputed whole, vectorised (the same bits).
    pub(super) fn recheck(&mut self, y: &[f64], kf: usize) {
        let (n, r, gamma) = (self.n, self.rows.len(), self.gamma);
        let mut block = [0.0; row_kernels::BLOCK];
        for b in 0..self.flagged.len() {
            let lo = self.flagged[b];
            let hi = (lo + row_kernels::BLOCK).min(n);
            let open = |c: &Self, i: usize| c.d[i] - gamma * c.e[i] < 0.0;
            let count = (lo..hi).filter(|&i| open(self, i)).count();
            let whole = count >= BLOCK_DD && hi - lo == row_kernels::BLOCK;
            if whole {
                let (fcols, offs) = (&self.fcols, &self.offs);
                let (y, ylo) = (&y[..r], &self.ylo[..r]);
                row_kernels::reduced_dd_block(lo, kf, y, ylo, fcols, offs, &mut block, self.avx512);
            }
            for i in lo..hi {
                if open(self, i) {
                    let exact = if whole {
                        block[i - lo]
                    } else {
                        self.reduced_dd(y, kf, i)
                    };
                    self.d[i] = exact;
                    self.e[i] = exact.abs() / 8.0 + 1e-14 * self.e[i];
                }
            }
        }
    }

    /// p_i − (y + y_lo)·ā_i in double-double, rounded (p_i = [i < kf]).
    pub(super) fn reduced_dd(&self, y: &[f64], kf: usize, i: usize) -> f64 {
        let p = (i < kf) as u8 as f64;
        let hi_terms = self
            .rows
            .iter()
            .zip(y)
            .map(|(&j, &yk)| (yk, self.entry(j, i)));
        let lo_terms = self
            .rows
            .iter()
            .zip(&self.ylo)
            .map(|(&j, &yk)| (yk, self.entry(j, i)));
        residual2(p, hi_terms.chain(lo_terms))
    }

    /// min_i (d_i − γ e_i): a lower bound on the exact min of the values in d.
    pub(super) fn min_lower(&self) -> f64 {
        if !self.flagged_ok {
            return row_kernels::min_lower(&self.d, &self.e, self.gamma);
        }
        // Outside the flagged blocks every d_i − γ e_i ≥ 0 (or NaN, skipped either way).
        self.flagged_blocks()
            .map(|(lo, hi)| row_kernels::min_lower(&self.d[lo..hi], &self.e[lo..hi], self.gamma))
            .fold(f64::INFINITY, f64::min)
    }

    /// The flagged blocks as index ranges (see `flagged`).
    pub(super) fn flagged_blocks(&self) -> impl Iterator<Item = (usize, usize)> + '_ {
        let n = self.n;
        self.flagged
            .iter()
            .map(move |&lo| (lo, (lo + row_kernels::BLOCK).min(n)))
    }
}

/// d_i −= Σ_k ys_k f_{rows[k+1]}(z_i) and e_i += Σ_k |ys_k f_{rows[k+1]}(z_i)| over the grid
/// (ys pairs with the function rows, rows[0] = 0 being the constant): one fused pass when the
/// rows are 0, 1, …, m (fcols as it stands), else a pass per row. The same bits either way.
pub(super) fn sub_function_rows(
    d: &mut [f64],
    e: &mut [f64],
    ys: &[f64],
    fcols: &[f64],
    rows: &[usize],
    avx512: bool,
) {
    let n = d.len();
    if rows.iter().enumerate().all(|(k, &j)| k == j) {
        row_kernels::sub_rows_abs(d, e, ys, fcols, avx512);
    } else {
        for (y, &j) in ys.iter().zip(&rows[1..]) {
            row_kernels::sub_scaled_abs(d, e, *y, &fcols[(j - 1) * n..j * n], avx512);
        }
    }
}
