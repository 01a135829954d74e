//! The published transforms (Peters & Klein 2015 Section 4.3; 2016 supplementary Table 1)
//! through our verifier, inverse and encode/decode round trips, and the volume bound.

use momentlab::quantize::curve::MonomialCurve;
use momentlab::quantize::linalg::mat_mul;
use momentlab::quantize::theta::{published, verify};
use momentlab::quantize::volume::{volume_bound_bits, volume_bound_reciprocal};
use momentlab::quantize::Curve;

#[test]
fn published_transforms_pass_the_verifier_with_the_quoted_gains() {
    // quoted: θ2 2 bits, θ4 12.2783 bits, θ6 30.511 bits
    for (m, quoted, digits) in [(2, 2.0, 1e-12), (4, 12.2783, 5e-5), (6, 30.511, 5e-4)] {
        let th = published(m).unwrap();
        let curve = MonomialCurve::power(m).unwrap();
        let v = verify(&th, &curve).unwrap();
        assert!(v.exact);
        // the tables are printed with ~10 significant digits: containment holds up to that
        assert!(
            v.max_violation < 1e-6,
            "m={m}: violation {}",
            v.max_violation
        );
        for (lo, hi) in &v.row_ranges {
            assert!(
                *lo > -1e-6 && *hi < 1.0 + 1e-6 && hi - lo > 0.999,
                "m={m}: {lo} {hi}"
            );
        }
        let g = th.gain_bits();
        assert!(
            (g - quoted).abs() < digits,
            "m={m}: gain {g} vs quoted {quoted}"
        );
    }
}

#[test]
fn inverse_times_theta_is_identity() {
    for m in [2, 4, 6] {
        let th = published(m).unwrap();
        let p = mat_mul(&th.inverse, &th.matrix);
        for (i, row) in p.iter().enumerate() {
            for (j, v) in row.iter().enumerate() {
                let e = if i == j { 1.0 } else { 0.0 };
                assert!((v - e).abs() < 1e-9, "m={m} ({i},{j}) {v}");
            }
        }
    }
}

#[test]
fn encode_f32_decode_round_trip() {
    for m in [2, 4, 6] {
        let th = published(m).unwrap();
        let curve = MonomialCurve::power(m).unwrap();
        let mut worst: f64 = 0.0;
        for k in 0..=2000 {
            let z = k as f64 / 2000.0;
            let mut b = vec![0.0; m];
            curve.eval(z, &mut b);
            let mut s = vec![0.0; m];
            th.encode(&b, &mut s);
            let stored: Vec<f64> = s.iter().map(|&v| v as f32 as f64).collect();
            let mut back = vec![0.0; m];
            th.decode(&stored, &mut back);
            for (p, q) in back.iter().zip(&b) {
                worst = worst.max((p - q).abs());
            }
        }
        assert!(worst < 1e-6, "m={m}: round trip error {worst}");
    }
}

#[test]
fn volume_bound_for_six_moments() {
    assert_eq!(volume_bound_reciprocal(6), Some(44_008_272_000));
    assert!((volume_bound_bits(6) - 44_008_272_000f64.log2()).abs() < 1e-9);
    assert!((volume_bound_bits(6) - 35.357).abs() < 5e-4);
}
