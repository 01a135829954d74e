//! The bad-input corpus: hostile and edge inputs to every command, each with its expected
//! one-line error and exit code (2: usage error found by the argument parser, 1: any other
//! error). Every run is killed after 10 s (a runaway is a failure, not a slow pass); no run may
//! panic (101) or abort (134), and stderr must be exactly one line.

use momentlab::stack::{DepthStack, StackMeta};
use std::io::{Read, Write};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

fn bin() -> &'static str {
    env!("CARGO_BIN_EXE_momentlab")
}

/// Run with a hard 10 s limit; returns (exit code, stdout, stderr). Killed runs fail the test.
fn run(args: &[&str], stdin: Option<&str>) -> (i32, String, String) {
    let mut child = Command::new(bin())
        .args(args)
        .env("CI", "1")
        .stdin(if stdin.is_some() {
            Stdio::piped()
        } else {
            Stdio::null()
        })
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    if let Some(text) = stdin {
        let mut w = child.stdin.take().unwrap();
        let text = text.to_string();
        std::thread::spawn(move || {
            let _ = w.write_all(text.as_bytes());
        });
    }
    let mut out = child.stdout.take().unwrap();
    let mut err = child.stderr.take().unwrap();
    let t_out = std::thread::spawn(move || {
        let mut s = String::new();
        let _ = out.read_to_string(&mut s);
        s
    });
    let t_err = std::thread::spawn(move || {
        let mut s = String::new();
        let _ = err.read_to_string(&mut s);
        s
    });
    let start = Instant::now();
    let status = loop {
        if let Some(s) = child.try_wait().unwrap() {
            break s;
        }
        if start.elapsed() > Duration::from_secs(10) {
            let _ = child.kill();
            let _ = child.wait();
            panic!("{args:?}: still running after 10 s (killed)");
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    let code = status
        .code()
        .unwrap_or_else(|| panic!("{args:?}: killed by a signal"));
    (code, t_out.join().unwrap(), t_err.join().unwrap())
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
        let root = std::env::temp_dir().join(format!("momentlab-bad-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&root);
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
        (args(&["stability", "--samples", "0"]), None, 2, "--samples"),
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
        (args(&["bench", "shadow", "--reps", "0"]), None, 2, "--reps"),
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
            args(&[
                "recommend",
                "--stacks",
                &f.p("empty"),
                "--speed-inputs",
                "10",
            ]),
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
                "--techniques",
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
            args(&["recommend", "--techniques", "lp:z,z^2"]),
            None,
            1,
            "'lp:z,z^2': recommend compares closed-form",
        ),
        (
            args(&["recommend", "--techniques", "nope", "--stacks", &f.p("a")]),
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
        (args(&["search", "--keep", "0"]), None, 2, "not in (0, 1]"),
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

/// `-` is stdin for FILE arguments, and `--json` is accepted by the JSON commands.
#[test]
fn dash_is_stdin() {
    for a in [vec!["lp", "-"], vec!["lp", "-", "--json"], vec!["lp"]] {
        let (code, out, err) = run(&a, Some(LP_OK));
        assert_eq!(code, 0, "{a:?}: {err}");
        let v: serde_json::Value = serde_json::from_str(&out).unwrap();
        assert_eq!(v["results"][0]["status"], "optimal", "{a:?}");
    }
}
