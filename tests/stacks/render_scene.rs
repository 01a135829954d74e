//! Scene files: primitives, transforms, OBJ meshes, the embedded dataset, and rejection of bad
//! scene input (never a panic).

use crate::common::{momentlab, no_mesh, tmp};
use momentlab::render::scene::load_obj_bytes;
use momentlab::render::{default_dataset, embedded_scenes, render_view, Scene};
use momentlab::stack::validate;
use std::path::PathBuf;

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
    let dir = tmp("render-cli");
    std::fs::write(
        dir.join("bad.json"),
        r#"{"name":"b","lights":[{"dir":[0,-1,0]}],"objects":[{"type":"box","size":[1,0,1]}]}"#,
    )
    .unwrap();
    let out = dir.join("out");
    let run = |args: &[&str]| {
        let o = momentlab().args(args).output().unwrap();
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
    // `--resolution 0` is a usage error (exit 2): tests/project/bad_input/per_command.rs.
    let e = run(&["render", "--scenes", "/nonexistent/dir", "--out", o]);
    assert!(e.contains("/nonexistent/dir"), "{e}");

    // a good run of one small scene writes 4 valid stacks
    let s = momentlab()
        .args(["render", "--only", "thin", "--resolution", "32", "--out", o])
        .output()
        .unwrap();
    assert!(s.status.success());
    let st = momentlab::stack::load_dir(&PathBuf::from(o)).unwrap();
    assert_eq!(st.len(), 4);
    assert_eq!(st[0].file_stem(), "thin_light0");
}

/// A z-up box (x, y in [0, 2], z from 0 to 4) as OBJ.
const Z_UP_BOX: &[u8] = b"v 0 0 0\nv 2 0 0\nv 2 2 0\nv 0 2 0\nv 0 0 4\nv 2 0 4\nv 2 2 4\nv 0 2 4\n\
f 1 2 3 4\nf 5 6 7 8\nf 1 2 6 5\nf 2 3 7 6\nf 3 4 8 7\nf 4 1 5 8\n";

#[test]
fn z_up_meshes_are_rotated_before_they_are_fitted_onto_the_ground() {
    let load = |mesh_fields: &str, transform: &str| {
        let text = format!(
            r#"{{"name":"z","lights":[{{"dir":[0,-1,0]}}],"objects":[{{"type":"mesh",
            "path":"box.obj","fit":2.0{mesh_fields}{transform}}}]}}"#
        );
        Scene::from_json(&text, &|_| Ok(Z_UP_BOX.to_vec())).unwrap()
    };
    // up_axis z and an explicit −90° about X give the same: standing upright on y = 0,
    // height (the file's z extent 4) scaled to 2, centred in x/z
    for fields in [r#","up_axis":"z""#, r#","rotate":[-90,0,0]"#] {
        let (lo, hi) = bounds(&load(fields, ""));
        let want_lo = [-0.5, 0.0, -0.5];
        let want_hi = [0.5, 2.0, 0.5];
        for k in 0..3 {
            assert!((lo[k] - want_lo[k]).abs() < 1e-12, "{fields}: {lo:?}");
            assert!((hi[k] - want_hi[k]).abs() < 1e-12, "{fields}: {hi:?}");
        }
        // the object transform comes after: translate moves the grounded mesh
        let (lo, _) = bounds(&load(fields, r#","transform":{"translate":[0,3,0]}"#));
        assert!((lo[1] - 3.0).abs() < 1e-12, "{lo:?}");
    }
    // without up_axis the z-up box lies on its side (height 1 after fitting its 4 long z edge)
    let (lo, hi) = bounds(&load("", ""));
    assert!(
        lo[1].abs() < 1e-12 && (hi[1] - 1.0).abs() < 1e-12,
        "{lo:?} {hi:?}"
    );
    let e = Scene::from_json(
        r#"{"name":"z","lights":[{"dir":[0,-1,0]}],"objects":[{"type":"mesh","path":"b.obj","up_axis":"x"}]}"#,
        &|_| Ok(Z_UP_BOX.to_vec()),
    )
    .unwrap_err();
    assert!(format!("{e:#}").contains("unknown variant `x`"), "{e:#}");
}

#[test]
fn lights_must_shine_down_onto_the_receivers() {
    let scene = |light: &str| {
        parse(&format!(
            r#"{{"name":"l","lights":[{light}],"objects":[{{"type":"plane","size":[1,1]}}]}}"#
        ))
    };
    for (light, want) in [
        (r#"{"dir":[0,1,0]}"#, "travels upward"),
        (r#"{"dir":[0.3,0.2,0]}"#, "travels upward"),
        (r#"{"dir":[1,0,0]}"#, "is (nearly) horizontal"),
        (r#"{"dir":[1,-0.01,0]}"#, "is (nearly) horizontal"),
        (
            r#"{"azimuth_deg":10,"elevation_deg":0}"#,
            "elevation_deg 0 outside [1, 90]",
        ),
        (
            r#"{"azimuth_deg":10,"elevation_deg":95}"#,
            "elevation_deg 95 outside",
        ),
    ] {
        let e = format!("{:#}", scene(light).unwrap_err());
        assert!(e.contains(want) && !e.contains('\n'), "{light}: {e}");
    }
    // just above the limit is accepted, in both forms
    assert!(scene(r#"{"dir":[1,-0.02,0]}"#).is_ok());
    assert!(scene(r#"{"azimuth_deg":10,"elevation_deg":1}"#).is_ok());
}

#[test]
fn scenes_option_takes_a_folder_a_scene_file_or_a_mesh_file() {
    let dir = tmp("scenes-arg");
    std::fs::write(dir.join("box.obj"), Z_UP_BOX).unwrap();
    std::fs::write(
        dir.join("one.json"),
        r#"{"name":"one","lights":[{"dir":[0,-1,0]},{"dir":[0.3,-1,0]}],"objects":[
        {"type":"plane","size":[8,8]},{"type":"mesh","path":"box.obj","up_axis":"z","fit":2}]}"#,
    )
    .unwrap();
    let out = dir.join("out");
    let o = out.to_str().unwrap();
    let run = |args: &[&str]| momentlab().args(args).output().unwrap();
    let ok = |args: &[&str]| {
        let r = run(args);
        assert!(
            r.status.success(),
            "{args:?}: {}",
            String::from_utf8_lossy(&r.stderr)
        );
    };
    let fails = |args: &[&str]| {
        let r = run(args);
        assert_eq!(r.status.code(), Some(1), "{args:?}");
        let e = String::from_utf8_lossy(&r.stderr).to_string();
        assert_eq!(e.lines().count(), 1, "{e}");
        e
    };
    let scene_file = dir.join("one.json");
    ok(&[
        "render",
        "--scenes",
        scene_file.to_str().unwrap(),
        "--resolution",
        "16",
        "--out",
        o,
    ]);
    assert_eq!(momentlab::stack::load_dir(&out).unwrap().len(), 2);

    // a mesh file directly: lights on the command line (two views), z up
    let mesh = dir.join("box.obj");
    let m = mesh.to_str().unwrap();
    let out2 = dir.join("out2");
    let o2 = out2.to_str().unwrap();
    ok(&[
        "render",
        "--scenes",
        m,
        "--light",
        "30,60",
        "--light",
        "0.2,-1,0",
        "--up-axis",
        "z",
        "--resolution",
        "16",
        "--out",
        o2,
    ]);
    let st = momentlab::stack::load_dir(&out2).unwrap();
    assert_eq!(st.len(), 2);
    assert_eq!(st[0].file_stem(), "box_light0");
    // the same from the sidecar box.lights.json
    std::fs::write(
        dir.join("box.lights.json"),
        r#"{"lights":[{"azimuth_deg":30,"elevation_deg":60},{"dir":[0.2,-1,0]}],"up_axis":"z"}"#,
    )
    .unwrap();
    let out3 = dir.join("out3");
    ok(&[
        "render",
        "--scenes",
        m,
        "--resolution",
        "16",
        "--out",
        out3.to_str().unwrap(),
    ]);
    let st3 = momentlab::stack::load_dir(&out3).unwrap();
    assert_eq!(st3, st);
    // the folder skips the sidecar (it is not a scene file); --out holds the stacks of the
    // first run, replaced only with --force
    ok(&[
        "render",
        "--scenes",
        dir.to_str().unwrap(),
        "--resolution",
        "16",
        "--out",
        o,
        "--force",
    ]);

    // errors: no lights; an upward light; --light for a folder; an unsupported mesh format
    std::fs::remove_file(dir.join("box.lights.json")).unwrap();
    let e = fails(&["render", "--scenes", m, "--out", o]);
    assert!(e.contains("no lights") && e.contains("--light"), "{e}");
    let e = fails(&["render", "--scenes", m, "--light", "0,1,0", "--out", o]);
    assert!(e.contains("travels upward"), "{e}");
    // a malformed --light is a usage error (exit 2) naming the value
    let r = run(&["render", "--scenes", m, "--light", "1,2,3,4", "--out", o]);
    assert_eq!(r.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&r.stderr).contains("expected AZ,EL or X,Y,Z"));
    let e = fails(&[
        "render",
        "--scenes",
        dir.to_str().unwrap(),
        "--light",
        "30,60",
        "--out",
        o,
    ]);
    assert!(e.contains("apply to a mesh file"), "{e}");
    std::fs::write(dir.join("x.fbx"), b"Kaydara FBX Binary").unwrap();
    let e = fails(&[
        "render",
        "--scenes",
        dir.join("x.fbx").to_str().unwrap(),
        "--light",
        "30,60",
        "--out",
        o,
    ]);
    assert!(
        e.contains("FBX (.fbx) is not a supported mesh format"),
        "{e}"
    );
    let e = fails(&[
        "render",
        "--scenes",
        dir.join("gone.glb").to_str().unwrap(),
        "--out",
        o,
    ]);
    assert!(e.contains("no such file or folder"), "{e}");
}
