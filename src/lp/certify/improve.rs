//! Accurate pivots: where a basis does not certify, simplex steps in the certifier's own
//! coordinates (row-scaled basis matrix, refined weights and duals), each from a fresh
//! factorisation, until it certifies or the steps run out.

use super::bound::sub_function_rows;
use super::*;

impl Certifier {
    /// Certify `basis`, and where that fails make up to `steps` simplex pivots in these
    /// accurate coordinates (every step from a fresh factorisation with refined weights and
    /// duals): a primal step on the most negative capped reduced cost u_i·d_i, or a dual step
    /// when a refined weight is negative. `basis` holds the last basis tried.
    pub fn improve(
        &mut self,
        b: &[f64],
        kf: usize,
        basis: &mut [usize],
        steps: usize,
    ) -> Result<Certified, String> {
        self.improve_from(b, kf, basis, steps, None)
    }

    /// [`Self::improve`] right after [`Self::optimal`] failed on the same `basis` with reason
    /// `why`: that check's factorisation, weights and duals are the first step's, not
    /// recomputed (the same pivots as `improve`, one certificate check fewer).
    pub fn improve_checked(
        &mut self,
        b: &[f64],
        kf: usize,
        basis: &mut [usize],
        steps: usize,
        why: String,
    ) -> Result<Certified, String> {
        self.improve_from(b, kf, basis, steps, Some(why))
    }

    pub(super) fn improve_from(
        &mut self,
        b: &[f64],
        kf: usize,
        basis: &mut [usize],
        steps: usize,
        mut checked: Option<String>,
    ) -> Result<Certified, String> {
        let mut last = String::new();
        for step in 0..=steps {
            self.bland = step >= BLAND_AFTER;
            match checked.take() {
                Some(why) => last = why,
                None => match self.optimal(b, kf, basis) {
                    Ok(c) => return Ok(c),
                    Err(e) => last = e,
                },
            }
            if !self.factored {
                break;
            }
            if !self.duals_fresh {
                self.dual(basis, kf);
                let y = std::mem::take(&mut self.y);
                self.reduced(&y, Some(kf));
                self.y = y;
            }
            if !self.step(basis) {
                break;
            }
        }
        Err(last)
    }

    /// One pivot (see [`Self::improve`]); false when none is possible.
    pub(super) fn step(&mut self, basis: &mut [usize]) -> bool {
        let r = self.rows.len();
        let l = (0..r)
            .min_by(|&a, &b| self.xraw[a].total_cmp(&self.xraw[b]))
            .unwrap_or(0);
        if !self.primal_ok && self.xraw[l] < 0.0 {
            // Dual step: row l of B̃⁻¹, entering by the dual ratio test.
            self.tmp.iter_mut().for_each(|v| *v = 0.0);
            self.tmp[l] = 1.0;
            self.solve(true, Which::Tmp);
            for k in 0..r {
                self.tmp[k] *= self.scale[self.rows[k]];
            }
            // α_i = Σ_k tmp_k ā_ki for every column (as −α in `ra`, Σ|·| in `rm`).
            let (ra, rm) = (&mut self.ra, &mut self.rm);
            ra.fill(-self.tmp[0]);
            rm.fill(self.tmp[0].abs());
            sub_function_rows(ra, rm, &self.tmp[1..], &self.fcols, &self.rows, self.avx512);
            let mut best: Option<(usize, f64)> = None;
            for lo in (0..self.n).step_by(row_kernels::BLOCK) {
                let hi = (lo + row_kernels::BLOCK).min(self.n);
                if !row_kernels::any_above(&self.ra[lo..hi], &self.rm[lo..hi], 1e-9) {
                    continue;
                }
                for i in lo..hi {
                    let a = -self.ra[i];
                    if a < -1e-9 * self.rm[i].max(f64::MIN_POSITIVE) && !basis.contains(&i) {
                        let ratio = self.d[i].max(0.0) / -a;
                        if best.is_none_or(|(_, r0)| ratio < r0) {
                            best = Some((i, ratio));
                        }
                    }
                }
            }
            return match best {
                Some((q, _)) => {
                    basis[l] = q;
                    true
                }
                None => false,
            };
        }
        // Primal step on the most negative capped reduced cost.
        let mut best: Option<(usize, f64)> = None;
        // Only the flagged blocks hold values below their bound (and e is only set there).
        let below = self.flagged_blocks().flat_map(|(lo, hi)| {
            row_kernels::below(&self.d[lo..hi], &self.e[lo..hi], self.gamma)
                .map(move |(i, low)| (lo + i, low))
        });
        for (i, low) in below {
            if !basis.contains(&i) {
                let v = low * self.cap(i);
                if best.is_none_or(|(_, v0)| v < v0) {
                    best = Some((i, v));
                    if self.bland {
                        break;
                    }
                }
            }
        }
        let Some((q, _)) = best else {
            return false;
        };
        for k in 0..r {
            let j = self.rows[k];
            self.tmp[k] = self.scale[j] * self.entry(j, q);
        }
        self.solve(false, Which::Tmp);
        for t in 0..r {
            self.tmp[t] *= self.colscale[t];
        }
        let amax = self.tmp.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        // Bland's ratio test (no tolerance, ties to the smallest grid index) or Harris's two
        // passes with weights below TOL_WEIGHT as ties; pivots below 1e-9·max|α| never leave.
        let pick = if self.bland {
            ratio::harris(&self.xraw, &self.tmp, 1e-9 * amax, 0.0, Some(basis))
        } else {
            ratio::harris(&self.xraw, &self.tmp, 1e-9 * amax, TOL_WEIGHT, None)
        };
        match pick {
            Some(t) => {
                basis[t] = q;
                true
            }
            None => false,
        }
    }

    /// u_i = min(1, min_j b_j / f_j(z_i)) over the sign-definite rows: every exactly feasible
    /// w has w_i ≤ u_i.
    pub(super) fn cap(&self, i: usize) -> f64 {
        let mut u = 1.0f64;
        for (j, inv) in &self.finv {
            if inv[i] != 0.0 {
                u = u.min((self.bbar[*j] * inv[i]).max(0.0) * (1.0 + 1e-12));
            }
        }
        u
    }
}
