use super::*;

#[test]
fn sub_scaled_abs_is_the_same_on_every_path() {
    let f: Vec<f64> = (0..37).map(|i| (i as f64 * 0.37).sin() * 1e3).collect();
    let mut d1 = vec![0.5; 37];
    let mut e1 = vec![0.5; 37];
    let (mut d2, mut e2) = (d1.clone(), e1.clone());
    sub_scaled_abs(&mut d1, &mut e1, -0.3, &f, false);
    sub_scaled_abs(&mut d2, &mut e2, -0.3, &f, has_avx512());
    assert_eq!(d1, d2);
    assert_eq!(e1, e2);
    assert_eq!(d1[3], 0.5 + 0.3 * f[3]);
    assert_eq!(e1[3], 0.5 + (0.3 * f[3]).abs());
}

#[test]
fn sub_rows_abs_is_row_by_row_sub_scaled_abs_bit_for_bit() {
    for n in [1usize, 15, 16, 37, 64] {
        let mat: Vec<f64> = (0..3 * n).map(|i| (i as f64 * 0.37).sin() * 1e3).collect();
        let ys = [-0.3, 1.7e5, 2.5e-7];
        let d0: Vec<f64> = (0..n).map(|i| (i % 3) as f64 - 0.25).collect();
        let e0: Vec<f64> = d0.iter().map(|v| v.abs()).collect();
        let (mut d1, mut e1) = (d0.clone(), e0.clone());
        for (k, &y) in ys.iter().enumerate() {
            sub_scaled_abs(&mut d1, &mut e1, y, &mat[k * n..(k + 1) * n], false);
        }
        for avx in [false, has_avx512()] {
            let (mut d2, mut e2) = (d0.clone(), e0.clone());
            sub_rows_abs(&mut d2, &mut e2, &ys, &mat, avx);
            assert_eq!(d1, d2, "n = {n}");
            assert_eq!(e1, e2, "n = {n}");
        }
    }
}

#[test]
fn reduced_costs_is_fill_then_rows_bit_for_bit_and_flags_every_negative_block() {
    // Row counts of the unrolled kernels (0…12) and of the general one (13).
    for (n, rows) in [1usize, 15, 16, 37, 64, 100]
        .into_iter()
        .flat_map(|n| [0usize, 1, 3, 5, 12, 13].map(|k| (n, k)))
    {
        let mat: Vec<f64> = (0..(rows + 1) * n)
            .map(|i| (i as f64 * 0.37).sin() * 1e3)
            .collect();
        let ys: Vec<f64> = (0..rows)
            .map(|k| [-0.3e-3, 1.7e-4, 2.5e-7][k % 3] * (1.0 + k as f64))
            .collect();
        // Rows in a shuffled order of the matrix's rows.
        let offs: Vec<usize> = (0..rows).map(|k| ((k * 7 + 3) % (rows + 1)) * n).collect();
        for kf in [0, n / 3, n] {
            for y0 in [0.25f64, -0.5] {
                let (mut d1, mut e1) = (vec![0.0; n], vec![0.0; n]);
                for i in 0..n {
                    d1[i] = if i < kf { 1.0 - y0 } else { -y0 };
                    e1[i] = if i < kf { 1.0 + y0.abs() } else { y0.abs() };
                }
                for (&y, &o) in ys.iter().zip(&offs) {
                    sub_scaled_abs(&mut d1, &mut e1, y, &mat[o..o + n], false);
                }
                let g = 1e-3;
                let want: Vec<usize> = (0..n)
                    .step_by(BLOCK)
                    .filter(|&lo| {
                        let hi = (lo + BLOCK).min(n);
                        any_below(&d1[lo..hi], &e1[lo..hi], g)
                    })
                    .collect();
                // The bound on e of the lazy pass: exact, loose, and too tight (e then
                // differs outside the flagged blocks only if the bound is honoured).
                let fmax = |o: usize| mat[o..o + n].iter().fold(0.0f64, |a, v| a.max(v.abs()));
                let tight: f64 = 1.0
                    + y0.abs()
                    + ys.iter()
                        .zip(&offs)
                        .map(|(y, &o)| y.abs() * fmax(o))
                        .sum::<f64>();
                for (avx, bound) in [false, has_avx512()]
                    .into_iter()
                    .flat_map(|a| [(a, None), (a, Some(tight * 1.000001)), (a, Some(1e300))])
                {
                    let (mut d2, mut e2) = (vec![9.0; n], vec![9.0; n]);
                    let mut flagged = vec![7];
                    reduced_costs(
                        &mut d2,
                        &mut e2,
                        (kf, y0),
                        &ys,
                        &mat,
                        &offs,
                        (g, bound),
                        &mut flagged,
                        avx,
                    );
                    assert_eq!(d1, d2, "n = {n}, kf = {kf}");
                    assert_eq!(flagged, want, "n = {n}, kf = {kf}, bound {bound:?}");
                    if bound.is_none() {
                        assert_eq!(e1, e2, "n = {n}, kf = {kf}");
                    }
                    for &lo in &flagged {
                        let hi = (lo + BLOCK).min(n);
                        assert_eq!(e1[lo..hi], e2[lo..hi], "n = {n}, kf = {kf}");
                    }
                }
                // A bound below the true e leaves e unset in blocks that are then missed
                // where d is small but positive: the bound is what makes the pass exact.
                let mut missed = 0;
                for lo in (0..n - n % BLOCK).step_by(BLOCK) {
                    let hi = lo + BLOCK;
                    let open = (lo..hi).any(|i| d1[i] < g * tight);
                    missed += (!open && want.contains(&lo)) as usize;
                }
                assert_eq!(missed, 0, "a flagged block with every d_i ≥ γ E");
            }
        }
    }
}

#[test]
fn reduced_dd_block_is_residual2_bit_for_bit() {
    use crate::lp::dense::residual2;
    let n = 48;
    let mat: Vec<f64> = (0..3 * n).map(|i| (i as f64 * 0.37).sin() * 1e3).collect();
    let offs = [2 * n, 0];
    let y = [0.3, -1.7e9, 2.5e-7];
    let ylo = [1e-17, 3e-8, -2e-23];
    for (lo, kf) in [(0, 5), (16, 0), (32, 48)] {
        for avx in [false, has_avx512()] {
            let mut out = [0.0; BLOCK];
            reduced_dd_block(lo, kf, &y, &ylo, &mat, &offs, &mut out, avx);
            for t in 0..BLOCK {
                let i = lo + t;
                let a = |k: usize| if k == 0 { 1.0 } else { mat[offs[k - 1] + i] };
                let hi = (0..3).map(|k| (y[k], a(k)));
                let lo_terms = (0..3).map(|k| (ylo[k], a(k)));
                let p = if i < kf { 1.0 } else { 0.0 };
                assert_eq!(out[t], residual2(p, hi.chain(lo_terms)), "i = {i}");
            }
        }
    }
}

#[test]
fn price_screen_forms_d_as_sub_rows_abs_bit_for_bit() {
    for n in [1usize, 15, 16, 37, 64] {
        let mat: Vec<f64> = (0..3 * n).map(|i| (i as f64 * 0.37).sin() * 1e3).collect();
        let ys = [-0.3, 1.7e5, 2.5e-7];
        let cost: Vec<f64> = (0..n).map(|i| (i % 3) as f64 * 0.25).collect();
        let mut d1 = cost.clone();
        let mut e1 = cost.clone();
        sub_rows_abs(&mut d1, &mut e1, &ys, &mat, false);
        let t = vec![0.0; n];
        for avx in [false, has_avx512()] {
            let mut d2 = vec![f64::NAN; n];
            let mut flagged = Vec::new();
            price_screen(&mut d2, &cost, &ys, &mat, &t, 0.0, &mut flagged, avx);
            assert_eq!(d1, d2, "n = {n}");
        }
    }
}

/// No rows, so d is the costs: 37 points (two full blocks and a tail of 5), t = 1, g = 0.5:
/// d_i + 1 < −0.5 holds for d = −2 (point 3) and −4 (point 33, in the tail), so the minimum
/// is −4; block 0 is flagged by point 3, block 1 (d = 5, NaN at 20) is not, the tail by
/// its −0.5 (−0.5 + 1 ≤ 0.5) with minimum −4. Without point 33 the minimum is −2. With
/// costs 0 beyond the first block, g = 1.5 flags every block (0 + 1 ≤ 1.5) and no point
/// is below −2.5 (+∞).
#[test]
fn price_screen_exact_values() {
    let mut c = vec![5.0; 37];
    c[3] = -2.0;
    c[20] = f64::NAN;
    c[33] = -4.0;
    c[35] = -0.5;
    let t = vec![1.0; 37];
    let mut d = vec![0.0; 37];
    for avx in [false, has_avx512()] {
        let mut flagged = Vec::new();
        assert_eq!(
            price_screen(&mut d, &c, &[], &[], &t, 0.5, &mut flagged, avx),
            -4.0
        );
        assert_eq!(flagged, vec![(0, -2.0), (32, -4.0)]);
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<u64>>();
        assert_eq!(bits(&d), bits(&c));
        let mut c2 = c.clone();
        c2[33] = 5.0;
        assert_eq!(
            price_screen(&mut d, &c2, &[], &[], &t, 0.5, &mut flagged, avx),
            -2.0
        );
        assert_eq!(flagged, vec![(0, -2.0), (32, -0.5)]);
        c2[16..].fill(0.0);
        let got = price_screen(&mut d, &c2, &[], &[], &t, 1.5, &mut flagged, avx);
        assert_eq!(got, f64::INFINITY);
        assert_eq!(flagged, vec![(0, -2.0), (16, 0.0), (32, 0.0)]);
        assert_eq!(
            price_screen(&mut [], &[], &[], &[], &[], 0.5, &mut flagged, avx),
            f64::INFINITY
        );
        assert!(flagged.is_empty());
    }
}

#[test]
fn min_lower_and_any_below_match_a_scan() {
    let d: Vec<f64> = (0..23).map(|i| (i as f64 - 11.3).abs() * 1e-15).collect();
    let e = vec![1.0; 23];
    let g = 16.0 * f64::EPSILON;
    let want = d.iter().map(|d| d - g).fold(f64::INFINITY, f64::min);
    assert_eq!(min_lower(&d, &e, g), want);
    assert!(any_below(&d, &e, g));
    assert!(any_above(&[0.0, 2e-9], &[0.0, 1.0], 1e-9));
    assert!(!any_above(&[0.0, 1e-9], &[0.0, 1.0], 1e-9));
    assert!(any_above(&[1e-300], &[0.0], 1e-9));
    assert!(!any_below(&d, &e, 0.0));
    let scan: Vec<(usize, f64)> = (0..23)
        .map(|i| (i, d[i] - g * e[i]))
        .filter(|p| p.1 < 0.0)
        .collect();
    assert!(!scan.is_empty());
    assert_eq!(below(&d, &e, g).collect::<Vec<_>>(), scan);
    assert_eq!(min_lower(&[], &[], g), f64::INFINITY);
    let mut d2 = d.clone();
    d2[5] = f64::NAN;
    let want2 = d2.iter().map(|d| d - g).fold(f64::INFINITY, f64::min);
    assert_eq!(min_lower(&d2, &e, g), want2);
}
