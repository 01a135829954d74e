//! PCF reference, fragments, trivial counts, grid snapping and `metrics::evaluate` against an
//! independent brute-force loop (tests/common/kernel.rs).

use crate::common::kernel::*;
use crate::common::technique::Mock;
use momentlab::metrics::{self, Bias, EvalOptions, Receiver, Subject, Subsample};
use momentlab::Grid;
use rand::Rng;

/// A VSM (Cantelli) test technique on (z, z²): with a depth grid it asserts that z_f is
/// snapped to it, and it answers NaN when z_f lies in `nan_band` (to test NaN accounting).
fn test_vsm(grid: Option<Grid>, nan_band: Option<(f64, f64)>) -> Mock {
    let snapped = grid.clone();
    let basis = |z: f64, out: &mut [f64]| {
        out[0] = z;
        out[1] = z * z;
    };
    let mut t = Mock::new("test-vsm", 2, basis, move |b, zf| {
        if let Some((lo, hi)) = nan_band {
            if zf >= lo && zf < hi {
                return f64::NAN;
            }
        }
        if let Some(g) = &snapped {
            assert!(g.points().contains(&zf), "z_f {zf} not snapped to the grid");
        }
        vsm(b, zf)
    });
    t.grid = grid;
    t
}

fn plain_vsm() -> Mock {
    test_vsm(None, None)
}

/// Brute-force evaluation of the test VSM: (sum |G − PCF|, finite count, trivial, nan count).
fn brute_eval(
    s: &momentlab::stack::DepthStack,
    bias: &Bias,
    grid: Option<&Grid>,
    skip_trivial: bool,
    nan_band: Option<(f64, f64)>,
) -> (f64, usize, usize, usize) {
    let snapf = |z: f64| grid.map_or(z, |g| nearest(g, z));
    let (mut sum, mut n, mut trivial, mut nan) = (0.0, 0, 0, 0);
    for f in brute_fragments(s, bias) {
        let zf = snapf(f.ztech);
        let dist: Vec<(f64, f64)> = brute_distribution(s, f.x, f.y)
            .into_iter()
            .map(|(z, w, _, _)| (snapf(z), w))
            .collect();
        let fz: f64 = dist.iter().filter(|(z, _)| *z < zf).map(|(_, w)| w).sum();
        let is_trivial = fz == 0.0;
        trivial += is_trivial as usize;
        let g = if is_trivial && skip_trivial {
            0.0
        } else if nan_band.is_some_and(|(lo, hi)| zf >= lo && zf < hi) {
            f64::NAN
        } else {
            let b0: f64 = dist.iter().map(|(z, w)| w * z).sum();
            let b1: f64 = dist.iter().map(|(z, w)| w * z * z).sum();
            vsm(&[b0, b1], zf)
        };
        if g.is_finite() {
            sum += (g - f.pcf).abs();
            n += 1;
        } else {
            nan += 1;
        }
    }
    (sum, n, trivial, nan)
}

#[test]
fn pcf_fully_lit_plane_is_zero_and_techniques_are_lit_too() {
    let bias = Bias::default();
    // flat and tilted planes (slopes up to a steep 0.01 depth units per texel)
    for (i, &(a, b)) in [
        (0.0, 0.0),
        (0.003, 0.0),
        (-0.002, 0.004),
        (0.01, -0.01),
        (1e-5, 2e-5),
    ]
    .iter()
    .enumerate()
    {
        let s = plane(24, 20, 0.4, a, b);
        let frags = metrics::fragments(&s, i, &bias);
        assert_eq!(frags.len(), 24 * 20);
        for f in &frags {
            assert_eq!(
                f.pcf, 0.0,
                "plane ({a},{b}) texel {} not lit by PCF",
                f.texel
            );
            if a == 0.0 && b == 0.0 {
                assert!(f.trivial, "flat plane texel {} not trivial", f.texel);
            }
            assert_eq!(f.view, i);
        }
        // with a slope scale of 4 (the kernel radius) every plane fragment is trivial
        for f in metrics::fragments(
            &s,
            i,
            &Bias {
                technique_slope_scale: 4.0,
                ..bias
            },
        ) {
            assert!(f.trivial, "plane ({a},{b}) texel {} not trivial", f.texel);
        }
        // the technique, evaluated on every fragment (no trivial skipping), is lit as well
        let t = plain_vsm();
        let rep = metrics::evaluate(
            std::slice::from_ref(&s),
            &t,
            &EvalOptions {
                skip_trivial: Some(false),
                ..Default::default()
            },
        )
        .unwrap();
        assert_eq!(rep.error, 0.0);
        assert_eq!(rep.solved, 24 * 20);
        if a == 0.0 && b == 0.0 {
            assert_eq!(rep.trivial, 24 * 20);
        }
    }
}

#[test]
fn pcf_under_a_full_occluder_is_one() {
    let bias = Bias::default();
    // occluder plane at 0.2 over a tilted receiver around 0.6
    let s = stack_from("occluded", 20, 16, 2, |l, x, y| {
        Some(match l {
            0 => (0.2, 0.0, 0.0),
            _ => (
                (0.6 + 0.002 * x as f64 - 0.003 * y as f64) as f32,
                0.002,
                -0.003,
            ),
        })
    });
    let frags = metrics::fragments(&s, 0, &bias);
    assert_eq!(frags.len(), 2 * 20 * 16);
    for f in &frags {
        if f.layer == 0 {
            assert_eq!(f.pcf, 0.0);
            assert!(f.trivial);
        } else {
            assert!((f.pcf - 1.0).abs() < 1e-14, "pcf {}", f.pcf);
            assert!(!f.trivial);
        }
    }
}

#[test]
fn pcf_half_shadow_edge() {
    // occluder covers x < 10 at depth 0.1 over a receiver at 0.5; receiver-layer PCF at the
    // edge columns equals the summed 1-D weights of occluded columns
    let bias = Bias::default();
    let s = stack_from("edge", 20, 12, 2, |l, x, _| match l {
        0 if x < 10 => Some((0.1, 0.0, 0.0)),
        0 => Some((0.5, 0.0, 0.0)),
        _ if x < 10 => Some((0.5, 0.0, 0.0)),
        _ => None,
    });
    let g = momentlab::kernel::Gaussian::paper();
    for f in metrics::fragments(&s, 0, &bias) {
        let x = f.texel % 20;
        let expect: f64 = (-4i64..=4)
            .filter(|d| clampi(x, *d, 20) < 10)
            .map(|d| g.weights_1d()[(d + 4) as usize])
            .sum();
        let expect = if f.layer == 0 && x < 10 { 0.0 } else { expect };
        assert!((f.pcf - expect).abs() < 1e-14, "x {x} layer {}", f.layer);
    }
}

#[test]
fn fragments_match_brute_force_on_random_stacks() {
    let mut r = rng(11);
    let mut total = 0;
    for case in 0..40 {
        let (w, h) = (r.gen_range(1..22), r.gen_range(1..22));
        let s = random_stack(&mut r, "r", w, h);
        let bias = if case % 2 == 0 {
            Bias::default()
        } else {
            Bias {
                pcf_epsilon: r.gen_range(0.0..0.01),
                slope_scale: r.gen_range(0.0..3.0),
                technique_epsilon: r.gen_range(0.0..0.01),
                technique_slope_scale: r.gen_range(0.0..5.0),
                receiver: if r.gen_bool(0.5) {
                    Receiver::Lower
                } else {
                    Receiver::Fragment
                },
            }
        };
        let frags = metrics::fragments(&s, case, &bias);
        let brute = brute_fragments(&s, &bias);
        assert_eq!(frags.len(), brute.len());
        assert_eq!(frags.len(), s.fragment_count());
        for (f, b) in frags.iter().zip(&brute) {
            assert_eq!((f.texel, f.layer), (b.texel, b.layer));
            assert!((f.pcf - b.pcf).abs() < 1e-13, "pcf {} vs {}", f.pcf, b.pcf);
            assert!((f.zf - b.ztech).abs() < 1e-15);
            // trivial ⇔ F_Z(z_f − ε′) = 0, computed from the brute-force distribution
            let fz: f64 = brute_distribution(&s, b.x, b.y)
                .iter()
                .filter(|d| d.0 < b.ztech)
                .map(|d| d.1)
                .sum();
            assert_eq!(f.trivial, fz == 0.0);
            total += 1;
        }
    }
    assert!(total > 2000, "{total}");
}

#[test]
fn trivial_count_on_a_constructed_stack() {
    // 12×12: front plane at 0.5; a 2×2 occluder block at 0.2 around (3,3); second layer at
    // 0.7 under the block only. Front fragments at 0.5 near the block see 0.2 → not trivial.
    let s = stack_from("blocks", 12, 12, 2, |l, x, y| {
        let block = (3..5).contains(&x) && (3..5).contains(&y);
        match (l, block) {
            (0, true) => Some((0.2, 0.0, 0.0)),
            (0, false) => Some((0.5, 0.0, 0.0)),
            (1, true) => Some((0.7, 0.0, 0.0)),
            _ => None,
        }
    });
    let frags = metrics::fragments(&s, 0, &Bias::default());
    // block fragments (front) trivial (nothing below 0.2); second-layer fragments not;
    // front 0.5 fragments trivial iff the 9×9 window (clamped) avoids the block: the block is
    // within Chebyshev distance 4 of (x,y) iff x ≤ 8 and y ≤ 8 → 81 texels incl. the block.
    let expected_trivial = 4 + (144 - 81);
    let trivial = frags.iter().filter(|f| f.trivial).count();
    assert_eq!(frags.len(), 148);
    assert_eq!(trivial, expected_trivial);
    let rep = metrics::evaluate(
        std::slice::from_ref(&s),
        &plain_vsm(),
        &EvalOptions::default(),
    )
    .unwrap();
    assert_eq!(rep.trivial, expected_trivial);
    assert_eq!(rep.views[0].trivial, expected_trivial);
}

#[test]
fn pcf_as_a_technique_has_error_zero() {
    let mut r = rng(12);
    let stacks: Vec<_> = (0..6)
        .map(|i| {
            let (w, h) = (r.gen_range(5..30), r.gen_range(5..30));
            random_stack(&mut r, &format!("v{i}"), w, h)
        })
        .collect();
    let rep = metrics::evaluate_subject(&stacks, Subject::Pcf, &EvalOptions::default()).unwrap();
    assert_eq!(rep.error, 0.0);
    assert_eq!(rep.technique, "pcf");
    assert_eq!(
        rep.fragments,
        stacks.iter().map(|s| s.fragment_count()).sum::<usize>()
    );
    assert!(rep
        .views
        .iter()
        .all(|v| v.error == 0.0 && v.sum_abs_error == 0.0));
    // and the PCF values themselves are not all trivial zeros
    let nonzero: usize = stacks
        .iter()
        .enumerate()
        .map(|(i, s)| {
            metrics::fragments(s, i, &Bias::default())
                .iter()
                .filter(|f| f.pcf > 0.0)
                .count()
        })
        .sum();
    assert!(nonzero > 100);
}

/// `count` random views of 5 to 29 texels a side, from `seed`.
fn random_views(seed: u64, count: usize) -> Vec<momentlab::stack::DepthStack> {
    let mut r = rng(seed);
    (0..count)
        .map(|i| {
            let (w, h) = (r.gen_range(5..30), r.gen_range(5..30));
            random_stack(&mut r, &format!("v{i}"), w, h)
        })
        .collect()
}

/// VSM on a 64-point grid whose output is NaN for z_f in [0.4, 0.45].
fn snapped_vsm_with_nan_band() -> Mock {
    test_vsm(Some(Grid::uniform(64).unwrap()), Some((0.4, 0.45)))
}

/// Several subjects on the same fragments (built once) report what each reports alone: the
/// same errors, counts and per-view figures, in the order given.
#[test]
fn subjects_evaluated_together_equal_each_alone() {
    let stacks = random_views(14, 4);
    let (vsm, snapped) = (plain_vsm(), snapped_vsm_with_nan_band());
    let subjects = [
        Subject::Technique(&vsm),
        Subject::Pcf,
        Subject::Technique(&snapped),
        Subject::Cdf,
    ];
    let opts = EvalOptions {
        subsample: Subsample::Stride(2),
        ..EvalOptions::default()
    };
    let together = metrics::evaluate_subjects(&stacks, &subjects, &opts).unwrap();
    assert_eq!(together.len(), subjects.len());
    for (subject, t) in subjects.iter().zip(&together) {
        let alone = metrics::evaluate_subject(&stacks, *subject, &opts).unwrap();
        assert_eq!(t.technique, alone.technique);
        assert_eq!(t.error.to_bits(), alone.error.to_bits(), "{}", t.technique);
        assert_eq!(t.error_scaled, alone.error_scaled);
        assert_eq!(t.leak.to_bits(), alone.leak.to_bits());
        let counts = |e: &metrics::EvalReport| {
            (
                e.fragments,
                e.trivial,
                e.solved,
                e.non_finite,
                e.out_of_range,
            )
        };
        assert_eq!(counts(t), counts(&alone), "{}", t.technique);
        for (a, b) in t.views.iter().zip(&alone.views) {
            assert_eq!(a.sum_abs_error.to_bits(), b.sum_abs_error.to_bits());
            assert_eq!((a.fragments, a.trivial), (b.fragments, b.trivial));
        }
    }
    // The NaN band of the snapped technique is counted there only.
    assert!(together[2].non_finite > 0);
    assert_eq!(together[0].non_finite, 0);
    assert_eq!(together[1].error, 0.0);
}

#[test]
fn histograms_count_the_errors_the_kept_values_hold() {
    let stacks = random_views(15, 3);
    let (vsm, snapped) = (plain_vsm(), snapped_vsm_with_nan_band());
    let subjects = [Subject::Technique(&vsm), Subject::Technique(&snapped)];
    let edges: std::sync::Arc<[f64]> = std::sync::Arc::from(&[0.0, 1e-3, 0.01, 0.05, 0.2][..]);
    let counted = metrics::evaluate_subjects(
        &stacks,
        &subjects,
        &EvalOptions {
            histogram: Some(edges.clone()),
            ..EvalOptions::default()
        },
    )
    .unwrap();
    let kept = metrics::evaluate_subjects(
        &stacks,
        &subjects,
        &EvalOptions {
            keep_values: true,
            ..EvalOptions::default()
        },
    )
    .unwrap();
    for (c, k) in counted.iter().zip(&kept) {
        assert_eq!(c.error.to_bits(), k.error.to_bits());
        for (cv, kv) in c.views.iter().zip(&k.views) {
            assert!(kv.histogram.is_empty() && cv.values.is_none());
            let mut want = vec![0u64; edges.len() - 1];
            for v in kv.values.as_ref().unwrap() {
                let e = (v.g - v.pcf).abs();
                if e >= 0.0 {
                    // the last bin also holds everything above its lower edge
                    let k = (1..edges.len() - 1).filter(|&k| edges[k] <= e).count();
                    want[k] += 1;
                }
            }
            assert_eq!(cv.histogram, want, "{} {}", c.technique, cv.view);
            let finite = cv.fragments - cv.non_finite;
            assert_eq!(cv.histogram.iter().sum::<u64>() as usize, finite);
        }
    }
    // The NaN band of the snapped technique is in no bin.
    assert!(counted[1].non_finite > 0);
}

#[test]
fn evaluate_equals_brute_force_for_a_closed_form_technique() {
    let mut r = rng(13);
    for round in 0..6 {
        let stacks: Vec<_> = (0..3)
            .map(|i| {
                let (w, h) = (r.gen_range(3..26), r.gen_range(3..26));
                random_stack(&mut r, &format!("v{i}"), w, h)
            })
            .collect();
        let bias = if round % 2 == 0 {
            Bias::default()
        } else {
            Bias {
                pcf_epsilon: 0.003,
                slope_scale: 0.5,
                technique_epsilon: 0.002,
                technique_slope_scale: 1.0,
                ..Bias::default()
            }
        };
        for skip in [None, Some(true)] {
            let rep = metrics::evaluate(
                &stacks,
                &plain_vsm(),
                &EvalOptions {
                    bias,
                    skip_trivial: skip,
                    ..Default::default()
                },
            )
            .unwrap();
            let (mut sum, mut n, mut triv) = (0.0, 0, 0);
            for (s, v) in stacks.iter().zip(&rep.views) {
                let (vs, vn, vt, vnan) = brute_eval(s, &bias, None, skip == Some(true), None);
                assert_eq!(v.fragments, vn);
                assert_eq!(v.trivial, vt);
                assert_eq!(vnan, 0);
                assert!((v.error - vs / vn as f64).abs() < 1e-12);
                sum += vs;
                n += vn;
                triv += vt;
            }
            assert!((rep.error - sum / n as f64).abs() < 1e-12);
            assert_eq!(rep.trivial, triv);
            assert!(
                rep.error > 0.0,
                "VSM leaks light somewhere on random stacks"
            );
            if skip.is_none() {
                assert_eq!(
                    rep.solved, n,
                    "closed forms are evaluated everywhere by default"
                );
            } else {
                assert_eq!(rep.solved, n - triv);
            }
        }
    }
}

#[test]
fn grid_techniques_snap_depths_and_match_brute_force() {
    let mut r = rng(14);
    for (gi, grid) in [
        Grid::uniform(33).unwrap(),
        Grid::uniform(7).unwrap(),
        Grid::from_values(vec![0.0, 0.1, 0.15, 0.4, 0.41, 0.8, 1.0]).unwrap(),
    ]
    .into_iter()
    .enumerate()
    {
        let stacks: Vec<_> = (0..3)
            .map(|i| {
                let (w, h) = (r.gen_range(3..24), r.gen_range(3..24));
                random_stack(&mut r, &format!("g{gi}v{i}"), w, h)
            })
            .collect();
        let t = test_vsm(Some(grid.clone()), None);
        let bias = Bias::default();
        let rep = metrics::evaluate(&stacks, &t, &EvalOptions::default()).unwrap();
        let (mut sum, mut n, mut triv) = (0.0, 0, 0);
        for s in &stacks {
            let (vs, vn, vt, _) = brute_eval(s, &bias, Some(&grid), true, None);
            sum += vs;
            n += vn;
            triv += vt;
        }
        assert_eq!(rep.trivial, triv);
        assert_eq!(
            rep.solved,
            n - triv,
            "grid techniques skip trivial fragments"
        );
        assert!((rep.error - sum / n as f64).abs() < 1e-12);
        // snapping makes more fragments trivial, never fewer
        let unsnapped: usize = stacks
            .iter()
            .enumerate()
            .map(|(i, s)| {
                metrics::fragments(s, i, &bias)
                    .iter()
                    .filter(|f| f.trivial)
                    .count()
            })
            .sum();
        assert!(rep.trivial >= unsnapped);
    }
}

#[test]
fn snap_is_nearest_and_monotone() {
    let mut r = rng(15);
    let grid = Grid::from_values((0..50).map(|_| r.gen_range(-0.2..1.2)).collect()).unwrap();
    let mut prev = f64::NEG_INFINITY;
    let mut zs: Vec<f64> = (0..5000).map(|_| r.gen_range(-0.5..1.5)).collect();
    zs.sort_by(|a, b| a.partial_cmp(b).unwrap());
    for z in zs {
        let s = metrics::snap(&grid, z);
        assert_eq!(s, nearest(&grid, z), "z {z}");
        assert!(s >= prev);
        prev = s;
    }
}

#[test]
fn non_finite_outputs_are_counted_not_averaged() {
    let mut r = rng(16);
    let stacks: Vec<_> = (0..2)
        .map(|i| random_stack(&mut r, &format!("n{i}"), 17, 13))
        .collect();
    let band = (0.3, 0.5);
    let t = test_vsm(None, Some(band));
    let bias = Bias::default();
    let rep = metrics::evaluate(&stacks, &t, &EvalOptions::default()).unwrap();
    let (mut sum, mut n, mut nan) = (0.0, 0, 0);
    for s in &stacks {
        let (vs, vn, _, vnan) = brute_eval(s, &bias, None, false, Some(band));
        sum += vs;
        n += vn;
        nan += vnan;
    }
    assert!(nan > 0);
    assert_eq!(rep.non_finite, nan);
    assert_eq!(rep.fragments, n + nan);
    assert!(rep.error.is_finite());
    assert!((rep.error - sum / n as f64).abs() < 1e-12);
}

#[test]
fn subsampling() {
    let mut r = rng(17);
    let stacks: Vec<_> = (0..3)
        .map(|i| random_stack(&mut r, &format!("s{i}"), 21, 19))
        .collect();
    let t = plain_vsm();
    let run = |sub| {
        metrics::evaluate(
            &stacks,
            &t,
            &EvalOptions {
                subsample: sub,
                ..Default::default()
            },
        )
        .unwrap()
    };
    let all = run(Subsample::All);
    let s1 = run(Subsample::Stride(1));
    let f1 = run(Subsample::Random {
        fraction: 1.0,
        seed: 3,
    });
    assert_eq!(all.error, s1.error);
    assert_eq!(all.error, f1.error);
    let s3 = run(Subsample::Stride(3));
    for (v, s) in s3.views.iter().zip(&stacks) {
        assert_eq!(v.fragments, s.fragment_count().div_ceil(3));
        assert_eq!(v.fragments_total, s.fragment_count());
    }
    let a = run(Subsample::Random {
        fraction: 0.3,
        seed: 9,
    });
    let b = run(Subsample::Random {
        fraction: 0.3,
        seed: 9,
    });
    let c = run(Subsample::Random {
        fraction: 0.3,
        seed: 10,
    });
    assert_eq!(a.fragments, b.fragments);
    assert_eq!(a.error, b.error);
    assert_ne!((a.fragments, a.error), (c.fragments, c.error));
    let share = a.fragments as f64 / all.fragments as f64;
    assert!((share - 0.3).abs() < 0.06, "share {share}");
    // a subsample's error is the brute-force mean over the same fragments (keep_values)
    let kv = metrics::evaluate(
        &stacks,
        &t,
        &EvalOptions {
            subsample: Subsample::Stride(4),
            keep_values: true,
            ..Default::default()
        },
    )
    .unwrap();
    let vals: Vec<_> = kv
        .views
        .iter()
        .flat_map(|v| v.values.clone().unwrap())
        .collect();
    assert_eq!(vals.len(), kv.fragments);
    let mean = vals.iter().map(|v| (v.g - v.pcf).abs()).sum::<f64>() / vals.len() as f64;
    assert!((mean - kv.error).abs() < 1e-12);
}

#[test]
fn bad_input_is_rejected_with_a_message() {
    let t = plain_vsm();
    let good = plane(8, 8, 0.5, 0.0, 0.0);
    let eval = |s: &momentlab::stack::DepthStack, o: &EvalOptions| {
        metrics::evaluate(std::slice::from_ref(s), &t, o)
            .unwrap_err()
            .to_string()
    };
    let mut s = good.clone();
    s.depth[0][10] = f32::NAN;
    let e = eval(&s, &EvalOptions::default());
    assert!(
        e.contains("texel (2, 1)") && e.contains("test/plane"),
        "{e}"
    );
    let mut s = good.clone();
    s.depth[0][3] = 1.5;
    assert!(eval(&s, &EvalOptions::default()).contains("outside [0,1]"));
    let mut s = good.clone();
    s.dzdu[0].pop();
    assert!(eval(&s, &EvalOptions::default()).contains("layer 0"));
    let mut s = good.clone();
    s.dzdv.clear();
    assert!(eval(&s, &EvalOptions::default()).contains("slope layers"));
    let bad_bias = EvalOptions {
        bias: Bias {
            pcf_epsilon: f64::NAN,
            ..Bias::default()
        },
        ..Default::default()
    };
    assert!(eval(&good, &bad_bias).contains("pcf_epsilon"));
    let bad_sub = EvalOptions {
        subsample: Subsample::Stride(0),
        ..Default::default()
    };
    assert!(eval(&good, &bad_sub).contains("stride"));
    let bad_frac = EvalOptions {
        subsample: Subsample::Random {
            fraction: 1.5,
            seed: 0,
        },
        ..Default::default()
    };
    assert!(eval(&good, &bad_frac).contains("fraction"));
}

#[test]
fn progress_reaches_the_total() {
    use std::sync::atomic::{AtomicUsize, Ordering};
    use std::sync::Arc;
    let mut r = rng(18);
    let stacks: Vec<_> = (0..2)
        .map(|i| random_stack(&mut r, &format!("p{i}"), 40, 30))
        .collect();
    let last = Arc::new(AtomicUsize::new(0));
    let total = Arc::new(AtomicUsize::new(0));
    let (l2, t2) = (last.clone(), total.clone());
    let rep = metrics::evaluate(
        &stacks,
        &plain_vsm(),
        &EvalOptions {
            progress: Some(Arc::new(move |d, n| {
                l2.fetch_max(d, Ordering::Relaxed);
                t2.store(n, Ordering::Relaxed);
            })),
            ..Default::default()
        },
    )
    .unwrap();
    assert_eq!(last.load(Ordering::Relaxed), rep.fragments);
    assert_eq!(total.load(Ordering::Relaxed), rep.fragments);
}

#[test]
fn front_shadows_match_fragments() {
    let mut r = rng(19);
    let s = random_stack(&mut r, "f", 15, 11);
    let bias = Bias::default();
    let fs = metrics::front_shadows(&s, Subject::Technique(&plain_vsm()), &bias).unwrap();
    let frags = metrics::fragments(&s, 0, &bias);
    let front: Vec<_> = frags.iter().filter(|f| f.layer == 0).collect();
    for f in &front {
        assert_eq!(fs.pcf[f.texel], f.pcf);
        assert!(fs.g[f.texel].is_finite());
    }
    let holes = (0..s.texel_count())
        .filter(|&t| !s.depth[0][t].is_finite())
        .count();
    assert_eq!(fs.pcf.iter().filter(|v| v.is_nan()).count(), holes);
}

#[test]
fn cdf_subject_is_the_bias_floor() {
    let mut r = rng(20);
    let stacks: Vec<_> = (0..3)
        .map(|i| random_stack(&mut r, &format!("c{i}"), 19, 14))
        .collect();
    // without any bias PCF is exactly F_Z(z_f): the CDF subject has error 0
    let zero = Bias {
        pcf_epsilon: 0.0,
        slope_scale: 0.0,
        technique_epsilon: 0.0,
        technique_slope_scale: 0.0,
        ..Bias::default()
    };
    let opts = EvalOptions {
        bias: zero,
        ..Default::default()
    };
    let rep = metrics::evaluate_subject(&stacks, Subject::Cdf, &opts).unwrap();
    // (only summation-order rounding: PCF sums g_x·g_y row by row)
    assert!(rep.error < 1e-15, "{}", rep.error);
    // with the default biases it is the brute-force mean |F_Z(z_f − ε′) − PCF|
    let bias = Bias::default();
    let rep = metrics::evaluate_subject(&stacks, Subject::Cdf, &EvalOptions::default()).unwrap();
    let (mut sum, mut n) = (0.0, 0);
    for s in &stacks {
        for f in brute_fragments(s, &bias) {
            let fz: f64 = brute_distribution(s, f.x, f.y)
                .iter()
                .filter(|d| d.0 < f.ztech)
                .map(|d| d.1)
                .sum();
            sum += (fz - f.pcf).abs();
            n += 1;
        }
    }
    assert!(sum > 0.0);
    assert!((rep.error - sum / n as f64).abs() < 1e-12);
}
