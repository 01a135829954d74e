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

mod files;
mod per_command;
mod scenes;
mod shards;
mod streams;

fn args(a: &[&str]) -> Vec<String> {
    a.iter().map(|s| s.to_string()).collect()
}

/// One bad-input case: (arguments, stdin, expected exit code, expected part of the one-line
/// error).
type Case<'a> = (Vec<String>, Option<String>, i32, &'a str);

/// The fixtures and paths the cases name.
struct Ctx {
    f: Fixtures,
    out_x: String,
    out_q: String,
    theta_dir: String,
    big: &'static str,
    shadow_huge: String,
    shadow_nan: String,
}

impl Ctx {
    fn new() -> Ctx {
        let f = Fixtures::new();
        Ctx {
            out_x: f.p("x"),
            out_q: f.p("q"),
            theta_dir: format!("{}/reports/theta", env!("CARGO_MANIFEST_DIR")),
            big: "18446744073709551615",
            shadow_huge: shadow_batch("[1e308, 0.3, 0.2, 0.1]", "0.5"),
            shadow_nan: shadow_batch("[0.5, 0.3, 0.2]", "0.5"),
            f,
        }
    }
}

/// Run every case: each must exit with its code and print exactly one stderr line holding its
/// text; none may panic (101) or abort (134).
fn check(cases: Vec<Case>) {
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
}

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
