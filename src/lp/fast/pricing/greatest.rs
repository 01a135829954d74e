//! Greatest-improvement pricing over a column table (the coarse subgrid of partial pricing).
//!
//! Among the columns with reduced cost d_j = [j < split] − y·a_j below −τ_d, the one whose
//! pivot lowers the objective most: the largest gain −d_j θ_j, with θ_j = min_{t: α_tj > τ_p}
//! x_t / α_tj the ratio-test step of α_j = B⁻¹a_j (ties: the lower d_j, then the lower j). On
//! Algorithm 1, Dantzig's rule (the lowest d_j) picks an end of the grid where the dual
//! polynomial y·a(z) extrapolates the basis: d_j is huge there but θ_j tiny, and the entering
//! column then walks in from the end one short step per pivot. θ_j needs no division per row:
//! 1/θ_j = max_t α_tj / x_t from the reciprocals of the basic weights (x_t = 0: 1/x_t = ∞,
//! θ_j = 0).
//!
//! Two kernels: AVX-512F (one register of [`LANES`] columns per row, the best column per lane
//! in registers) and a scalar one for every other CPU, also the reference of the tests. Both use
//! fused multiply-adds in the same order, so both return the same column.

#![allow(clippy::needless_range_loop)] // lane and row loops over fixed-size arrays

use super::{ColumnTable, Kernel, LANES};

/// A column found by [`scan`]: its index in the table, reduced cost and gain −d θ.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Improving {
    pub j: usize,
    pub d: f64,
    pub gain: f64,
}

/// The basis a scan prices against: its inverse (row-major r × r), the basic weights, and
/// the tolerances (reduced costs below −tol_d qualify, pivot elements above tol_piv count).
#[derive(Clone, Copy)]
pub(crate) struct Basis<'a> {
    pub binv: &'a [f64],
    pub x: &'a [f64],
    pub tol_d: f64,
    pub tol_piv: f64,
}

/// The column of greatest gain over the whole table (None when no reduced cost is below
/// −tol_d). Excluded columns (+∞ penalty) never qualify.
pub(crate) fn scan(
    table: &ColumnTable,
    y: &[f64],
    split: usize,
    basis: &Basis,
) -> Option<Improving> {
    let r = table.r();
    assert!(y.len() >= r && basis.binv.len() >= r * r && basis.x.len() >= r);
    macro_rules! by_rows {
        ($f:ident) => {
            match r {
                1 => $f::<1>(table, y, split, basis),
                2 => $f::<2>(table, y, split, basis),
                3 => $f::<3>(table, y, split, basis),
                4 => $f::<4>(table, y, split, basis),
                5 => $f::<5>(table, y, split, basis),
                6 => $f::<6>(table, y, split, basis),
                7 => $f::<7>(table, y, split, basis),
                8 => $f::<8>(table, y, split, basis),
                9 => $f::<9>(table, y, split, basis),
                10 => $f::<10>(table, y, split, basis),
                11 => $f::<11>(table, y, split, basis),
                12 => $f::<12>(table, y, split, basis),
                13 => $f::<13>(table, y, split, basis),
                // More rows (m ≥ 13): the loop compiled with FMA (AVX-512 implies it,
                // see Kernel::supported), not the scalar one, whose mul_add is a libm call.
                _ => scan_fma(table, y, split, basis),
            }
        };
    }
    match table.kernel() {
        // SAFETY: the table's kernel is supported by this CPU (detected); sizes asserted.
        #[cfg(target_arch = "x86_64")]
        Kernel::Avx512 => unsafe { by_rows!(scan_avx512) },
        // SAFETY: the AVX2 kernel is only detected with FMA.
        #[cfg(target_arch = "x86_64")]
        Kernel::Avx2 => unsafe { scan_fma(table, y, split, basis) },
        _ => scan_scalar(table, y, split, basis),
    }
}

/// [`scan_scalar`] compiled with FMA, so that its fused multiply-adds are instructions, not
/// calls.
///
/// # Safety
/// The CPU must support FMA.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "fma")]
unsafe fn scan_fma(
    table: &ColumnTable,
    y: &[f64],
    split: usize,
    basis: &Basis,
) -> Option<Improving> {
    scan_scalar(table, y, split, basis)
}

/// [`scan`] without SIMD (any row count; the reference of the AVX-512 kernel).
#[inline(always)]
pub(crate) fn scan_scalar(
    table: &ColumnTable,
    y: &[f64],
    split: usize,
    basis: &Basis,
) -> Option<Improving> {
    let (data, ld) = table.rows();
    let r = table.r();
    let pen = table.penalties();
    let xinv: Vec<f64> = basis.x[..r].iter().map(|&x| recip(x)).collect();
    let mut best: Option<Improving> = None;
    for j in 0..table.len() {
        let a = |k: usize| data[k * ld + j];
        let mut s = y[0] * a(0);
        for k in 1..r {
            s = y[k].mul_add(a(k), s);
        }
        let d = reduced(pen[j] - s, j < split);
        if d.is_nan() || d >= -basis.tol_d {
            continue;
        }
        let mut inv = 0.0f64;
        for t in 0..r {
            let mut at = basis.binv[t * r] * a(0);
            for k in 1..r {
                at = basis.binv[t * r + k].mul_add(a(k), at);
            }
            let v = at * xinv[t];
            if at > basis.tol_piv && v > inv {
                inv = v;
            }
        }
        let cand = Improving {
            j,
            d,
            gain: gain(d, inv),
        };
        if best.is_none_or(|b| better(&cand, &b)) {
            best = Some(cand);
        }
    }
    best
}

/// [`scan`] for R rows with AVX-512F.
///
/// # Safety
/// The CPU must support AVX-512F; `y`, `basis.binv`, `basis.x` hold at least R, R², R entries.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
unsafe fn scan_avx512<const R: usize>(
    table: &ColumnTable,
    y: &[f64],
    split: usize,
    basis: &Basis,
) -> Option<Improving> {
    use std::arch::x86_64::*;
    let (data, ld) = table.rows();
    let (data, pen) = (data.as_ptr(), table.penalties().as_ptr());
    let zero = _mm512_setzero_pd();
    let yv: [__m512d; R] = std::array::from_fn(|k| _mm512_set1_pd(y[k]));
    let xinv: [__m512d; R] = std::array::from_fn(|t| _mm512_set1_pd(recip(basis.x[t])));
    let one = _mm512_set1_pd(1.0);
    let neg_tol = _mm512_set1_pd(-basis.tol_d);
    let tol_piv = _mm512_set1_pd(basis.tol_piv);
    let splitv = _mm512_set1_pd(split as f64);
    let iota = _mm512_setr_pd(0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0);
    let mut bg = _mm512_set1_pd(f64::NEG_INFINITY);
    let mut bd = zero;
    let mut bj = _mm512_set1_pd(-1.0);
    for b in 0..table.blocks() {
        let base = b * LANES;
        // SAFETY (all loads): k < R = table.r() rows of ld ≥ base + LANES columns; pen has ld.
        let a: [__m512d; R] = std::array::from_fn(|k| _mm512_loadu_pd(data.add(k * ld + base)));
        let mut s = _mm512_mul_pd(yv[0], a[0]);
        for k in 1..R {
            s = _mm512_fmadd_pd(yv[k], a[k], s);
        }
        let idx = _mm512_add_pd(_mm512_set1_pd(base as f64), iota);
        let below = _mm512_cmp_pd_mask::<_CMP_LT_OQ>(idx, splitv);
        let d = _mm512_sub_pd(_mm512_loadu_pd(pen.add(base)), s);
        let d = _mm512_mask_add_pd(d, below, d, one);
        let neg = _mm512_cmp_pd_mask::<_CMP_LT_OQ>(d, neg_tol);
        if neg == 0 {
            continue;
        }
        let mut inv = zero;
        for t in 0..R {
            let row = &basis.binv[t * R..(t + 1) * R];
            let mut at = _mm512_mul_pd(_mm512_set1_pd(row[0]), a[0]);
            for k in 1..R {
                at = _mm512_fmadd_pd(_mm512_set1_pd(row[k]), a[k], at);
            }
            let v = _mm512_mul_pd(at, xinv[t]);
            let m = _mm512_cmp_pd_mask::<_CMP_GT_OQ>(at, tol_piv)
                & _mm512_cmp_pd_mask::<_CMP_GT_OQ>(v, inv);
            inv = _mm512_mask_mov_pd(inv, m, v);
        }
        let positive = _mm512_cmp_pd_mask::<_CMP_GT_OQ>(inv, zero);
        let g = _mm512_maskz_div_pd(positive, _mm512_sub_pd(zero, d), inv);
        // better(candidate, lane's best): greater gain, then lower d, then lower index.
        let gt = _mm512_cmp_pd_mask::<_CMP_GT_OQ>(g, bg);
        let geq = _mm512_cmp_pd_mask::<_CMP_EQ_OQ>(g, bg);
        let dlt = _mm512_cmp_pd_mask::<_CMP_LT_OQ>(d, bd);
        let deq = _mm512_cmp_pd_mask::<_CMP_EQ_OQ>(d, bd);
        let jlt = _mm512_cmp_pd_mask::<_CMP_LT_OQ>(idx, bj);
        let empty = _mm512_cmp_pd_mask::<_CMP_LT_OQ>(bj, zero);
        let take = neg & (empty | gt | (geq & (dlt | (deq & jlt))));
        bg = _mm512_mask_mov_pd(bg, take, g);
        bd = _mm512_mask_mov_pd(bd, take, d);
        bj = _mm512_mask_mov_pd(bj, take, idx);
    }
    let (mut g, mut d, mut j) = ([0.0; LANES], [0.0; LANES], [0.0; LANES]);
    _mm512_storeu_pd(g.as_mut_ptr(), bg);
    _mm512_storeu_pd(d.as_mut_ptr(), bd);
    _mm512_storeu_pd(j.as_mut_ptr(), bj);
    let mut best: Option<Improving> = None;
    for l in 0..LANES {
        if j[l] >= 0.0 {
            let cand = Improving {
                j: j[l] as usize,
                d: d[l],
                gain: g[l],
            };
            if best.is_none_or(|b| better(&cand, &b)) {
                best = Some(cand);
            }
        }
    }
    best
}

/// d = (pen − s) + [j < split] (the rounding of the Dantzig kernels).
#[inline(always)]
fn reduced(pen_minus_s: f64, below: bool) -> f64 {
    if below {
        pen_minus_s + 1.0
    } else {
        pen_minus_s
    }
}

/// 1/x for a positive weight, +∞ otherwise (a degenerate row: θ = 0).
#[inline(always)]
fn recip(x: f64) -> f64 {
    if x > 0.0 {
        1.0 / x
    } else {
        f64::INFINITY
    }
}

/// −d θ from 1/θ = `inv`; 0 when no pivot element is positive (no step bound: an unbounded
/// ray, which only rounding produces here; ranked last).
#[inline(always)]
fn gain(d: f64, inv: f64) -> f64 {
    if inv > 0.0 {
        -d / inv
    } else {
        0.0
    }
}

/// a ranks before b: greater gain, then lower reduced cost, then lower index.
#[inline(always)]
fn better(a: &Improving, b: &Improving) -> bool {
    a.gain > b.gain || (a.gain == b.gain && (a.d < b.d || (a.d == b.d && a.j < b.j)))
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// The definition, with a division per row: the gain −d·min_t x_t/α_t of every column.
    fn brute(t: &ColumnTable, cols: &[Vec<f64>], y: &[f64], split: usize, b: &Basis) -> Vec<f64> {
        let r = t.r();
        (0..cols.len())
            .map(|j| {
                let a = &cols[j];
                let s: f64 = (0..r).map(|k| y[k] * a[k]).sum();
                let d = t.penalties()[j] - s + (j < split) as u8 as f64;
                if d.is_nan() || d >= -b.tol_d {
                    return f64::NAN;
                }
                let theta = (0..r)
                    .filter_map(|i| {
                        let at: f64 = (0..r).map(|k| b.binv[i * r + k] * a[k]).sum();
                        (at > b.tol_piv).then(|| b.x[i].max(0.0) / at)
                    })
                    .fold(f64::INFINITY, f64::min);
                if theta.is_finite() {
                    -d * theta
                } else {
                    0.0
                }
            })
            .collect()
    }

    #[test]
    fn kernels_agree_and_pick_the_greatest_gain() {
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        let mut found = 0;
        for trial in 0..3000 {
            let r = 1 + trial % 15;
            let len = rng.gen_range(1..60);
            let cols: Vec<Vec<f64>> = (0..len)
                .map(|_| (0..r).map(|_| rng.gen_range(-3.0..3.0)).collect())
                .collect();
            let mut t = ColumnTable::new(r, len, |k, j| cols[j][k]);
            for j in 0..len {
                if rng.gen_bool(0.1) {
                    t.set_excluded(j, true);
                }
            }
            let y: Vec<f64> = (0..r).map(|_| rng.gen_range(-4.0..4.0)).collect();
            let binv: Vec<f64> = (0..r * r).map(|_| rng.gen_range(-2.0..2.0)).collect();
            // Degenerate rows (x = 0) and negative rounding-level weights too.
            let x: Vec<f64> = (0..r)
                .map(|_| match rng.gen_range(0..5) {
                    0 => 0.0,
                    1 => -1e-17,
                    _ => rng.gen_range(0.0..1.0),
                })
                .collect();
            let b = Basis {
                binv: &binv,
                x: &x,
                tol_d: 1e-10,
                tol_piv: 1e-9,
            };
            let split = rng.gen_range(0..=len);
            let scalar = scan_scalar(&t, &y, split, &b);
            assert_eq!(scan(&t, &y, split, &b), scalar, "trial {trial}");
            let gains = brute(&t, &cols, &y, split, &b);
            match scalar {
                None => assert!(gains.iter().all(|g| g.is_nan()), "trial {trial}"),
                Some(c) => {
                    found += 1;
                    let top = gains
                        .iter()
                        .copied()
                        .filter(|g| !g.is_nan())
                        .fold(0.0, f64::max);
                    assert!(
                        (gains[c.j] - top).abs() <= 1e-9 * (1.0 + top),
                        "trial {trial}"
                    );
                    assert!(
                        (c.gain - gains[c.j]).abs() <= 1e-9 * (1.0 + top),
                        "trial {trial}"
                    );
                }
            }
        }
        assert!(found > 2000, "{found}");
    }
}
