//! Checkpoints and resume of the long commands (docs/files.md, "Interrupted runs"): each command
//! killed at seeded random points — by SIGKILL, or by SIGINT/SIGTERM — and rerun ends with the
//! artefacts of an uninterrupted run, byte for byte or, where a field records time, field for
//! field; an interrupt exits 130 with one line and leaves a state the rerun continues from.

use super::common::{bin, tmp};
use rand::{Rng, SeedableRng};
use serde_json::Value;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// Fields that record time (or a rate over time): compared by presence only.
const TIME_FIELDS: [&str; 5] = [
    "seconds",
    "cpu_seconds",
    "shade_seconds",
    "solves_per_second",
    "fragments_per_second",
];

/// `momentlab args` in folder `dir` (outputs under `dir/out`), progress off.
fn command(dir: &Path, args: &[&str]) -> Command {
    let mut c = Command::new(bin());
    c.args(args)
        .args(["--out", "out"])
        .current_dir(dir)
        .env("MOMENTLAB_PROGRESS", "off")
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped());
    c
}

struct Run {
    code: Option<i32>,
    stdout: String,
    stderr: String,
}

/// Run to the end, or send `signal` after `after` (counted from the first unit kept in the
/// checkpoint `wait.1` of `wait.0/out`, when given).
fn run(
    dir: &Path,
    args: &[&str],
    stop: Option<(Duration, i32)>,
    wait: Option<(&Path, &str)>,
) -> Run {
    let mut child = command(dir, args).spawn().unwrap();
    let (mut out, mut err) = (child.stdout.take().unwrap(), child.stderr.take().unwrap());
    let o = std::thread::spawn(move || {
        let mut s = String::new();
        std::io::Read::read_to_string(&mut out, &mut s).unwrap();
        s
    });
    let e = std::thread::spawn(move || {
        let mut s = String::new();
        std::io::Read::read_to_string(&mut err, &mut s).unwrap();
        s
    });
    if let Some((after, sig)) = stop {
        if let Some((d, name)) = wait {
            while units(d, name) == 0 && child.try_wait().unwrap().is_none() {
                std::thread::sleep(Duration::from_millis(2));
            }
        }
        let t0 = Instant::now();
        while t0.elapsed() < after {
            if child.try_wait().unwrap().is_some() {
                break;
            }
            std::thread::sleep(Duration::from_millis(5));
        }
        // SAFETY: a plain kill(2) of our own child (it may have exited: then ESRCH or a zombie).
        unsafe { libc::kill(child.id() as i32, sig) };
    }
    let status = child.wait().unwrap();
    Run {
        code: status.code(),
        stdout: o.join().unwrap(),
        stderr: e.join().unwrap(),
    }
}

/// Every file under `root`, by relative path.
fn files(root: &Path) -> BTreeMap<String, PathBuf> {
    fn walk(d: &Path, root: &Path, out: &mut BTreeMap<String, PathBuf>) {
        for e in std::fs::read_dir(d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                walk(&p, root, out);
            } else {
                let rel = p.strip_prefix(root).unwrap().to_string_lossy().into_owned();
                out.insert(rel, p);
            }
        }
    }
    let mut out = BTreeMap::new();
    if root.exists() {
        walk(root, root, &mut out);
    }
    out
}

/// JSON with every time field replaced by a marker (kept where present).
fn mask(mut v: Value) -> Value {
    match &mut v {
        Value::Object(m) => {
            for (k, x) in m.iter_mut() {
                *x = if TIME_FIELDS.contains(&k.as_str()) {
                    Value::String("time".into())
                } else {
                    mask(x.take())
                };
            }
        }
        Value::Array(a) => {
            for x in a.iter_mut() {
                *x = mask(x.take());
            }
        }
        _ => {}
    }
    v
}

/// Text with the run time of a Markdown summary ("… in 3 s;") masked.
fn mask_text(s: &str) -> String {
    let mut out = String::new();
    let mut rest = s;
    while let Some(i) = rest.find(" in ") {
        let after = &rest[i + 4..];
        let digits = after.bytes().take_while(|b| b.is_ascii_digit()).count();
        out.push_str(&rest[..i + 4]);
        if digits > 0 && after[digits..].starts_with(" s") {
            out.push('N');
            rest = &after[digits..];
        } else {
            rest = after;
        }
    }
    out.push_str(rest);
    out
}

/// The artefacts of `a` and `b` are equal: the same files, each byte for byte, JSON field for
/// field but for the time fields, Markdown but for its run time.
fn assert_same(a: &Path, b: &Path, what: &str) {
    let (fa, fb) = (files(a), files(b));
    assert_eq!(
        fa.keys().collect::<Vec<_>>(),
        fb.keys().collect::<Vec<_>>(),
        "{what}: other files"
    );
    for (name, pa) in &fa {
        let (x, y) = (
            std::fs::read(pa).unwrap(),
            std::fs::read(&fb[name]).unwrap(),
        );
        if x == y {
            continue;
        }
        if name.ends_with(".json") {
            let (vx, vy): (Value, Value) = (
                serde_json::from_slice(&x).unwrap(),
                serde_json::from_slice(&y).unwrap(),
            );
            assert_eq!(mask(vx), mask(vy), "{what}: {name} differs");
        } else if name.ends_with(".md") {
            let (tx, ty) = (String::from_utf8(x).unwrap(), String::from_utf8(y).unwrap());
            assert_eq!(mask_text(&tx), mask_text(&ty), "{what}: {name} differs");
        } else {
            panic!("{what}: {name} differs");
        }
    }
}

/// Units in the checkpoint `name` of `dir/out`.
fn units(dir: &Path, name: &str) -> usize {
    std::fs::read_dir(dir.join("out/checkpoint").join(name).join("units"))
        .map(|d| {
            d.filter(|e| {
                e.as_ref()
                    .is_ok_and(|e| e.path().extension().is_some_and(|x| x == "json"))
            })
            .count()
        })
        .unwrap_or(0)
}

/// An interrupted run's stderr: exit 130, its last line the interrupt, no other error line.
fn assert_interrupted(r: &Run, command: &str, what: &str) {
    assert_eq!(r.code, Some(130), "{what}: {}", r.stderr);
    let last = r.stderr.lines().last().unwrap_or("");
    assert!(
        last.starts_with(&format!("error: {command}: interrupted by SIG"))
            && last.ends_with("the same command resumes from them"),
        "{what}: {}",
        r.stderr
    );
    assert_eq!(
        r.stderr.lines().filter(|l| l.contains("error")).count(),
        1,
        "{what}: {}",
        r.stderr
    );
}

/// Kill `args` at 5 seeded random points (SIGKILL, SIGINT or SIGTERM; some reruns killed
/// again), rerun until it completes, and compare with an uninterrupted run: the artefacts in
/// `out/` and, where `stdout_json`, the JSON on stdout. A rerun that finds units prints the
/// resume line and takes them from the checkpoint.
fn kill_and_resume(command: &str, checkpoint: &str, args: &[&str], stdout_json: bool, seed: u64) {
    let mut argv = vec![command];
    argv.extend_from_slice(args);
    let root = tmp(&format!("resume-{command}"));
    let reference = root.join("reference");
    std::fs::create_dir_all(&reference).unwrap();
    let t0 = Instant::now();
    let r = run(&reference, &argv, None, None);
    let full = t0.elapsed();
    assert_eq!(r.code, Some(0), "{command}: {}", r.stderr);
    assert!(
        !reference.join("out/checkpoint").exists(),
        "{command}: checkpoint left after a complete run"
    );
    let ref_json: Option<Value> = stdout_json.then(|| serde_json::from_str(&r.stdout).unwrap());
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let mut resumed_with_units = 0;
    for point in 0..5 {
        let dir = root.join(format!("kill{point}"));
        std::fs::create_dir_all(&dir).unwrap();
        let sig = [libc::SIGKILL, libc::SIGINT, libc::SIGTERM][point % 3];
        let mut kills: usize = if point % 2 == 1 { 2 } else { 1 };
        let mut last: Option<Run> = None;
        for attempt in 0..10 {
            assert!(attempt < 9, "{command}: no run completed");
            let stop = (kills > 0).then(|| {
                let at = full.mul_f64(rng.gen_range(0.05..0.95));
                (at, sig)
            });
            // The first point waits for a kept unit instead (then a random 0–50 ms), so that
            // one rerun resumes whatever the machine's load does to the timing.
            let stop = match stop {
                Some((_, sig)) if point == 0 => {
                    Some((Duration::from_millis(rng.gen_range(0..50)), sig))
                }
                s => s,
            };
            let after_unit = point == 0 && attempt == 0;
            kills = kills.saturating_sub(1);
            let had = units(&dir, checkpoint);
            let what = format!("{command} point {point} run {attempt}");
            let r = run(&dir, &argv, stop, after_unit.then_some((&dir, checkpoint)));
            if stop.is_none() || r.code == Some(0) {
                assert_eq!(r.code, Some(0), "{what}: {}", r.stderr);
                if had > 0 {
                    resumed_with_units += 1;
                    assert!(
                        r.stderr.contains(&format!(
                            "{command}: resuming the interrupted run in out/checkpoint/{checkpoint}: {had} "
                        )),
                        "{what}: {}",
                        r.stderr
                    );
                }
                last = Some(r);
                break;
            }
            if sig != libc::SIGKILL {
                assert_interrupted(&r, command, &what);
                // An interrupt stops between two writes: no temporary file of the writer.
                for f in files(&dir.join("out")).keys() {
                    assert!(!f.ends_with(".tmp"), "{what}: {f} left behind");
                }
            }
            // Stopped after its last output, while or after its checkpoint was removed (run.json
            // goes first): the run is complete, and a rerun would refuse to replace its outputs.
            let outputs = |d: &Path| -> Vec<String> {
                files(&d.join("out"))
                    .into_keys()
                    .filter(|f| !f.starts_with("checkpoint/"))
                    .collect()
            };
            let run_json = dir.join("out/checkpoint").join(checkpoint).join("run.json");
            if !run_json.exists() && outputs(&dir) == outputs(&reference) {
                let _ = std::fs::remove_dir_all(dir.join("out/checkpoint"));
                break;
            }
        }
        assert!(
            !dir.join("out/checkpoint").exists(),
            "{command} point {point}: checkpoint left after the run completed"
        );
        assert_same(
            &reference.join("out"),
            &dir.join("out"),
            &format!("{command} point {point}"),
        );
        if let (Some(want), Some(last)) = (&ref_json, &last) {
            let got: Value = serde_json::from_str(&last.stdout).unwrap();
            assert_eq!(
                mask(got),
                mask(want.clone()),
                "{command} point {point}: stdout"
            );
        }
    }
    // The points are spread over the run: some kill after units were kept.
    assert!(
        resumed_with_units > 0,
        "{command}: no rerun found completed units (the runs were too short to interrupt)"
    );
    let _ = std::fs::remove_dir_all(&root);
}

#[test]
fn theta_resumes_after_kills() {
    kill_and_resume(
        "theta",
        "theta4",
        &["--m", "4", "--restarts", "24"],
        false,
        56,
    );
}

#[test]
fn stability_resumes_after_kills() {
    kill_and_resume(
        "stability",
        "stability",
        &[
            "--inputs",
            "800",
            "--technique",
            "vsm,hamburger4,hamburger6",
        ],
        false,
        57,
    );
}

#[test]
fn evaluate_resumes_after_kills() {
    kill_and_resume(
        "evaluate",
        "evaluate",
        &[
            "--technique",
            "vsm,hamburger4",
            "--resolution",
            "32",
            "--eye-resolution",
            "16",
            "--json",
        ],
        true,
        58,
    );
}

#[test]
fn quantize_resumes_after_kills() {
    let theta = Path::new(env!("CARGO_MANIFEST_DIR")).join("reports/theta");
    kill_and_resume(
        "quantize",
        "quantize",
        &[
            "--resolution",
            "32",
            "--technique",
            "vsm,hamburger4,hamburger6",
            "--alphas",
            "1e-4,1e-3",
            "--theta-dir",
            theta.to_str().unwrap(),
        ],
        false,
        59,
    );
}

#[test]
fn tune_resumes_after_kills() {
    kill_and_resume(
        "tune",
        "tune",
        &[
            "--resolution",
            "32",
            "--technique",
            "vsm,hamburger4",
            "--storages",
            "f32,unorm16",
            "--fragments",
            "512",
            "--screen",
            "128",
            "--json",
        ],
        true,
        60,
    );
}

/// SIGINT once the first starts are kept: exit 130 and exactly one stderr line; the checkpoint
/// holds whole units only; the same command then reuses them (it says how many) and ends with
/// the artefacts of an uninterrupted run. A changed command does not take the stale state.
#[test]
fn sigint_leaves_a_state_that_resumes() {
    let root = tmp("resume-sigint");
    let args = ["theta", "--m", "4", "--restarts", "48"];
    let dir = root.join("interrupted");
    std::fs::create_dir_all(&dir).unwrap();
    let mut child = command(&dir, &args).spawn().unwrap();
    let t0 = Instant::now();
    while units(&dir, "theta4") < 2 {
        assert!(
            t0.elapsed() < Duration::from_secs(120),
            "no unit kept in 120 s"
        );
        assert!(child.try_wait().unwrap().is_none(), "theta ended early");
        std::thread::sleep(Duration::from_millis(5));
    }
    // SAFETY: kill(2) of our own running child.
    assert_eq!(unsafe { libc::kill(child.id() as i32, libc::SIGINT) }, 0);
    let out = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(130), "{err}");
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(
        err.starts_with("error: theta: interrupted by SIGINT; files written so far are whole, the same command resumes from them"),
        "{err}"
    );
    let kept = units(&dir, "theta4");
    assert!(kept >= 2);
    assert!(dir.join("out/checkpoint/theta4/run.json").is_file());
    for f in files(&dir.join("out")).keys() {
        assert!(!f.ends_with(".tmp"), "{f} left behind");
    }
    assert!(
        !dir.join("out/theta4.json").exists(),
        "an interrupted search wrote its result"
    );
    // Another seed: refused, naming the parameter, and the state is left as it was.
    let other = run(
        &dir,
        &["theta", "--m", "4", "--restarts", "48", "--seed", "2"],
        None,
        None,
    );
    assert_eq!(other.code, Some(1), "{}", other.stderr);
    assert!(
        other.stderr.contains("other parameters (seed)") && other.stderr.contains("--force"),
        "{}",
        other.stderr
    );
    assert_eq!(units(&dir, "theta4"), kept);
    // The same command resumes: it reports the kept starts and ends as an uninterrupted run.
    let r = run(&dir, &args, None, None);
    assert_eq!(r.code, Some(0), "{}", r.stderr);
    assert!(
        r.stderr.contains(&format!(
            "theta: resuming the interrupted run in out/checkpoint/theta4: {kept} of 48 starts done"
        )),
        "{}",
        r.stderr
    );
    let reference = root.join("reference");
    std::fs::create_dir_all(&reference).unwrap();
    let r = run(&reference, &args, None, None);
    assert_eq!(r.code, Some(0), "{}", r.stderr);
    assert_same(
        &reference.join("out"),
        &dir.join("out"),
        "theta after SIGINT",
    );
    let _ = std::fs::remove_dir_all(&root);
}
