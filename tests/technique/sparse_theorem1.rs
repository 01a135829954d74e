//! Supplementary Theorem 1: two Diracs reproduce b₁, b₂, b₃.

use momentlab::technique::sparse::{two_diracs, two_diracs_with, C0};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Reproduction error of b_j, relative to the magnitude Σ w_i |z_i|^j of the sum (≥ 1): the
/// rounding floor of evaluating w₂z₂ʲ + w₃z₃ʲ at all.
fn reproduce(b: [f64; 3], z: [f64; 2], w: [f64; 2]) -> f64 {
    (1..=3)
        .map(|j| {
            let mag = (w[0] * z[0].abs().powi(j) + w[1] * z[1].abs().powi(j)).max(1.0);
            (w[0] * z[0].powi(j) + w[1] * z[1].powi(j) - b[j as usize - 1]).abs() / mag
        })
        .fold(0.0, f64::max)
}

#[test]
fn theorem1_reproduces_three_moments() {
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    let mut worst = 0.0f64;
    for it in 0..100_000 {
        // Arbitrary b₁, σ² > 0 and b₃ (Theorem 1 needs only σ² > 0); magnitudes O(1).
        let b1: f64 = rng.gen_range(-1.0..1.0);
        let var: f64 = 10f64.powf(rng.gen_range(-3.0..0.0));
        let b2 = b1 * b1 + var;
        let b3: f64 = if it % 2 == 0 {
            // third central moment σ³·skew with skewness in [−5, 5]
            b1 * b1 * b1 + 3.0 * b1 * var + var.powf(1.5) * rng.gen_range(-5.0..5.0)
        } else {
            // moments of a random distribution on [0,1]
            let k = rng.gen_range(2..6);
            let atoms: Vec<(f64, f64)> = (0..k).map(|_| (rng.gen(), rng.gen())).collect();
            let s: f64 = atoms.iter().map(|a| a.1).sum();
            let m = |j: i32| atoms.iter().map(|a| a.1 * a.0.powi(j)).sum::<f64>() / s;
            let (b1, b2, b3) = (m(1), m(2), m(3));
            if b2 - b1 * b1 <= 1e-3 {
                continue;
            }
            let t = two_diracs(b1, b2, b3).unwrap();
            worst = worst.max(reproduce([b1, b2, b3], t.z, t.w));
            assert!(t.w.iter().all(|w| (0.0..=1.0).contains(w)));
            continue;
        };
        let t = two_diracs(b1, b2, b3).expect("σ² > 0");
        assert!(t.z[0] < t.z[1]);
        assert!(t.w.iter().all(|w| (0.0..=1.0).contains(w)), "{t:?}");
        assert!((t.w[0] + t.w[1] - 1.0).abs() < 1e-14);
        let err = reproduce([b1, b2, b3], t.z, t.w);
        worst = worst.max(err);
    }
    eprintln!("max error {worst:.2e}");
    assert!(worst < 1e-12, "max error {worst}");
}

#[test]
fn theorem1_far_dirac_is_conditioned_by_its_distance() {
    // Arbitrary b₃ ∈ [−2, 2] with σ² ≥ 1e-3 can put one Dirac hundreds of units away with a
    // weight ~1e-8; the relative reproduction error then grows with |z| (rounding of c₂ = b₂ − b₁²)
    // but stays below 1e-9.
    let mut rng = ChaCha8Rng::seed_from_u64(4);
    let mut worst = 0.0f64;
    for _ in 0..50_000 {
        let b1: f64 = rng.gen_range(-1.0..1.0);
        let var: f64 = 10f64.powf(rng.gen_range(-3.0..0.0));
        let b3: f64 = rng.gen_range(-2.0..2.0);
        let t = two_diracs(b1, b1 * b1 + var, b3).unwrap();
        assert!(t.w.iter().all(|w| (0.0..=1.0).contains(w)));
        worst = worst.max(reproduce([b1, b1 * b1 + var, b3], t.z, t.w));
    }
    eprintln!("far-Dirac max relative error {worst:.2e}");
    assert!(worst < 1e-9);
}

#[test]
fn theorem1_rejects_zero_variance_and_nan() {
    assert!(two_diracs(0.5, 0.25, 0.125).is_none());
    assert!(two_diracs(0.5, 0.2, 0.1).is_none());
    assert!(two_diracs(f64::NAN, 0.3, 0.1).is_none());
    // σ² > 0 at the edge: a two-point distribution is recovered exactly.
    let (z, w) = ([0.2, 0.9], [0.3, 0.7]);
    let m = |j: i32| w[0] * f64::powi(z[0], j) + w[1] * f64::powi(z[1], j);
    let t = two_diracs(m(1), m(2), m(3)).unwrap();
    assert!((t.z[0] - 0.2).abs() < 1e-12 && (t.z[1] - 0.9).abs() < 1e-12);
    assert!((t.w[0] - 0.3).abs() < 1e-12);
}

#[test]
fn theorem1_recommended_c0_is_more_accurate_in_f32() {
    // Moments of distributions in [0,1] with small variance in f32: c₀ from c₁, c₂ avoids the
    // cancellation in b₁b₃ − b₂². Compare mean reproduction errors (measured in f64).
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    let (mut e_rec, mut e_exp, mut n) = (0.0f64, 0.0f64, 0);
    for _ in 0..20_000 {
        let c: f64 = rng.gen_range(0.2..0.9);
        let d: f64 = 10f64.powf(rng.gen_range(-2.5..-1.0));
        let (z, w) = ([c, c + d], [rng.gen_range(0.1..0.9), 0.0]);
        let w = [w[0], 1.0 - w[0]];
        let m = |j: i32| (w[0] * f64::powi(z[0], j) + w[1] * f64::powi(z[1], j)) as f32;
        let b = [m(1), m(2), m(3)];
        let bd = [b[0] as f64, b[1] as f64, b[2] as f64];
        for (form, acc) in [(C0::FromC1C2, &mut e_rec), (C0::Expanded, &mut e_exp)] {
            if let Some(t) = two_diracs_with(b[0], b[1], b[2], form) {
                *acc += reproduce(
                    bd,
                    [t.z[0] as f64, t.z[1] as f64],
                    [t.w[0] as f64, t.w[1] as f64],
                );
            } else {
                *acc += 1.0;
            }
        }
        n += 1;
    }
    let (e_rec, e_exp) = (e_rec / n as f64, e_exp / n as f64);
    eprintln!("f32 mean error: recommended c0 {e_rec:.2e}, expanded {e_exp:.2e}");
    assert!(e_rec < e_exp, "recommended {e_rec} vs expanded {e_exp}");
}
