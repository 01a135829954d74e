//! Pricing kernels of the fast solver (this file: the column table and the blocked scans;
//! [`dantzig`]: the dense pass; [`greatest`]: greatest improvement on the coarse subgrid): the entering column of a simplex pivot is the column
//! with the most negative reduced cost d_j = cost_j − yᵀa_j (Dantzig's rule). For Algorithm 1
//! the costs are a step, cost_j = [j < split], so one kernel serves every pass.
//!
//! The columns are stored row by row in blocks of [`LANES`] columns, zero-padded to a whole
//! block: a pass computes the inner products of one block in registers (r fused multiply-adds
//! per lane) and keeps the minimum per lane, with no stores and no data-dependent branches.
//! Padding columns are zero and permanently excluded.

#![allow(clippy::needless_range_loop)] // lane and row loops over fixed-size register arrays

pub(crate) mod dantzig;
pub(crate) mod greatest;

/// Columns per block (two AVX2 registers of f64).
pub(crate) const LANES: usize = 8;

/// The pricing kernels: scalar, and on x86-64 AVX2+FMA and AVX-512F.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(crate) enum Kernel {
    #[default]
    Scalar,
    #[cfg(target_arch = "x86_64")]
    Avx2,
    #[cfg(target_arch = "x86_64")]
    Avx512,
}

impl Kernel {
    /// Every kernel (supported or not).
    pub(crate) fn all() -> Vec<Kernel> {
        #[cfg(target_arch = "x86_64")]
        return vec![Kernel::Scalar, Kernel::Avx2, Kernel::Avx512];
        #[cfg(not(target_arch = "x86_64"))]
        return vec![Kernel::Scalar];
    }

    /// Whether this CPU can run the kernel.
    pub(crate) fn supported(self) -> bool {
        match self {
            Kernel::Scalar => true,
            #[cfg(target_arch = "x86_64")]
            Kernel::Avx2 => crate::lp::cpu::has_avx2_fma(),
            #[cfg(target_arch = "x86_64")]
            Kernel::Avx512 => crate::lp::cpu::has_avx512() && crate::lp::cpu::has_fma(),
        }
    }

    /// The kernel to use: `MOMENTLAB_PRICING=scalar|avx2|avx512` if set and supported (for
    /// benchmarks on one machine), else the fastest supported one.
    pub(crate) fn detect() -> Kernel {
        if let Ok(name) = std::env::var("MOMENTLAB_PRICING") {
            let wanted = Kernel::all()
                .into_iter()
                .find(|k| k.name() == name.trim().to_ascii_lowercase());
            if let Some(k) = wanted.filter(|k| k.supported()) {
                return k;
            }
        }
        Kernel::fastest()
    }

    /// Lower-case name (as in `MOMENTLAB_PRICING`).
    pub(crate) fn name(self) -> &'static str {
        match self {
            Kernel::Scalar => "scalar",
            #[cfg(target_arch = "x86_64")]
            Kernel::Avx2 => "avx2",
            #[cfg(target_arch = "x86_64")]
            Kernel::Avx512 => "avx512",
        }
    }

    /// The fastest supported kernel.
    pub(crate) fn fastest() -> Kernel {
        #[cfg(target_arch = "x86_64")]
        {
            if Kernel::Avx512.supported() {
                return Kernel::Avx512;
            }
            if Kernel::Avx2.supported() {
                return Kernel::Avx2;
            }
        }
        Kernel::Scalar
    }
}

/// A column table in blocks: row k of column j at `data[k * ld + j]`, `ld` a multiple of
/// [`LANES`], columns `len..ld` zero. Columns can be excluded from pricing (basic columns:
/// their reduced cost is zero in exact arithmetic but can come out at −1e-8 on the
/// ill-conditioned bases of neighbouring grid points); an excluded column carries +∞ in `pen`,
/// which the kernels add to its reduced cost.
#[derive(Clone, Debug, Default)]
pub(crate) struct ColumnTable {
    data: Vec<f64>,
    pen: Vec<f64>,
    ld: usize,
    r: usize,
    len: usize,
    /// The fastest kernel this CPU supports (detected once).
    kernel: Kernel,
}

impl ColumnTable {
    /// The table of `len` columns with `r` rows, entry (k, j) = `entry(k, j)`.
    pub(crate) fn new(r: usize, len: usize, entry: impl Fn(usize, usize) -> f64) -> ColumnTable {
        let ld = len.div_ceil(LANES).max(1) * LANES;
        let mut data = vec![0.0; r * ld];
        for k in 0..r {
            for j in 0..len {
                data[k * ld + j] = entry(k, j);
            }
        }
        let mut pen = vec![0.0; ld];
        pen[len..].iter_mut().for_each(|p| *p = f64::INFINITY);
        ColumnTable {
            data,
            pen,
            ld,
            r,
            len,
            kernel: Kernel::detect(),
        }
    }

    /// Entry (k, j).
    pub(crate) fn entry(&self, k: usize, j: usize) -> f64 {
        self.data[k * self.ld + j]
    }

    /// All entries, row by row (row k at `[k * ld ..]`), and the leading dimension ld.
    pub(crate) fn rows(&self) -> (&[f64], usize) {
        (&self.data, self.ld)
    }

    /// Number of rows r.
    pub(crate) fn r(&self) -> usize {
        self.r
    }

    /// Number of columns (without the padding).
    pub(crate) fn len(&self) -> usize {
        self.len
    }

    /// The exclusion penalties (0, or +∞ for excluded and padding columns), one per column.
    pub(crate) fn penalties(&self) -> &[f64] {
        &self.pen
    }

    /// The kernel detected for this CPU.
    pub(crate) fn kernel(&self) -> Kernel {
        self.kernel
    }

    /// Exclude column j < len from (or readmit it to) pricing; padding is always excluded.
    pub(crate) fn set_excluded(&mut self, j: usize, excluded: bool) {
        assert!(j < self.len, "column {j} out of range");
        self.pen[j] = if excluded { f64::INFINITY } else { 0.0 };
    }

    /// Number of blocks.
    pub(crate) fn blocks(&self) -> usize {
        self.ld / LANES
    }

    /// The block range covering columns lo..hi (clamped to the table).
    pub(crate) fn block_range(&self, lo: usize, hi: usize) -> (usize, usize) {
        let hi = hi.min(self.len);
        if lo >= hi {
            return (0, 0);
        }
        (lo / LANES, hi.div_ceil(LANES))
    }

    /// The lowest reduced cost d_j = [j < split] − y·a_j below `best.1` over the columns of
    /// blocks blo..bhi that are not excluded, as (j, d_j); `best` itself when no column is
    /// lower. Among equal reduced costs the lowest j wins.
    pub(crate) fn scan(
        &self,
        y: &[f64],
        split: usize,
        blo: usize,
        bhi: usize,
        best: (usize, f64),
    ) -> (usize, f64) {
        self.scan_ranges(y, split, &[(blo, bhi)], best)
    }

    /// [`Self::scan`] over several block ranges in one pass (ranges may overlap), with the
    /// fastest kernel this CPU supports.
    pub(crate) fn scan_ranges(
        &self,
        y: &[f64],
        split: usize,
        ranges: &[(usize, usize)],
        best: (usize, f64),
    ) -> (usize, f64) {
        self.scan_ranges_with(self.kernel, y, split, ranges, best)
    }

    /// [`Self::scan_ranges`] with a given kernel (which must be supported: see
    /// [`Kernel::supported`]).
    pub(crate) fn scan_ranges_with(
        &self,
        kernel: Kernel,
        y: &[f64],
        split: usize,
        ranges: &[(usize, usize)],
        best: (usize, f64),
    ) -> (usize, f64) {
        assert!(y.len() >= self.r);
        assert!(ranges
            .iter()
            .all(|&(blo, bhi)| blo <= bhi && bhi <= self.blocks()));
        assert!(
            kernel.supported(),
            "pricing kernel {kernel:?} not supported by this CPU"
        );
        macro_rules! by_rows {
            ($f:ident) => {
                match self.r {
                    1 => self.$f::<1>(y, split, ranges, best),
                    2 => self.$f::<2>(y, split, ranges, best),
                    3 => self.$f::<3>(y, split, ranges, best),
                    4 => self.$f::<4>(y, split, ranges, best),
                    5 => self.$f::<5>(y, split, ranges, best),
                    6 => self.$f::<6>(y, split, ranges, best),
                    7 => self.$f::<7>(y, split, ranges, best),
                    8 => self.$f::<8>(y, split, ranges, best),
                    9 => self.$f::<9>(y, split, ranges, best),
                    10 => self.$f::<10>(y, split, ranges, best),
                    11 => self.$f::<11>(y, split, ranges, best),
                    12 => self.$f::<12>(y, split, ranges, best),
                    13 => self.$f::<13>(y, split, ranges, best),
                    _ => self.scan_ranges_scalar(y, split, ranges, best),
                }
            };
        }
        match kernel {
            Kernel::Scalar => self.scan_ranges_scalar(y, split, ranges, best),
            // SAFETY: the CPU supports the kernel's features (asserted), and the block ranges
            // lie inside the table (asserted).
            #[cfg(target_arch = "x86_64")]
            Kernel::Avx2 => unsafe { by_rows!(scan_avx2) },
            #[cfg(target_arch = "x86_64")]
            Kernel::Avx512 => unsafe { by_rows!(scan_avx512) },
        }
    }

    fn scan_ranges_scalar(
        &self,
        y: &[f64],
        split: usize,
        ranges: &[(usize, usize)],
        best: (usize, f64),
    ) -> (usize, f64) {
        ranges.iter().fold(best, |b, &(blo, bhi)| {
            self.scan_scalar(y, split, blo, bhi, b)
        })
    }

    /// [`Self::scan`] for R rows with AVX2: two registers of four columns per block, the
    /// running minimum and its column index kept per lane.
    ///
    /// # Safety
    /// The CPU must support AVX2 and FMA; every range within `self.blocks()`,
    /// `y.len() ≥ R = self.r`.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    unsafe fn scan_avx2<const R: usize>(
        &self,
        y: &[f64],
        split: usize,
        ranges: &[(usize, usize)],
        best: (usize, f64),
    ) -> (usize, f64) {
        use std::arch::x86_64::*;
        let ld = self.ld;
        let data = self.data.as_ptr();
        let pen = self.pen.as_ptr();
        let mut yv = [_mm256_setzero_pd(); R];
        for k in 0..R {
            yv[k] = _mm256_set1_pd(y[k]);
        }
        let one = _mm256_set1_pd(1.0);
        let splitv = _mm256_set1_pd(split as f64);
        let step = _mm256_set1_pd(LANES as f64);
        let mut bv0 = _mm256_set1_pd(best.1);
        let mut bv1 = bv0;
        let mut bi0 = _mm256_set1_pd(-1.0);
        let mut bi1 = bi0;
        for &(blo, bhi) in ranges {
            let b0 = (blo * LANES) as f64;
            let mut idx0 = _mm256_setr_pd(b0, b0 + 1.0, b0 + 2.0, b0 + 3.0);
            let mut idx1 = _mm256_add_pd(idx0, _mm256_set1_pd(4.0));
            for b in blo..bhi {
                let base = b * LANES;
                // SAFETY (all loads): k < R = self.r rows of ld ≥ base + LANES columns, and pen
                // has ld entries.
                let mut s0 = _mm256_mul_pd(yv[0], _mm256_loadu_pd(data.add(base)));
                let mut s1 = _mm256_mul_pd(yv[0], _mm256_loadu_pd(data.add(base + 4)));
                for k in 1..R {
                    let row = data.add(k * ld + base);
                    s0 = _mm256_fmadd_pd(yv[k], _mm256_loadu_pd(row), s0);
                    s1 = _mm256_fmadd_pd(yv[k], _mm256_loadu_pd(row.add(4)), s1);
                }
                // d = [j < split] − s + pen
                let c0 = _mm256_and_pd(_mm256_cmp_pd::<_CMP_LT_OQ>(idx0, splitv), one);
                let c1 = _mm256_and_pd(_mm256_cmp_pd::<_CMP_LT_OQ>(idx1, splitv), one);
                let d0 = _mm256_add_pd(_mm256_sub_pd(c0, s0), _mm256_loadu_pd(pen.add(base)));
                let d1 = _mm256_add_pd(_mm256_sub_pd(c1, s1), _mm256_loadu_pd(pen.add(base + 4)));
                let m0 = _mm256_cmp_pd::<_CMP_LT_OQ>(d0, bv0);
                let m1 = _mm256_cmp_pd::<_CMP_LT_OQ>(d1, bv1);
                bv0 = _mm256_min_pd(d0, bv0);
                bv1 = _mm256_min_pd(d1, bv1);
                bi0 = _mm256_blendv_pd(bi0, idx0, m0);
                bi1 = _mm256_blendv_pd(bi1, idx1, m1);
                idx0 = _mm256_add_pd(idx0, step);
                idx1 = _mm256_add_pd(idx1, step);
            }
        }
        let mut v = [0.0f64; LANES];
        let mut ix = [0.0f64; LANES];
        _mm256_storeu_pd(v.as_mut_ptr(), bv0);
        _mm256_storeu_pd(v.as_mut_ptr().add(4), bv1);
        _mm256_storeu_pd(ix.as_mut_ptr(), bi0);
        _mm256_storeu_pd(ix.as_mut_ptr().add(4), bi1);
        reduce_lanes(&v, &ix, best)
    }

    /// [`Self::scan`] for R rows with AVX-512: one register of eight columns per block, the
    /// running minimum and its column index kept per lane, in two accumulators (even and odd
    /// blocks of a range) so that the min/compare chains of consecutive blocks overlap.
    ///
    /// # Safety
    /// The CPU must support AVX-512F; every range within `self.blocks()`, `y.len() ≥ R = self.r`.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx512f")]
    unsafe fn scan_avx512<const R: usize>(
        &self,
        y: &[f64],
        split: usize,
        ranges: &[(usize, usize)],
        best: (usize, f64),
    ) -> (usize, f64) {
        use std::arch::x86_64::*;
        let ld = self.ld;
        let data = self.data.as_ptr();
        let pen = self.pen.as_ptr();
        let mut yv = [_mm512_setzero_pd(); R];
        for k in 0..R {
            yv[k] = _mm512_set1_pd(y[k]);
        }
        let one = _mm512_set1_pd(1.0);
        let splitv = _mm512_set1_pd(split as f64);
        let iota = _mm512_setr_pd(0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0);
        let (mut bv0, mut bi0) = (_mm512_set1_pd(best.1), _mm512_set1_pd(-1.0));
        let (mut bv1, mut bi1) = (bv0, bi0);
        // Block b into the accumulator (bv, bi): its reduced costs d = [j < split] − s + pen,
        // computed as (pen − s) + [j < split] (the same rounding), a running per-lane minimum.
        macro_rules! block {
            ($b:expr, $bv:ident, $bi:ident) => {{
                let base = $b * LANES;
                // SAFETY (all loads): k < R = self.r rows of ld ≥ base + LANES columns, and
                // pen has ld entries.
                let mut s = _mm512_mul_pd(yv[0], _mm512_loadu_pd(data.add(base)));
                for k in 1..R {
                    s = _mm512_fmadd_pd(yv[k], _mm512_loadu_pd(data.add(k * ld + base)), s);
                }
                let idx = _mm512_add_pd(_mm512_set1_pd(base as f64), iota);
                let below = _mm512_cmp_pd_mask::<_CMP_LT_OQ>(idx, splitv);
                let d = _mm512_sub_pd(_mm512_loadu_pd(pen.add(base)), s);
                let d = _mm512_mask_add_pd(d, below, d, one);
                let m = _mm512_cmp_pd_mask::<_CMP_LT_OQ>(d, $bv);
                $bv = _mm512_min_pd(d, $bv);
                $bi = _mm512_mask_blend_pd(m, $bi, idx);
            }};
        }
        for &(blo, bhi) in ranges {
            let mut b = blo;
            while b + 1 < bhi {
                block!(b, bv0, bi0);
                block!(b + 1, bv1, bi1);
                b += 2;
            }
            if b < bhi {
                block!(b, bv0, bi0);
            }
        }
        // Per lane, the lower value of the two accumulators, the lower index among equals
        // (an accumulator still at best.1 has index −1 and a value no lower than the other's).
        let lt = _mm512_cmp_pd_mask::<_CMP_LT_OQ>(bv1, bv0);
        let eq = _mm512_cmp_pd_mask::<_CMP_EQ_OQ>(bv1, bv0);
        let lower_ix = _mm512_cmp_pd_mask::<_CMP_LT_OQ>(bi1, bi0);
        let take = lt | (eq & lower_ix);
        let bv = _mm512_mask_blend_pd(take, bv0, bv1);
        let bi = _mm512_mask_blend_pd(take, bi0, bi1);
        // Lane reduction without data-dependent branches: the lowest value, then the lowest
        // index among the lanes holding it (lanes still at best.1 never improved).
        let minv = _mm512_reduce_min_pd(bv);
        if minv.partial_cmp(&best.1) != Some(std::cmp::Ordering::Less) {
            return best;
        }
        let eq = _mm512_cmp_pd_mask::<_CMP_EQ_OQ>(bv, _mm512_set1_pd(minv));
        let j = _mm512_mask_reduce_min_pd(eq, bi);
        (j as usize, minv)
    }

    /// [`Self::scan`] without SIMD (any row count; also the reference in tests).
    pub(crate) fn scan_scalar(
        &self,
        y: &[f64],
        split: usize,
        blo: usize,
        bhi: usize,
        best: (usize, f64),
    ) -> (usize, f64) {
        let mut out = best;
        for j in blo * LANES..bhi * LANES {
            let s: f64 = (0..self.r).map(|k| y[k] * self.data[k * self.ld + j]).sum();
            let d = if j < split { 1.0 - s } else { -s } + self.pen[j];
            if d < out.1 {
                out = (j, d);
            }
        }
        out
    }
}

/// The lowest of the lane minima `v` (with column indices `ix`, −1 where a lane never went
/// below best.1) and its lowest index, or `best` when no lane improved; branch-free selects.
#[inline(always)]
fn reduce_lanes(v: &[f64; LANES], ix: &[f64; LANES], best: (usize, f64)) -> (usize, f64) {
    let minv = v
        .iter()
        .fold(f64::INFINITY, |a, &b| if b < a { b } else { a });
    if minv.partial_cmp(&best.1) != Some(std::cmp::Ordering::Less) {
        return best;
    }
    let j = v.iter().zip(ix).fold(
        f64::INFINITY,
        |a, (&vl, &il)| if vl == minv && il < a { il } else { a },
    );
    (j as usize, minv)
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// Brute force: the lowest reduced cost over columns lo..hi (first among equals).
    fn brute(
        cols: &[Vec<f64>],
        y: &[f64],
        split: usize,
        lo: usize,
        hi: usize,
        best: (usize, f64),
    ) -> (usize, f64) {
        let mut out = best;
        for (j, a) in cols.iter().enumerate().take(hi).skip(lo) {
            let s: f64 = a.iter().zip(y).map(|(a, y)| a * y).sum();
            let d = if j < split { 1.0 - s } else { -s };
            if d < out.1 {
                out = (j, d);
            }
        }
        out
    }

    #[test]
    fn scan_matches_brute_force_for_every_row_count_and_kernel() {
        let kernels: Vec<Kernel> = Kernel::all()
            .into_iter()
            .filter(|k| k.supported())
            .collect();
        eprintln!("pricing kernels tested: {kernels:?}");
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        for trial in 0..3000 {
            let r = 1 + trial % 15;
            // Mostly a few blocks; every fifth trial long ranges (both accumulators, odd ends).
            let len = if trial % 5 == 0 {
                rng.gen_range(70..400)
            } else {
                rng.gen_range(1..70)
            };
            let cols: Vec<Vec<f64>> = (0..len)
                .map(|_| (0..r).map(|_| rng.gen_range(-1.0..1.0)).collect())
                .collect();
            let t = ColumnTable::new(r, len, |k, j| cols[j][k]);
            let y: Vec<f64> = (0..r).map(|_| rng.gen_range(-2.0..2.0)).collect();
            let split = rng.gen_range(0..=len);
            let lo = rng.gen_range(0..len);
            let hi = rng.gen_range(lo + 1..=len);
            let (blo, bhi) = t.block_range(lo, hi);
            // The blocks cover lo..hi and at most LANES − 1 more columns on each side.
            assert!(blo * LANES <= lo && bhi * LANES >= hi && bhi * LANES < hi + LANES);
            let start = if trial % 2 == 0 {
                (usize::MAX, f64::INFINITY)
            } else {
                (usize::MAX, -0.1)
            };
            let want = brute(&cols, &y, split, blo * LANES, bhi * LANES, start);
            for &kernel in &kernels {
                let got = t.scan_ranges_with(kernel, &y, split, &[(blo, bhi)], start);
                assert_eq!(
                    got.0, want.0,
                    "trial {trial}: r = {r}, len = {len}, {kernel:?}"
                );
                if got.0 != usize::MAX {
                    assert!((got.1 - want.1).abs() <= 1e-12, "trial {trial}, {kernel:?}");
                } else {
                    assert_eq!(got.1, start.1);
                }
            }
            // Several ranges in one pass = the best of the single-range passes.
            let (b2lo, b2hi) = (blo / 2, blo / 2 + (bhi - blo).min(2));
            let want2 = t.scan_ranges_with(Kernel::Scalar, &y, split, &[(b2lo, b2hi)], want);
            for &kernel in &kernels {
                let got = t.scan_ranges_with(kernel, &y, split, &[(blo, bhi), (b2lo, b2hi)], start);
                assert_eq!(got.0, want2.0, "trial {trial}: two ranges, {kernel:?}");
            }
            let scalar = t.scan_scalar(&y, split, blo, bhi, start);
            assert_eq!(scalar.0, want.0, "trial {trial} (scalar)");
            // Excluded columns never come out.
            let mut t = t;
            for j in (0..len).step_by(3) {
                t.set_excluded(j, true);
            }
            let mut want = start;
            for j in blo * LANES..(bhi * LANES).min(len) {
                if j % 3 != 0 {
                    want = brute(&cols, &y, split, j, j + 1, want);
                }
            }
            for &kernel in &kernels {
                let got = t.scan_ranges_with(kernel, &y, split, &[(blo, bhi)], start);
                assert_eq!(got.0, want.0, "trial {trial} (excluded), {kernel:?}");
            }
        }
    }

    #[test]
    fn padding_columns_never_enter() {
        // Every real column has reduced cost 3; the padding (zero columns, reduced cost 0)
        // must not come out, neither below a negative threshold nor from +∞.
        let t = ColumnTable::new(3, 5, |_, _| -1.0);
        let y = [1.0, 1.0, 1.0];
        assert_eq!(t.blocks(), 1);
        assert_eq!(
            t.scan(&y, 0, 0, 1, (usize::MAX, -1e-10)),
            (usize::MAX, -1e-10)
        );
        assert_eq!(t.scan(&y, 0, 0, 1, (usize::MAX, f64::INFINITY)), (0, 3.0));
        assert_eq!(
            t.scan_scalar(&y, 0, 0, 1, (usize::MAX, f64::INFINITY)),
            (0, 3.0)
        );
    }
}
