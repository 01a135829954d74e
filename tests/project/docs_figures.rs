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
        "lp-families",
        "dataset",
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
        } else if p
            .extension()
            .is_some_and(|x| x == "json" || x == "md" || x == "txt")
        {
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

/// Replace the first number of the first line of `file` starting with `prefix` (after the
/// prefix) by that number + `by`, keeping its decimals.
fn bump_number_in_line(file: &Path, prefix: &str, by: f64) {
    let s = std::fs::read_to_string(file).unwrap();
    let row = s
        .lines()
        .find(|l| l.starts_with(prefix))
        .unwrap_or_else(|| panic!("{}: no line '{prefix}…'", file.display()))
        .to_string();
    let tail = &row[prefix.len()..];
    let b = tail.as_bytes();
    let i = (0..b.len())
        .find(|&i| b[i].is_ascii_digit() && (i == 0 || !b[i - 1].is_ascii_alphanumeric()))
        .unwrap();
    let j = (i..b.len())
        .find(|&j| !(b[j].is_ascii_digit() || b[j] == b'.'))
        .unwrap_or(b.len());
    let old = &tail[i..j];
    let decimals = old.split_once('.').map_or(0, |x| x.1.len());
    let new = format!("{:.*}", decimals, old.parse::<f64>().unwrap() + by);
    let changed = format!("{prefix}{}{new}{}", &tail[..i], &tail[j..]);
    assert_ne!(row, changed);
    std::fs::write(file, s.replacen(&row, &changed, 1)).unwrap();
}

/// Per generated block of docs/: one number changed in the artefact it quotes.
type Perturb = fn(&Path);

const PERTURBATIONS: [(&str, &str, Perturb); 11] = [
    ("stability", "a share above the bound", |r| {
        edit_json(&r.join("stability/stability.json"), |v| {
            let x = v["by_mode"][4][3][1]["over_share"].as_f64().unwrap();
            v["by_mode"][4][3][1]["over_share"] = serde_json::json!(x + 0.001);
        })
    }),
    ("theta-comparison", "a CPU time of θ₆", |r| {
        let f = r.join("theta/comparison.md");
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
    }),
    ("theta-comparison", "a basin's runner-up", |r| {
        edit_json(&r.join("theta/summary.json"), |v| {
            for row in v["rows"].as_array_mut().unwrap() {
                if row["m"] == 8 {
                    let x = row["basin"]["runner_up_bits"].as_f64().unwrap();
                    row["basin"]["runner_up_bits"] = serde_json::json!(x - 0.01);
                }
            }
        })
    }),
    ("theta-basis", "a basis θ's CPU time", |r| {
        let basis = std::fs::read_dir(r.join("theta/basis"))
            .unwrap()
            .map(|e| e.unwrap().path())
            .find(|p| p.extension().is_some_and(|x| x == "json"))
            .unwrap();
        edit_json(&basis, |v| {
            let x = v["cpu_seconds"].as_f64().unwrap();
            v["cpu_seconds"] = serde_json::json!(x + 1.0);
        })
    }),
    ("theta-fig5", "the hull ratio of θ₃", |r| {
        bump_number_in_line(
            &r.join("theta/comparison.md"),
            "Fig. 5 analogue (fig5.svg): hull of b([0,1]) ",
            0.001,
        )
    }),
    ("quantize-alpha", "the best α of one row", |r| {
        edit_json(&r.join("default/quantize/quantize.json"), |v| {
            let a = v["sweeps"][0]["alphas"][3].clone();
            v["sweeps"][0]["best_alpha"] = a;
        })
    }),
    (
        "quantize-usable",
        "the error at the smallest usable α",
        |r| {
            edit_json(&r.join("default/quantize/quantize.json"), |v| {
                let row = v["usable_16bit"]
                    .as_array_mut()
                    .unwrap()
                    .iter_mut()
                    .find(|u| u["smallest_usable_alpha"].is_number())
                    .expect("no usable 16-bit row");
                let x = row["error_there"].as_f64().unwrap();
                row["error_there"] = serde_json::json!(x + 0.001);
            })
        },
    ),
    (
        "lp-families",
        "a family's mean µs per LP in one stage",
        |r| {
            let f = r.join("search/lp_time_m4.txt");
            let s = std::fs::read_to_string(&f).unwrap();
            let row = s
                .lines()
                .find(|l| l.starts_with("stage 0") && l.contains("exp(±40z)"))
                .unwrap()
                .to_string();
            let us = row.split_whitespace().nth_back(2).unwrap().to_string();
            let changed = row.replacen(
                &format!(" {us} "),
                &format!(" {:.1} ", us.parse::<f64>().unwrap() + 5.0),
                1,
            );
            assert_ne!(row, changed);
            std::fs::write(&f, s.replace(&row, &changed)).unwrap();
        },
    ),
    ("dataset", "one scene's fragments and the total", |r| {
        edit_json(&r.join("default/evaluate/hamburger4_f32.json"), |v| {
            let x = v["scenes"][0][2].as_f64().unwrap();
            v["scenes"][0][2] = serde_json::json!(x + 1.0);
            let t = v["fragments"].as_f64().unwrap();
            v["fragments"] = serde_json::json!(t + 1.0);
        })
    }),
    ("race-times", "the LP solves of the m = 4 race", |r| {
        edit_json(&r.join("search/wall_m4.json"), |v| {
            let x = v["lp_solves"].as_f64().unwrap();
            v["lp_solves"] = serde_json::json!(x + 1e6);
        })
    }),
    ("gpu-cost", "VSM's measured lookup times", |r| {
        gpu_artefacts(r).into_iter().for_each(|f| {
            edit_json(&f, |v| {
                for p in v["points"].as_array_mut().unwrap() {
                    if p["technique"] == "vsm" {
                        let ms = &mut p["lookup_ms"]["median"];
                        *ms = serde_json::json!(ms.as_f64().unwrap() * 1.5);
                    }
                }
            })
        })
    }),
];

fn gpu_artefacts(reports: &Path) -> Vec<PathBuf> {
    std::fs::read_dir(reports.join("gpu"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "json"))
        .collect()
}

/// One number changed in each artefact that docs/ quotes, on a fresh copy of reports/ each:
/// the block quoting it no longer matches. Every generated block of docs/ has its change here.
#[test]
fn a_changed_number_in_an_artefact_fails_the_docs_check() {
    let blocks = doc_blocks();
    let block = |name: &str| blocks.iter().find(|b| b.1 == name).unwrap().2.clone();
    for (_, name, _) in blocks
        .iter()
        .filter(|b| !CHECKED_ELSEWHERE.contains(&b.1.as_str()))
    {
        assert!(
            PERTURBATIONS.iter().any(|p| p.0 == name) || name == "gpu",
            "docs/ block '{name}' has no changed-number check in PERTURBATIONS"
        );
    }
    let tmp = std::env::temp_dir().join(format!("momentlab-docs-figures-{}", std::process::id()));
    for (name, what, perturb) in PERTURBATIONS {
        std::fs::remove_dir_all(&tmp).ok();
        copy_dir(&root().join("reports"), &tmp);
        // Sanity: the copy renders what docs/ shows.
        assert_eq!(readme::render(name, &tmp).unwrap(), block(name), "{name}");
        perturb(&tmp);
        assert_ne!(
            readme::render(name, &tmp).unwrap(),
            block(name),
            "{name}: changing {what} left the block as it is"
        );
        // docs/gpu.md's `gpu` block quotes the same artefact.
        if name == "gpu-cost" && blocks.iter().any(|b| b.1 == "gpu") {
            assert_ne!(
                readme::render("gpu", &tmp).unwrap(),
                block("gpu"),
                "gpu: changing {what} left the block as it is"
            );
        }
    }
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

/// The cells of a Markdown table row: split at every '|' that is not escaped (`\|`), as
/// GitHub's tables do (a '|' inside a code span splits too).
fn table_cells(row: &str) -> usize {
    let b = row.trim().as_bytes();
    let pipes = (0..b.len())
        .filter(|&i| b[i] == b'|' && (i == 0 || b[i - 1] != b'\\'))
        .count();
    pipes.saturating_sub(1)
}

/// (line number, cells, header cells) of every table row of `text` whose cell count differs
/// from its header's: a table the reader sees with shifted columns.
fn ragged_rows(text: &str) -> Vec<(usize, usize, usize)> {
    let mut out = Vec::new();
    let mut header: Option<usize> = None;
    let mut fenced = false;
    for (n, line) in text.lines().enumerate() {
        if line.trim_start().starts_with("```") {
            fenced = !fenced;
        }
        let t = line.trim();
        if fenced || !(t.starts_with('|') && t.ends_with('|')) {
            header = None;
            continue;
        }
        let cells = table_cells(t);
        match header {
            None => header = Some(cells),
            Some(h) if h != cells => out.push((n + 1, cells, h)),
            _ => {}
        }
    }
    out
}

/// Every table of README and docs/ (generated or not) has as many cells in each row as in its
/// header; an unescaped '|' in a cell (a family "|c| < 20") fails.
#[test]
fn docs_tables_have_whole_rows() {
    assert_eq!(
        ragged_rows("| a | b |\n|---|---|\n| exp(c·z), |c| < 20 | 1 |\n"),
        vec![(3, 4, 2)]
    );
    assert!(ragged_rows("| a | b |\n|---|---|\n| exp(c·z), \\|c\\| < 20 | 1 |\n").is_empty());
    let mut bad = Vec::new();
    let mut files = pages();
    files.push(root().join("README.md"));
    for p in files {
        for (line, cells, header) in ragged_rows(&std::fs::read_to_string(&p).unwrap()) {
            bad.push(format!(
                "{}:{line}: {cells} cells, the header has {header}",
                p.display()
            ));
        }
    }
    assert!(
        bad.is_empty(),
        "ragged Markdown tables:\n{}",
        bad.join("\n")
    );
}

/// The summary of the m = 2 validation in docs/search.md ("m = 2 with `--correction best`") is
/// what reports/search/validate_m2.txt records: the orders, the winner and false-elimination
/// verdicts, the tied sets' sizes and worst ranks, and the races' share of the LP solves.
#[test]
fn the_m2_validation_summary_is_the_artefacts() {
    let text = std::fs::read_to_string(root().join("reports/search/validate_m2.txt")).unwrap();
    let orders = text.matches("--race-seed ").count();
    assert_eq!(orders, 10, "racing orders in the artefact");
    let all = |needle: &str| text.matches(needle).count() == orders;
    assert!(all("tied for first in the race; in the tied set: true"));
    assert!(all("(+0.0000 pp over the exhaustive winner)"));
    assert!(all("better than the race winner on the full sample: 0 []"));
    assert!(all("that of the stage reference): 0 []"));
    // "validate: 6 tied (worst exhaustive rank 7), …" and "(15.2 % of exhaustive …)".
    let number_after = |line: &str, key: &str| -> f64 {
        let rest = &line[line.find(key).unwrap() + key.len()..];
        let end = rest
            .find(|c: char| !(c.is_ascii_digit() || c == '.'))
            .unwrap_or(rest.len());
        rest[..end].parse().unwrap()
    };
    let mut tied = Vec::new();
    let mut worst = Vec::new();
    let mut share = Vec::new();
    for line in text.lines() {
        if line.starts_with("validate: ") && line.contains(" tied (worst exhaustive rank ") {
            tied.push(number_after(line, "validate: "));
            worst.push(number_after(line, "worst exhaustive rank "));
        }
        if line.starts_with("--race-seed ") {
            share.push(number_after(line, "LP solves planned ("));
        }
    }
    let max = |v: &[f64]| v.iter().cloned().fold(f64::MIN, f64::max);
    let min = |v: &[f64]| v.iter().cloned().fold(f64::MAX, f64::min);
    let expected = format!(
        "the tied sets held {} to {} candidates (worst exhaustive rank {}), and\neach race \
         solved {:.1}–{:.1} % of the exhaustive sweep's LPs.",
        min(&tied),
        max(&tied),
        max(&worst),
        min(&share),
        max(&share)
    );
    let doc = std::fs::read_to_string(root().join("docs/search.md")).unwrap();
    assert!(
        doc.contains(&expected),
        "docs/search.md should say:\n{expected}"
    );
    assert!(doc.contains("is recorded in reports/search/validate_m2.txt: in every order the"));
}
