//! The bad-input corpus: hostile and edge inputs to every command, each with its expected
//! one-line error and exit code (2: usage error found by the argument parser, 1: any other
//! error). Every run is killed after 10 s (a runaway is a failure, not a slow pass); no run may
//! panic (101) or abort (134), and stderr must be exactly one line.

use crate::common::{bin, run_limited, tmp, tmp_path};
use momentlab::stack::{DepthStack, StackMeta};
use std::io::{Read, Write};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::Duration;

/// Run with a hard 10 s limit; returns (exit code, stdout, stderr). Killed runs fail the test.
fn run(args: &[&str], stdin: Option<&str>) -> (i32, String, String) {
    let mut cmd = Command::new(bin());
    cmd.args(args).env("CI", "1");
    let (code, out, err) = run_limited(&mut cmd, stdin, Some(Duration::from_secs(10)));
    let code = code.unwrap_or_else(|| panic!("{args:?}: killed by a signal"));
    (code, out, err)
}

fn meta(width: usize, layers: usize) -> StackMeta {
    serde_json::from_value(serde_json::json!({
        "scene": "s", "view": "v", "light_dir": [0.0, 0.0, -1.0], "near": 1.0, "far": 2.0,
        "width": width, "height": width, "layers": layers,
    }))
    .unwrap()
}

/// A valid stack; `empty`: every texel without a surface (0 fragments).
fn stack(empty: bool) -> DepthStack {
    let n = 16 * 16;
    let depth: Vec<f32> = (0..n)
        .map(|t| {
            if empty {
                f32::INFINITY
            } else {
                0.2 + 0.5 * (t % 7) as f32 / 7.0
            }
        })
        .collect();
    DepthStack {
        meta: meta(16, 1),
        depth: vec![depth],
        dzdu: vec![vec![0.0; n]],
        dzdv: vec![vec![0.0; n]],
    }
}

/// A stack written with a lossy compression (PXR24: f32 → f24).
fn write_pxr24(path: &Path) {
    use exr::prelude::*;
    let n = 16 * 16;
    let ch = |name: &str, v: f32| {
        AnyChannel::new(
            Text::new_or_none(name).unwrap(),
            FlatSamples::F32(vec![v; n]),
        )
    };
    let list: SmallVec<[AnyChannel<FlatSamples>; 4]> = SmallVec::from_vec(vec![
        ch("layer000.Z", 0.5),
        ch("layer000.dzdu", 0.0),
        ch("layer000.dzdv", 0.0),
    ]);
    let enc = Encoding {
        compression: Compression::PXR24,
        blocks: Blocks::ScanLines,
        line_order: LineOrder::Increasing,
    };
    let layer = Layer::new(
        (16, 16),
        LayerAttributes::default(),
        enc,
        AnyChannels::sort(list),
    );
    Image::from_layer(layer).write().to_file(path).unwrap();
    std::fs::write(
        path.with_extension("json"),
        serde_json::to_string(&meta(16, 1)).unwrap(),
    )
    .unwrap();
}

struct Fixtures {
    root: PathBuf,
}

impl Fixtures {
    fn new() -> Fixtures {
        let root = tmp_path("bad");
        for d in ["empty", "a", "b", "huge", "lossy", "wide"] {
            std::fs::create_dir_all(root.join(d)).unwrap();
        }
        momentlab::stack::write(&root.join("empty/v.exr"), &stack(true)).unwrap();
        momentlab::stack::write(&root.join("a/v.exr"), &stack(false)).unwrap();
        momentlab::stack::write(&root.join("b/v.exr"), &stack(false)).unwrap();
        // Sidecars whose sizes would allocate petabytes.
        momentlab::stack::write(&root.join("huge/v.exr"), &stack(false)).unwrap();
        let mut m = serde_json::to_value(meta(16, 1)).unwrap();
        m["layers"] = serde_json::json!(1_000_000_000_000_000u64);
        std::fs::write(root.join("huge/v.json"), m.to_string()).unwrap();
        momentlab::stack::write(&root.join("wide/v.exr"), &stack(false)).unwrap();
        let mut m = serde_json::to_value(meta(16, 1)).unwrap();
        m["width"] = serde_json::json!(100_000_000u64);
        m["height"] = serde_json::json!(100_000_000u64);
        std::fs::write(root.join("wide/v.json"), m.to_string()).unwrap();
        write_pxr24(&root.join("lossy/v.exr"));
        Fixtures { root }
    }
    fn p(&self, rel: &str) -> String {
        self.root.join(rel).display().to_string()
    }
}

impl Drop for Fixtures {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.root);
    }
}

const LP_OK: &str = r#"{"basis": ["z", "z^2"], "problems": [{"moments": [0.5, 0.3], "zf": 0.6}]}"#;

fn shadow_batch(moments: &str, zf: &str) -> String {
    format!(r#"{{"technique": "hamburger4", "problems": [{{"moments": {moments}, "zf": {zf}}}]}}"#)
}

#[test]
fn bad_inputs_are_one_line_errors_with_their_exit_code() {
    let f = Fixtures::new();
    let out_x = f.p("x");
    let out_q = f.p("q");
    let theta_dir = format!("{}/reports/theta", env!("CARGO_MANIFEST_DIR"));
    let big = "18446744073709551615";
    let shadow_huge = shadow_batch("[1e308, 0.3, 0.2, 0.1]", "0.5");
    let shadow_nan = shadow_batch("[0.5, 0.3, 0.2]", "0.5");
    // (arguments, stdin, expected exit code, expected part of the one-line error)
    let cases: Vec<(Vec<String>, Option<String>, i32, &str)> = vec![
        // Sizes that used to panic (capacity overflow) or run away (allocation failure).
        (
            args(&["candidates", "list", "--grid", big]),
            None,
            2,
            "--grid",
        ),
        (
            args(&["candidates", "list", "--grid", "100000000"]),
            None,
            2,
            "not in 2..=1048576",
        ),
        (args(&["stability", "--grid", big]), None, 2, "--grid"),
        (
            args(&["stability", "--grid", "100000000"]),
            None,
            2,
            "not in 2..=65536",
        ),
        (args(&["stability", "--inputs", "0"]), None, 2, "--inputs"),
        // Flags the command would have ignored, and checks that used to wait for the dataset.
        (
            args(&["bench", "lp", "--corpus", "adversarial", "--n", "64"]),
            None,
            1,
            "--n does not apply to --corpus adversarial",
        ),
        (
            args(&["bench", "lp", "--corpus", "moments", "--large"]),
            None,
            1,
            "--large does not apply to --corpus moments",
        ),
        (
            args(&["bench", "lp", "--basis", "z,z^2", "--m", "3"]),
            None,
            1,
            "--basis and --m both choose the functions",
        ),
        (
            args(&["search", "--synthetic", "100", "--max-fragments", "10"]),
            None,
            2,
            "--max-fragments",
        ),
        (args(&["search", "--plan", "--json"]), None, 2, "--json"),
        (
            args(&["search", "--solver", "foo"]),
            None,
            1,
            "--solver: unknown LP solver 'foo'",
        ),
        (
            args(&[
                "search",
                "--report-only",
                "--compare",
                "/nonexistent-momentlab",
            ]),
            None,
            1,
            "--compare /nonexistent-momentlab",
        ),
        (
            args(&["stability", "--inputs", "5", "--technique", "vsm,hamburgr4"]),
            None,
            1,
            "--technique hamburgr4",
        ),
        (
            args(&["shadow"]),
            Some(
                r#"{"technique": "vsm", "esm_c": 5, "problems": [{"moments": [0.5, 0.3], "zf": 0.5}]}"#
                    .to_string(),
            ),
            1,
            "\"esm_c\" does not apply to vsm",
        ),
        (
            args(&["theta", "--summary", "/nonexistent-momentlab-summary"]),
            None,
            1,
            "--summary /nonexistent-momentlab-summary: no such folder",
        ),
        // A bias beyond the depth range made every output non-finite (scored as 0 % error).
        (
            args(&[
                "evaluate",
                "--technique",
                "hamburger4",
                "--technique-epsilon",
                "1e300",
            ]),
            None,
            1,
            "technique_epsilon must be in [0, 1], got 1e300",
        ),
        (
            args(&["evaluate", "--technique", "vsm", "--slope-scale", "1e9"]),
            None,
            1,
            "slope_scale must be in [0, 1000]",
        ),
        (args(&["search", "--grid", "1e11"]), None, 2, "--grid"),
        (
            args(&["search", "--grid", "100000000000"]),
            None,
            2,
            "--grid",
        ),
        (
            args(&["bench", "shadow", "--inputs", "1e12"]),
            None,
            2,
            "--inputs",
        ),
        (
            args(&["bench", "shadow", "--inputs", "1000000000000"]),
            None,
            2,
            "not in 1..=10000000",
        ),
        (
            args(&["bench", "shadow", "--repeats", "0"]),
            None,
            2,
            "--repeats",
        ),
        (
            args(&["import", &f.p("huge/v.exr")]),
            None,
            1,
            "layers = 1000000000000000",
        ),
        (
            args(&["import", &f.p("wide/v.exr")]),
            None,
            1,
            "width and height",
        ),
        // Silent data loss: two inputs with one file name.
        (
            args(&["import", &f.p("a/v.exr"), &f.p("b/v.exr"), "--out", &out_x]),
            None,
            1,
            "would both be written",
        ),
        // Silently wrong: empty inputs, out-of-range z_f and moments, lossy EXR.
        (
            args(&["evaluate", "--technique", "vsm", "--stacks", &f.p("empty")]),
            None,
            1,
            "0 fragments",
        ),
        (
            args(&["recommend", "--stacks", &f.p("empty"), "--fragments", "10"]),
            None,
            1,
            "0 fragments",
        ),
        (
            args(&[
                "quantize",
                "--stacks",
                &f.p("empty"),
                "--theta-dir",
                &theta_dir,
                "--technique",
                "vsm",
                "--out",
                &out_q,
            ]),
            None,
            1,
            "0 fragments",
        ),
        (
            args(&["shadow"]),
            Some(shadow_huge),
            1,
            "moment 1 = 1e308 is outside",
        ),
        (
            args(&["shadow"]),
            Some(shadow_nan),
            1,
            "needs 4 moments, got 3",
        ),
        (args(&["shadow"]), Some(String::new()), 1, "malformed JSON"),
        (
            args(&["lp"]),
            Some(r#"{"basis": ["z"], "problems": [{"moments": [0.5], "zf": 7}]}"#.into()),
            1,
            "outside [0,1]",
        ),
        (
            args(&["lp", "-"]),
            Some("{".into()),
            1,
            "malformed input JSON",
        ),
        (
            args(&["lp"]),
            Some(r#"{"basis": ["z"], "grid": {"points": 100000000000}, "problems": []}"#.into()),
            1,
            "more than the supported",
        ),
        (
            args(&["lp", &f.p("missing.json")]),
            None,
            1,
            "missing.json: no such file",
        ),
        (
            args(&["import", &f.p("lossy/v.exr")]),
            None,
            1,
            "PXR24 is lossy",
        ),
        (
            args(&["bench", "lp", "--repeats", "0"]),
            None,
            2,
            "--repeats",
        ),
        (args(&["bench", "lp", "--n", "1"]), None, 2, "--n"),
        (
            args(&["recommend", "--technique", "lp:z,z^2"]),
            None,
            1,
            "unknown 'lp:z'",
        ),
        (
            args(&["recommend", "--technique", "nope", "--stacks", &f.p("a")]),
            None,
            1,
            "'nope'",
        ),
        // Negative numbers without '=' reach the range check.
        (
            args(&["evaluate", "--technique", "vsm", "--pcf-epsilon", "-1"]),
            None,
            2,
            "-1 is negative",
        ),
        (
            args(&["recommend", "--tolerance", "-1"]),
            None,
            2,
            "-1 is negative",
        ),
        (
            args(&["reproduce", "--tolerance", "-1"]),
            None,
            2,
            "-1 is negative",
        ),
        (args(&["search", "--lp-budget", "x"]), None, 2, "--lp-budget"),
        (args(&["search", "--growth", "1"]), None, 2, "--growth"),
        // Rejected before any rendering.
        (args(&["search", "--m", "0"]), None, 2, "--m"),
        (args(&["search", "--m", "9"]), None, 2, "--m"),
        (
            args(&["evaluate", "--technique", "vsm", "--stride", "0"]),
            None,
            2,
            "--stride",
        ),
        (
            args(&["evaluate", "--technique", "vsm", "--sample", "0"]),
            None,
            2,
            "not in (0, 1]",
        ),
        (
            args(&["evaluate", "--technique", "nope", "--stacks", &f.p("a")]),
            None,
            1,
            "nope",
        ),
        (
            args(&["evaluate", "--technique", "vsm", "--resolution", "100000"]),
            None,
            2,
            "--resolution",
        ),
        (
            args(&["render", "--resolution", "0"]),
            None,
            2,
            "--resolution",
        ),
        (
            args(&["render", "--resolution", "100000"]),
            None,
            2,
            "--resolution",
        ),
        (args(&["reproduce", "--run", "../x"]), None, 1, "--run"),
        (
            args(&["reproduce", "--tiny", "--resolution", "4"]),
            None,
            2,
            "--resolution",
        ),
        (
            args(&["candidates", "index", "99999999"]),
            None,
            1,
            "99999999",
        ),
        (args(&["candidates", "count", "--m", "0"]), None, 2, "--m"),
        (args(&["candidates", "subset", "z,nope"]), None, 1, "nope"),
        (args(&["import", "-"]), None, 1, "stdin"),
        (
            args(&["import", &f.p("nothing.exr")]),
            None,
            1,
            "no such file",
        ),
        (
            args(&["merge", &f.p("nothing"), "--out", &out_x]),
            None,
            1,
            "nothing",
        ),
        (args(&["evaluate"]), None, 2, "--technique"),
        (args(&["frobnicate"]), None, 2, "frobnicate"),
        (args(&["lp", "--frobnicate"]), None, 2, "--frobnicate"),
    ];
    let mut failures = Vec::new();
    for (a, stdin, code, want) in &cases {
        let refs: Vec<&str> = a.iter().map(String::as_str).collect();
        let (got, _, err) = run(&refs, stdin.as_deref());
        let lines: Vec<&str> = err.lines().collect();
        let ok = got == *code && lines.len() == 1 && err.contains(want);
        if !ok {
            failures.push(format!(
                "{a:?}: exit {got} (want {code}), stderr {err:?} (want one line with {want:?})"
            ));
        }
        assert!(got != 101 && got != 134, "{a:?}: panic/abort: {err}");
    }
    assert!(
        failures.is_empty(),
        "{} of {} cases:\n{}",
        failures.len(),
        cases.len(),
        failures.join("\n")
    );
    // Nothing was written by the refused import.
    assert!(!Path::new(&out_x).join("v.exr").exists());
}

fn args(a: &[&str]) -> Vec<String> {
    a.iter().map(|s| s.to_string()).collect()
}

/// Closing stdout early (`| head -c 10`) ends the command quietly with exit 0.
#[test]
fn broken_pipe_ends_quietly() {
    let problems: Vec<String> = (0..3000)
        .map(|k| {
            format!(
                r#"{{"moments": [0.5, 0.3], "zf": {}}}"#,
                (k % 100) as f64 / 100.0
            )
        })
        .collect();
    let batch = format!(
        r#"{{"basis": ["z", "z^2"], "problems": [{}]}}"#,
        problems.join(",")
    );
    for (a, stdin) in [
        (vec!["lp", "-"], Some(batch)),
        (vec!["candidates", "list"], None),
    ] {
        let mut child = Command::new(bin())
            .args(&a)
            .env("MOMENTLAB_PROGRESS", "off")
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        let mut w = child.stdin.take().unwrap();
        std::thread::spawn(move || {
            if let Some(s) = stdin {
                let _ = w.write_all(s.as_bytes());
            }
        });
        let mut out = child.stdout.take().unwrap();
        let mut head = [0u8; 10];
        out.read_exact(&mut head).unwrap();
        drop(out);
        let mut err = String::new();
        child
            .stderr
            .take()
            .unwrap()
            .read_to_string(&mut err)
            .unwrap();
        let status = child.wait().unwrap();
        assert_eq!(status.code(), Some(0), "{a:?}: {err}");
        assert!(err.is_empty(), "{a:?}: {err}");
    }
}

/// `-` is stdin for FILE arguments.
#[test]
fn dash_is_stdin() {
    for a in [vec!["lp", "-"], vec!["lp"]] {
        let (code, out, err) = run(&a, Some(LP_OK));
        assert_eq!(code, 0, "{a:?}: {err}");
        let v: serde_json::Value = serde_json::from_str(&out).unwrap();
        assert_eq!(v["results"][0]["status"], "optimal", "{a:?}");
    }
}

// ---------------------------------------------------------------------------------------------
// Writes confined and refused, merges verified, sizes bounded, meaning validated.

/// A scratch folder (removed on drop) holding an `in/` and an `out/` area.
struct Scratch(PathBuf);

impl Scratch {
    fn new(tag: &str) -> Scratch {
        Scratch(tmp(&format!("w-{tag}")))
    }
    fn path(&self, rel: &str) -> PathBuf {
        self.0.join(rel)
    }
    fn p(&self, rel: &str) -> String {
        self.path(rel).display().to_string()
    }
    fn write(&self, rel: &str, text: &str) -> String {
        let p = self.path(rel);
        std::fs::create_dir_all(p.parent().unwrap()).unwrap();
        std::fs::write(&p, text).unwrap();
        p.display().to_string()
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// Every file under `d` (relative path → bytes), for "nothing changed" checks.
fn snapshot(d: &Path) -> std::collections::BTreeMap<String, Vec<u8>> {
    let mut out = std::collections::BTreeMap::new();
    let mut todo = vec![d.to_path_buf()];
    while let Some(x) = todo.pop() {
        let Ok(rd) = std::fs::read_dir(&x) else {
            continue;
        };
        for e in rd {
            let p = e.unwrap().path();
            let m = std::fs::symlink_metadata(&p).unwrap();
            let rel = p.strip_prefix(d).unwrap().display().to_string();
            if m.is_dir() {
                todo.push(p);
            } else if m.file_type().is_symlink() {
                let t = std::fs::read_link(&p).unwrap();
                out.insert(rel, format!("-> {}", t.display()).into_bytes());
            } else {
                out.insert(rel, std::fs::read(&p).unwrap());
            }
        }
    }
    out
}

/// Run with extra environment variables and an optional stdout file.
fn run_env(args: &[&str], env: &[(&str, &str)], stdout: Option<std::fs::File>) -> (i32, String) {
    let mut c = Command::new(bin());
    c.args(args)
        .env("CI", "1")
        .env("MOMENTLAB_PROGRESS", "off")
        .stdin(Stdio::null());
    for (k, v) in env {
        c.env(k, v);
    }
    match stdout {
        Some(f) => c.stdout(Stdio::from(f)),
        None => c.stdout(Stdio::null()),
    };
    let out = c.stderr(Stdio::piped()).output().unwrap();
    let code = out
        .status
        .code()
        .unwrap_or_else(|| panic!("{args:?}: killed by a signal"));
    (code, String::from_utf8_lossy(&out.stderr).into_owned())
}

/// Assert exit `code` and exactly one stderr line containing every `want`.
fn expect(args: &[&str], code: i32, want: &[&str]) -> String {
    let (got, _, err) = run(args, None);
    assert!(got != 101 && got != 134, "{args:?}: panic/abort: {err}");
    assert_eq!(got, code, "{args:?}: {err}");
    assert_eq!(err.lines().count(), 1, "{args:?}: not one line: {err:?}");
    for w in want {
        assert!(err.contains(w), "{args:?}: {err:?} lacks {w:?}");
    }
    err
}

fn scene(name: &str, lights: &str, object: &str) -> String {
    format!(r#"{{"name": "{name}", "lights": [{lights}], "objects": [{object}]}}"#)
}

const PLANE: &str = r#"{"type": "plane", "size": [1, 1]}"#;
const LIGHT: &str = r#"{"dir": [0, -1, 0.2]}"#;

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

#[test]
fn inputs_are_bounded_regular_files_and_names_are_plain() {
    let s = Scratch::new("inputs");
    // lp: 100 functions is a one-line error, not a panic in the dense kernels.
    let basis: Vec<String> = (1..=100).map(|k| format!("\"z^{k}\"")).collect();
    let moments: Vec<String> = (1..=100)
        .map(|k| format!("{}", 1.0 / (k + 1) as f64))
        .collect();
    let batch = format!(
        r#"{{"basis": [{}], "problems": [{{"moments": [{}], "zf": 0.5}}]}}"#,
        basis.join(","),
        moments.join(",")
    );
    let f = s.write("lp100.json", &batch);
    expect(&["lp", &f], 1, &["100 functions", "limit of 31"]);
    // ESM with a moment below e^{80·0} = 1: no distribution has it (was G = 1).
    let f = s.write(
        "esm.json",
        r#"{"technique": "esm", "problems": [{"moments": [0.5], "zf": 0.5}]}"#,
    );
    expect(
        &["shadow", &f],
        1,
        &["moment 1 = 5e-1 is outside the range"],
    );
    // Non-regular files: a FIFO (must not block), a directory, a link to /dev/zero.
    let fifo = s.path("pipe.json");
    let c = std::ffi::CString::new(fifo.to_str().unwrap()).unwrap();
    assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0);
    expect(
        &["lp", fifo.to_str().unwrap()],
        1,
        &["pipe.json: is a FIFO"],
    );
    expect(
        &["shadow", &s.p("")],
        1,
        &["is a directory, not a regular file"],
    );
    let zero = s.path("zero.json");
    std::os::unix::fs::symlink("/dev/zero", &zero).unwrap();
    expect(
        &[
            "candidates",
            "count",
            "--m",
            "2",
            "--catalog",
            zero.to_str().unwrap(),
        ],
        1,
        &["zero.json: is a character device"],
    );
    expect(
        &["lp", "--catalog", zero.to_str().unwrap(), &s.p("esm.json")],
        1,
        &["is a character device"],
    );
    // A depth stack or mesh that is a link to a device is named as such, never "no such file".
    let zexr = s.path("zero.exr");
    std::os::unix::fs::symlink("/dev/zero", &zexr).unwrap();
    expect(
        &["import", zexr.to_str().unwrap()],
        1,
        &["zero.exr: is a character device, not a regular file"],
    );
    let zdir = s.path("zstacks");
    std::fs::create_dir_all(&zdir).unwrap();
    std::os::unix::fs::symlink("/dev/zero", zdir.join("v.exr")).unwrap();
    expect(
        &[
            "evaluate",
            "--technique",
            "vsm",
            "--stacks",
            zdir.to_str().unwrap(),
        ],
        1,
        &["v.exr: is a character device, not a regular file"],
    );
    let zobj = s.path("zero.obj");
    std::os::unix::fs::symlink("/dev/zero", &zobj).unwrap();
    expect(
        &[
            "render",
            "--scenes",
            zobj.to_str().unwrap(),
            "--out",
            &s.p("zr"),
        ],
        1,
        &["zero.obj: is a character device, not a regular file"],
    );
    // Catalog names with a comma or a newline.
    for (tag, name, want) in [
        ("comma", "a,b", "contains a comma"),
        ("newline", "a\\nb", "control character"),
        ("semicolon", "a;b", "contains a semicolon"),
    ] {
        let cat = s.write(
            &format!("cat-{tag}.json"),
            &format!(r#"{{"functions": [{{"name": "{name}", "formula": "z"}}, {{"name": "y", "formula": "z^2"}}]}}"#),
        );
        expect(
            &["candidates", "count", "--m", "1", "--catalog", &cat],
            1,
            &[want],
        );
    }
}

#[test]
fn stacks_are_checked_for_meaning_and_never_rewritten_in_place() {
    let f = Fixtures::new();
    let s = Scratch::new("stacks");
    // A sidecar with an unknown field: refused (a copy would silently drop it).
    momentlab::stack::write(&s.path("extra/v.exr"), &stack(false)).unwrap();
    let mut m = serde_json::to_value(meta(16, 1)).unwrap();
    m["exposure"] = serde_json::json!(2.0);
    std::fs::write(s.path("extra/v.json"), m.to_string()).unwrap();
    expect(
        &["import", &s.p("extra/v.exr"), "--out", &s.p("o1")],
        1,
        &["unknown field `exposure`"],
    );
    // Two channels for one layer's Z (layer0.Z and layer000.Z).
    {
        use exr::prelude::*;
        let n = 16 * 16;
        let ch = |name: &str| {
            AnyChannel::new(
                Text::new_or_none(name).unwrap(),
                FlatSamples::F32(vec![0.5; n]),
            )
        };
        let list: SmallVec<[AnyChannel<FlatSamples>; 4]> = SmallVec::from_vec(vec![
            ch("layer0.Z"),
            ch("layer000.Z"),
            ch("layer000.dzdu"),
            ch("layer000.dzdv"),
        ]);
        let enc = Encoding {
            compression: Compression::ZIP16,
            blocks: Blocks::ScanLines,
            line_order: LineOrder::Increasing,
        };
        let layer = Layer::new(
            (16, 16),
            LayerAttributes::default(),
            enc,
            AnyChannels::sort(list),
        );
        Image::from_layer(layer)
            .write()
            .to_file(s.path("twice.exr"))
            .unwrap();
        std::fs::write(
            s.path("twice.json"),
            serde_json::to_string(&meta(16, 1)).unwrap(),
        )
        .unwrap();
    }
    expect(
        &["import", &s.p("twice.exr")],
        1,
        &["'layer0.Z'", "'layer000.Z'", "one channel per layer"],
    );
    // `import X --out X` must not rewrite its own input, with or without --force.
    let before = snapshot(&f.root.join("a"));
    for force in [false, true] {
        let mut a = args(&["import", &f.p("a/v.exr"), "--out", &f.p("a")]);
        if force {
            a.push("--force".into());
        }
        let refs: Vec<&str> = a.iter().map(String::as_str).collect();
        expect(&refs, 1, &["rewritten in place"]);
    }
    assert_eq!(snapshot(&f.root.join("a")), before);
    assert!(!s.path("o1").exists());
}

/// A small exhaustive synthetic sweep (m = 1, 64 grid points) into the results folder `results`.
fn tiny_sweep(results: &str) -> Vec<String> {
    args(&[
        "search",
        "--synthetic",
        "40",
        "--m",
        "1",
        "--exhaustive",
        "--grid",
        "64",
        "--no-closed-forms",
        "--fig3-points",
        "8",
        "--results",
        results,
    ])
}

/// Every writing subcommand, pointed at a folder that holds a file it would write: refused
/// (one line, exit 1) before its work, the file untouched, nothing else written there.
#[test]
fn writing_commands_refuse_existing_files_without_force() {
    let f = Fixtures::new();
    let s = Scratch::new("force");
    let theta_dir = format!("{}/reports/theta", env!("CARGO_MANIFEST_DIR"));
    let a = f.p("a");
    let cases: Vec<(&str, Vec<String>)> = vec![
        (
            "render/thin_light0.json",
            args(&[
                "render",
                "--only",
                "thin",
                "--resolution",
                "16",
                "--out",
                &s.p("render"),
            ]),
        ),
        (
            "import/v.exr",
            args(&["import", &f.p("a/v.exr"), "--out", &s.p("import")]),
        ),
        (
            "pictures/s_v_vsm.png",
            args(&[
                "evaluate",
                "--technique",
                "vsm",
                "--stacks",
                &a,
                "--pictures",
                &s.p("pictures"),
            ]),
        ),
        (
            "merge/results.jsonl",
            args(&["merge", &a, "--out", &s.p("merge")]),
        ),
        (
            "theta/theta2.hlsl",
            args(&[
                "theta",
                "--moments",
                "2",
                "--restarts",
                "1",
                "--out",
                &s.p("theta"),
            ]),
        ),
        (
            "summary/summary.json",
            args(&["theta", "--summary", &s.p("summary")]),
        ),
        (
            "quantize/quantize_alpha.svg",
            args(&[
                "quantize",
                "--stacks",
                &a,
                "--theta-dir",
                &theta_dir,
                "--techniques",
                "vsm",
                "--out",
                &s.p("quantize"),
            ]),
        ),
        (
            "stability/heatmap_u16.svg",
            args(&["stability", "--samples", "5", "--out", &s.p("stability")]),
        ),
        // The sweep's report: a chart, and the Markdown of `--report-only` on finished rows.
        (
            "sweep-report/fig4_m1.svg",
            [
                tiny_sweep(&s.p("sweep")),
                args(&["--out", &s.p("sweep-report")]),
            ]
            .concat(),
        ),
        (
            "report-only/search_m1.md",
            [
                tiny_sweep(&s.p("finished")),
                args(&["--report-only", "--out", &s.p("report-only")]),
            ]
            .concat(),
        ),
        (
            "reproduce/r/index.html",
            args(&[
                "reproduce",
                "--tiny",
                "--run",
                "r",
                "--out",
                &s.p("reproduce"),
                "--results",
                &s.p("reproduce-data"),
            ]),
        ),
    ];
    // Finished rows for `--report-only`.
    let (code, _, err) = run(
        &[tiny_sweep(&s.p("finished")), args(&["--no-report"])]
            .concat()
            .iter()
            .map(String::as_str)
            .collect::<Vec<_>>(),
        None,
    );
    assert_eq!(code, 0, "{err}");
    for (file, a) in &cases {
        s.write(file, "precious\n");
        let dir = s.path(file).parent().unwrap().to_path_buf();
        let before = snapshot(&dir);
        let refs: Vec<&str> = a.iter().map(String::as_str).collect();
        expect(&refs, 1, &["exists already", "--force"]);
        assert_eq!(snapshot(&dir), before, "{a:?} changed {}", dir.display());
    }
    // A dangling link where an output goes: refused, and with --force replaced, never followed.
    let victim = s.path("outside/victim.exr");
    std::fs::create_dir_all(s.path("outside")).unwrap();
    std::fs::create_dir_all(s.path("linked")).unwrap();
    std::os::unix::fs::symlink(&victim, s.path("linked/thin_light0.exr")).unwrap();
    let render = ["render", "--only", "thin", "--resolution", "16", "--out"];
    let mut r: Vec<&str> = render.to_vec();
    let linked = s.p("linked");
    r.push(&linked);
    expect(&r, 1, &["thin_light0.exr exists already"]);
    r.push("--force");
    let (code, _, err) = run(&r, None);
    assert_eq!(code, 0, "{err}");
    assert!(!victim.exists(), "the link was followed out of --out");
    assert_eq!(
        momentlab::stack::load_dir(&s.path("linked")).unwrap().len(),
        4
    );
    // The sweep never created its results folder; with --force its report replaces the chart.
    assert!(!s.path("sweep").exists());
    let mut forced = [
        tiny_sweep(&s.p("sweep")),
        args(&["--out", &s.p("sweep-report")]),
    ]
    .concat();
    forced.push("--force".into());
    let (code, _, err) = run(&forced.iter().map(String::as_str).collect::<Vec<_>>(), None);
    assert_eq!(code, 0, "{err}");
    let svg = std::fs::read_to_string(s.path("sweep-report/fig4_m1.svg")).unwrap();
    assert!(svg.starts_with("<svg") && svg.contains("Candidate errors, m = 1"));
    assert!(s.path("sweep-report/search_m1.md").exists());
    // --force replaces a stale file.
    let (code, _, err) = run(
        &[
            "render",
            "--only",
            "thin",
            "--resolution",
            "16",
            "--out",
            &s.p("render"),
            "--force",
        ],
        None,
    );
    assert_eq!(code, 0, "{err}");
    assert_eq!(
        momentlab::stack::load_dir(&s.path("render")).unwrap().len(),
        4
    );
}

/// stdout on a full device: one line, exit 1 (a closed pipe stays quiet: broken_pipe_ends_quietly).
#[test]
fn stdout_write_errors_are_one_line_errors() {
    let f = Fixtures::new();
    let s = Scratch::new("full");
    let full = || {
        std::fs::OpenOptions::new()
            .write(true)
            .open("/dev/full")
            .unwrap()
    };
    let lp = s.write("lp.json", LP_OK);
    let cmds: Vec<Vec<String>> = vec![
        args(&["import", &f.p("a/v.exr")]),
        args(&["evaluate", "--technique", "vsm", "--stacks", &f.p("a")]),
        args(&[
            "render",
            "--only",
            "thin",
            "--resolution",
            "16",
            "--out",
            &s.p("r"),
        ]),
        args(&["stability", "--samples", "5", "--out", &s.p("st"), "--json"]),
        args(&["lp", &lp]),
        args(&["candidates", "count", "--m", "2"]),
    ];
    for a in &cmds {
        let refs: Vec<&str> = a.iter().map(String::as_str).collect();
        let (code, err) = run_env(&refs, &[], Some(full()));
        assert_eq!(code, 1, "{a:?}: {err}");
        assert_eq!(err.lines().count(), 1, "{a:?}: {err:?}");
        assert!(
            err.contains("stdout") && err.contains("No space left"),
            "{a:?}: {err}"
        );
    }
}

/// An error after progress output is the last line of stderr, and the only error line: with
/// progress lines due all the time, `evaluate > /dev/full` shows progress, then the error.
#[test]
fn an_error_after_progress_is_the_last_line() {
    for mode in ["lines", "bar"] {
        let full = std::fs::OpenOptions::new()
            .write(true)
            .open("/dev/full")
            .unwrap();
        let (code, err) = run_env(
            &["evaluate", "--technique", "vsm", "--resolution", "24"],
            &[
                ("MOMENTLAB_PROGRESS", mode),
                ("MOMENTLAB_PROGRESS_INTERVAL", "0"),
            ],
            Some(full),
        );
        assert_eq!(code, 1, "{err}");
        let lines: Vec<&str> = err.lines().collect();
        if mode == "lines" {
            assert!(
                lines.iter().any(|l| l.starts_with("evaluate vsm: ")),
                "no progress shown: {err:?}"
            );
        }
        let last = lines.last().unwrap();
        assert!(
            last.starts_with("error: writing stdout") && last.contains("No space left"),
            "{mode}: the last line is not the error: {err:?}"
        );
        assert_eq!(
            lines.iter().filter(|l| l.contains("error")).count(),
            1,
            "{mode}: {err:?}"
        );
        assert!(!err.contains('\r'), "{mode}: {err:?}");
    }
}

/// Thread requests beyond the CPUs are clamped; the note never precedes an error line.
#[test]
fn thread_requests_are_clamped_and_quiet_on_errors() {
    for var in ["SLURM_CPUS_PER_TASK", "RAYON_NUM_THREADS"] {
        let (code, err) = run_env(&["candidates", "subset", "z,nope"], &[(var, "20000")], None);
        assert_eq!(code, 1, "{err}");
        assert_eq!(err.lines().count(), 1, "{var}: {err:?}");
        let (code, err) = run_env(
            &["candidates", "count", "--m", "2"],
            &[(var, "20000")],
            None,
        );
        assert_eq!(code, 0, "{err}");
        assert!(
            err.contains(var) && err.contains("20000") && err.contains("used"),
            "{var}: {err:?}"
        );
    }
}

/// A sharded synthetic sweep (small and fast): `search --shard i/2` into `dir`.
fn shard(dir: &str, i: usize, seed: &str) -> (i32, String) {
    let sh = format!("{i}/2");
    let (code, _, err) = run(
        &[
            "search",
            "--synthetic",
            "40",
            "--m",
            "1",
            "--exhaustive",
            "--no-report",
            "--grid",
            "64",
            "--seed",
            seed,
            "--shard",
            &sh,
            "--results",
            dir,
        ],
        None,
    );
    (code, err)
}

fn rows_of(dir: &Path) -> Vec<String> {
    std::fs::read_to_string(dir.join("results.jsonl"))
        .unwrap()
        .lines()
        .map(str::to_string)
        .collect()
}

fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for e in std::fs::read_dir(from).unwrap() {
        let p = e.unwrap().path();
        if p.is_file() {
            std::fs::copy(&p, to.join(p.file_name().unwrap())).unwrap();
        }
    }
}

#[test]
fn merges_and_reports_verify_their_shards() {
    let s = Scratch::new("merge");
    for i in 0..2 {
        let (code, err) = shard(&s.p(&format!("s{i}")), i, "1");
        assert_eq!(code, 0, "{err}");
    }
    let (code, err) = shard(&s.p("foreign1"), 1, "2");
    assert_eq!(code, 0, "{err}");
    let (s0, s1) = (s.p("s0"), s.p("s1"));
    // The good merge, for reference.
    let (code, _, err) = run(&["merge", &s0, &s1, "--out", &s.p("good")], None);
    assert_eq!(code, 0, "{err}");
    let n = rows_of(&s.path("good")).len();
    assert_eq!(
        n,
        rows_of(&s.path("s0")).len() + rows_of(&s.path("s1")).len()
    );
    // Broken copies of shard 0.
    let variant = |tag: &str, edit: &dyn Fn(&Path)| -> String {
        let d = s.path(tag);
        copy_dir(&s.path("s0"), &d);
        edit(&d);
        d.display().to_string()
    };
    let torn = variant("torn", &|d| {
        let mut f = std::fs::OpenOptions::new()
            .append(true)
            .open(d.join("results.jsonl"))
            .unwrap();
        f.write_all(br#"{"index": 99, "functions": ["#).unwrap();
    });
    let empty = variant("empty", &|d| {
        std::fs::remove_file(d.join("results.jsonl")).unwrap()
    });
    let dup = variant("dup", &|d| {
        let rows = rows_of(d);
        let mut f = std::fs::OpenOptions::new()
            .append(true)
            .open(d.join("results.jsonl"))
            .unwrap();
        writeln!(f, "{}", rows[0]).unwrap();
    });
    let lost = variant("lost", &|d| {
        let rows = rows_of(d);
        std::fs::write(d.join("results.jsonl"), rows[1..].join("\n") + "\n").unwrap();
    });
    let unfinished = variant("unfinished", &|d| {
        std::fs::remove_file(d.join("complete.json")).unwrap()
    });
    let foreign = s.p("foreign1");
    let cases: Vec<(Vec<&str>, &[&str])> = vec![
        (vec![&torn, &s1], &["torn row"]),
        (
            vec![&empty, &s1],
            &["marked complete but has no results.jsonl"],
        ),
        (vec![&dup, &s1], &["appears twice"]),
        (vec![&lost, &s1], &["rows, but complete.json says"]),
        (vec![&unfinished, &s1], &["is not complete"]),
        (vec![&s0, &foreign], &["different configuration"]),
        (vec![&s0], &["shard 1/2 is missing"]),
        (vec![&s0, &s0], &["given twice"]),
    ];
    for (i, (dirs, want)) in cases.iter().enumerate() {
        let out = s.p(&format!("m{i}"));
        let mut a = vec!["merge"];
        a.extend(dirs.iter().copied());
        a.extend(["--out", &out]);
        expect(&a, 1, want);
        assert!(!Path::new(&out).exists(), "{a:?} wrote {out}");
    }
    // --report-only refuses the same things, and a single shard presented as the whole run.
    let report = |dir: &str| {
        vec![
            "search",
            "--synthetic",
            "40",
            "--m",
            "1",
            "--exhaustive",
            "--grid",
            "64",
            "--seed",
            "1",
            "--report-only",
            "--results",
            dir.to_string().leak(),
            "--report",
            s.p("rep").leak(),
        ]
    };
    expect(&report(&s0), 1, &["shard 0/2 of a sharded run", "merge"]);
    let merged_dup = variant("merged-dup", &|d| {
        std::fs::remove_dir_all(d).unwrap();
        copy_dir(&s.path("good"), d);
        let rows = rows_of(d);
        let mut f = std::fs::OpenOptions::new()
            .append(true)
            .open(d.join("results.jsonl"))
            .unwrap();
        writeln!(f, "{}", rows[0]).unwrap();
    });
    expect(&report(&merged_dup), 1, &["appears twice"]);
    expect(&report(&torn), 1, &["torn row"]);
    assert!(!s.path("rep").exists());
}

#[test]
fn a_second_writer_on_one_results_folder_fails_cleanly() {
    let s = Scratch::new("lock");
    // Deterministic: the folder is held (the lock the sweep takes), the second writer fails.
    let d = s.path("held");
    std::fs::create_dir_all(&d).unwrap();
    let lock = std::fs::OpenOptions::new()
        .create(true)
        .truncate(false)
        .write(true)
        .open(d.join(".momentlab.lock"))
        .unwrap();
    lock.try_lock().unwrap();
    let held = d.display().to_string();
    let (code, err) = shard(&held, 0, "1");
    assert_eq!(code, 1, "{err}");
    assert_eq!(err.lines().count(), 1, "{err:?}");
    assert!(err.contains("in use by another momentlab run"), "{err}");
    expect(
        &["merge", &s.p("nothing"), "--out", &held],
        1,
        &["in use", "another momentlab run"],
    );
    assert!(!d.join("results.jsonl").exists() && !d.join("config.json").exists());
    drop(lock);
    // Two concurrent runs into one folder: each either completes or is refused cleanly, and
    // the rows are there once each.
    let dir = s.p("both");
    let spawn = || {
        let dir = dir.clone();
        std::thread::spawn(move || shard(&dir, 0, "1"))
    };
    let (a, b) = (spawn(), spawn());
    let outcomes = [a.join().unwrap(), b.join().unwrap()];
    for (code, err) in &outcomes {
        assert!(
            *code == 0 || (*code == 1 && err.contains("in use by another momentlab run")),
            "{code}: {err}"
        );
        if *code == 1 {
            assert_eq!(err.lines().count(), 1, "{err:?}");
        }
    }
    assert!(outcomes.iter().any(|(c, _)| *c == 0));
    let rows = rows_of(&s.path("both"));
    let mut idx: Vec<u64> = rows
        .iter()
        .map(|r| {
            serde_json::from_str::<serde_json::Value>(r).unwrap()["index"]
                .as_u64()
                .unwrap()
        })
        .collect();
    let n = idx.len();
    idx.sort();
    idx.dedup();
    assert_eq!(idx.len(), n, "rows written twice");
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(s.path("both/complete.json")).unwrap())
            .unwrap();
    assert_eq!(summary["candidates"].as_u64().unwrap() as usize, n);
}

/// Checks that used to run after the expensive work now come first (each case would render
/// the default dataset or run a θ search before failing; the 10 s limit of `run` catches it).
#[test]
fn checks_come_before_the_work() {
    let s = Scratch::new("early");
    let file = s.write("file", "x");
    expect(
        &["theta", "--moments", "4", "--out", &file],
        1,
        &["--out", "not a folder"],
    );
    expect(
        &["search", "--results", &file],
        1,
        &["--results", "not a folder"],
    );
    expect(
        &["search", "--names", "z,nope"],
        1,
        &["unknown function 'nope'"],
    );
    expect(
        &[
            "search",
            "--m",
            "2",
            "--names",
            "z,z^2",
            "--report-only",
            "--results",
            &s.p("none"),
        ],
        1,
        &["--report-only"],
    );
}

/// SIGINT or SIGTERM during a long command: exit status 130 and exactly one stderr line saying
/// so (progress output ends first), and the output folder holds no half-written file.
#[test]
fn interrupts_exit_130_with_one_line() {
    let s = Scratch::new("interrupt");
    for (sig, name, args) in [
        (
            libc::SIGINT,
            "SIGINT",
            vec![
                "theta",
                "--m",
                "4",
                "--restarts",
                "100000",
                "--out",
                "theta",
            ],
        ),
        (
            libc::SIGTERM,
            "SIGTERM",
            vec!["stability", "--samples", "200000", "--out", "stab"],
        ),
    ] {
        let mut args: Vec<String> = args.iter().map(|a| a.to_string()).collect();
        let last = args.len() - 1;
        args[last] = s.p(&args[last]);
        let child = Command::new(bin())
            .args(&args)
            .env("MOMENTLAB_PROGRESS", "lines")
            .env("MOMENTLAB_PROGRESS_INTERVAL", "0.1")
            .stdin(Stdio::null())
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        std::thread::sleep(std::time::Duration::from_millis(1500));
        assert_eq!(unsafe { libc::kill(child.id() as i32, sig) }, 0);
        let out = child.wait_with_output().unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(130), "{args:?}: {err}");
        let lines: Vec<&str> = err.lines().collect();
        let last = lines.last().unwrap();
        assert!(
            last.starts_with(&format!("error: {}: interrupted by {name}", args[0])),
            "{err}"
        );
        assert_eq!(
            lines.iter().filter(|l| l.contains("error")).count(),
            1,
            "{err}"
        );
        // Whatever was written is whole: no temporary file of the writer left behind.
        if let Ok(d) = std::fs::read_dir(&args[args.len() - 1]) {
            for e in d {
                let n = e.unwrap().file_name().to_string_lossy().into_owned();
                assert!(!n.ends_with(".tmp"), "{n} left in the output folder");
            }
        }
    }
}
