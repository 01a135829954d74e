//! The committed artefacts under reports/ record commands that still run: every recorded
//! `momentlab …` command line (JSON "command" fields, commands in backticks or `<code>` in the
//! Markdown/HTML reports, the report's provenance row) parses with today's command line and uses
//! no hidden (old) spelling of a flag; no artefact names a /tmp path. The scanner is checked on
//! planted artefacts.

use clap::{CommandFactory, Parser};
use std::path::{Path, PathBuf};

/// Shell-like split: whitespace separates, '…' and "…" quote.
fn split_args(s: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut cur = String::new();
    let mut quote: Option<char> = None;
    let mut any = false;
    for c in s.chars() {
        match quote {
            Some(q) if c == q => quote = None,
            Some(_) => cur.push(c),
            None if c == '\'' || c == '"' => {
                quote = Some(c);
                any = true;
            }
            None if c.is_whitespace() => {
                if any || !cur.is_empty() {
                    out.push(std::mem::take(&mut cur));
                }
                any = false;
            }
            None => cur.push(c),
        }
    }
    if any || !cur.is_empty() {
        out.push(cur);
    }
    out
}

/// Why a recorded command would not run today as written (None: it does). `full`: the whole
/// line must parse (a recorded command line); otherwise (a command named in prose, such as
/// "`momentlab recommend --tolerance`") only its subcommands and flag names must exist.
fn dead(command: &str, full: bool) -> Option<String> {
    let mut args = split_args(command);
    if args.is_empty() {
        return Some("empty command".into());
    }
    args[0] = "momentlab".into();
    if args.len() > 1
        && !args[1].starts_with('-')
        && crate::cli::Cli::command()
            .find_subcommand(&args[1])
            .is_none()
    {
        return Some(format!("no subcommand '{}'", args[1]));
    }
    if let Err(e) = crate::cli::Cli::try_parse_from(&args) {
        if !full {
            return flags_dead(&args);
        }
        use clap::error::ErrorKind::*;
        if !matches!(e.kind(), DisplayHelp | DisplayVersion) {
            return Some(e.to_string().lines().next().unwrap_or("").to_string());
        }
    }
    flags_dead(&args)
}

/// A flag of `args` that is not a visible long name of its subcommand.
fn flags_dead(args: &[String]) -> Option<String> {
    let root = crate::cli::Cli::command();
    let mut cmd = &root;
    for a in &args[1..] {
        match cmd.find_subcommand(a) {
            Some(c) => cmd = c,
            None => break,
        }
    }
    for a in args.iter().skip(1).filter(|a| a.starts_with("--")) {
        let name = a[2..].split('=').next().unwrap();
        if name.is_empty() || name == "help" || name == "version" {
            continue;
        }
        let visible = cmd.get_arguments().any(|arg| {
            arg.get_long() == Some(name)
                || arg.get_visible_aliases().is_some_and(|v| v.contains(&name))
        });
        if !visible {
            return Some(format!(
                "--{name} is not a visible flag of '{}'",
                cmd.get_name()
            ));
        }
    }
    None
}

/// A momentlab command line (another tool's, such as `cargo test`, is not checked here).
fn is_command(s: &str) -> bool {
    let first = s.split_whitespace().next().unwrap_or("");
    first == "momentlab" || first.ends_with("/momentlab")
}

/// Command lines in an artefact's text: (command, recorded as run).
fn commands(path: &Path, text: &str) -> Vec<(String, bool)> {
    let mut out = Vec::new();
    let ext = path.extension().and_then(|e| e.to_str()).unwrap_or("");
    if ext == "json" {
        fn walk(v: &serde_json::Value, out: &mut Vec<(String, bool)>) {
            match v {
                serde_json::Value::Object(m) => {
                    for (k, x) in m {
                        match (k.as_str(), x) {
                            ("command", serde_json::Value::String(s)) if is_command(s) => {
                                out.push((s.clone(), true))
                            }
                            ("command", serde_json::Value::String(_)) => {}
                            _ => walk(x, out),
                        }
                    }
                }
                serde_json::Value::Array(a) => a.iter().for_each(|x| walk(x, out)),
                _ => {}
            }
        }
        if let Ok(v) = serde_json::from_str::<serde_json::Value>(text) {
            walk(&v, &mut out);
        }
        return out;
    }
    for (open, close) in [("`", "`"), ("<code>", "</code>")] {
        let mut rest = text;
        while let Some(p) = rest.find(open) {
            let after = &rest[p + open.len()..];
            let Some(e) = after.find(close) else { break };
            let span = after[..e]
                .replace("&lt;", "<")
                .replace("&gt;", ">")
                .replace("&quot;", "\"")
                .replace("&#39;", "'")
                .replace("&amp;", "&");
            if is_command(&span) {
                // A command with a path to the binary was copied from a shell: recorded.
                let recorded = !span.starts_with("momentlab ");
                out.push((span, recorded));
            }
            rest = &after[e + close.len()..];
        }
    }
    // The report's provenance row: "| command | momentlab … |" or <td>command</td><td>…</td>.
    for line in text.lines() {
        if let Some(r) = line.strip_prefix("| command | ") {
            out.push((r.trim_end_matches(" |").to_string(), true));
        }
    }
    let mut rest = text;
    while let Some(p) = rest.find("<td>command</td><td>") {
        let after = &rest[p + "<td>command</td><td>".len()..];
        let e = after.find("</td>").unwrap_or(after.len());
        out.push((
            after[..e]
                .replace("&#39;", "'")
                .replace("&quot;", "\"")
                .replace("&amp;", "&"),
            true,
        ));
        rest = &after[e..];
    }
    out
}

/// Every finding in the text artefacts under `dir`.
fn scan(dir: &Path) -> Vec<String> {
    let mut bad = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                stack.push(p);
                continue;
            }
            let ext = p.extension().and_then(|e| e.to_str()).unwrap_or("");
            if !matches!(
                ext,
                "json" | "md" | "html" | "csv" | "glsl" | "hlsl" | "wgsl"
            ) {
                continue;
            }
            let text = std::fs::read_to_string(&p).unwrap_or_default();
            let rel = p.strip_prefix(dir).unwrap_or(&p).display().to_string();
            if text.contains("/tmp/") {
                bad.push(format!("{rel}: names a /tmp path"));
            }
            for (c, full) in commands(&p, &text) {
                if let Some(why) = dead(&c, full) {
                    bad.push(format!("{rel}: `{c}`: {why}"));
                }
            }
        }
    }
    bad.sort();
    bad
}

#[test]
fn committed_artefacts_record_live_commands_and_no_tmp_paths() {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("reports");
    let bad = scan(&root);
    assert!(
        bad.is_empty(),
        "stale artefacts under reports/:\n{}",
        bad.join("\n")
    );
}

#[test]
fn the_scanner_finds_planted_dead_flags_and_tmp_paths() {
    let dir = crate::common::tmp_path("artefacts");
    std::fs::create_dir_all(dir.join("theta")).unwrap();
    let w = |f: &str, s: &str| std::fs::write(dir.join(f), s).unwrap();
    // Live commands: no finding.
    w(
        "theta/ok.json",
        r#"{"command": "momentlab theta --basis 'sin(2πz),cos(2πz)' --restarts 4", "x": 1}"#,
    );
    w(
        "ok.md",
        "Run `momentlab candidates count --m 4` here; see `momentlab recommend --tolerance`.\n",
    );
    // Another tool's command (scripts/time-tests.sh records `cargo test --release`).
    w(
        "wall.json",
        r#"{"command": "cargo test --release", "seconds": 1}"#,
    );
    assert_eq!(scan(&dir), Vec::<String>::new());
    // Planted: a removed flag, a /tmp path, an unknown subcommand.
    w(
        "theta/dead.json",
        r#"{"command": "./target/release/momentlab theta --moments 2 --output reports/theta/theta2.json"}"#,
    );
    w("tmp.md", "Mean over 12 views (/tmp/t16/stacks512).\n");
    w(
        "prose.md",
        "Keep more with `momentlab search --max-keep 9`.\n",
    );
    w(
        "index.html",
        "<table><tr><td>command</td><td>momentlab frobnicate --now</td></tr></table>",
    );
    let bad = scan(&dir);
    assert_eq!(bad.len(), 4, "{bad:#?}");
    assert!(
        bad.iter()
            .any(|b| b.starts_with("prose.md") && b.contains("--max-keep")),
        "{bad:#?}"
    );
    assert!(
        bad.iter()
            .any(|b| b.starts_with("theta/dead.json") && b.contains("--output")),
        "{bad:#?}"
    );
    assert!(
        bad.iter()
            .any(|b| b.starts_with("tmp.md") && b.contains("/tmp")),
        "{bad:#?}"
    );
    assert!(
        bad.iter()
            .any(|b| b.starts_with("index.html") && b.contains("frobnicate")),
        "{bad:#?}"
    );
    std::fs::remove_dir_all(&dir).ok();
}
