//! Scene files: primitives, transforms, OBJ meshes, the embedded dataset, and rejection of bad
//! scene input (never a panic).

use momentlab::render::scene::load_obj_bytes;
use momentlab::render::{default_dataset, embedded_scenes, render_view, Scene};
use momentlab::stack::validate;
use std::path::PathBuf;

fn no_mesh(p: &str) -> anyhow::Result<Vec<u8>> {
    anyhow::bail!("no mesh {p}")
}

fn parse(text: &str) -> anyhow::Result<Scene> {
    Scene::from_json(text, &no_mesh)
}

fn bounds(s: &Scene) -> ([f64; 3], [f64; 3]) {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for v in s.triangles.iter().flatten() {
        for k in 0..3 {
            lo[k] = lo[k].min(v[k]);
            hi[k] = hi[k].max(v[k]);
        }
    }
    (lo, hi)
}

#[test]
fn transforms_scale_rotate_translate_in_that_order() {
    // box 2×1×4, scaled by 0.5, rotated 90° about y (x→−z, z→x), moved by (10, 1, 0)
    let s = parse(
        r#"{"name":"t","lights":[{"dir":[0,-1,0]}],"objects":[{"type":"box","size":[2,1,4],
        "transform":{"scale":0.5,"rotate":[0,90,0],"translate":[10,1,0]}}]}"#,
    )
    .unwrap();
    assert_eq!(s.triangles.len(), 12);
    let (lo, hi) = bounds(&s);
    let want_lo = [9.0, 1.0, -0.5];
    let want_hi = [11.0, 1.5, 0.5];
    for k in 0..3 {
        assert!((lo[k] - want_lo[k]).abs() < 1e-12, "{lo:?}");
        assert!((hi[k] - want_hi[k]).abs() < 1e-12, "{hi:?}");
    }
    assert_eq!(s.lights[0].name, "light0");
}

#[test]
fn light_angles_and_directions() {
    let s = parse(
        r#"{"name":"t","lights":[{"name":"a","azimuth_deg":0,"elevation_deg":90},
        {"azimuth_deg":90,"elevation_deg":30},{"dir":[0,-3,4]}],
        "objects":[{"type":"plane","size":[1,1]}]}"#,
    )
    .unwrap();
    let d = |i: usize| s.lights[i].dir;
    assert!((d(0)[1] + 1.0).abs() < 1e-12 && d(0)[0].abs() < 1e-12);
    // azimuth 90°, elevation 30°: light comes from +z, travels towards −z and down
    let e = 30f64.to_radians();
    assert!((d(1)[1] + e.sin()).abs() < 1e-12 && (d(1)[2] + e.cos()).abs() < 1e-12);
    assert!((d(2)[1] + 0.6).abs() < 1e-12 && (d(2)[2] - 0.8).abs() < 1e-12);
}

#[test]
fn obj_meshes_load_and_fit() {
    let obj = b"v 0 0 0\nv 2 0 0\nv 2 0 2\nv 0 0 2\nv 1 4 1\nf 1 2 3 4\nf 1 2 5\n";
    let tris = load_obj_bytes(obj).unwrap();
    assert_eq!(tris.len(), 3); // quad triangulated + one triangle
    let s = Scene::from_json(
        r#"{"name":"m","lights":[{"dir":[0,-1,0]}],
            "objects":[{"type":"mesh","path":"x.obj","fit":2.0}]}"#,
        &|p| {
            assert_eq!(p, "x.obj");
            Ok(obj.to_vec())
        },
    )
    .unwrap();
    let (lo, hi) = bounds(&s);
    // largest extent 4 (y) scaled to 2, centred in x/z, base at y = 0
    assert!((hi[1] - 2.0).abs() < 1e-12 && lo[1].abs() < 1e-12);
    assert!((lo[0] + 0.5).abs() < 1e-12 && (hi[0] - 0.5).abs() < 1e-12);
    assert!(load_obj_bytes(b"v 0 0 0\nv 1 0 0\n").is_err());
    assert!(load_obj_bytes(b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n").is_err());
}

#[test]
fn bad_scenes_are_rejected_with_a_message() {
    let cases = [
        ("{", "malformed scene JSON"),
        (
            r#"{"name":"b","lights":[{"dir":[0,-1,0]}],"objects":[{"type":"teapot"}]}"#,
            "teapot",
        ),
        (
            r#"{"name":"b","lights":[{"dir":[0,-1,0]}],"objects":[{"type":"box","size":[1,1]}]}"#,
            "malformed scene JSON",
        ),
        (
            r#"{"name":"b","lights":[{"dir":[0,-1,0]}],"objects":[{"type":"box","size":[1,-1,1]}]}"#,
            "box size must be positive",
        ),
        (
            r#"{"name":"b","lights":[{"dir":[0,-1,0]}],"objects":[{"type":"plane","size":[1,1],"colour":3}]}"#,
            "colour",
        ),
        (
            r#"{"name":"b","lights":[],"objects":[{"type":"plane","size":[1,1]}]}"#,
            "no lights",
        ),
        (
            r#"{"name":"b","lights":[{"dir":[0,0,0]}],"objects":[{"type":"plane","size":[1,1]}]}"#,
            "zero or not finite",
        ),
        (
            r#"{"name":"b","lights":[{"azimuth_deg":10}],"objects":[{"type":"plane","size":[1,1]}]}"#,
            "either",
        ),
        (
            r#"{"name":"b","lights":[{"azimuth_deg":10,"elevation_deg":-5}],"objects":[{"type":"plane","size":[1,1]}]}"#,
            "elevation_deg -5",
        ),
        (
            r#"{"name":"b","lights":[{"dir":[0,-1,0]}],"objects":[]}"#,
            "no triangles",
        ),
        (
            r#"{"name":"b","lights":[{"dir":[0,-1,0]}],"objects":[{"type":"mesh","path":"gone.obj"}]}"#,
            "no mesh gone.obj",
        ),
        (
            r#"{"name":"b","lights":[{"dir":[0,-1,0]}],"objects":[{"type":"city","grid":[2,2],"spacing":1,"footprint":[0.5,2],"height":[1,2],"seed":1}]}"#,
            "footprint",
        ),
    ];
    for (text, want) in cases {
        let e = parse(text)
            .err()
            .unwrap_or_else(|| panic!("accepted: {text}"));
        let msg = format!("{e:#}");
        assert!(msg.contains(want), "{msg:?} lacks {want:?}");
    }
}

#[test]
fn embedded_dataset_is_three_scenes_by_four_views_and_hard() {
    let scenes = embedded_scenes().unwrap();
    let names: Vec<&str> = scenes.iter().map(|s| s.name.as_str()).collect();
    assert_eq!(names, ["city", "stairs", "thin"]);
    assert!(scenes.iter().all(|s| s.lights.len() == 4));
    let stacks = default_dataset(64).unwrap();
    assert_eq!(stacks.len(), 12);
    for st in &stacks {
        validate(st).unwrap();
        assert!(
            st.fragment_count() > st.texel_count() / 4,
            "{}",
            st.file_stem()
        );
        assert!(st.meta.layers >= 4, "{} {}", st.file_stem(), st.meta.layers);
    }
    // the city has many layers in every view
    assert!(stacks[..4].iter().all(|s| s.meta.layers >= 8));
    // the same view rendered twice is identical (deterministic, thread-count independent)
    let again = render_view(&scenes[0], 2, 64);
    assert_eq!(again, stacks[2]);
}

#[test]
fn render_cli_rejects_bad_input_with_one_line() {
    let bin = env!("CARGO_BIN_EXE_momentlab");
    let dir = std::env::temp_dir().join(format!("momentlab_render_cli_{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(
        dir.join("bad.json"),
        r#"{"name":"b","lights":[{"dir":[0,-1,0]}],"objects":[{"type":"box","size":[1,0,1]}]}"#,
    )
    .unwrap();
    let out = dir.join("out");
    let run = |args: &[&str]| {
        let o = std::process::Command::new(bin).args(args).output().unwrap();
        assert_eq!(o.status.code(), Some(1), "{args:?}");
        let e = String::from_utf8_lossy(&o.stderr).to_string();
        assert_eq!(e.lines().count(), 1, "{e}");
        e
    };
    let o = out.to_str().unwrap();
    let e = run(&["render", "--scenes", dir.to_str().unwrap(), "--out", o]);
    assert!(
        e.contains("bad.json") && e.contains("box size must be positive"),
        "{e}"
    );
    let e = run(&["render", "--only", "nope", "--out", o]);
    assert!(e.contains("--only nope") && e.contains("city"), "{e}");
    // `--resolution 0` is a usage error (exit 2): tests/cli_bad_input.rs.
    let e = run(&["render", "--scenes", "/nonexistent/dir", "--out", o]);
    assert!(e.contains("/nonexistent/dir"), "{e}");

    // a good run of one small scene writes 4 valid stacks
    let s = std::process::Command::new(bin)
        .args(["render", "--only", "thin", "--resolution", "32", "--out", o])
        .output()
        .unwrap();
    assert!(s.status.success());
    let st = momentlab::stack::load_dir(&PathBuf::from(o)).unwrap();
    assert_eq!(st.len(), 4);
    assert_eq!(st[0].file_stem(), "thin_light0");
}
