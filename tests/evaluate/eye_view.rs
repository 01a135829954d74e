//! Eye-view pictures: the bilinear shadow-map lookup against a hand computation, and the PCF
//! eye view of a sphere over a plane against the analytic shadow disk.

use crate::common::{decode_png, no_mesh, tmp};
use momentlab::metrics::eye::{self, bilinear};
use momentlab::metrics::{Bias, Subject};
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

/// A sphere floating over a square ground plane, as a scene file; `camera` is the JSON of the
/// light's camera field (or empty).
fn disk_scene_json(camera: &str) -> String {
    let cam = if camera.is_empty() {
        String::new()
    } else {
        format!(", \"camera\": {camera}")
    };
    format!(
        r#"{{ "name": "disk",
  "lights": [ {{ "name": "sun", "azimuth_deg": 0, "elevation_deg": 70{cam} }} ],
  "objects": [
    {{ "type": "plane", "size": [4, 4] }},
    {{ "type": "sphere", "radius": 0.5, "segments": 24, "transform": {{ "translate": [0, 1.5, 0] }} }}
  ] }}"#
    )
}

#[test]
fn the_scene_file_camera_replaces_the_default() {
    let plain = Scene::from_json(&disk_scene_json(""), &no_mesh).unwrap();
    assert_eq!(plain.lights[0].camera, None);
    let d = eye::camera_of(&plain.lights[0]);
    assert_eq!(d, eye::default_camera(plain.lights[0].dir));
    // default: 40° above the horizon
    assert!((d[1] + eye::DEFAULT_ELEVATION_DEG.to_radians().sin()).abs() < 1e-12);

    // From straight above: the camera looks along −y (normalized), and the centre pixel sees
    // the top of the sphere (y = 2), which the default camera at 40° does not.
    let top = Scene::from_json(&disk_scene_json(r#"{ "dir": [0, -3, 0] }"#), &no_mesh).unwrap();
    assert_eq!(top.lights[0].camera, Some([0.0, -1.0, 0.0]));
    assert_eq!(eye::camera_of(&top.lights[0]), [0.0, -1.0, 0.0]);
    let res = 63;
    let v = eye::eye_view(&top.triangles, eye::camera_of(&top.lights[0]), res).unwrap();
    let c = v.points[(res / 2) * res + res / 2].unwrap();
    assert!((c.world[1] - 2.0).abs() < 0.02, "{:?}", c.world);
    assert!(c.normal[1] > 0.99, "{:?}", c.normal);
    // Seen from above, the floating sphere hides the ground under it; the default camera at 40°
    // sees that ground beside the sphere.
    let under = |v: &eye::EyeView| {
        v.points
            .iter()
            .flatten()
            .filter(|p| p.world[1].abs() < 1e-6 && p.world[0].hypot(p.world[2]) < 0.45)
            .count()
    };
    assert_eq!(under(&v), 0);
    let dv = eye::eye_view(&plain.triangles, d, res).unwrap();
    assert!(under(&dv) > 10, "{}", under(&dv));

    // Azimuth/elevation: where the camera looks from, as for lights.
    let ae = Scene::from_json(
        &disk_scene_json(r#"{ "azimuth_deg": 90, "elevation_deg": 30 }"#),
        &no_mesh,
    )
    .unwrap();
    let cam = ae.lights[0].camera.unwrap();
    let want = [0.0, -0.5, -(3f64.sqrt() / 2.0)];
    assert!((0..3).all(|k| (cam[k] - want[k]).abs() < 1e-12), "{cam:?}");
}

#[test]
fn bad_cameras_are_one_line_errors() {
    for (cam, want) in [
        (
            r#"{ "azimuth_deg": 10, "elevation_deg": 95 }"#,
            "light 'sun': camera: elevation_deg 95 outside [1, 90]",
        ),
        (
            r#"{ "dir": [0, 1, 0] }"#,
            "light 'sun': camera: dir [0.0, 1.0, 0.0] looks upward",
        ),
        (
            r#"{ "dir": [1, 0, 0] }"#,
            "light 'sun': camera: dir [1.0, 0.0, 0.0] is (nearly) horizontal",
        ),
        (r#"{ "dir": [0, 0, 0] }"#, "light 'sun': camera: direction"),
        (
            r#"{ "azimuth_deg": 10 }"#,
            "light 'sun': camera: give either \"dir\" or both",
        ),
        (r#"{ "fov": 30 }"#, "unknown field `fov`"),
    ] {
        let e = Scene::from_json(&disk_scene_json(cam), &no_mesh).unwrap_err();
        let msg = format!("{e:#}");
        assert!(msg.contains(want), "{cam}: {msg}");
        assert!(!msg.contains('\n'), "{cam}: {msg}");
    }
}

struct Dir(std::path::PathBuf);
impl Dir {
    fn new(tag: &str) -> Dir {
        Dir(tmp(&format!("eye-{tag}")))
    }
    fn p(&self, rel: &str) -> std::path::PathBuf {
        self.0.join(rel)
    }
}
impl Drop for Dir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

fn momentlab(args: &[&str]) -> std::process::Output {
    crate::common::momentlab()
        .args(args)
        .env("CI", "1")
        .output()
        .unwrap()
}

#[test]
fn evaluate_writes_eye_and_layer_pictures_with_the_scene_camera() {
    use momentlab::report::pictures::{BAR_LABEL_PX, BAR_PX, GAP_PX};
    let d = Dir::new("cli");
    for (sub, cam) in [("plain", ""), ("top", r#"{ "dir": [0, -1, 0] }"#)] {
        std::fs::create_dir_all(d.p(sub)).unwrap();
        std::fs::write(d.p(&format!("{sub}/disk.json")), disk_scene_json(cam)).unwrap();
        let out = momentlab(&[
            "evaluate",
            "--technique",
            "pcf,vsm",
            "--scenes",
            d.p(&format!("{sub}/disk.json")).to_str().unwrap(),
            "--resolution",
            "32",
            "--eye-resolution",
            "40",
            "--layer-pictures",
            "3",
            "--out",
            d.p(&format!("{sub}/out")).to_str().unwrap(),
        ]);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
    }
    let mut names: Vec<String> = std::fs::read_dir(d.p("top/out"))
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().to_string())
        .filter(|n| !n.starts_with('.'))
        .collect();
    names.sort();
    // Two layers under the sphere's shadow (sphere front and back, ground): layers 0..=2.
    let mut want = Vec::new();
    for t in ["pcf", "vsm"] {
        want.push(format!("disk_sun_{t}.eye.png"));
        for k in 0..3 {
            want.push(format!("disk_sun_{t}.layer{k}.png"));
        }
        want.push(format!("disk_sun_{t}.png"));
    }
    want.sort();
    assert_eq!(names, want);
    let (w, h, top) = decode_png(&d.p("top/out/disk_sun_vsm.eye.png"));
    assert_eq!((w, h), (3 * 40 + 3 * GAP_PX + BAR_PX + BAR_LABEL_PX, 40));
    let (_, _, plain) = decode_png(&d.p("plain/out/disk_sun_vsm.eye.png"));
    assert_ne!(top, plain, "the scene file's camera changes the eye view");
    // From straight above the sphere covers the picture's centre: lit from 70°, its top is
    // bright in the PCF panel.
    let centre = 3 * (20 * w + 20);
    assert!(top[centre] > 180, "{}", top[centre]);
}

#[test]
fn eye_view_scenes_must_match_the_stacks() {
    let d = Dir::new("match");
    std::fs::write(d.p("disk.json"), disk_scene_json("")).unwrap();
    let out = momentlab(&[
        "render",
        "--scenes",
        d.p("disk.json").to_str().unwrap(),
        "--resolution",
        "16",
        "--out",
        d.p("stacks").to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    // The same scene name with other geometry: the light frame differs.
    std::fs::create_dir_all(d.p("other")).unwrap();
    std::fs::write(
        d.p("other/disk.json"),
        disk_scene_json("").replace("\"radius\": 0.5", "\"radius\": 0.9"),
    )
    .unwrap();
    // Another scene name.
    std::fs::create_dir_all(d.p("renamed")).unwrap();
    std::fs::write(
        d.p("renamed/ball.json"),
        disk_scene_json("").replace("\"disk\"", "\"ball\""),
    )
    .unwrap();
    for (scenes, want) in [
        (
            "other/disk.json",
            "stack disk/sun was not rendered from scene 'disk'",
        ),
        (
            "renamed/ball.json",
            "--scenes: no scene named 'disk' for stack disk/sun",
        ),
    ] {
        let out = momentlab(&[
            "evaluate",
            "--technique",
            "vsm",
            "--stacks",
            d.p("stacks").to_str().unwrap(),
            "--scenes",
            d.p(scenes).to_str().unwrap(),
            "--out",
            d.p("pics").to_str().unwrap(),
        ]);
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{scenes}");
        assert!(err.contains(want), "{scenes}: {err}");
        assert_eq!(err.trim().lines().count(), 1, "{err}");
        assert!(!d.p("pics").join("disk_sun_vsm.png").exists());
    }
    // Stacks without --scenes: the light-view pictures only, said on stderr.
    let out = momentlab(&[
        "evaluate",
        "--technique",
        "vsm",
        "--stacks",
        d.p("stacks").to_str().unwrap(),
        "--out",
        d.p("pics").to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(String::from_utf8_lossy(&out.stderr).contains("no eye-view pictures"));
    assert!(d.p("pics/disk_sun_vsm.png").exists());
    assert!(!d.p("pics/disk_sun_vsm.eye.png").exists());
    // Flags that need --out, and a layer count out of range.
    for args in [
        vec!["--layer-pictures", "2"],
        vec!["--eye-resolution", "64"],
        vec!["--layer-pictures", "0", "--out", "x"],
    ] {
        let mut a = vec!["evaluate", "--technique", "vsm", "--resolution", "16"];
        a.extend(args.iter().copied());
        let out = momentlab(&a);
        assert!(!out.status.success(), "{args:?}");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(
            err.contains("--out") || err.contains("0 is not in 1..=64"),
            "{args:?}: {err}"
        );
    }
}

#[test]
fn lp_candidate_eye_view_agrees_with_pcf_away_from_the_penumbra() {
    // An LP candidate (sharp lower bound on a grid) from the eye: no LP where no window depth
    // lies below the point (G = 0 exactly), and fully shadowed ground inside the disk.
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
    let st = render_view(&sc, 0, 128);
    let view = eye::eye_view(&tris, eye::default_camera([0.3, -1.0, 0.0]), 96).unwrap();
    let lp = momentlab::technique::lp_candidate::LpCandidate::from_spec_on("z,z^2,z^3,z^4", 256)
        .unwrap();
    let g = eye::shadows(&view, &st, Subject::Technique(&lp), &Bias::default()).unwrap();
    let band = 5.0 * std::f64::consts::SQRT_2 * st.meta.texel_size;
    let inner = r * (std::f64::consts::PI / segments as f64).cos();
    let (mut inside, mut outside) = (0, 0);
    for (p, s) in view.points.iter().zip(&g) {
        let Some(p) = p else { continue };
        if p.world[1].abs() > 1e-6 {
            continue;
        }
        let d = p.world[0].hypot(p.world[2]);
        if d < inner - band {
            assert!(*s > 0.9, "ground at {d} inside the shadow: {s}");
            inside += 1;
        } else if d > r + band {
            assert_eq!(*s, 0.0, "ground at {d} outside the shadow");
            outside += 1;
        }
    }
    assert!(inside > 20 && outside > 500, "{inside} {outside}");
}
