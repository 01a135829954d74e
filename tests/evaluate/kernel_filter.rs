//! The 9×9 Gaussian, separable filtering and moment maps against direct 81-tap sums.

use crate::common::kernel::*;
use momentlab::kernel::{self, Gaussian};
use rand::Rng;

#[test]
fn gaussian_weights_sum_to_one_and_are_symmetric() {
    let g = Gaussian::paper();
    assert_eq!(g.radius(), 4);
    assert_eq!(g.sigma(), 2.4);
    let w = g.weights_1d();
    assert_eq!(w.len(), 9);
    assert!((w.iter().sum::<f64>() - 1.0).abs() < 1e-15);
    for i in 0..9 {
        assert_eq!(w[i], w[8 - i], "1-D weights symmetric");
        assert!(w[i] > 0.0);
    }
    for i in 0..4 {
        assert!(w[i] < w[i + 1], "weights increase towards the centre");
    }
    let taps = g.taps();
    assert_eq!(taps.len(), 81);
    assert!((taps.iter().map(|t| t.2).sum::<f64>() - 1.0).abs() < 1e-14);
    // against the independent 2-D formula
    for ((dx, dy, w), (bx, by, bw)) in taps.iter().zip(brute_weights()) {
        assert_eq!((*dx, *dy), (bx, by));
        assert!((w - bw).abs() < 1e-15, "tap ({dx},{dy}): {w} vs {bw}");
        assert_eq!(g.weight(*dx, *dy), g.weight(-dx, *dy));
        assert_eq!(g.weight(*dx, *dy), g.weight(*dy, *dx));
    }
    assert_eq!(g.weight(5, 0), 0.0);
}

#[test]
fn separable_filter_equals_direct_sum_with_clamped_edges() {
    let mut r = rng(1);
    let g = Gaussian::paper();
    let mut checked = 0;
    for case in 0..150 {
        // include maps narrower than the kernel and degenerate 1×n maps
        let (w, h) = if case < 10 {
            (1 + case % 3, 1 + case / 3)
        } else {
            (r.gen_range(1..24), r.gen_range(1..24))
        };
        let map: Vec<f64> = (0..w * h)
            .map(|_| {
                if r.gen_bool(0.2) {
                    1.0
                } else {
                    r.gen_range(-3.0..3.0)
                }
            })
            .collect();
        let out = kernel::filter_separable(&map, w, h, g.weights_1d());
        for y in 0..h {
            for x in 0..w {
                let direct: f64 = brute_weights()
                    .iter()
                    .map(|&(dx, dy, wt)| wt * map[clampi(y, dy, h) * w + clampi(x, dx, w)])
                    .sum();
                assert!(
                    (out[y * w + x] - direct).abs() < 1e-13,
                    "{w}×{h} at ({x},{y}): {} vs {direct}",
                    out[y * w + x]
                );
                checked += 1;
            }
        }
    }
    assert!(checked > 10_000, "checked {checked}");
}

#[test]
fn constant_map_is_preserved() {
    let g = Gaussian::paper();
    let out = kernel::filter_separable(&vec![0.37; 13 * 7], 13, 7, g.weights_1d());
    assert!(out.iter().all(|v| (v - 0.37).abs() < 1e-15));
}

#[test]
fn moment_maps_equal_direct_81_tap_sums() {
    let mut r = rng(2);
    let basis = |z: f64, out: &mut [f64]| {
        out[0] = z;
        out[1] = z * z;
        out[2] = (6.0 * z).sin();
        out[3] = (-3.0 * z).exp();
    };
    for case in 0..30 {
        let (w, h) = (r.gen_range(1..20), r.gen_range(1..20));
        let s = random_stack(&mut r, &format!("r{case}"), w, h);
        let maps = kernel::moment_maps(&s, 4, basis);
        assert_eq!(maps.len(), 4);
        let front = kernel::front_map(&s);
        let mut b = [0.0; 4];
        for y in 0..h {
            for x in 0..w {
                let mut direct = [0.0; 4];
                for (z, wt, _, _) in brute_distribution(&s, x, y) {
                    basis(z, &mut b);
                    for j in 0..4 {
                        direct[j] += wt * b[j];
                    }
                }
                for j in 0..4 {
                    assert!((maps[j][y * w + x] - direct[j]).abs() < 1e-13);
                }
                // the library's depth distribution agrees with the brute-force one
                let d = kernel::depth_distribution(&front, w, h, x, y, &Gaussian::paper());
                for ((z, wt), (bz, bw, _, _)) in d.iter().zip(brute_distribution(&s, x, y)) {
                    assert_eq!(*z, bz);
                    assert!((wt - bw).abs() < 1e-15);
                }
            }
        }
    }
}

#[test]
fn background_reads_as_depth_one() {
    // a 1-layer stack whose left half is empty: front map = 1 there
    let s = stack_from("half", 10, 4, 1, |_, x, _| {
        (x >= 5).then_some((0.25f32, 0.0, 0.0))
    });
    let f = kernel::front_map(&s);
    assert_eq!(f[0], 1.0);
    assert_eq!(f[9], 0.25);
    let maps = kernel::moment_maps(&s, 1, |z, o| o[0] = z);
    // far left column: weights of columns x−4..x+4 clamped at 0 → texel 0 sees x = 0..4 (all 1)
    assert!((maps[0][0] - 1.0).abs() < 1e-15);
    assert!((maps[0][9] - 0.25).abs() < 1e-15);
}
