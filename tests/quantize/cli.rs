//! `momentlab theta` end to end: JSON fields, snippets, summary, and one-line errors.

use crate::common::{momentlab, tmp, tmp_path};

#[test]
fn theta2_json_and_snippets() {
    let dir = tmp_path("theta-cli");
    let out = momentlab()
        .args(["theta", "--m", "2", "--restarts", "2", "--json", "--out"])
        .arg(&dir)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    for k in [
        "m",
        "basis",
        "matrix",
        "offset",
        "inverse",
        "gain_bits",
        "max_violation",
        "seconds",
        "basin",
        "best_start",
    ] {
        assert!(v.get(k).is_some(), "missing {k}");
    }
    assert_eq!(v["m"], 2);
    assert!((v["gain_bits"].as_f64().unwrap() - 2.0).abs() < 1e-7);
    assert!(v["max_violation"].as_f64().unwrap() < 0.0);
    for f in ["theta2.hlsl", "theta2.glsl", "theta2.wgsl"] {
        let s = std::fs::read_to_string(dir.join(f)).unwrap();
        assert!(s.contains("ncodeMoments2") && s.contains("ecodeMoments2"));
    }
    assert_eq!(v["snippet_channel_order"], "paper");
    // --snippets re-emits the same snippets from the JSON alone
    let before = std::fs::read_to_string(dir.join("theta2.glsl")).unwrap();
    assert!(
        before.contains("vec2 encodeMoments2Vec(float z)"),
        "{before}"
    );
    std::fs::remove_file(dir.join("theta2.glsl")).unwrap();
    std::fs::remove_file(dir.join("theta2.hlsl")).unwrap();
    let wgsl = std::fs::read_to_string(dir.join("theta2.wgsl")).unwrap();
    std::fs::remove_file(dir.join("theta2.wgsl")).unwrap();
    let out = momentlab()
        .args(["theta", "--snippets"])
        .arg(&dir)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert_eq!(
        std::fs::read_to_string(dir.join("theta2.glsl")).unwrap(),
        before
    );
    assert!(std::fs::read_to_string(dir.join("theta2.hlsl"))
        .unwrap()
        .contains("float2 EncodeMoments2Vec(float z)"));
    assert_eq!(
        std::fs::read_to_string(dir.join("theta2.wgsl")).unwrap(),
        wgsl
    );
    assert!(
        wgsl.contains("fn encodeMoments2Vec(z: f32) -> vec2<f32>"),
        "{wgsl}"
    );
    // the JSON file is what was printed; both starts reach the single θ2 basin
    let file: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("theta2.json")).unwrap()).unwrap();
    assert_eq!(file, v);
    assert_eq!(v["basin"]["starts"].as_array().unwrap().len(), 2);
    // a second run into the same directory refuses to overwrite, before searching
    let again = momentlab()
        .args(["theta", "--m", "2", "--out"])
        .arg(&dir)
        .output()
        .unwrap();
    assert!(!again.status.success());
    let err = String::from_utf8_lossy(&again.stderr);
    assert!(err.contains("exists") && err.contains("--force"), "{err}");
    // summary over a directory with only θ2: table lists ours and the published ones
    let out = momentlab()
        .args(["theta", "--summary"])
        .arg(&dir)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let md = std::fs::read_to_string(dir.join("comparison.md")).unwrap();
    assert!(md.contains("| 2 | 2.0000000") && md.contains("30.511"));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn snippets_replace_existing_snippets_only_with_force() {
    let dir = tmp_path("theta-snippets-force");
    let out = momentlab()
        .args(["theta", "--m", "2", "--restarts", "1", "--out"])
        .arg(&dir)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    // An edited theta2.glsl and a missing theta2.hlsl: refused before any snippet is written.
    std::fs::write(dir.join("theta2.glsl"), "mine").unwrap();
    std::fs::remove_file(dir.join("theta2.hlsl")).unwrap();
    let out = momentlab()
        .args(["theta", "--snippets"])
        .arg(&dir)
        .output()
        .unwrap();
    assert!(
        !out.status.success(),
        "replaced theta2.glsl without --force"
    );
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.trim_end().lines().count() == 1
            && err.contains("theta2.glsl")
            && err.contains("exists already")
            && err.contains("--force"),
        "{err}"
    );
    assert_eq!(
        std::fs::read_to_string(dir.join("theta2.glsl")).unwrap(),
        "mine"
    );
    assert!(
        !dir.join("theta2.hlsl").exists(),
        "written before the check"
    );
    // With --force both are written.
    let out = momentlab()
        .args(["theta", "--force", "--snippets"])
        .arg(&dir)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(std::fs::read_to_string(dir.join("theta2.glsl"))
        .unwrap()
        .contains("encodeMoments2Vec"));
    assert!(dir.join("theta2.hlsl").exists());
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn default_output_is_a_run_directory_under_results() {
    let cwd = tmp("theta-cwd");
    let out = momentlab()
        .current_dir(&cwd)
        .args(["theta", "--m", "2", "--restarts", "1"])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(out.stdout.is_empty(), "JSON on stdout only with --json");
    for f in ["theta2.json", "theta2.hlsl", "theta2.glsl"] {
        assert!(cwd.join("results/theta2-seed1").join(f).exists(), "{f}");
    }
    assert!(!cwd.join("reports").exists());
    let _ = std::fs::remove_dir_all(&cwd);
}

#[test]
fn bad_input_gives_one_line_errors() {
    for args in [
        vec!["theta", "--m", "0"],
        vec!["theta", "--basis", "z,z"],
        vec!["theta", "--basis", "z,2*z"],
        vec!["theta", "--basis", "z,no_such_function(z"],
        vec!["theta", "--m", "2", "--restarts", "0"],
        vec!["theta", "--m", "2", "--restarts", "4", "--starts", "4"],
        vec!["theta", "--m", "2", "--starts", "x"],
        vec!["theta", "--m", "2", "--hop-sigma", "0"],
        vec!["theta", "--m", "2", "--max-sweeps", "0"],
        vec!["theta"],
        vec!["theta", "--snippets", "/nonexistent/momentlab"],
        vec!["theta", "--snippets", "/", "--m", "2"],
    ] {
        let out = momentlab().args(&args).output().unwrap();
        assert!(!out.status.success(), "{args:?} succeeded");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(
            err.starts_with("error: ") && err.trim_end().lines().count() == 1,
            "{args:?}: {err}"
        );
    }
}
