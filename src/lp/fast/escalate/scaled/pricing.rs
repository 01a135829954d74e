//! Pricing of the scaled simplex: partial first (the coarse subgrid, the neighbours of the
//! basic columns and of z_f, the fine window around the best of these), Dantzig's full pass
//! where the subset holds no eligible column, f64 reduced costs with their rounding bound and
//! double-double rechecks where the sign is open.

use super::*;

impl ScaledSimplex {
    /// Entering column: an eligible column of [`Self::price_partial`] where it finds one,
    /// else the full pass of [`Self::price_full`] (Bland's rule always takes the full pass).
    /// None only from the full pass: no non-basic column is eligible, the phase's optimum.
    pub(super) fn price(&mut self, kf: usize, phase1: bool, bland: bool) -> Option<usize> {
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
    pub(super) fn price_partial(&mut self, kf: usize, phase1: bool) -> Option<usize> {
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
    pub(super) fn consider_range(
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
    pub(super) fn reduced_range(&mut self, lo: usize, hi: usize) {
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
    pub(super) fn reduced_coarse(&mut self) {
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
    pub(super) fn check_partial(&mut self, q: usize, kf: usize, phase1: bool) {
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
    pub(super) fn check_full(&mut self, q: Option<usize>, kf: usize, phase1: bool, bland: bool) {
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
    pub(super) fn price_full(&mut self, kf: usize, phase1: bool, bland: bool) -> Option<usize> {
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
    pub(super) fn magnitudes(&mut self, lo: usize, hi: usize) {
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
    pub(super) fn rounding_factor(&self) -> f64 {
        4.0 * (self.r as f64 + 2.0) * f64::EPSILON
    }

    /// d_i = c_i − y·a_i and e_i = |c_i| + Σ_k |y_k a_ki| in f64 from the duals' high parts for
    /// every column (one vectorised pass per row).
    pub(super) fn reduced_f64(&mut self, kf: usize, phase1: bool) {
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
    pub(super) fn consider(
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
    pub(super) fn price_scan(&self, kf: usize, phase1: bool, bland: bool) -> Option<usize> {
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
}
