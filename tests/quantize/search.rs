//! The θ search: θ2 is recovered exactly, θ3 ≥ 6.2 bits, a seeded fast run reaches the
//! published θ4 gain, and every result is strictly contained (exact verifier).

use momentlab::quantize::curve::{MonomialCurve, SampledCurve};
use momentlab::quantize::linalg::mat_mul;
use momentlab::quantize::optimize::{optimize, Options};
use momentlab::quantize::theta::{published, verify, Theta};
use momentlab::quantize::Curve;

fn run(curve: &dyn Curve, restarts: usize, hops: usize, seed: u64) -> Theta {
    let opts = Options {
        seed,
        restarts,
        hops,
        hop_sigma: 0.3,
        ..Default::default()
    };
    optimize(curve, &opts, &|_, _| {}).unwrap().theta
}

fn check_contained_and_invertible(th: &Theta, curve: &dyn Curve) {
    let v = verify(th, curve).unwrap();
    assert!(v.max_violation < 0.0, "violation {}", v.max_violation);
    let p = mat_mul(&th.inverse, &th.matrix);
    for (i, row) in p.iter().enumerate() {
        for (j, x) in row.iter().enumerate() {
            assert!((x - if i == j { 1.0 } else { 0.0 }).abs() < 1e-9);
        }
    }
}

/// Row (a, t) up to reflection s ↦ 1 − s, i.e. (a, t) ~ (−a, 1 − t).
fn same_row(a: &[f64], t: f64, b: &[f64], u: f64, tol: f64) -> bool {
    let d = |s: f64, o: f64| {
        a.iter().zip(b).all(|(p, q)| (p - s * q).abs() < tol) && (t - o).abs() < tol
    };
    d(1.0, u) || d(-1.0, 1.0 - u)
}

#[test]
fn theta2_is_the_published_one_up_to_row_order_and_reflection() {
    let curve = MonomialCurve::power(2).unwrap();
    let pubd = published(2).unwrap();
    for seed in 1..=5 {
        let th = run(&curve, 2, 0, seed);
        check_contained_and_invertible(&th, &curve);
        assert!((th.gain_bits() - 2.0).abs() < 1e-7, "{}", th.gain_bits());
        for (pa, pt) in pubd.matrix.iter().zip(&pubd.offset) {
            let found = th
                .matrix
                .iter()
                .zip(&th.offset)
                .any(|(a, &t)| same_row(a, t, pa, *pt, 1e-6));
            assert!(
                found,
                "seed {seed}: row {pa:?} missing in {:?} {:?}",
                th.matrix, th.offset
            );
        }
    }
}

#[test]
fn theta3_reaches_the_published_gain() {
    let curve = MonomialCurve::power(3).unwrap();
    let th = run(&curve, 2, 0, 1);
    check_contained_and_invertible(&th, &curve);
    assert!(th.gain_bits() >= 6.2, "{}", th.gain_bits());
}

#[test]
fn seeded_fast_run_reaches_published_theta4() {
    let curve = MonomialCurve::power(4).unwrap();
    let th = run(&curve, 2, 10, 1);
    check_contained_and_invertible(&th, &curve);
    assert!(th.gain_bits() >= 12.278, "{}", th.gain_bits());
}

#[test]
fn sampled_oracle_finds_the_same_theta2_gain() {
    // the generic (non-polynomial) path on a polynomial basis: same optimum
    let curve = SampledCurve::new(
        vec!["z".into(), "z^2".into()],
        4096,
        Box::new(|z, o: &mut [f64]| {
            o[0] = z;
            o[1] = z * z;
        }),
    )
    .unwrap();
    let th = run(&curve, 2, 0, 3);
    let exact = verify(&th, &MonomialCurve::power(2).unwrap()).unwrap();
    assert!(exact.max_violation < 1e-9, "{}", exact.max_violation);
    assert!((th.gain_bits() - 2.0).abs() < 1e-6);
}
