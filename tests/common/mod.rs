//! Helpers shared by the test binaries; each `tests/<group>/main.rs` declares this module
//! with `#[path = "../common/mod.rs"]`. Here: scratch folders and running the `momentlab`
//! binary. The submodules hold fixtures: [`geom`] (3-vectors), [`kernel`] (in-memory depth stacks and a brute-force
//! kernel/evaluation loop), [`lp`] (checking an LP's support), [`search`] (function tables),
//! [`technique`] (a configurable test technique) and [`shader`] (the shader compile check).
#![allow(dead_code)]

pub mod geom;
pub mod gpu;
pub mod kernel;
pub mod lp;
pub mod search;
pub mod shader;
pub mod technique;

use std::io::{Read, Write};
use std::path::PathBuf;
use std::process::{Command, Stdio};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::{Duration, Instant};

/// A path under the system temp folder that no other call of this process returns (the test
/// binaries run many tests in one process): `momentlab-<pid>-<k>-<name>`, with nothing there.
pub fn tmp_path(name: &str) -> PathBuf {
    static N: AtomicUsize = AtomicUsize::new(0);
    let k = N.fetch_add(1, Ordering::Relaxed);
    let d = std::env::temp_dir().join(format!("momentlab-{}-{k}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    let _ = std::fs::remove_file(&d);
    d
}

/// A fresh, empty folder (see [`tmp_path`]).
pub fn tmp(name: &str) -> PathBuf {
    let d = tmp_path(name);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// The `momentlab` binary built for these tests.
pub fn bin() -> &'static str {
    env!("CARGO_BIN_EXE_momentlab")
}

/// A command running the `momentlab` binary.
pub fn momentlab() -> Command {
    Command::new(bin())
}

/// Runs `momentlab args` with `stdin` (none: no input) and progress reporting off; returns
/// (exit code, stdout, stderr), −1 for a run ended by a signal.
pub fn run(args: &[&str], stdin: Option<&str>) -> (i32, String, String) {
    let mut cmd = momentlab();
    cmd.args(args).env("MOMENTLAB_PROGRESS", "off");
    let (code, out, err) = run_limited(&mut cmd, stdin, None);
    (code.unwrap_or(-1), out, err)
}

/// Runs `cmd` with `stdin` (none: no input), reading stdout and stderr as it runs; with a
/// `limit`, a run still going after it is killed and the test fails. Returns (exit code, None
/// when ended by a signal; stdout; stderr). The program may exit (e.g. on a bad argument)
/// before reading its input: a broken pipe is expected then, and the exit status tells the
/// rest.
pub fn run_limited(
    cmd: &mut Command,
    stdin: Option<&str>,
    limit: Option<Duration>,
) -> (Option<i32>, String, String) {
    let mut child = cmd
        .stdin(if stdin.is_some() {
            Stdio::piped()
        } else {
            Stdio::null()
        })
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let writer = stdin.map(|text| {
        let mut w = child.stdin.take().unwrap();
        let text = text.to_string();
        std::thread::spawn(move || {
            let _ = w.write_all(text.as_bytes());
        })
    });
    let read_all = |mut r: Box<dyn Read + Send>| {
        std::thread::spawn(move || {
            let mut s = String::new();
            let _ = r.read_to_string(&mut s);
            s
        })
    };
    let t_out = read_all(Box::new(child.stdout.take().unwrap()));
    let t_err = read_all(Box::new(child.stderr.take().unwrap()));
    let start = Instant::now();
    let status = loop {
        if let Some(s) = child.try_wait().unwrap() {
            break s;
        }
        if let Some(limit) = limit.filter(|&l| start.elapsed() > l) {
            let _ = child.kill();
            let _ = child.wait();
            panic!("{cmd:?}: still running after {limit:?} (killed)");
        }
        std::thread::sleep(Duration::from_millis(10));
    };
    if let Some(w) = writer {
        w.join().unwrap();
    }
    (status.code(), t_out.join().unwrap(), t_err.join().unwrap())
}

/// A mesh loader for scenes that must not load any mesh file.
pub fn no_mesh(p: &str) -> anyhow::Result<Vec<u8>> {
    anyhow::bail!("no mesh {p}")
}

/// Decodes an RGB PNG: (width, height, RGB bytes).
pub fn decode_png(path: &std::path::Path) -> (usize, usize, Vec<u8>) {
    let dec = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(path).unwrap()));
    let mut reader = dec.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    assert_eq!(info.color_type, png::ColorType::Rgb);
    buf.truncate(info.buffer_size());
    (info.width as usize, info.height as usize, buf)
}

/// The bit patterns of per-layer depths, for bit-exact comparisons.
pub fn bits(v: &[Vec<f32>]) -> Vec<Vec<u32>> {
    v.iter()
        .map(|l| l.iter().map(|x| x.to_bits()).collect())
        .collect()
}
