//! `momentlab gpu check` on the default scenes: the committed tune exports as shipped pass, a
//! changed constant fails with one line naming the setting and the worst texel; a machine
//! without an adapter gets one line. (Every technique × storage on the default scenes:
//! tests/gpu/pipeline.rs, through the same `gpu::study::check_setting`.)

use crate::common::gpu::gpu_or_skip;
use momentlab::shader::wgsl::literal;
use momentlab::tune::space::Setting;
use std::path::{Path, PathBuf};
use std::process::Command;

fn momentlab(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_momentlab"))
        .args(args)
        .env("XDG_RUNTIME_DIR", std::env::temp_dir())
        .output()
        .expect("run momentlab")
}

fn last_line(b: &[u8]) -> String {
    String::from_utf8_lossy(b)
        .lines()
        .last()
        .unwrap_or("")
        .to_string()
}

const EXPORTS: &str = "reports/default/tune/export";

/// The committed exports' folders, sorted.
fn export_dirs() -> Vec<PathBuf> {
    let base = Path::new(env!("CARGO_MANIFEST_DIR")).join(EXPORTS);
    let mut dirs: Vec<PathBuf> = std::fs::read_dir(&base)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.is_dir())
        .collect();
    dirs.sort();
    assert!(dirs.len() >= 2, "{}: no exports", base.display());
    dirs
}

/// The committed tune exports as shipped pass `gpu check`; the first export whose α appears as
/// a literal in its `shadow.wgsl`, with that literal multiplied by 10 in the WGSL only, fails
/// with one line naming the setting and the worst texel.
#[test]
fn committed_exports_pass_and_a_changed_constant_fails() {
    if gpu_or_skip("committed_exports_pass_and_a_changed_constant_fails").is_none() {
        return;
    }
    let dirs: Vec<String> = export_dirs()
        .iter()
        .map(|d| d.display().to_string())
        .collect();
    let mut args = vec!["gpu", "check", "--resolution", "32", "--receivers", "600"];
    for d in &dirs {
        args.extend(["--export", d.as_str()]);
    }
    let ok = momentlab(&args);
    assert!(
        ok.status.success(),
        "{}",
        String::from_utf8_lossy(&ok.stderr)
    );
    let out = String::from_utf8_lossy(&ok.stdout);
    let views = momentlab::render::default_dataset_views().unwrap().len();
    assert_eq!(
        out.lines().filter(|l| l.starts_with("ok ")).count(),
        dirs.len() * views,
        "{out}"
    );

    // α of an export changed in the shipped WGSL only
    let (src, setting, wgsl, alpha) = export_dirs()
        .into_iter()
        .find_map(|d| {
            let v: serde_json::Value =
                serde_json::from_str(&std::fs::read_to_string(d.join("setting.json")).unwrap())
                    .unwrap();
            let s: Setting = serde_json::from_value(v["setting"].clone()).unwrap();
            let wgsl = std::fs::read_to_string(d.join("shadow.wgsl")).unwrap();
            let alpha = literal(s.alpha as f32);
            wgsl.contains(&alpha).then_some((d, s, wgsl, alpha))
        })
        .expect("no export has its α as a literal in shadow.wgsl");
    let tmp = std::env::temp_dir().join(format!("momentlab-gpu-tamper-{}", std::process::id()));
    std::fs::create_dir_all(&tmp).unwrap();
    std::fs::copy(src.join("setting.json"), tmp.join("setting.json")).unwrap();
    std::fs::write(
        tmp.join("shadow.wgsl"),
        wgsl.replace(&alpha, &literal((10.0 * setting.alpha) as f32)),
    )
    .unwrap();
    let t = tmp.display().to_string();
    let bad = momentlab(&[
        "gpu",
        "check",
        "--resolution",
        "32",
        "--receivers",
        "600",
        "--export",
        &t,
    ]);
    let _ = std::fs::remove_dir_all(&tmp);
    assert_eq!(bad.status.code(), Some(1), "{}", setting.label());
    let err = last_line(&bad.stderr);
    let named = format!(
        "{} {}",
        setting.family.technique.name(),
        setting.family.storage.name()
    );
    assert!(
        err.starts_with("error: gpu check:") && err.contains(&named) && err.contains("texel"),
        "{err}"
    );
}

#[test]
fn without_an_adapter_the_error_is_one_line() {
    let out = Command::new(env!("CARGO_BIN_EXE_momentlab"))
        .args(["gpu", "check", "--resolution", "16"])
        .env("VK_ICD_FILENAMES", "/nonexistent/icd.json")
        .env("VK_DRIVER_FILES", "/nonexistent/icd.json")
        .env("XDG_RUNTIME_DIR", std::env::temp_dir())
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    let lines: Vec<&str> = err.lines().filter(|l| l.starts_with("error: ")).collect();
    assert_eq!(lines.len(), 1, "{err}");
    assert!(lines[0].contains("no GPU adapter"), "{err}");
    assert_eq!(last_line(&out.stderr), lines[0]);
}

/// The Vulkan loader's files on this machine (`libvulkan.so*` in the usual library folders).
fn vulkan_loader_files() -> Vec<std::path::PathBuf> {
    let mut dirs: Vec<std::path::PathBuf> = Vec::new();
    for top in ["/lib", "/lib64", "/usr/lib", "/usr/lib64", "/usr/local/lib"] {
        let top = Path::new(top);
        dirs.push(top.to_path_buf());
        if let Ok(rd) = std::fs::read_dir(top) {
            dirs.extend(rd.flatten().map(|e| e.path()).filter(|p| p.is_dir()));
        }
    }
    let mut files = Vec::new();
    for d in dirs {
        if let Ok(rd) = std::fs::read_dir(&d) {
            for e in rd.flatten() {
                let name = e.file_name().to_string_lossy().into_owned();
                if name.starts_with("libvulkan.so") && e.path().is_file() {
                    files.push(e.path());
                }
            }
        }
    }
    files.sort();
    files.dedup();
    files
}

/// With no Vulkan loader at all (its files hidden behind /dev/null in a private mount
/// namespace, `unshare -rm`), `gpu check` and `gpu bench` end with the one-line "no GPU
/// adapter" error, never a panic. Where user namespaces are not allowed the test skips loudly.
#[test]
fn without_a_vulkan_loader_the_error_is_one_line() {
    let probe = Command::new("unshare").args(["-rm", "true"]).output();
    if !probe.is_ok_and(|o| o.status.success()) {
        eprintln!(
            "SKIPPED without_a_vulkan_loader_the_error_is_one_line: `unshare -rm` is not \
             available here (no user namespaces)"
        );
        return;
    }
    let mut script = String::from("set -e\n");
    for f in vulkan_loader_files() {
        script.push_str(&format!("mount --bind /dev/null '{}'\n", f.display()));
    }
    script.push_str("set +e\n\"$0\" gpu check --resolution 16\necho \"rc=$?\" >&2\n");
    script.push_str("\"$0\" gpu bench --sizes 16 --out \"$1\"\necho \"rc=$?\" >&2\n");
    let tmp = std::env::temp_dir().join(format!("momentlab-noloader-{}", std::process::id()));
    let out = Command::new("unshare")
        .args(["-rm", "sh", "-c", &script, env!("CARGO_BIN_EXE_momentlab")])
        .arg(&tmp)
        .env("XDG_RUNTIME_DIR", std::env::temp_dir())
        .output()
        .unwrap();
    let _ = std::fs::remove_dir_all(&tmp);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    let errors: Vec<&str> = err.lines().filter(|l| l.starts_with("error: ")).collect();
    assert_eq!(errors.len(), 2, "{err}");
    assert!(errors.iter().all(|l| l.contains("no GPU adapter")), "{err}");
    assert_eq!(err.matches("rc=1").count(), 2, "{err}");
    assert!(!err.contains("panicked"), "{err}");
}

#[test]
fn bad_lists_are_refused_before_any_gpu_work() {
    let out = momentlab(&["gpu", "check", "--storage", "f64"]);
    assert_eq!(out.status.code(), Some(1));
    assert!(last_line(&out.stderr).contains("--storage: unknown 'f64'"));
    let out = momentlab(&["gpu", "bench", "--filters", "4"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(
        last_line(&out.stderr).contains("odd"),
        "{}",
        last_line(&out.stderr)
    );
}
