//! docs/*.md against the committed artefacts: every generated block `<!-- generated:NAME -->`
//! … `<!-- end -->` equals what reports/ renders (src/report/docs_figures.rs,
//! src/report/readme.rs), every picture of docs/img/ is a byte-for-byte copy of its pipeline
//! artefact and is shown by a page, and every documented output of a command
//! ("`momentlab …` → `N`") is what the binary prints. `MOMENTLAB_UPDATE_README=1` rewrites the
//! blocks and copies the pictures. A changed number in an artefact fails the check (checked on
//! a temporary copy of reports/).

use momentlab::report::{docs_figures, readme};
use std::path::{Path, PathBuf};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn pages() -> Vec<PathBuf> {
    let mut out: Vec<PathBuf> = std::fs::read_dir(root().join("docs"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "md"))
        .collect();
    out.sort();
    out
}

fn update() -> bool {
    std::env::var("MOMENTLAB_UPDATE_README").as_deref() == Ok("1")
}

/// (page, block name, block text) of every generated block of docs/.
fn doc_blocks() -> Vec<(PathBuf, String, String)> {
    let mut out = Vec::new();
    for p in pages() {
        let text = std::fs::read_to_string(&p).unwrap();
        for (name, body) in readme::blocks(&text).unwrap() {
            out.push((p.clone(), name, body));
        }
    }
    out
}

/// Blocks of docs/ that another test renders and checks: docs/files.md's `fuzz` (tests/fuzz).
const CHECKED_ELSEWHERE: [&str; 1] = ["fuzz"];

#[test]
fn docs_blocks_equal_the_artefacts() {
    let reports = root().join("reports");
    if update() {
        for p in pages() {
            let text = std::fs::read_to_string(&p).unwrap();
            let old = readme::blocks(&text).unwrap();
            let new = readme::splice(&text, |n| {
                if CHECKED_ELSEWHERE.contains(&n) {
                    Ok(old
                        .iter()
                        .find(|b| b.0 == n)
                        .map(|b| b.1.clone())
                        .unwrap_or_default())
                } else {
                    readme::render(n, &reports)
                }
            })
            .unwrap();
            if new != text {
                std::fs::write(&p, new).unwrap();
                eprintln!("{}: generated blocks rewritten", p.display());
            }
        }
        return;
    }
    let blocks = doc_blocks();
    for needed in [
        "race-times",
        "stability",
        "theta-comparison",
        "theta-basis",
        "quantize-alpha",
    ] {
        assert!(
            blocks.iter().any(|b| b.1 == needed),
            "no page of docs/ has the block '{needed}'"
        );
    }
    for (page, name, body) in blocks
        .iter()
        .filter(|b| !CHECKED_ELSEWHERE.contains(&b.1.as_str()))
    {
        assert_eq!(
            body,
            &readme::render(name, &reports).unwrap(),
            "{} block '{name}' differs from what reports/ renders; run \
             MOMENTLAB_UPDATE_README=1 cargo test --release --test project docs_",
            page.display()
        );
    }
}

#[test]
fn docs_pictures_are_the_pipelines_artefacts_and_pages_show_them() {
    let reports = root().join("reports");
    let docs = root().join("docs");
    if update() {
        for (to, from) in docs_figures::IMAGES {
            let to = docs.join(to);
            std::fs::create_dir_all(to.parent().unwrap()).unwrap();
            std::fs::copy(reports.join(from), &to).unwrap();
        }
    }
    let all_text: String = pages()
        .iter()
        .map(|p| std::fs::read_to_string(p).unwrap())
        .collect();
    assert!(docs_figures::IMAGES.len() >= 6);
    for (to, from) in docs_figures::IMAGES {
        let a = std::fs::read(docs.join(to)).unwrap_or_else(|e| panic!("docs/{to}: {e}"));
        let b = std::fs::read(reports.join(from)).unwrap();
        assert!(
            a == b,
            "docs/{to} is not a copy of reports/{from}; run MOMENTLAB_UPDATE_README=1 cargo \
             test --release --test project docs_pictures"
        );
        assert!(
            all_text.contains(&format!("]({to})")),
            "no page of docs/ shows {to}"
        );
    }
    // Every picture under docs/img is one of them.
    for e in std::fs::read_dir(docs.join("img")).unwrap() {
        let name = format!("img/{}", e.unwrap().file_name().to_string_lossy());
        assert!(
            docs_figures::IMAGES.iter().any(|i| i.0 == name),
            "docs/{name} is not generated (list it in docs_figures::IMAGES or remove it)"
        );
    }
}

fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for e in std::fs::read_dir(from).unwrap() {
        let e = e.unwrap();
        let p = e.path();
        if p.is_dir() {
            copy_dir(&p, &to.join(e.file_name()));
        } else if p.extension().is_some_and(|x| x == "json" || x == "md") {
            std::fs::copy(&p, to.join(e.file_name())).unwrap();
        }
    }
}

fn edit_json(path: &Path, f: impl FnOnce(&mut serde_json::Value)) {
    let mut v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
    f(&mut v);
    std::fs::write(path, serde_json::to_string(&v).unwrap()).unwrap();
}

/// One number changed in each artefact that docs/ quotes, and its block no longer matches.
#[test]
fn a_changed_number_in_an_artefact_fails_the_docs_check() {
    let tmp = std::env::temp_dir().join(format!("momentlab-docs-figures-{}", std::process::id()));
    std::fs::remove_dir_all(&tmp).ok();
    copy_dir(&root().join("reports"), &tmp);
    let blocks = doc_blocks();
    let block = |name: &str| blocks.iter().find(|b| b.1 == name).unwrap().2.clone();
    // Sanity: the copy renders what docs/ shows.
    for name in [
        "stability",
        "theta-comparison",
        "theta-basis",
        "quantize-alpha",
    ] {
        assert_eq!(readme::render(name, &tmp).unwrap(), block(name), "{name}");
    }
    // A share above the bound (stability.md).
    edit_json(&tmp.join("stability/stability.json"), |v| {
        let x = v["by_mode"][4][3][1]["over_share"].as_f64().unwrap();
        v["by_mode"][4][3][1]["over_share"] = serde_json::json!(x + 0.001);
    });
    assert_ne!(
        readme::render("stability", &tmp).unwrap(),
        block("stability")
    );
    // A CPU time in the θ comparison table (theta.md).
    let f = tmp.join("theta/comparison.md");
    let s = std::fs::read_to_string(&f).unwrap();
    let row = s
        .lines()
        .find(|l| l.starts_with("| 6 |"))
        .unwrap()
        .to_string();
    let cells: Vec<&str> = row.split(" | ").collect();
    let cpu: f64 = cells[3].parse().unwrap();
    let mut changed = cells.clone();
    let new_cpu = format!("{:.1}", cpu + 1.0);
    changed[3] = &new_cpu;
    std::fs::write(&f, s.replace(&row, &changed.join(" | "))).unwrap();
    assert_ne!(
        readme::render("theta-comparison", &tmp).unwrap(),
        block("theta-comparison")
    );
    // A basin share (theta.md).
    edit_json(&tmp.join("theta/summary.json"), |v| {
        for r in v["rows"].as_array_mut().unwrap() {
            if r["m"] == 8 {
                let x = r["basin"]["runner_up_bits"].as_f64().unwrap();
                r["basin"]["runner_up_bits"] = serde_json::json!(x - 0.01);
            }
        }
    });
    assert_ne!(
        readme::render("theta-comparison", &tmp).unwrap(),
        block("theta-comparison")
    );
    // A basis θ's CPU time (theta.md).
    let basis = std::fs::read_dir(tmp.join("theta/basis"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .find(|p| p.extension().is_some_and(|x| x == "json"))
        .unwrap();
    edit_json(&basis, |v| {
        let x = v["cpu_seconds"].as_f64().unwrap();
        v["cpu_seconds"] = serde_json::json!(x + 1.0);
    });
    assert_ne!(
        readme::render("theta-basis", &tmp).unwrap(),
        block("theta-basis")
    );
    // The best α of one quantize row (theta.md).
    edit_json(&tmp.join("default/quantize/quantize.json"), |v| {
        let a = v["sweeps"][0]["alphas"][3].clone();
        v["sweeps"][0]["best_alpha"] = a;
    });
    assert_ne!(
        readme::render("quantize-alpha", &tmp).unwrap(),
        block("quantize-alpha")
    );
    std::fs::remove_dir_all(&tmp).ok();
}

/// Documented outputs "`momentlab ARGS` → `OUT`" on one line of docs/: the binary prints OUT.
#[test]
fn documented_command_outputs_are_what_the_binary_prints() {
    let mut checked = 0;
    for p in pages() {
        let text = std::fs::read_to_string(&p).unwrap();
        for line in text.lines() {
            let mut rest = line;
            while let Some(i) = rest.find("`momentlab ") {
                let after = &rest[i + 1..];
                let Some(e) = after.find('`') else { break };
                let cmd = &after[..e];
                let tail = &after[e + 1..];
                rest = tail;
                let Some(out) = tail.strip_prefix(" → `") else {
                    continue;
                };
                let Some(out) = out.split('`').next() else {
                    continue;
                };
                let args = shell_words(cmd.strip_prefix("momentlab ").unwrap());
                let o = std::process::Command::new(env!("CARGO_BIN_EXE_momentlab"))
                    .args(&args)
                    .output()
                    .unwrap();
                assert!(o.status.success(), "{}: `{cmd}` failed", p.display());
                assert_eq!(
                    String::from_utf8_lossy(&o.stdout).trim(),
                    out,
                    "{}: `{cmd}`",
                    p.display()
                );
                checked += 1;
            }
        }
    }
    assert!(checked >= 2, "only {checked} documented outputs found");
}

/// Split a command line as a POSIX shell would for plain words and '…' / "…" quotes.
pub fn shell_words(s: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut cur = String::new();
    let mut any = false;
    let mut quote = None;
    for c in s.chars() {
        match (quote, c) {
            (None, '\'' | '"') => {
                quote = Some(c);
                any = true;
            }
            (Some(q), c) if c == q => quote = None,
            (None, c) if c.is_whitespace() => {
                if any {
                    out.push(std::mem::take(&mut cur));
                    any = false;
                }
            }
            (_, c) => {
                cur.push(c);
                any = true;
            }
        }
    }
    if any {
        out.push(cur);
    }
    out
}
