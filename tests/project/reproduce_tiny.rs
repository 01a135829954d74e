//! `momentlab reproduce --tiny` end to end: every artefact exists and parses, the report links
//! only to files that exist, numbers are finite, and the report's numbers equal those of
//! `momentlab evaluate` on the same stacks.

use crate::common::{bin, tmp_path};
use std::path::{Path, PathBuf};
use std::process::Command;

fn walk(dir: &Path, out: &mut Vec<PathBuf>) {
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() {
            walk(&p, out);
        } else {
            out.push(p);
        }
    }
}

fn all_numbers_finite(v: &serde_json::Value, path: &str, nulls: &mut Vec<String>) {
    match v {
        serde_json::Value::Number(n) => assert!(n.as_f64().unwrap().is_finite(), "{path}"),
        serde_json::Value::Null => nulls.push(path.to_string()),
        serde_json::Value::Array(a) => a
            .iter()
            .enumerate()
            .for_each(|(i, x)| all_numbers_finite(x, &format!("{path}[{i}]"), nulls)),
        serde_json::Value::Object(o) => o
            .iter()
            .for_each(|(k, x)| all_numbers_finite(x, &format!("{path}.{k}"), nulls)),
        _ => {}
    }
}

#[test]
fn tiny_reproduce_writes_a_complete_consistent_report() {
    let root = tmp_path("reproduce");
    // The default places (relative to the working directory), spelled out for the first run.
    let reports = root.join("results/reports");
    let results = root.join("results");
    let reproduce = || {
        let mut c = Command::new(bin());
        c.args(["reproduce", "--tiny", "--run", "t"])
            .arg("--out")
            .arg(&reports)
            .arg("--results")
            .arg(&results)
            .env("CI", "1");
        c
    };
    // A run killed once it has marked its folder: the same command resumes it (its own
    // unfinished run), without --force.
    let mut killed = reproduce()
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    let mark = reports.join("t/.momentlab-run.json");
    while !mark.exists() && killed.try_wait().unwrap().is_none() {
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    killed.kill().ok();
    assert!(
        !killed.wait().unwrap().success(),
        "the first run was not interrupted"
    );
    let out = reproduce().output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "reproduce failed:\n{stderr}");
    let run = reports.join("t");

    // The HTML and Markdown reports reference only files that exist, and figures are there.
    let html = std::fs::read_to_string(run.join("index.html")).unwrap();
    let refs = momentlab::report::document::html_references(&html);
    assert!(refs.iter().any(|r| r.ends_with("speed_accuracy.svg")));
    assert!(refs.iter().any(|r| r.ends_with(".png")));
    for r in &refs {
        assert!(run.join(r).is_file(), "index.html references missing {r}");
    }
    let md = std::fs::read_to_string(run.join("report.md")).unwrap();
    for part in md.split("](").skip(1) {
        let target = &part[..part.find(')').unwrap()];
        assert!(
            run.join(target).is_file(),
            "report.md references missing {target}"
        );
    }

    // Every artefact parses: JSON (numbers finite), PNG decodes, SVG is a complete document.
    let mut files = Vec::new();
    walk(&run, &mut files);
    let (mut json, mut png, mut svg) = (0, 0, 0);
    for f in &files {
        match f.extension().and_then(|e| e.to_str()) {
            Some("json") => {
                let text = std::fs::read_to_string(f).unwrap();
                let v: serde_json::Value =
                    serde_json::from_str(&text).unwrap_or_else(|e| panic!("{}: {e}", f.display()));
                let mut nulls = Vec::new();
                all_numbers_finite(&v, &f.display().to_string(), &mut nulls);
                json += 1;
            }
            Some("png") => {
                let dec =
                    png::Decoder::new(std::io::BufReader::new(std::fs::File::open(f).unwrap()));
                let mut reader = dec.read_info().unwrap();
                let mut buf = vec![0; reader.output_buffer_size().unwrap()];
                let info = reader.next_frame(&mut buf).unwrap();
                assert!(info.width > 0 && info.height > 0);
                png += 1;
            }
            Some("svg") => {
                let s = std::fs::read_to_string(f).unwrap();
                assert!(
                    s.trim_start().starts_with("<svg") && s.trim_end().ends_with("</svg>"),
                    "{}",
                    f.display()
                );
                svg += 1;
            }
            _ => {}
        }
    }
    assert!(
        json >= 20 && png >= 1 && svg >= 3,
        "json {json}, png {png}, svg {svg}"
    );

    // The evaluated errors are finite and the report's numbers equal `momentlab evaluate`.
    let h4: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(run.join("evaluate/hamburger4_f64.json")).unwrap(),
    )
    .unwrap();
    let err = h4["error"].as_f64().unwrap();
    assert!(err.is_finite() && (0.0..1.0).contains(&err));
    let ev = Command::new(bin())
        .args([
            "evaluate",
            "--technique",
            "hamburger4",
            "--json",
            "--stacks",
        ])
        .arg(results.join("t/stacks"))
        .output()
        .unwrap();
    assert!(
        ev.status.success(),
        "{}",
        String::from_utf8_lossy(&ev.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&ev.stdout).unwrap();
    let e2 = v["error"].as_f64().unwrap();
    assert!((err - e2).abs() < 1e-12, "reproduce {err} vs evaluate {e2}");
    assert!(html.contains(&format!("{:.3} %", 100.0 * err)));

    // The finished run is not resumed: the same run again, with the default folders, is refused
    // before any work (one line naming a file, --force to replace) and changes nothing; by
    // default nothing goes to the tracked reports/ folder.
    assert!(
        !run.join(".momentlab-run.json").exists(),
        "finished run still marked"
    );
    let index = std::fs::read(run.join("index.html")).unwrap();
    let again = Command::new(bin())
        .args(["reproduce", "--tiny", "--run", "t"])
        .current_dir(&root)
        .env("CI", "1")
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&again.stderr);
    assert_eq!(again.status.code(), Some(1), "{err}");
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(
        err.contains("exists already") && err.contains("--force"),
        "{err}"
    );
    assert!(
        !root.join("reports").exists(),
        "reproduce wrote to reports/"
    );
    assert_eq!(std::fs::read(run.join("index.html")).unwrap(), index);
    let h4b = std::fs::read_to_string(run.join("evaluate/hamburger4_f64.json")).unwrap();
    assert_eq!(serde_json::from_str::<serde_json::Value>(&h4b).unwrap(), h4);
    std::fs::remove_dir_all(&root).ok();
}

#[test]
fn bad_arguments_are_one_line_errors() {
    for args in [
        vec!["reproduce", "--run", "../x"],
        vec!["reproduce", "--tolerance=-1"],
        vec!["reproduce", "--tiny", "--resolution", "4"],
    ] {
        let out = Command::new(bin()).args(&args).output().unwrap();
        assert!(!out.status.success(), "{args:?}");
        let e = String::from_utf8_lossy(&out.stderr);
        assert_eq!(e.trim().lines().count(), 1, "{args:?}: {e}");
    }
}

/// A link where the run's folder goes (`<out>/<run>` or `<results>/<run>`) is refused before
/// anything is written, never followed out of --out or --results.
#[test]
fn a_linked_run_folder_is_refused() {
    let root = std::env::temp_dir().join(format!("momentlab-runlink-{}", std::process::id()));
    std::fs::remove_dir_all(&root).ok();
    for linked in ["out", "results"] {
        let (out, results, outside) =
            (root.join("out"), root.join("results"), root.join("outside"));
        for d in [&out, &results, &outside] {
            std::fs::create_dir_all(d).unwrap();
        }
        std::os::unix::fs::symlink(&outside, root.join(linked).join("default")).unwrap();
        let o = Command::new(bin())
            .args(["reproduce", "--tiny", "--skip-search", "--out"])
            .arg(&out)
            .arg("--results")
            .arg(&results)
            .output()
            .unwrap();
        let e = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{linked}: {e}");
        assert!(
            e.contains("symbolic link") && e.trim().lines().count() == 1,
            "{e}"
        );
        assert_eq!(
            std::fs::read_dir(&outside).unwrap().count(),
            0,
            "{linked}: wrote outside"
        );
        std::fs::remove_dir_all(&root).unwrap();
    }
}

/// Without an adapter (`MOMENTLAB_GPU_ADAPTER=none`, which fails like a machine with no GPU,
/// driver or Vulkan loader, on any machine) `reproduce` says in one line that it skipped the
/// GPU step, still succeeds, writes no GPU artefacts, and its report says the step was skipped.
#[test]
fn without_an_adapter_reproduce_skips_the_gpu_step() {
    let root = tmp_path("reproduce-no-adapter");
    let out = Command::new(bin())
        .args(["reproduce", "--tiny", "--skip-search", "--run", "n"])
        .arg("--out")
        .arg(root.join("r"))
        .arg("--results")
        .arg(root.join("d"))
        .env("CI", "1")
        .env("MOMENTLAB_GPU_ADAPTER", "none")
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "reproduce failed:\n{stderr}");
    let gpu_lines: Vec<&str> = stderr
        .lines()
        .filter(|l| l.contains("GPU") && !l.starts_with('['))
        .collect();
    assert_eq!(gpu_lines.len(), 1, "{gpu_lines:?}");
    assert!(
        gpu_lines[0].contains("GPU step skipped: no GPU adapter"),
        "{}",
        gpu_lines[0]
    );
    let run = root.join("r/n");
    let gpu_dir = run.join("gpu");
    let written: Vec<_> = std::fs::read_dir(&gpu_dir)
        .map(|d| d.map(|e| e.unwrap().file_name()).collect())
        .unwrap_or_default();
    assert!(
        written.is_empty(),
        "GPU artefacts without a GPU: {written:?}"
    );
    let md = std::fs::read_to_string(run.join("report.md")).unwrap();
    let section = md
        .split("## On a GPU")
        .nth(1)
        .expect("the report has a GPU section");
    assert!(
        section.contains("The GPU step was skipped: no GPU adapter"),
        "{}",
        &section[..section.len().min(400)]
    );
    let html = std::fs::read_to_string(run.join("index.html")).unwrap();
    assert!(html.contains("The GPU step was skipped"));
    std::fs::remove_dir_all(&root).ok();
}
