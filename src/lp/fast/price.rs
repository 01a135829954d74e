//! Pricing: the entering column of a simplex step. Partial pricing (coarse subgrid, the
//! neighbours of z_f and of the support, the fine window around the best), the full pass that
//! proves optimality and Bland's rule; the kernels are in [`crate::lp::fast::pricing`].

use super::{FastSolver, ART, TOL_D, TOL_PIV};
use crate::lp::fast::pricing::dantzig::price;
use crate::lp::fast::pricing::greatest as gi_pricing;
use crate::lp::fast::pricing::{ColumnTable, LANES};

/// A reduced cost below this (costs are 0 or 1, columns have RMS 1) triggers greatest-
/// improvement pricing on the coarse subgrid ([`gi_pricing`]): stacks corpus at n = 1024,
/// 10.2 → 7.4 pivots per window, with about one such scan per window.
const GI_TRIGGER: f64 = -1.0;

/// The columns in pricing blocks and the partial-pricing state.
pub(super) struct Pricing {
    /// is_basic[i]: grid column i is in the basis.
    pub(super) is_basic: Vec<bool>,
    /// Coarse stride of partial pricing (1 = always full pricing).
    pub(super) stride: usize,
    /// All columns, and the coarse subgrid of partial pricing (every `stride`-th point and
    /// the last one, at grid indices `coarse_idx`).
    pub(super) fine: ColumnTable,
    pub(super) coarse: ColumnTable,
    pub(super) coarse_idx: Vec<usize>,
    /// For grid index i: its position in `coarse`, or u32::MAX when it is not a coarse point.
    pub(super) coarse_pos: Vec<u32>,
}

impl FastSolver {
    /// Partial pricing: reduced costs on a coarse subgrid (every `stride`-th point and the last
    /// one), next to z_f and next to the current support points, then on the whole fine window
    /// between the coarse neighbours of the best of these. Reduced costs are smooth in z on
    /// either side of z_f, so this usually finds a good entering column at a fraction of a full
    /// pass. Returns (usize::MAX, −TOL_D) when it finds no negative reduced cost (then a full
    /// pass decides).
    pub(super) fn price_partial(&self, kf: usize) -> (usize, f64) {
        let (n, r, st) = (self.n, self.r, self.pricing.stride);
        let y = &self.y[..r];
        let none = (usize::MAX, -TOL_D);
        // Coarse subgrid.
        let coarse = &self.pricing.coarse;
        // Coarse points below kf: j·st < kf for the regular ones, and the extra last point
        // n − 1 only when kf = n.
        let nc = self.pricing.coarse_idx.len();
        let regular = if (nc - 1) * st == n - 1 { nc } else { nc - 1 };
        let csplit = kf.div_ceil(st).min(regular) + (regular < nc && kf == n) as usize;
        debug_assert_eq!(csplit, self.pricing.coarse_idx.partition_point(|&i| i < kf));
        let cb = coarse.scan(y, csplit, 0, coarse.blocks(), none);
        let mut best = if cb.0 == usize::MAX {
            none
        } else {
            (self.pricing.coarse_idx[cb.0], cb.1)
        };
        // Narrow dips of the reduced cost appear next to the current support points and at
        // the step at z_f: scan a few neighbours of each (whole blocks, overlaps merged).
        const W: usize = 3;
        let mut ranges = [(0usize, 0usize); 10];
        let mut nr = 0;
        ranges[nr] = self.pricing.fine.block_range(kf.saturating_sub(W), kf + W);
        nr += 1;
        for &bt in &self.basis {
            if bt != ART && nr < ranges.len() {
                ranges[nr] = self
                    .pricing
                    .fine
                    .block_range(bt.saturating_sub(W), bt + W + 1);
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
        best = self
            .pricing
            .fine
            .scan_ranges(y, kf, &ranges[..distinct], best);
        if best.0 == usize::MAX {
            return best;
        }
        if best.1 < GI_TRIGGER {
            // A reduced cost this large comes from the dual polynomial extrapolating the basis
            // (an end of the grid): the coarse point of greatest improvement enters instead.
            let basis = gi_pricing::Basis {
                binv: &self.binv.inv,
                x: &self.x,
                tol_d: TOL_D,
                tol_piv: TOL_PIV,
            };
            if let Some(g) = gi_pricing::scan(coarse, y, csplit, &basis) {
                best = (self.pricing.coarse_idx[g.j], g.d);
            }
        }
        // The reduced cost is smooth between coarse points: the minimum of the whole fine
        // window around the best point is the entering column.
        let c = best.0;
        let window = self
            .pricing
            .fine
            .block_range(c.saturating_sub(st - 1), (c + st).min(n));
        self.scan_fine(y, kf, window, best)
    }

    /// Full pricing: the non-basic column with the lowest reduced cost, or (usize::MAX, 0) when
    /// none is below −TOL_D / 4 (basic columns, whose reduced cost is 0 up to rounding, then
    /// never come out lowest).
    pub(super) fn price_full(&self, kf: usize) -> (usize, f64) {
        let y = &self.y[..self.r];
        let got = self.scan_fine(
            y,
            kf,
            (0, self.pricing.fine.blocks()),
            (usize::MAX, -0.25 * TOL_D),
        );
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
        self.pricing.fine.scan(y, kf, blo, bhi, best)
    }

    /// Mark grid column i basic (excluded from pricing) or not.
    pub(super) fn set_basic(&mut self, i: usize, on: bool) {
        self.pricing.is_basic[i] = on;
        self.pricing.fine.set_excluded(i, on);
        // A table lookup, not `i % stride` (an integer division, ~60 per solve).
        let c = self.pricing.coarse_pos[i];
        if c != u32::MAX {
            self.pricing.coarse.set_excluded(c as usize, on);
        }
    }
}

/// Blocks of [`LANES`] columns per scan of [`price_bland`].
const BLAND_BLOCKS: usize = 16;

/// Bland's rule: the first column (in grid order) whose reduced cost d_i = [i < kf] − y·a_i is
/// below −TOL_D, basic columns excluded. The blocked scan finds the first group of
/// [`BLAND_BLOCKS`] blocks holding one, and the column is found there with the kernel's
/// operations in its order (y_0 a_0i, then fused multiply-adds; the same bits). When there is
/// none, Dantzig's full pass gives the least reduced cost (for the optimality checks), with
/// s = y·a_i of every column.
pub(super) fn price_bland(
    table: &ColumnTable,
    n: usize,
    r: usize,
    y: &[f64],
    kf: usize,
    basis: &[usize],
    s: &mut [f64],
) -> (usize, f64) {
    let blocks = table.blocks();
    let (data, ld) = table.rows();
    let pen = table.penalties();
    let mut lo = 0;
    while lo < blocks {
        let hi = (lo + BLAND_BLOCKS).min(blocks);
        if table.scan(y, kf, lo, hi, (usize::MAX, -TOL_D)).0 != usize::MAX {
            for i in lo * LANES..(hi * LANES).min(n) {
                let mut si = y[0] * data[i];
                for k in 1..r {
                    si = y[k].mul_add(data[k * ld + i], si);
                }
                let d = (pen[i] - si) + if i < kf { 1.0 } else { 0.0 };
                if d < -TOL_D {
                    return (i, d);
                }
            }
        }
        lo = hi;
    }
    price(table, n, r, y, kf, basis, s)
}

#[cfg(test)]
mod tests {
    use super::{price, price_bland, TOL_D};
    use crate::lp::fast::pricing::ColumnTable;
    use rand::{Rng, SeedableRng};

    /// Bland's rule as defined: Dantzig's pass for s = y·a_i (basic columns at reduced cost 0),
    /// then the first column with d_i < −TOL_D, else the pass's own answer. The blocked
    /// search gives the same column and value on 3 000 random tables (r = 1…9, n up to 700,
    /// some columns basic, duals scaled so that few or no reduced costs are negative).
    #[test]
    fn bland_is_the_first_negative_reduced_cost() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(17);
        let mut found = 0;
        for _ in 0..3000 {
            let (r, n) = (rng.gen_range(1..=9), rng.gen_range(1..700));
            let entries: Vec<f64> = (0..r * n).map(|_| rng.gen_range(-1.0..1.0)).collect();
            let mut table = ColumnTable::new(r, n, |k, i| entries[k * n + i]);
            let scale = [0.0, 1e-3, 0.3, 1.0][rng.gen_range(0..4)];
            let y: Vec<f64> = (0..r).map(|_| scale * rng.gen_range(-1.0..1.0)).collect();
            let kf = rng.gen_range(0..=n);
            let basis: Vec<usize> = (0..r.min(n)).map(|_| rng.gen_range(0..n)).collect();
            for &b in &basis {
                table.set_excluded(b, true);
            }
            let mut s = vec![0.0; n];
            let (iq, dq) = price(&table, n, r, &y, kf, &basis, &mut s);
            let want = (0..n)
                .map(|i| (i, if i < kf { 1.0 - s[i] } else { -s[i] }))
                .find(|&(_, d)| dq < -TOL_D && d < -TOL_D)
                .unwrap_or((iq, dq));
            let got = price_bland(&table, n, r, &y, kf, &basis, &mut vec![0.0; n]);
            assert_eq!(got.0, want.0, "r {r} n {n} kf {kf}");
            assert_eq!(got.1.to_bits(), want.1.to_bits(), "{got:?} {want:?}");
            found += (want.1 < -TOL_D) as usize;
        }
        assert!(found > 1000 && found < 2900, "{found}");
    }
}
