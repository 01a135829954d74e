//! Kernels over the grid points of one row of the LP, used by the certificate
//! ([`crate::lp::certify`]): pure functions over slices, written so the compiler vectorises them
//! (no fused multiply-add: the results are the same, bit for bit, on every path).

#![allow(clippy::needless_range_loop)] // lane-indexed blocks the compiler vectorises

/// Grid points per block of [`any_below`] scans.
pub const BLOCK: usize = 16;

pub(crate) use crate::lp::cpu::has_avx512;

/// d_i −= y·f_i and e_i += |y·f_i| (one row of d = p − Σ_j y_j f_j(z_i) and of its magnitude).
pub fn sub_scaled_abs(d: &mut [f64], e: &mut [f64], y: f64, f: &[f64], avx512: bool) {
    #[cfg(target_arch = "x86_64")]
    if avx512 {
        // SAFETY: `avx512` is only true where the CPU has AVX-512F (`has_avx512`).
        unsafe { sub_scaled_abs_avx512(d, e, y, f) };
        return;
    }
    let _ = avx512;
    sub_scaled_abs_generic(d, e, y, f);
}

#[inline(always)]
fn sub_scaled_abs_generic(d: &mut [f64], e: &mut [f64], y: f64, f: &[f64]) {
    let n = d.len().min(e.len()).min(f.len());
    let (d, e, f) = (&mut d[..n], &mut e[..n], &f[..n]);
    for i in 0..n {
        let t = y * f[i];
        d[i] -= t;
        e[i] += t.abs();
    }
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
unsafe fn sub_scaled_abs_avx512(d: &mut [f64], e: &mut [f64], y: f64, f: &[f64]) {
    sub_scaled_abs_generic(d, e, y, f)
}

/// d_i −= Σ_k y_k f_k(z_i) and e_i += Σ_k |y_k f_k(z_i)|, the rows f_k at mat[k·n..(k+1)·n]
/// (n = d.len()): [`sub_scaled_abs`] for every row in one pass over d and e, with the same
/// operations in the same order per point (the same bits).
pub fn sub_rows_abs(d: &mut [f64], e: &mut [f64], ys: &[f64], mat: &[f64], avx512: bool) {
    let n = d.len();
    assert!(e.len() == n && mat.len() >= ys.len() * n);
    #[cfg(target_arch = "x86_64")]
    if avx512 {
        // SAFETY: `avx512` is only true where the CPU has AVX-512F (`has_avx512`).
        unsafe { sub_rows_abs_avx512(d, e, ys, mat) };
        return;
    }
    let _ = avx512;
    sub_rows_abs_generic(d, e, ys, mat);
}

#[inline(always)]
fn sub_rows_abs_generic(d: &mut [f64], e: &mut [f64], ys: &[f64], mat: &[f64]) {
    let n = d.len();
    let full = n - n % BLOCK;
    for lo in (0..full).step_by(BLOCK) {
        let mut db = [0.0; BLOCK];
        let mut eb = [0.0; BLOCK];
        db.copy_from_slice(&d[lo..lo + BLOCK]);
        eb.copy_from_slice(&e[lo..lo + BLOCK]);
        for (k, &y) in ys.iter().enumerate() {
            let f = &mat[k * n + lo..k * n + lo + BLOCK];
            for t in 0..BLOCK {
                let v = y * f[t];
                db[t] -= v;
                eb[t] += v.abs();
            }
        }
        d[lo..lo + BLOCK].copy_from_slice(&db);
        e[lo..lo + BLOCK].copy_from_slice(&eb);
    }
    for (k, &y) in ys.iter().enumerate() {
        let f = &mat[k * n..(k + 1) * n];
        for i in full..n {
            let v = y * f[i];
            d[i] -= v;
            e[i] += v.abs();
        }
    }
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
unsafe fn sub_rows_abs_avx512(d: &mut [f64], e: &mut [f64], ys: &[f64], mat: &[f64]) {
    sub_rows_abs_generic(d, e, ys, mat)
}

/// A Dantzig pricing pass with its screening, in one pass over the grid:
/// d_i = c_i − Σ_k y_k f_k(z_i), with c_i = `cost[i]` and the rows f_k at mat[k·n..(k+1)·n]
/// (n = d.len()), per point the operations of filling d with c and then [`sub_rows_abs`] in
/// the same order (the same bits of d). With thresholds t and one
/// rounding bound g for all points it returns min d_i over the points with d_i + t_i < −g
/// (+∞ for none) and lists in `flagged`, as (first index, min d_i of the block), every block
/// of [`BLOCK`] points holding some d_i + t_i ≤ g. NaN values never qualify and are skipped
/// in the block minima.
#[allow(clippy::too_many_arguments)] // one fused pass: the reduced costs and their screening
pub fn price_screen(
    d: &mut [f64],
    cost: &[f64],
    ys: &[f64],
    mat: &[f64],
    t: &[f64],
    g: f64,
    flagged: &mut Vec<(usize, f64)>,
    avx512: bool,
) -> f64 {
    let n = d.len();
    assert!(cost.len() == n && t.len() == n && mat.len() >= ys.len() * n);
    flagged.clear();
    #[cfg(target_arch = "x86_64")]
    if avx512 {
        // SAFETY: `avx512` is only true where the CPU has AVX-512F (`has_avx512`).
        return unsafe { price_screen_avx512(d, cost, ys, mat, t, g, flagged) };
    }
    let _ = avx512;
    price_screen_generic(d, cost, ys, mat, t, g, flagged)
}

#[inline(always)]
fn price_screen_generic(
    d: &mut [f64],
    cost: &[f64],
    ys: &[f64],
    mat: &[f64],
    t: &[f64],
    g: f64,
    flagged: &mut Vec<(usize, f64)>,
) -> f64 {
    let n = d.len();
    let mut lanes = [f64::INFINITY; BLOCK];
    let full = n - n % BLOCK;
    for lo in (0..full).step_by(BLOCK) {
        let mut db: [f64; BLOCK] = cost[lo..lo + BLOCK].try_into().unwrap();
        for (k, &y) in ys.iter().enumerate() {
            let f: &[f64; BLOCK] = mat[k * n + lo..k * n + lo + BLOCK].try_into().unwrap();
            for j in 0..BLOCK {
                db[j] -= y * f[j];
            }
        }
        d[lo..lo + BLOCK].copy_from_slice(&db);
        let tb: &[f64; BLOCK] = t[lo..lo + BLOCK].try_into().unwrap();
        let mut hit = false;
        let mut low = [f64::INFINITY; BLOCK];
        for j in 0..BLOCK {
            // Plain comparisons (false for NaN) and selects: vector code, no branches.
            let (v, s) = (db[j], db[j] + tb[j]);
            hit |= s <= g;
            let below = if s < -g { v } else { f64::INFINITY };
            lanes[j] = if below < lanes[j] { below } else { lanes[j] };
            low[j] = if v < low[j] { v } else { low[j] };
        }
        if hit {
            // The block minimum by halving (vector code rather than a chain of 16 minima).
            for w in [8, 4, 2, 1] {
                for j in 0..w {
                    low[j] = if low[j + w] < low[j] {
                        low[j + w]
                    } else {
                        low[j]
                    };
                }
            }
            flagged.push((lo, low[0]));
        }
    }
    let mut out = lanes.iter().fold(f64::INFINITY, |a, &b| a.min(b));
    let (mut hit, mut low) = (false, f64::INFINITY);
    for i in full..n {
        let mut v = cost[i];
        for (k, &y) in ys.iter().enumerate() {
            v -= y * mat[k * n + i];
        }
        d[i] = v;
        let s = v + t[i];
        hit |= s <= g;
        if s < -g {
            out = out.min(v);
        }
        low = low.min(v);
    }
    if hit {
        flagged.push((full, low));
    }
    out
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
unsafe fn price_screen_avx512(
    d: &mut [f64],
    cost: &[f64],
    ys: &[f64],
    mat: &[f64],
    t: &[f64],
    g: f64,
    flagged: &mut Vec<(usize, f64)>,
) -> f64 {
    price_screen_generic(d, cost, ys, mat, t, g, flagged)
}

/// The reduced costs of a dual vector over the grid in one pass:
/// d_i = p_i − y₀ − Σ_k y_k f_k(z_i) and e_i = p_i + |y₀| + Σ_k |y_k f_k(z_i)| with
/// p_i = [i < kf], the row f_k at `mat[offs[k]..offs[k] + n]` (n = d.len()). Returns in `flagged`
/// the first index of every block of [`BLOCK`] points holding some d_i − γ e_i < 0. Per point the
/// same operations in the same order as filling d and e and then [`sub_scaled_abs`] row by row
/// (the same bits).
///
/// With `ebound` = Some(E), E ≥ every e_i (e.g. 1 + |y₀| + Σ_k |y_k| max_i |f_k(z_i)|), e is
/// only computed in the blocks with some d_i < γ E, the only ones that can be flagged, and left
/// as it was elsewhere: d and `flagged` are the same, e the same in the flagged blocks.
#[allow(clippy::too_many_arguments)] // one fused pass: the reduced costs and their bound
pub fn reduced_costs(
    d: &mut [f64],
    e: &mut [f64],
    (kf, y0): (usize, f64),
    ys: &[f64],
    mat: &[f64],
    offs: &[usize],
    (gamma, ebound): (f64, Option<f64>),
    flagged: &mut Vec<usize>,
    avx512: bool,
) {
    let n = d.len();
    assert!(e.len() == n && ys.len() == offs.len());
    assert!(offs.iter().all(|&o| o + n <= mat.len()));
    flagged.clear();
    let y = (kf, y0);
    let g = (gamma, ebound);
    #[cfg(target_arch = "x86_64")]
    if avx512 {
        // SAFETY: `avx512` is only true where the CPU has AVX-512F (`has_avx512`).
        unsafe { reduced_costs_avx512(d, e, y, ys, mat, offs, g, flagged) };
        return;
    }
    let _ = avx512;
    reduced_costs_generic(d, e, y, ys, mat, offs, g, flagged);
}

/// [`reduced_costs_rows`] for the number of function rows at hand (unrolled up to 12).
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn reduced_costs_generic(
    d: &mut [f64],
    e: &mut [f64],
    y: (usize, f64),
    ys: &[f64],
    mat: &[f64],
    offs: &[usize],
    g: (f64, Option<f64>),
    flagged: &mut Vec<usize>,
) {
    macro_rules! by_rows {
        ($($k:literal)*) => {
            match ys.len() {
                $($k => reduced_costs_rows::<$k>(d, e, y, ys, mat, offs, g, flagged),)*
                _ => reduced_costs_any(d, e, y, ys, mat, offs, g, flagged),
            }
        };
    }
    by_rows!(0 1 2 3 4 5 6 7 8 9 10 11 12)
}

/// [`reduced_costs`] for K function rows: the rows as K slices of length n, the row loop
/// unrolled (the same operations in the same order as [`reduced_costs_any`]).
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn reduced_costs_rows<const K: usize>(
    d: &mut [f64],
    e: &mut [f64],
    (kf, y0): (usize, f64),
    ys: &[f64],
    mat: &[f64],
    offs: &[usize],
    (gamma, ebound): (f64, Option<f64>),
    flagged: &mut Vec<usize>,
) {
    let n = d.len();
    let rows: [&[f64]; K] = std::array::from_fn(|k| &mat[offs[k]..offs[k] + n]);
    let yk: [f64; K] = std::array::from_fn(|k| ys[k]);
    let full = n - n % BLOCK;
    let ay0 = y0.abs();
    let open = ebound.map(|b| gamma * b);
    let (dfull, efull) = (&mut d[..full], &mut e[..full]);
    for (b, (dc, ec)) in dfull
        .chunks_exact_mut(BLOCK)
        .zip(efull.chunks_exact_mut(BLOCK))
        .enumerate()
    {
        let lo = b * BLOCK;
        let f: [&[f64; BLOCK]; K] =
            std::array::from_fn(|k| rows[k][lo..lo + BLOCK].try_into().expect("block"));
        let mut db = [0.0; BLOCK];
        for t in 0..BLOCK {
            let p = if lo + t < kf { 1.0 } else { 0.0 };
            db[t] = p - y0;
        }
        for k in 0..K {
            for t in 0..BLOCK {
                db[t] -= yk[k] * f[k][t];
            }
        }
        dc.copy_from_slice(&db);
        if let Some(open) = open {
            let mut candidate = false;
            for t in 0..BLOCK {
                candidate |= db[t] < open;
            }
            if !candidate {
                continue;
            }
        }
        let mut eb = [0.0; BLOCK];
        for t in 0..BLOCK {
            let p = if lo + t < kf { 1.0 } else { 0.0 };
            eb[t] = p + ay0;
        }
        for k in 0..K {
            for t in 0..BLOCK {
                eb[t] += (yk[k] * f[k][t]).abs();
            }
        }
        let mut hit = false;
        for t in 0..BLOCK {
            hit |= db[t] - gamma * eb[t] < 0.0;
        }
        ec.copy_from_slice(&eb);
        if hit {
            flagged.push(lo);
        }
    }
    reduced_costs_tail(d, e, (kf, y0), ys, mat, offs, gamma, flagged);
}

/// The points after the last whole block, one by one.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn reduced_costs_tail(
    d: &mut [f64],
    e: &mut [f64],
    (kf, y0): (usize, f64),
    ys: &[f64],
    mat: &[f64],
    offs: &[usize],
    gamma: f64,
    flagged: &mut Vec<usize>,
) {
    let n = d.len();
    let full = n - n % BLOCK;
    let ay0 = y0.abs();
    let mut hit = false;
    for i in full..n {
        let p = if i < kf { 1.0 } else { 0.0 };
        let (mut di, mut ei) = (p - y0, p + ay0);
        for (&y, &o) in ys.iter().zip(offs) {
            let v = y * mat[o + i];
            di -= v;
            ei += v.abs();
        }
        d[i] = di;
        e[i] = ei;
        hit |= di - gamma * ei < 0.0;
    }
    if hit {
        flagged.push(full);
    }
}

/// [`reduced_costs`] for any number of function rows.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn reduced_costs_any(
    d: &mut [f64],
    e: &mut [f64],
    (kf, y0): (usize, f64),
    ys: &[f64],
    mat: &[f64],
    offs: &[usize],
    (gamma, ebound): (f64, Option<f64>),
    flagged: &mut Vec<usize>,
) {
    let n = d.len();
    let full = n - n % BLOCK;
    let ay0 = y0.abs();
    // d_i < γ E is necessary for d_i − γ e_i < 0.
    let open = ebound.map(|b| gamma * b);
    for lo in (0..full).step_by(BLOCK) {
        let mut db = [0.0; BLOCK];
        for t in 0..BLOCK {
            let p = if lo + t < kf { 1.0 } else { 0.0 };
            db[t] = p - y0;
        }
        for (&y, &o) in ys.iter().zip(offs) {
            let f = &mat[o + lo..o + lo + BLOCK];
            for t in 0..BLOCK {
                db[t] -= y * f[t];
            }
        }
        d[lo..lo + BLOCK].copy_from_slice(&db);
        if let Some(open) = open {
            let mut candidate = false;
            for t in 0..BLOCK {
                candidate |= db[t] < open;
            }
            if !candidate {
                continue;
            }
        }
        let mut eb = [0.0; BLOCK];
        for t in 0..BLOCK {
            let p = if lo + t < kf { 1.0 } else { 0.0 };
            eb[t] = p + ay0;
        }
        for (&y, &o) in ys.iter().zip(offs) {
            let f = &mat[o + lo..o + lo + BLOCK];
            for t in 0..BLOCK {
                eb[t] += (y * f[t]).abs();
            }
        }
        let mut hit = false;
        for t in 0..BLOCK {
            hit |= db[t] - gamma * eb[t] < 0.0;
        }
        e[lo..lo + BLOCK].copy_from_slice(&eb);
        if hit {
            flagged.push(lo);
        }
    }
    reduced_costs_tail(d, e, (kf, y0), ys, mat, offs, gamma, flagged);
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
#[allow(clippy::too_many_arguments)]
unsafe fn reduced_costs_avx512(
    d: &mut [f64],
    e: &mut [f64],
    kf: (usize, f64),
    ys: &[f64],
    mat: &[f64],
    offs: &[usize],
    gamma: (f64, Option<f64>),
    flagged: &mut Vec<usize>,
) {
    reduced_costs_generic(d, e, kf, ys, mat, offs, gamma, flagged)
}

/// For the [`BLOCK`] grid points from `lo`: out_t = p_i − Σ_k (y_k + ylo_k) f_k(z_i) in
/// double-double (Dekker's exact products, Knuth's exact sums; rounded once at the end), with
/// p_i = [i < kf], f_0 = 1 and f_k (k ≥ 1) at `mat[offs[k−1] + i]`. The terms in the order
/// y_0, …, y_{r−1}, ylo_0, …, ylo_{r−1}: per point the same operations as
/// `dense::residual2(p_i, those terms)` (the same bits), over a whole block at once.
#[allow(clippy::too_many_arguments)] // one fused pass over a block
pub fn reduced_dd_block(
    lo: usize,
    kf: usize,
    y: &[f64],
    ylo: &[f64],
    mat: &[f64],
    offs: &[usize],
    out: &mut [f64; BLOCK],
    avx512: bool,
) {
    assert!(y.len() == ylo.len() && offs.len() + 1 == y.len());
    assert!(offs.iter().all(|&o| o + lo + BLOCK <= mat.len()));
    #[cfg(target_arch = "x86_64")]
    if avx512 {
        // SAFETY: `avx512` is only true where the CPU has AVX-512F (`has_avx512`).
        unsafe { reduced_dd_block_avx512(lo, kf, y, ylo, mat, offs, out) };
        return;
    }
    let _ = avx512;
    reduced_dd_block_generic(lo, kf, y, ylo, mat, offs, out);
}

#[inline(always)]
fn reduced_dd_block_generic(
    lo: usize,
    kf: usize,
    y: &[f64],
    ylo: &[f64],
    mat: &[f64],
    offs: &[usize],
    out: &mut [f64; BLOCK],
) {
    const SPLIT: f64 = 134_217_729.0; // 2^27 + 1, as in dense::two_prod
    let mut s = [0.0f64; BLOCK];
    let mut err = [0.0f64; BLOCK];
    for t in 0..BLOCK {
        s[t] = if lo + t < kf { 1.0 } else { 0.0 };
    }
    let ones = [1.0f64; BLOCK];
    for part in [y, ylo] {
        for (k, &yk) in part.iter().enumerate() {
            let f: &[f64] = if k == 0 {
                &ones
            } else {
                &mat[offs[k - 1] + lo..offs[k - 1] + lo + BLOCK]
            };
            let c = SPLIT * yk;
            let ah = c - (c - yk);
            let al = yk - ah;
            for t in 0..BLOCK {
                let b = f[t];
                let p = yk * b;
                let cb = SPLIT * b;
                let bh = cb - (cb - b);
                let bl = b - bh;
                let ep = ((ah * bh - p) + ah * bl + al * bh) + al * bl;
                let np = -p;
                let sum = s[t] + np;
                let bb = sum - s[t];
                let es = (s[t] - (sum - bb)) + (np - bb);
                s[t] = sum;
                err[t] += es - ep;
            }
        }
    }
    for t in 0..BLOCK {
        out[t] = s[t] + err[t];
    }
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
unsafe fn reduced_dd_block_avx512(
    lo: usize,
    kf: usize,
    y: &[f64],
    ylo: &[f64],
    mat: &[f64],
    offs: &[usize],
    out: &mut [f64; BLOCK],
) {
    reduced_dd_block_generic(lo, kf, y, ylo, mat, offs, out)
}

/// Whether some d_i − γ e_i < 0 (d and e of equal length).
pub fn any_below(d: &[f64], e: &[f64], gamma: f64) -> bool {
    let mut hit = false;
    for (d, e) in d.iter().zip(e) {
        hit |= d - gamma * e < 0.0;
    }
    hit
}

/// (i, d_i − γ e_i) for every i where that is negative, in index order; blocks of [`BLOCK`]
/// points are skipped with one vectorised [`any_below`] test each.
pub fn below<'a>(
    d: &'a [f64],
    e: &'a [f64],
    gamma: f64,
) -> impl Iterator<Item = (usize, f64)> + 'a {
    let n = d.len().min(e.len());
    (0..n)
        .step_by(BLOCK)
        .filter(move |&lo| {
            let hi = (lo + BLOCK).min(n);
            any_below(&d[lo..hi], &e[lo..hi], gamma)
        })
        .flat_map(move |lo| lo..(lo + BLOCK).min(n))
        .filter_map(move |i| {
            let v = d[i] - gamma * e[i];
            (v < 0.0).then_some((i, v))
        })
}

/// Whether some a_i > c · max(m_i, f64::MIN_POSITIVE) (the slices of equal length): a block
/// test for entries that are positive beyond their own rounding scale.
pub fn any_above(a: &[f64], m: &[f64], c: f64) -> bool {
    let mut hit = false;
    for (a, m) in a.iter().zip(m) {
        hit |= *a > c * m.max(f64::MIN_POSITIVE);
    }
    hit
}

/// Whether some d_i + t_i ≤ γ e_i, i.e. d_i + t_i may be negative within the rounding bound
/// γ e_i (the slices of equal length).
pub fn any_below_shifted(d: &[f64], t: &[f64], e: &[f64], gamma: f64) -> bool {
    let mut hit = false;
    for ((d, t), e) in d.iter().zip(t).zip(e) {
        hit |= d + t <= gamma * e;
    }
    hit
}

/// min_i (d_i − γ e_i) (+∞ for no points; NaN values are skipped, as by `f64::min`).
pub fn min_lower(d: &[f64], e: &[f64], gamma: f64) -> f64 {
    const L: usize = 8;
    let mut lanes = [f64::INFINITY; L];
    let (dc, ec) = (d.chunks_exact(L), e.chunks_exact(L));
    let (dr, er) = (dc.remainder(), ec.remainder());
    for (d8, e8) in dc.zip(ec) {
        for k in 0..L {
            // A plain comparison (false for NaN) compiles to a vector min; f64::min does not.
            let v = d8[k] - gamma * e8[k];
            lanes[k] = if v < lanes[k] { v } else { lanes[k] };
        }
    }
    let tail = dr.iter().zip(er).map(|(d, e)| d - gamma * e);
    tail.chain(lanes).fold(f64::INFINITY, f64::min)
}

#[cfg(test)]
mod tests;
