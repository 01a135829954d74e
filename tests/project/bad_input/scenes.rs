//! Scenes and meshes: names, transforms, counts, lights and glTF buffers validated before any
//! rendering.

use super::*;

/// A .gltf with one triangle whose buffer is the file `uri`.
fn gltf_with_buffer(uri: &str) -> String {
    format!(
        r#"{{"asset":{{"version":"2.0"}},"scenes":[{{"nodes":[0]}}],"nodes":[{{"mesh":0}}],
"meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}}}}]}}],
"accessors":[{{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","max":[1,1,1],"min":[0,0,0]}}],
"bufferViews":[{{"buffer":0,"byteLength":36}}],"buffers":[{{"byteLength":36,"uri":"{uri}"}}]}}"#
    )
}

#[test]
fn scenes_names_and_transforms_are_validated_before_rendering() {
    let s = Scratch::new("scenes");
    let out = s.p("deep/a/out");
    let cases: Vec<(String, &[&str])> = vec![
        (
            scene("../../evil", LIGHT, PLANE),
            &["scene name '../../evil' is not a plain name"],
        ),
        (
            scene("a\\nb", LIGHT, PLANE),
            &["scene name 'a\\nb' is not a plain name"],
        ),
        (
            scene(
                "s",
                r#"{"name": "l", "dir": [0,-1,0]}, {"name": "l", "dir": [1,-1,0]}"#,
                PLANE,
            ),
            &["two lights named 'l'"],
        ),
        (
            scene("s", r#"{"name": "../x", "dir": [0,-1,0]}"#, PLANE),
            &["light name '../x'"],
        ),
        (
            scene(
                "s",
                LIGHT,
                r#"{"type": "box", "size": [1,1,1], "transform": {"scale": 0}}"#,
            ),
            &["object 0: transform", "determinant"],
        ),
        (
            scene(
                "s",
                LIGHT,
                r#"{"type": "box", "size": [1,1,1], "transform": {"scale": 1e300}}"#,
            ),
            &["object 0: transform"],
        ),
        (
            scene(
                "s",
                LIGHT,
                r#"{"type": "box", "size": [1,1,1], "transform": {"translate": [1e308, 0, 0]}}"#,
            ),
            &["object 0: transform puts a vertex at coordinate 1e308"],
        ),
        (
            scene(
                "s",
                LIGHT,
                r#"{"type": "box", "size": [1,1,1], "transform": {"scale": [1, 1e-40, 1]}}"#,
            ),
            &["object 0: transform", "degenerate"],
        ),
    ];
    for (i, (json, want)) in cases.iter().enumerate() {
        let dir = s.path(&format!("case{i}"));
        s.write(&format!("case{i}/s.json"), json);
        expect(
            &[
                "render",
                "--scenes",
                dir.to_str().unwrap(),
                "--resolution",
                "16",
                "--out",
                &out,
            ],
            1,
            want,
        );
    }
    // Two scene files with one name: refused before rendering (not "rendered 2 views").
    s.write("dup/a.json", &scene("same", LIGHT, PLANE));
    s.write("dup/b.json", &scene("same", LIGHT, PLANE));
    expect(
        &[
            "render",
            "--scenes",
            &s.p("dup"),
            "--resolution",
            "16",
            "--out",
            &out,
        ],
        1,
        &["two outputs named 'same_light0.exr'"],
    );
    // Nothing was written anywhere: not in --out, not above it.
    assert!(!s.path("deep/a/out").exists());
    assert!(!s.path("evil").exists() && !s.path("deep/evil").exists());
    assert!(!s.path("evil_light0.exr").exists());
}

#[test]
fn scene_counts_are_bounded_before_anything_is_built() {
    let s = Scratch::new("counts");
    let out = s.p("out");
    let big = "1000000000";
    let cases: Vec<(String, &[&str])> = vec![
        (
            r#"{"type":"city","grid":[100000,100000],"spacing":1,"footprint":[0.2,0.5],"height":[1,2],"seed":1}"#.into(),
            &["object 0 (city): grid [100000, 100000]", "more than the 50000000"],
        ),
        (
            r#"{"type":"city","grid":[2,2],"bridges":18446744073709551615,"spacing":1,"footprint":[0.2,0.5],"height":[1,2],"seed":1}"#.into(),
            &["object 0 (city)", "bridges 18446744073709551615"],
        ),
        (
            format!(r#"{{"type":"sphere","radius":1,"segments":{big}}}"#),
            &["object 0 (sphere): segments 1000000000"],
        ),
        (
            format!(r#"{{"type":"torus","radius":1,"tube":0.2,"segments":{big}}}"#),
            &["object 0 (torus): segments 1000000000"],
        ),
        (
            format!(r#"{{"type":"cylinder","radius":1,"height":1,"segments":{big}}}"#),
            &["object 0 (cylinder): segments 1000000000"],
        ),
        (
            format!(r#"{{"type":"cards","count":{big},"size":[1,1],"region":[0,0,0,1,1,1],"seed":1}}"#),
            &["object 0 (cards): count 1000000000"],
        ),
        (
            format!(r#"{{"type":"stairs","steps":{big},"width":1,"step_depth":1,"step_height":1}}"#),
            &["object 0 (stairs): steps 1000000000"],
        ),
        (
            format!(r#"{{"type":"fence","width":1,"height":1,"bars":{big},"bar_width":0.1,"thickness":0.1}}"#),
            &["object 0 (fence): bars 1000000000"],
        ),
        (
            format!(r#"{{"type":"grating","size":[1,1],"bars":[{big},1],"bar_width":0.1,"thickness":0.1}}"#),
            &["object 0 (grating): bars [1000000000, 1]"],
        ),
        (
            format!(r#"{{"type":"arcade","columns":{big},"spacing":1,"radius":0.1,"height":1,"depth":1,"roof":0.1}}"#),
            &["object 0 (arcade): columns 1000000000"],
        ),
        // each object within the limit, the scene not
        (
            format!("{PLANE}, {}", [r#"{"type":"cards","count":20000000,"size":[1,1],"region":[0,0,0,1,1,1],"seed":1}"#; 2].join(", ")),
            &["object 2 (cards): count 20000000 brings the scene to 80000002 triangles"],
        ),
    ];
    for (i, (object, want)) in cases.iter().enumerate() {
        let f = s.write(&format!("case{i}.json"), &scene("s", LIGHT, object));
        let err = expect(
            &[
                "render",
                "--scenes",
                &f,
                "--resolution",
                "32",
                "--out",
                &out,
            ],
            1,
            want,
        );
        assert!(err.contains(&format!("case{i}.json")), "{err}");
    }
    assert!(!s.path("out").exists());
}

#[test]
fn render_refuses_views_with_more_layers_than_a_stack_holds() {
    let s = Scratch::new("layers");
    let out = s.p("out");
    // 6000 cards stacked on one column: thousands of surfaces along the middle texels' rays
    let cards =
        r#"{"type":"cards","count":6000,"size":[10,10],"region":[0,0,0,0.01,5,0.01],"seed":1}"#;
    s.write("in/a.json", &scene("a", LIGHT, PLANE));
    let sun = r#"{"azimuth_deg": 30, "elevation_deg": 60}"#;
    s.write("in/b.json", &scene("b", sun, cards));
    let err = expect(
        &[
            "render",
            "--scenes",
            &s.p("in"),
            "--resolution",
            "16",
            "--out",
            &out,
        ],
        1,
        &[
            "scene 'b' view 'light0' at 16×16",
            "more than the 4096 layers a stack may hold",
        ],
    );
    assert!(!err.contains("'a'"), "{err}");
    // nothing left behind: not b's files, and a's (written first) removed again
    assert_eq!(
        snapshot(&s.path("out")).len(),
        0,
        "{:?}",
        snapshot(&s.path("out"))
    );
}

#[test]
fn render_light_errors_name_the_bad_value() {
    let s = Scratch::new("lightarg");
    let obj = s.write("q.obj", "v 0 0 0\nv 1 0 0\nv 0 0 1\nf 1 2 3\n");
    let out = s.p("out");
    for (light, want) in [
        ("NaN,60", "azimuth_deg NaN outside [-360, 360]"),
        ("inf,60", "azimuth_deg inf outside [-360, 360]"),
        ("-inf,60", "azimuth_deg -inf outside [-360, 360]"),
        ("1e308,60", "azimuth_deg 1e308 outside [-360, 360]"),
        ("361,60", "azimuth_deg 361 outside [-360, 360]"),
        ("30,NaN", "elevation_deg NaN outside [1, 90]"),
        ("30,95", "elevation_deg 95 outside [1, 90]"),
    ] {
        let err = expect(
            &["render", "--scenes", &obj, "--light", light, "--out", &out],
            1,
            &["light 'light0'", want],
        );
        assert!(
            !(light.ends_with(",60") && err.contains("elevation")),
            "{err}"
        );
    }
    // a full turn either way is fine
    for light in ["-360,60", "360,60"] {
        let (code, _, err) = run(
            &[
                "render",
                "--scenes",
                &obj,
                "--light",
                light,
                "--resolution",
                "16",
                "--out",
                &out,
                "--force",
            ],
            None,
        );
        assert_eq!(code, 0, "{light}: {err}");
    }
}

#[test]
fn gltf_buffers_stay_in_the_folder_of_the_gltf() {
    let s = Scratch::new("gltfuri");
    let out = s.p("out");
    let tri: Vec<u8> = [0f32, 0., 0., 1., 0., 0., 0., 0., 1.]
        .iter()
        .flat_map(|f| f.to_le_bytes())
        .collect();
    std::fs::create_dir_all(s.path("m/sub")).unwrap();
    std::fs::write(s.path("m/tri.bin"), &tri).unwrap();
    std::fs::write(s.path("m/sub/tri.bin"), &tri).unwrap();
    std::fs::write(s.path("outside.bin"), &tri).unwrap();
    std::os::unix::fs::symlink(s.path("outside.bin"), s.path("m/link.bin")).unwrap();
    std::os::unix::fs::symlink("/etc/passwd", s.path("m/passwd.bin")).unwrap();
    for (i, uri) in [
        "../outside.bin",
        "../../../../../../../etc/passwd",
        "/etc/passwd",
        "sub/../../outside.bin",
        "file:///etc/passwd",
        "file:/etc/passwd",
        "..\\\\outside.bin",
        "link.bin",
        "passwd.bin",
    ]
    .iter()
    .enumerate()
    {
        let g = s.write(&format!("m/g{i}.gltf"), &gltf_with_buffer(uri));
        // the JSON text of the uri is how the error shows it (control characters escaped)
        let err = expect(
            &["render", "--scenes", &g, "--light", "30,60", "--out", &out],
            1,
            &[&format!("g{i}.gltf"), &format!("'{uri}'")],
        );
        assert!(
            err.contains("not a file in the folder of the .gltf")
                || err.contains("outside the folder of the .gltf")
                || err.contains("remote URI"),
            "{uri}: {err}"
        );
    }
    // files next to it or below it are read
    for uri in ["tri.bin", "sub/tri.bin", "./tri.bin"] {
        let g = s.write("m/ok.gltf", &gltf_with_buffer(uri));
        let (code, _, err) = run(
            &[
                "render",
                "--scenes",
                &g,
                "--light",
                "30,60",
                "--resolution",
                "16",
                "--out",
                &out,
                "--force",
            ],
            None,
        );
        assert_eq!(code, 0, "{uri}: {err}");
    }
    // also as a mesh of a scene file in another folder
    s.write(
        "scenes/s.json",
        &scene("s", LIGHT, r#"{"type":"mesh","path":"../m/g0.gltf"}"#),
    );
    expect(
        &[
            "render",
            "--scenes",
            &s.p("scenes/s.json"),
            "--out",
            &out,
            "--force",
        ],
        1,
        &["mesh '../m/g0.gltf'", "'../outside.bin'"],
    );
}
