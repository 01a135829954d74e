//! README.md against the committed artefacts and the code it describes.
//!
//! * Every generated block (`<!-- generated:NAME -->` … `<!-- end -->`) equals what
//!   `momentlab::report::readme::render` writes from reports/ (the command table: what
//!   `momentlab --help` lists). `MOMENTLAB_UPDATE_README=1` rewrites the blocks instead.
//! * A copy of the artefacts with one number changed renders a different block (the check can
//!   fail).
//! * Outside the generated blocks README holds no figure: every digit outside code is one of a
//!   few names checked here one by one.
//! * README has at most 200 lines; its layout table names every part of src/ and only
//!   existing paths.

use clap::CommandFactory;
use momentlab::report::readme;
use std::path::{Path, PathBuf};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn readme_text() -> String {
    std::fs::read_to_string(root().join("README.md")).unwrap()
}

/// The command table: every subcommand of `momentlab --help` (and of its command groups)
/// with its one-line description.
fn command_table() -> String {
    let cli = crate::cli::Cli::command();
    let mut s = String::from("| command | what |\n| --- | --- |\n");
    let about = |c: &clap::Command| {
        c.get_about()
            .map(|a| a.to_string())
            .unwrap_or_default()
            .trim_end_matches('.')
            .replace('|', "\\|")
    };
    for c in cli.get_subcommands().filter(|c| !c.is_hide_set()) {
        let subs: Vec<&clap::Command> = c.get_subcommands().filter(|c| !c.is_hide_set()).collect();
        if subs.is_empty() || c.get_name() == "candidates" {
            s.push_str(&format!(
                "| `momentlab {}` | {} |\n",
                c.get_name(),
                about(c)
            ));
        } else {
            for sub in subs {
                s.push_str(&format!(
                    "| `momentlab {} {}` | {} |\n",
                    c.get_name(),
                    sub.get_name(),
                    about(sub)
                ));
            }
        }
    }
    s
}

fn render(name: &str, reports: &Path) -> anyhow::Result<String> {
    if name == "commands" {
        Ok(command_table())
    } else {
        readme::render(name, reports)
    }
}

#[test]
fn readme_blocks_equal_what_the_artefacts_render() {
    let text = readme_text();
    let reports = root().join("reports");
    if std::env::var("MOMENTLAB_UPDATE_README").as_deref() == Ok("1") {
        let new = readme::splice(&text, |n| render(n, &reports)).unwrap();
        std::fs::write(root().join("README.md"), new).unwrap();
        eprintln!("README.md: generated blocks rewritten");
        return;
    }
    let blocks = readme::blocks(&text).unwrap();
    let names: Vec<&str> = blocks.iter().map(|b| b.0.as_str()).collect();
    for want in readme::NAMES.iter().copied().chain(["commands"]) {
        assert!(names.contains(&want), "README has no block '{want}'");
    }
    for (name, body) in &blocks {
        let fresh = render(name, &reports).unwrap();
        assert_eq!(
            body, &fresh,
            "README block '{name}' differs from what reports/ renders; run \
             MOMENTLAB_UPDATE_README=1 cargo test --release --test project readme_figures"
        );
    }
}

fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for e in std::fs::read_dir(from).unwrap() {
        let p = e.unwrap().path();
        let t = to.join(p.file_name().unwrap());
        if p.is_dir() {
            copy_dir(&p, &t);
        } else if matches!(
            p.extension().and_then(|e| e.to_str()),
            Some("json") | Some("md")
        ) {
            std::fs::copy(&p, &t).unwrap();
        }
    }
}

#[test]
fn one_changed_number_in_an_artefact_fails_the_check() {
    let tmp = crate::common::tmp_path("readme");
    copy_dir(&root().join("reports"), &tmp);
    let blocks = readme::blocks(&readme_text()).unwrap();
    let block = |n: &str| blocks.iter().find(|b| b.0 == n).unwrap().1.clone();
    // The untouched copy renders README's blocks.
    for n in readme::NAMES
        .iter()
        .filter(|&&n| blocks.iter().any(|b| b.0 == n))
    {
        assert_eq!(readme::render(n, &tmp).unwrap(), block(n), "{n}");
    }
    // One technique's error in its JSON, changed in the 4th significant digit.
    let f = tmp.join("default/evaluate/hamburger4_f32.json");
    let mut v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&f).unwrap()).unwrap();
    let e = v["error"].as_f64().unwrap();
    v["error"] = serde_json::json!(e * 1.001 + 1e-4);
    std::fs::write(&f, serde_json::to_string(&v).unwrap()).unwrap();
    assert_ne!(
        readme::render("techniques", &tmp).unwrap(),
        block("techniques")
    );
    // One digit of the m = 4 winner's error in the sweep report.
    let f = tmp.join("search/search_m4.md");
    let s = std::fs::read_to_string(&f).unwrap();
    let line = s
        .lines()
        .find(|l| l.starts_with("The winner of "))
        .unwrap()
        .to_string();
    let pos = line.find(" %").unwrap() - 1;
    let mut changed = line.clone().into_bytes();
    changed[pos] = if changed[pos] == b'9' {
        b'8'
    } else {
        changed[pos] + 1
    };
    let changed = String::from_utf8(changed).unwrap();
    std::fs::write(&f, s.replace(&line, &changed)).unwrap();
    assert_ne!(readme::render("sweeps", &tmp).unwrap(), block("sweeps"));
    // One θ gain.
    let f = tmp.join("theta/summary.json");
    let mut v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&f).unwrap()).unwrap();
    let g = v["rows"][0]["ours_gain_bits"].as_f64().unwrap();
    v["rows"][0]["ours_gain_bits"] = serde_json::json!(g + 0.001);
    std::fs::write(&f, serde_json::to_string(&v).unwrap()).unwrap();
    assert_ne!(readme::render("theta", &tmp).unwrap(), block("theta"));
    // The m = 4 race's sweep time, one second more.
    let docs = std::fs::read_to_string(root().join("docs/search.md")).unwrap();
    let docs_blocks = readme::blocks(&docs).unwrap();
    let times = &docs_blocks.iter().find(|b| b.0 == "race-times").unwrap().1;
    let f = tmp.join("search/wall_m4.json");
    let mut v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&f).unwrap()).unwrap();
    let t = v["sweep_seconds"].as_f64().unwrap();
    v["sweep_seconds"] = serde_json::json!(t + 1.0);
    std::fs::write(&f, serde_json::to_string(&v).unwrap()).unwrap();
    assert_ne!(&readme::render("race-times", &tmp).unwrap(), times);
    std::fs::remove_dir_all(&tmp).ok();
}

/// README outside generated blocks, fenced code, code spans and link targets.
fn prose(readme_text: &str) -> String {
    let outside = readme::outside_blocks(readme_text);
    let mut out = String::new();
    let mut fenced = false;
    for line in outside.lines() {
        if line.trim_start().starts_with("```") {
            fenced = !fenced;
            continue;
        }
        if fenced {
            continue;
        }
        let mut l = String::new();
        let mut in_code = false;
        let mut chars = line.chars().peekable();
        while let Some(c) = chars.next() {
            if c == '`' {
                in_code = !in_code;
                continue;
            }
            if in_code {
                continue;
            }
            // Link targets `](…)`: paths, not figures.
            if c == ']' && chars.peek() == Some(&'(') {
                for d in chars.by_ref() {
                    if d == ')' {
                        break;
                    }
                }
                l.push(']');
                continue;
            }
            l.push(c);
        }
        out.push_str(&l);
        out.push('\n');
    }
    out
}

/// Names that contain digits, each checked against the code or the artefacts.
fn named_digits() -> Vec<(&'static str, bool)> {
    let paper_line =
        std::fs::read_to_string(root().join("reports/search/search_m4.md")).unwrap_or_default();
    let catalog = std::fs::read_to_string(root().join("src/lib.rs")).unwrap();
    vec![
        // The paper's Algorithm 1 (the discretized moment problem), named in the crate docs.
        ("Algorithm 1", catalog.contains("Algorithm 1")),
        // Technique names: Hamburger/Hausdorff four-moment and six-moment shadow mapping.
        ("4MSM", momentlab::technique::by_name("hamburger4").is_ok()),
        ("6MSM", momentlab::technique::by_name("hamburger6").is_ok()),
        // The paper's figures, named by the sweep and θ reports.
        ("Fig. 3", paper_line.contains("Fig. 3")),
        ("Fig. 4", paper_line.contains("Fig. 4")),
        ("Fig. 5", root().join("reports/theta/fig5.svg").is_file()),
        // The licence, as Cargo.toml declares it.
        (
            "MIT OR Apache-2.0",
            std::fs::read_to_string(root().join("Cargo.toml"))
                .unwrap()
                .contains("license = \"MIT OR Apache-2.0\""),
        ),
        ("Apache-2.0", true),
    ]
}

#[test]
fn readme_has_no_unchecked_numbers_outside_generated_blocks() {
    let mut p = prose(&readme_text());
    for (name, ok) in named_digits() {
        assert!(ok, "README names '{name}', which the check no longer finds");
        p = p.replace(name, "");
    }
    let bad: Vec<&str> = p
        .lines()
        .filter(|l| l.chars().any(|c| c.is_ascii_digit()))
        .collect();
    assert!(
        bad.is_empty(),
        "README has figures outside generated blocks (put them in a block rendered from \
         reports/, or in code):\n{}",
        bad.join("\n")
    );
}

#[test]
fn a_planted_number_in_prose_is_found() {
    let text = "a `--m 4` b [x](docs/a1.md)\n<!-- generated:t -->\n5 %\n<!-- end -->\n";
    assert!(!prose(text).chars().any(|c| c.is_ascii_digit()));
    let planted = format!("{text}error 5.3 %\n");
    assert!(prose(&planted).contains("5.3"));
}

#[test]
fn readme_is_short_and_its_layout_matches_src() {
    let text = readme_text();
    let lines = text.lines().count();
    assert!(lines <= 200, "README has {lines} lines (at most 200)");
    // Every part of src/ is in the layout table, and every `src/…` path of the table exists.
    let start = text
        .find("\n## Layout\n")
        .expect("README has its Layout section");
    let layout = &text[start + 1..];
    let layout = &layout[..layout[3..].find("\n## ").map_or(layout.len(), |e| e + 3)];
    let rows: Vec<&str> = layout.lines().filter(|l| l.starts_with("| `")).collect();
    assert!(rows.len() > 10, "README's layout table not found: {layout}");
    let table = rows.join("\n");
    for row in &rows {
        for span in row.split('`').skip(1).step_by(2) {
            if span.starts_with("src/") {
                assert!(
                    root().join(span).exists(),
                    "README's layout lists {span}, which does not exist"
                );
            }
        }
    }
    for e in std::fs::read_dir(root().join("src")).unwrap() {
        let e = e.unwrap();
        let name = e.file_name().to_string_lossy().to_string();
        if name == "lib.rs" || name == "main.rs" {
            continue;
        }
        let shown = if e.path().is_dir() {
            format!("`src/{name}/`")
        } else {
            format!("`src/{name}`")
        };
        assert!(
            table.contains(&shown),
            "README's layout does not list {shown}"
        );
    }
    // Every path in a code span or link of README exists.
    let mut rest = text.as_str();
    while let Some(p) = rest.find('`') {
        let after = &rest[p + 1..];
        let Some(e) = after.find('`') else { break };
        let span = &after[..e];
        if (span.starts_with("src/") || span.starts_with("scripts/") || span.starts_with("data/"))
            && !span.contains(' ')
        {
            assert!(
                root().join(span).exists(),
                "README names {span}, which does not exist"
            );
        }
        rest = &after[e + 1..];
    }
    let mut rest = text.as_str();
    while let Some(p) = rest.find("](") {
        let after = &rest[p + 2..];
        let Some(e) = after.find(')') else { break };
        let target = after[..e].split('#').next().unwrap();
        if !target.contains("://") && !target.is_empty() {
            assert!(
                root().join(target).exists(),
                "README links {target}, which does not exist"
            );
        }
        rest = &after[e + 1..];
    }
}

/// docs/lp.md's table "Where the code is" names every file of src/lp/ once, and only those.
#[test]
fn docs_lp_layout_lists_every_file_of_src_lp() {
    let text = std::fs::read_to_string(root().join("docs/lp.md")).unwrap();
    let start = text
        .find("## Where the code is (src/lp/)")
        .expect("docs/lp.md has its layout section");
    let section = &text[start..];
    let section = &section[..section[3..].find("\n## ").map_or(section.len(), |e| e + 3)];
    let mut listed: Vec<String> = section
        .lines()
        .filter_map(|l| l.strip_prefix("| `"))
        .filter_map(|l| l.split('`').next())
        .map(str::to_string)
        .collect();
    listed.sort();
    let mut files = Vec::new();
    let mut dirs = vec![root().join("src/lp")];
    while let Some(d) = dirs.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                dirs.push(p);
            } else if p.extension().is_some_and(|x| x == "rs") {
                let rel = p
                    .strip_prefix(root())
                    .unwrap()
                    .to_string_lossy()
                    .to_string();
                files.push(rel);
            }
        }
    }
    files.sort();
    assert_eq!(listed, files, "docs/lp.md's layout table against src/lp/");
}

/// README shows every GPU bench under reports/gpu/ as the paper's Figure 7 analogue: its
/// `gpu-bench` block names the adapter and shows the three panels (time per frame against
/// shadow-map size, filter size, output resolution), whose files exist.
#[test]
fn readme_shows_every_gpu_bench_as_the_figure_7_analogue() {
    let blocks = readme::blocks(&readme_text()).unwrap();
    let block = &blocks.iter().find(|b| b.0 == "gpu-bench").unwrap().1;
    let dir = root().join("reports/gpu");
    let mut n = 0;
    for e in std::fs::read_dir(&dir).unwrap() {
        let p = e.unwrap().path();
        if p.extension().is_none_or(|x| x != "json") {
            continue;
        }
        let v: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&p).unwrap()).unwrap();
        let name = v["adapter"]["name"].as_str().unwrap();
        assert!(block.contains(&format!("**{name}**")), "{name}: {block}");
        let stem = p.file_stem().unwrap().to_string_lossy();
        for axis in ["size", "filter", "output"] {
            let f = format!("reports/gpu/{stem}_{axis}.svg");
            assert!(block.contains(&format!("]({f})")), "{f}: {block}");
            assert!(root().join(&f).is_file(), "{f}");
        }
        n += 1;
    }
    assert!(n >= 1, "no bench under reports/gpu");
}
