//! Eye-view pictures: the bilinear shadow-map lookup against a hand computation, and the PCF
//! eye view of a sphere over a plane against the analytic shadow disk.

use momentlab::metrics::{Bias, Subject};
use momentlab::render::eye::{self, bilinear};
use momentlab::render::scene::{quad, sphere};
use momentlab::render::{render_view, Scene, Tri};

#[test]
fn bilinear_matches_a_hand_computation() {
    // 3 × 2 map
    let m = [1.0, 2.0, 4.0, 8.0, 16.0, 32.0];
    // texel centres at integers
    assert_eq!(bilinear(&m, 3, 2, 0.0, 0.0), 1.0);
    assert_eq!(bilinear(&m, 3, 2, 2.0, 1.0), 32.0);
    // (0.25, 0.5): rows 0 and 1 at x = 0.25: 1.25 and 10.0, mean 5.625
    assert!((bilinear(&m, 3, 2, 0.25, 0.5) - 5.625).abs() < 1e-12);
    // (1.5, 0.75): row 0: 3, row 1: 24 → 0.25·3 + 0.75·24 = 18.75
    assert!((bilinear(&m, 3, 2, 1.5, 0.75) - 18.75).abs() < 1e-12);
    // clamped edges: outside the map reads the edge texels
    assert_eq!(bilinear(&m, 3, 2, -3.0, -1.0), 1.0);
    assert!((bilinear(&m, 3, 2, 5.0, 0.5) - 18.0).abs() < 1e-12);
}

#[test]
fn pcf_eye_view_matches_the_analytic_shadow_disk() {
    let r = 0.5;
    let segments = 48;
    let mut tris: Vec<Tri> = Vec::new();
    sphere(&mut tris, r, segments);
    for t in &mut tris {
        for p in t.iter_mut() {
            p[1] += 1.5;
        }
    }
    quad(
        &mut tris,
        [-2.0, 0.0, -2.0],
        [-2.0, 0.0, 2.0],
        [2.0, 0.0, 2.0],
        [2.0, 0.0, -2.0],
    );
    let sc = Scene::new("disk", tris.clone(), vec![("l".into(), [0.0, -1.0, 0.0])]).unwrap();
    let res = 256;
    let st = render_view(&sc, 0, res);
    let view = eye::eye_view(&tris, eye::default_camera([0.3, -1.0, 0.0]), 200).unwrap();
    let pcf = eye::shadows(&view, &st, Subject::Pcf, &Bias::default()).unwrap();
    // reach of the square 9×9 kernel (4 texels per axis, up to 4√2 diagonally) plus one texel
    // of bilinear blending per axis, in world units
    let band = 5.0 * std::f64::consts::SQRT_2 * st.meta.texel_size;
    let inner = r * (std::f64::consts::PI / segments as f64).cos();
    let (mut inside, mut outside) = (0, 0);
    for (p, s) in view.points.iter().zip(&pcf) {
        let Some(p) = p else { continue };
        if p.world[1].abs() > 1e-6 {
            continue; // on the sphere
        }
        let d = p.world[0].hypot(p.world[2]);
        if d < inner - band {
            assert!(*s > 0.999, "ground at {d} inside the shadow: {s}");
            inside += 1;
        } else if d > r + band {
            assert!(*s < 1e-3, "ground at {d} outside the shadow: {s}");
            outside += 1;
        }
    }
    assert!(inside > 200 && outside > 1000, "{inside} {outside}");
}
