//! Unit tests of the scene file: shapes, transforms, lights.

use super::schema::{LightDesc, Object};
use super::transform::{check_affine, orient_mesh, Affine, UpAxis};
use super::{Scene, Tri};
use crate::linalg::v3::{dot, norm, sub};

fn object(json: &str) -> Object {
    serde_json::from_str(json).unwrap()
}

fn no_mesh(_: &str) -> anyhow::Result<Vec<u8>> {
    anyhow::bail!("no mesh files here")
}

/// Every procedural shape makes exactly the triangles `triangle_count` plans for it (the
/// count the scene's size limit is checked against before anything is built).
#[test]
fn planned_triangle_counts_are_the_built_ones() {
    let shapes = [
        r#"{"type": "plane", "size": [2, 3]}"#,
        r#"{"type": "box", "size": [1, 2, 3]}"#,
        r#"{"type": "cylinder", "radius": 1, "height": 2, "segments": 7}"#,
        r#"{"type": "torus", "radius": 2, "tube": 0.5, "segments": 9}"#,
        r#"{"type": "sphere", "radius": 1, "segments": 5}"#,
        r#"{"type": "sphere", "radius": 1, "segments": 3}"#,
        r#"{"type": "stairs", "steps": 4, "width": 1, "step_depth": 0.3, "step_height": 0.2}"#,
        r#"{"type": "stairs", "steps": 0, "width": 1, "step_depth": 0.3, "step_height": 0.2}"#,
        r#"{"type": "fence", "width": 4, "height": 1, "bars": 5, "bar_width": 0.1,
            "thickness": 0.1}"#,
        r#"{"type": "grating", "size": [2, 2], "bars": [3, 4], "bar_width": 0.1,
            "thickness": 0.05}"#,
        r#"{"type": "cards", "count": 6, "size": [0.2, 0.3], "region": [0,0,0,1,1,1],
            "seed": 3}"#,
        r#"{"type": "city", "grid": [3, 2], "spacing": 2, "footprint": [0.5, 1.5],
            "height": [1, 3], "bridges": 2, "seed": 1}"#,
        r#"{"type": "arcade", "columns": 3, "spacing": 2, "radius": 0.2, "height": 2,
            "depth": 3, "roof": 0.2}"#,
    ];
    for json in shapes {
        let o = object(json);
        let (_, planned) = o.shape.triangle_count().unwrap();
        let built = o.shape.triangles(&no_mesh).unwrap();
        assert_eq!(built.len() as u128, planned, "{json}");
        assert!(
            built.iter().flatten().flatten().all(|c| c.is_finite()),
            "{json}"
        );
    }
}

/// Sizes must be positive and finite, segment counts at least 3: one error naming the field.
#[test]
fn bad_shape_numbers_are_named() {
    for (json, want) in [
        (r#"{"type": "plane", "size": [0, 3]}"#, "plane size"),
        (r#"{"type": "box", "size": [1, -2, 3]}"#, "box size"),
        (
            r#"{"type": "cylinder", "radius": 1, "height": 2, "segments": 2}"#,
            "cylinder segments",
        ),
        (
            r#"{"type": "city", "grid": [1, 1], "spacing": 1, "footprint": [0.5, 1.5],
                "height": [1, 3], "seed": 1}"#,
            "city footprint",
        ),
        (
            r#"{"type": "arcade", "columns": 1, "spacing": 2, "radius": 0.2, "height": 2,
                "depth": 3, "roof": 0}"#,
            "arcade roof",
        ),
    ] {
        let err = object(json).shape.triangles(&no_mesh).unwrap_err();
        assert!(err.to_string().contains(want), "{json}: {err}");
    }
}

/// An object's transform is scale, then rotation about X, Y, Z (degrees), then translation.
#[test]
fn transforms_scale_then_rotate_then_translate() {
    let o = object(
        r#"{"type": "plane", "size": [1, 1],
            "transform": {"scale": [2, 1, 1], "rotate": [0, 0, 90], "translate": [0, 0, 5]}}"#,
    );
    let m = o.transform.matrix();
    check_affine(&m).unwrap();
    // (1, 0, 0) → scaled (2, 0, 0) → about Z by 90° (0, 2, 0) → translated (0, 2, 5).
    let p = m.apply([1.0, 0.0, 0.0]);
    assert!(norm(sub(p, [0.0, 2.0, 5.0])) < 1e-12, "{p:?}");
    // A pure rotation keeps lengths and angles: its columns are orthonormal.
    let r = object(r#"{"type": "plane", "size": [1, 1], "transform": {"rotate": [30, 40, 50]}}"#)
        .transform
        .matrix();
    let col = |j: usize| [r.a[0][j], r.a[1][j], r.a[2][j]];
    for i in 0..3 {
        for j in 0..3 {
            let want = if i == j { 1.0 } else { 0.0 };
            assert!((dot(col(i), col(j)) - want).abs() < 1e-12, "{i} {j}");
        }
    }
    let flat = Affine {
        a: [[1.0, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, 1.0]],
        t: [0.0; 3],
    };
    assert!(check_affine(&flat)
        .unwrap_err()
        .to_string()
        .contains("degenerate"));
}

/// A z-up mesh is turned to y-up ((x, y, z) ↦ (x, z, −y)); `fit` scales its largest extent
/// to the given size and stands it on y = 0, centred in x and z.
#[test]
fn meshes_are_oriented_then_fitted() {
    let mut tris: Vec<Tri> = vec![[[0.0, 1.0, 2.0], [4.0, 1.0, 2.0], [0.0, 3.0, 3.0]]];
    orient_mesh(&mut tris, UpAxis::Z, None, None).unwrap();
    assert!(
        norm(sub(tris[0][0], [0.0, 2.0, -1.0])) < 1e-15,
        "{:?}",
        tris[0][0]
    );
    orient_mesh(&mut tris, UpAxis::Y, None, Some(2.0)).unwrap();
    let (lo, hi) = super::bounds(&tris);
    assert_eq!(lo[1], 0.0);
    assert!((hi[0] - lo[0] - 2.0).abs() < 1e-12, "{lo:?} {hi:?}");
    assert!((lo[0] + hi[0]).abs() < 1e-12 && (lo[2] + hi[2]).abs() < 1e-12);
    assert!(orient_mesh(&mut tris, UpAxis::Y, None, Some(0.0)).is_err());
}

/// Lights: azimuth/elevation give d = (−cos el·cos az, −sin el, −cos el·sin az); a light
/// that does not shine down is refused.
#[test]
fn lights_point_down_onto_the_receivers() {
    let l: LightDesc = "90,30".parse().unwrap();
    let d = l.direction("l").unwrap();
    let want = [0.0, -0.5, -(3f64.sqrt()) / 2.0];
    assert!(norm(sub(d, want)) < 1e-12, "{d:?}");
    let up: LightDesc = "0,1,0".parse().unwrap();
    assert!(up
        .direction("l")
        .unwrap_err()
        .to_string()
        .contains("upward"));
    assert!("1,2,3,4".parse::<LightDesc>().is_err());
    let low: LightDesc = "0,0.5".parse().unwrap();
    assert!(low.direction("l").is_err(), "elevation below the minimum");
}

/// A whole scene file: objects placed by their transforms, lights named light0, light1, …
#[test]
fn a_scene_file_builds_its_objects_and_lights() {
    let json = r#"{"name": "s", "lights": [{"dir": [0, -1, 0]}, {"azimuth_deg": 0,
        "elevation_deg": 45, "camera": {"dir": [0, -1, -1]}}],
        "objects": [{"type": "plane", "size": [4, 4]},
                    {"type": "box", "size": [1, 1, 1], "transform": {"translate": [0, 2, 0]}}]}"#;
    let s = Scene::from_json(json, &no_mesh).unwrap();
    assert_eq!(s.triangles.len(), 2 + 12);
    let names: Vec<&str> = s.lights.iter().map(|l| l.name.as_str()).collect();
    assert_eq!(names, ["light0", "light1"]);
    assert!((norm(s.lights[1].camera.unwrap()) - 1.0).abs() < 1e-15);
    let top = s
        .triangles
        .iter()
        .flatten()
        .map(|v| v[1])
        .fold(0.0, f64::max);
    assert_eq!(top, 3.0);
    let far = json.replace("[0, 2, 0]", "[0, 2e9, 0]");
    assert!(
        Scene::from_json(&far, &no_mesh).is_err(),
        "beyond MAX_COORD"
    );
}
