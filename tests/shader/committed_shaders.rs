//! The shader files committed under reports/ are what the code emits now, and they compile:
//! * θ snippets (`reports/theta`, `reports/theta/basis`, `reports/default/theta`):
//!   `theta{tag}.glsl/.hlsl/.wgsl` equal what `momentlab theta --snippets DIR` writes from the
//!   `theta{tag}.json` beside them (in the channel order the JSON records);
//! * tune exports (`reports/default/tune/export/<scene>/`): `shadow.glsl/.hlsl/.wgsl` equal
//!   what `tune` writes for the committed `setting.json`, whose `shaders` lists them.
//!
//! Every module then goes through the compile check (tests/common/shader.rs): the texts
//! compared are the texts compiled. On drift the test fails; `MOMENTLAB_UPDATE_SHADERS=1`
//! rewrites the tune exports' shader files and `shaders` lists (for the θ snippets the message
//! names the `momentlab theta --snippets` command).

use crate::common::shader as shader_common;

use momentlab::quantize::codegen::{self, ChannelOrder};
use momentlab::quantize::{curve, theta::Theta};
use momentlab::shader::{self, Module};
use momentlab::tune::export;
use momentlab::tune::space::Setting;
use std::path::{Path, PathBuf};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn read(p: &Path) -> String {
    std::fs::read_to_string(p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

fn update() -> bool {
    std::env::var("MOMENTLAB_UPDATE_SHADERS").as_deref() == Ok("1")
}

/// The theta*.json files of a folder, sorted.
fn theta_jsons(dir: &Path) -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| {
            p.extension().is_some_and(|e| e == "json")
                && p.file_name()
                    .and_then(|n| n.to_str())
                    .is_some_and(|n| n.starts_with("theta"))
        })
        .collect();
    v.sort();
    v
}

#[test]
fn committed_theta_snippets_are_current_and_compile() {
    let glslang = shader_common::tools_present("committed_theta_snippets_are_current_and_compile");
    let mut checked = 0;
    for rel in [
        "reports/theta",
        "reports/theta/basis",
        "reports/default/theta",
    ] {
        let dir = root().join(rel);
        for p in theta_jsons(&dir) {
            let v: serde_json::Value = serde_json::from_str(&read(&p)).unwrap();
            let th = Theta::new(
                serde_json::from_value(v["basis"].clone()).unwrap(),
                serde_json::from_value(v["matrix"].clone()).unwrap(),
                serde_json::from_value(v["offset"].clone()).unwrap(),
            )
            .unwrap();
            let c = curve::from_names(&th.basis).unwrap();
            let tag = momentlab::pipeline::theta::snippet_tag(c.as_ref());
            let order = match v["snippet_channel_order"].as_str() {
                Some("search") => ChannelOrder::Search,
                _ => ChannelOrder::Paper,
            };
            let sn = codegen::snippet(&th, c.as_ref(), &tag, order).unwrap();
            let texts = [
                ("glsl", shader::glsl(&sn.glsl).unwrap()),
                ("hlsl", shader::hlsl(&sn.hlsl).unwrap()),
                ("wgsl", shader::wgsl(&sn.glsl).unwrap()),
            ];
            for (ext, text) in &texts {
                let f = dir.join(format!("theta{tag}.{ext}"));
                assert!(
                    f.is_file() && &read(&f) == text,
                    "{} differs from what the code emits; run momentlab theta --snippets {rel} \
                     --force",
                    f.display()
                );
            }
            for (lang, m) in [("glsl", &sn.glsl), ("hlsl", &sn.hlsl)] {
                shader_common::check(&format!("committed-theta{tag}-{lang}"), m, glslang)
                    .unwrap_or_else(|e| panic!("{}: {e}", p.display()));
            }
            checked += 1;
        }
    }
    // θ₂, θ₃, θ₄, θ₆, θ₈, two basis θ, and the default run's four
    assert!(checked >= 11, "{checked} theta*.json found");
}

#[test]
fn committed_tune_exports_are_current_and_compile() {
    let glslang = shader_common::tools_present("committed_tune_exports_are_current_and_compile");
    let base = root().join("reports/default/tune/export");
    let mut dirs: Vec<PathBuf> = std::fs::read_dir(&base)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.is_dir())
        .collect();
    dirs.sort();
    assert!(dirs.len() >= 2, "{}: no exports", base.display());
    let mut stale = Vec::new();
    for d in &dirs {
        let sj = d.join("setting.json");
        let v: serde_json::Value = serde_json::from_str(&read(&sj)).unwrap();
        let s: Setting = serde_json::from_value(v["setting"].clone()).unwrap();
        let module: Module = export::module(&s, export::header(&s))
            .unwrap()
            .unwrap_or_else(|| panic!("{}: no export for {}", sj.display(), s.label()));
        let texts = export::shader_texts(&module).unwrap();
        let names: Vec<String> = export::SHADER_FILES.iter().map(|n| n.to_string()).collect();
        let listed: Vec<String> = serde_json::from_value(v["shaders"].clone()).unwrap();
        let mut current = listed == names;
        for (name, text) in export::SHADER_FILES.iter().zip(&texts) {
            let f = d.join(name);
            if !f.is_file() || &read(&f) != text {
                current = false;
                if update() {
                    std::fs::write(&f, text).unwrap();
                }
            }
        }
        if !current {
            stale.push(d.display().to_string());
            if update() && listed != names {
                // the "shaders" list in place, the rest of the file as written by `tune`
                let text = read(&sj);
                let start = text.find("\"shaders\": [").unwrap();
                let end = start + text[start..].find(']').unwrap() + 1;
                let list: Vec<String> = names.iter().map(|n| format!("    \"{n}\"")).collect();
                let new = format!("\"shaders\": [\n{}\n  ]", list.join(",\n"));
                let text = format!("{}{new}{}", &text[..start], &text[end..]);
                assert_eq!(
                    serde_json::from_str::<serde_json::Value>(&text).unwrap()["shaders"],
                    serde_json::json!(names)
                );
                std::fs::write(&sj, text).unwrap();
            }
        }
        shader_common::check(
            &format!(
                "committed-export-{}",
                d.file_name().unwrap().to_string_lossy()
            ),
            &module,
            glslang,
        )
        .unwrap_or_else(|e| panic!("{}: {e}", d.display()));
    }
    if update() {
        eprintln!("rewrote the shader files of {stale:?}");
        return;
    }
    assert!(
        stale.is_empty(),
        "{stale:?}: shader files differ from what `tune` writes for setting.json; run \
         MOMENTLAB_UPDATE_SHADERS=1 cargo test --release --test shader committed_shaders"
    );
}
