//! The PCF reference on curved, tessellated surfaces: the front layer seen from a light is lit
//! by definition, so any PCF shadow on it is the reference's own acne. Sphere (convex), torus
//! (saddles on the inner ring) and an open bowl (concave) under lights; planes are covered by
//! the brute-force tests in tests/evaluate/metrics.rs.

use momentlab::metrics::{self, Bias, Receiver};
use momentlab::render::scene::{sphere, torus};
use momentlab::render::{render_view, Scene, Tri};

/// (front-layer fragments, share with PCF > 1e-3, mean PCF) of every view of `tris`.
fn false_shadow(tris: Vec<Tri>, dirs: &[[f64; 3]], receiver: Receiver) -> (usize, f64, f64) {
    let lights = dirs
        .iter()
        .enumerate()
        .map(|(i, d)| (format!("l{i}"), *d))
        .collect();
    let sc = Scene::new("curved", tris, lights).unwrap();
    let bias = Bias {
        receiver,
        ..Bias::default()
    };
    let (mut n, mut shadowed, mut sum) = (0usize, 0usize, 0.0);
    for i in 0..dirs.len() {
        let st = render_view(&sc, i, 160);
        for f in metrics::fragments(&st, 0, &bias) {
            if f.layer == 0 {
                n += 1;
                shadowed += (f.pcf > 1e-3) as usize;
                sum += f.pcf;
            }
        }
    }
    (n, shadowed as f64 / n as f64, sum / n as f64)
}

fn bowl(r: f64, n: usize) -> Vec<Tri> {
    // the lower half of a UV sphere: open at the top, its inside faces a light from above
    let mut t = Vec::new();
    sphere(&mut t, r, n);
    t.retain(|tri| tri.iter().all(|p| p[1] <= 1e-9));
    t
}

const TILTED: [[f64; 3]; 3] = [[0.0, -1.0, 0.0], [0.3, -1.0, 0.2], [-0.7, -0.6, 0.4]];

#[test]
fn no_self_shadow_on_a_tessellated_sphere() {
    for segments in [12, 24, 48] {
        let mut t = Vec::new();
        sphere(&mut t, 1.0, segments);
        let (n, share, mean) = false_shadow(t, &TILTED, Receiver::Lower);
        assert!(n > 10_000, "{n}");
        assert!(share <= 1e-3, "sphere {segments}: {share} of {n} shadowed");
        assert!(mean <= 1e-4, "sphere {segments}: mean {mean}");
    }
}

#[test]
fn no_self_shadow_in_a_bowl() {
    let up = [[0.0, -1.0, 0.0], [0.05, -1.0, 0.02]];
    for segments in [16, 32, 64] {
        let (n, share, _) = false_shadow(bowl(1.0, segments), &up, Receiver::Lower);
        assert!(share <= 1e-3, "bowl {segments}: {share} of {n} shadowed");
        // the fragment's own tangent plane alone shadows most of a concave surface
        let (_, old, _) = false_shadow(bowl(1.0, segments), &up, Receiver::Fragment);
        assert!(old > 0.5, "bowl {segments}: {old}");
    }
}

/// The saddles of a torus's inner ring: the path rule removes most but not all of the
/// fragment-plane acne (docs/evaluation.md states the measured shares).
#[test]
fn torus_saddles_keep_little_acne() {
    let up = [[0.0, -1.0, 0.0], [0.05, -1.0, 0.02]];
    for segments in [16, 32, 64] {
        let mut t = Vec::new();
        torus(&mut t, 1.0, 0.35, segments, segments / 2);
        let (n, share, mean) = false_shadow(t.clone(), &up, Receiver::Lower);
        let (_, old, old_mean) = false_shadow(t, &up, Receiver::Fragment);
        assert!(share <= 0.07, "torus {segments}: {share} of {n} shadowed");
        assert!(old >= 4.0 * share, "torus {segments}: {old} vs {share}");
        assert!(
            old_mean >= 20.0 * mean,
            "torus {segments}: {old_mean} vs {mean}"
        );
    }
}
