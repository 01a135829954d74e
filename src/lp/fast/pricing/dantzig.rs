//! The dense Dantzig kernel: every column's reduced cost in one pass (AVX2/FMA or generic).

use super::ColumnTable;

/// Dantzig pricing: s_i = y·a_i for every column; returns the column with the most negative
/// reduced cost d_i = [i < kf] − s_i and that reduced cost.
/// Basic columns are excluded (their reduced cost is 0 in exact arithmetic).
pub(crate) fn price(
    table: &ColumnTable,
    n: usize,
    r: usize,
    y: &[f64],
    kf: usize,
    basis: &[usize],
    s: &mut [f64],
) -> (usize, f64) {
    #[cfg(target_arch = "x86_64")]
    {
        if crate::lp::cpu::has_avx2_fma() {
            // SAFETY: the CPU supports the features enabled on `price_avx2`.
            return unsafe { price_avx2(table, n, r, y, kf, basis, s) };
        }
    }
    price_generic::<false>(table, n, r, y, kf, basis, s)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
unsafe fn price_avx2(
    table: &ColumnTable,
    n: usize,
    r: usize,
    y: &[f64],
    kf: usize,
    basis: &[usize],
    s: &mut [f64],
) -> (usize, f64) {
    price_generic::<true>(table, n, r, y, kf, basis, s)
}

#[inline(always)]
fn price_generic<const FMA: bool>(
    table: &ColumnTable,
    n: usize,
    r: usize,
    y: &[f64],
    kf: usize,
    basis: &[usize],
    s: &mut [f64],
) -> (usize, f64) {
    let (cols, ld) = table.rows();
    let s = &mut s[..n];
    let y0 = y[0];
    for (si, &c) in s.iter_mut().zip(&cols[..n]) {
        *si = y0 * c;
    }
    for k in 1..r {
        let yk = y[k];
        for (si, &c) in s.iter_mut().zip(&cols[k * ld..k * ld + n]) {
            *si = if FMA {
                yk.mul_add(c, *si)
            } else {
                yk * c + *si
            };
        }
    }
    for &bt in basis {
        if bt < n {
            s[bt] = if bt < kf { 1.0 } else { 0.0 };
        }
    }
    let (il, sl) = argmax(&s[..kf]);
    let (ir, sr) = argmax(&s[kf..]);
    let dl = 1.0 - sl;
    let dr = -sr;
    if dl <= dr {
        (il, dl)
    } else {
        (kf + ir, dr)
    }
}

/// Index and value of the maximum (first among equals; (0, −∞) when empty).
#[inline(always)]
fn argmax(s: &[f64]) -> (usize, f64) {
    const L: usize = 8;
    let mut bv = [f64::NEG_INFINITY; L];
    let mut bi = [0usize; L];
    let chunks = s.len() / L;
    for c in 0..chunks {
        let base = c * L;
        let ch = &s[base..base + L];
        for l in 0..L {
            if ch[l] > bv[l] {
                bv[l] = ch[l];
                bi[l] = base + l;
            }
        }
    }
    for (i, &v) in s.iter().enumerate().skip(chunks * L) {
        let l = i % L;
        if v > bv[l] {
            bv[l] = v;
            bi[l] = i;
        }
    }
    let mut best = (0usize, f64::NEG_INFINITY);
    for l in 0..L {
        if bv[l] > best.1 || (bv[l] == best.1 && bi[l] < best.0) {
            best = (bi[l], bv[l]);
        }
    }
    best
}
