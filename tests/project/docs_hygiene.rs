//! README.md and docs/ describe the tool as it is: no dates, clock times, commit hashes or
//! machine loads (run logs and history belong in CHANGELOG.md). The scanner is checked on
//! planted lines.

use std::path::PathBuf;

const MONTHS: [&str; 12] = [
    "Jan", "Feb", "Mar", "Apr", "May", "Jun", "Jul", "Aug", "Sep", "Oct", "Nov", "Dec",
];

fn words(line: &str) -> Vec<&str> {
    line.split(|c: char| !(c.is_ascii_alphanumeric() || c == '_'))
        .filter(|w| !w.is_empty())
        .collect()
}

fn is_day(w: &str) -> bool {
    w.len() <= 2 && w.parse::<u32>().is_ok_and(|d| (1..=31).contains(&d))
}

fn is_month(w: &str) -> bool {
    MONTHS.iter().any(|m| {
        w.starts_with(m) && w.len() >= 3 && {
            let full = [
                "January",
                "February",
                "March",
                "April",
                "May",
                "June",
                "July",
                "August",
                "September",
                "October",
                "November",
                "December",
            ];
            w.len() == 3 || full.contains(&w)
        }
    })
}

/// What in `line` looks like a run log: a date, a clock time, a commit hash, a machine load.
fn findings(line: &str) -> Vec<String> {
    let mut out = Vec::new();
    let lower = line.to_lowercase();
    for phrase in ["load average", "utc"] {
        if words(&lower).contains(&phrase) || (phrase.contains(' ') && lower.contains(phrase)) {
            out.push(format!("'{phrase}'"));
        }
    }
    let w = words(line);
    for k in 0..w.len() {
        // "Dec 3", "3 December"
        if is_month(w[k]) && (w.get(k + 1).is_some_and(|d| is_day(d)) || k > 0 && is_day(w[k - 1]))
        {
            out.push(format!("date '{}'", w[k]));
        }
        // commit hashes: 7–40 hex digits with at least one letter and one digit
        let t = w[k];
        if (7..=40).contains(&t.len())
            && t.chars()
                .all(|c| c.is_ascii_hexdigit() && !c.is_ascii_uppercase())
            && t.chars().any(|c| c.is_ascii_digit())
            && t.chars().any(|c| c.is_ascii_alphabetic())
        {
            out.push(format!("hash '{t}'"));
        }
    }
    // ISO dates 20YY-MM-DD and clock times HH:MM
    let b = line.as_bytes();
    for i in 0..b.len() {
        let digits =
            |r: std::ops::Range<usize>| r.clone().all(|j| j < b.len() && b[j].is_ascii_digit());
        let before_ok = i == 0 || !b[i - 1].is_ascii_digit();
        if before_ok
            && digits(i..i + 4)
            && b.get(i + 4) == Some(&b'-')
            && digits(i + 5..i + 7)
            && b.get(i + 7) == Some(&b'-')
            && digits(i + 8..i + 10)
        {
            out.push("ISO date".into());
        }
        // HH:MM, but not part of a duration H:MM:SS (Slurm's --time=02:00:00).
        if before_ok
            && (i == 0 || b[i - 1] != b':')
            && digits(i..i + 2)
            && b.get(i + 2) == Some(&b':')
            && digits(i + 3..i + 5)
            && !b.get(i + 5).is_some_and(|c| c.is_ascii_digit())
            && !(b.get(i + 5) == Some(&b':') && b.get(i + 6).is_some_and(|c| c.is_ascii_digit()))
        {
            out.push("clock time".into());
        }
    }
    out
}

#[test]
fn readme_and_docs_hold_no_run_logs() {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let mut files = vec![root.join("README.md")];
    for e in std::fs::read_dir(root.join("docs")).unwrap() {
        let p = e.unwrap().path();
        if p.extension().is_some_and(|x| x == "md") {
            files.push(p);
        }
    }
    let mut bad = Vec::new();
    for f in &files {
        for (n, line) in std::fs::read_to_string(f).unwrap().lines().enumerate() {
            let found = findings(line);
            if !found.is_empty() {
                bad.push(format!(
                    "{}:{}: {} — {line}",
                    f.strip_prefix(&root).unwrap().display(),
                    n + 1,
                    found.join(", ")
                ));
            }
        }
    }
    assert!(
        bad.is_empty(),
        "run logs in README/docs (history goes to CHANGELOG.md):\n{}",
        bad.join("\n")
    );
}

#[test]
fn the_scanner_finds_planted_run_logs_and_passes_plain_text() {
    for planted in [
        "measured Dec 3 on the shared machine",
        "on 22 Nov the ns column",
        "at 17:48 UTC",
        "commit 0a6c12d",
        "the final main e4d6b3f",
        "load average ≈ 13",
        "run of 2026-12-02",
        "took until 11:58",
        "(09:32: 36 exact)",
    ] {
        assert!(!findings(planted).is_empty(), "missed: {planted}");
    }
    for plain in [
        "The candidate index 66045 of C(37,4)",
        "theta_ad920539.json holds the basis",
        "exp(-10(z-0.5)^2) and 1e-9 tolerances",
        "the LP decides; May the grid be fine",
        "ratio 3:1 of the decimation",
        "a window of 9×9 taps, deadbeef",
        "sbatch --time=02:00:00 -- \\",
    ] {
        assert!(
            findings(plain).is_empty(),
            "false alarm on: {plain}: {:?}",
            findings(plain)
        );
    }
}

/// Phrases of a lab notebook: A/B logs, tried-and-dropped lists, superseded runs, before/after
/// figures. Their place is CHANGELOG.md.
const NOTEBOOK: [&str; 9] = [
    "tried and dropped",
    "a/b",
    "before →",
    "before ->",
    "superseded",
    "alternating runs",
    "alternated twice",
    "earlier versions of",
    "was tried and",
];

fn notebook_findings(line: &str) -> Vec<&'static str> {
    let lower = line.to_lowercase();
    // A phrase counts as words: not inside a longer word or path ("basis/b…" is not "A/B").
    let whole = |p: &str| {
        lower.match_indices(p).any(|(i, _)| {
            let before = lower[..i].chars().next_back();
            let after = lower[i + p.len()..].chars().next();
            !before.is_some_and(|c| c.is_alphanumeric() || c == '/')
                && !after.is_some_and(|c| c.is_alphanumeric() || c == '/')
        })
    };
    NOTEBOOK.iter().copied().filter(|p| whole(p)).collect()
}

fn doc_files() -> Vec<PathBuf> {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let mut files = vec![root.join("README.md")];
    for e in std::fs::read_dir(root.join("docs")).unwrap() {
        let p = e.unwrap().path();
        if p.extension().is_some_and(|x| x == "md") {
            files.push(p);
        }
    }
    files.sort();
    files
}

#[test]
fn readme_and_docs_hold_no_lab_notebook() {
    let mut bad = Vec::new();
    for f in doc_files() {
        for (n, line) in std::fs::read_to_string(&f).unwrap().lines().enumerate() {
            let found = notebook_findings(line);
            if !found.is_empty() {
                bad.push(format!("{}:{}: {found:?} — {line}", f.display(), n + 1));
            }
        }
    }
    assert!(
        bad.is_empty(),
        "lab-notebook text in README/docs (history goes to CHANGELOG.md):\n{}",
        bad.join("\n")
    );
}

#[test]
fn the_notebook_scanner_finds_planted_logs() {
    for planted in [
        "Tried and dropped: a composite phase 1",
        "two A/B pairs gave 55.8 µs",
        "flat n = 4096 mean before → after",
        "figures that were superseded",
        "three alternating runs of the command",
    ] {
        assert!(!notebook_findings(planted).is_empty(), "missed: {planted}");
    }
    for plain in [
        "the band solve restricts the LP",
        "a before/after picture",
        "θ of reports/theta/basis, the f32",
    ] {
        assert!(notebook_findings(plain).is_empty(), "false alarm: {plain}");
    }
}

/// Every `momentlab …` command of README and docs/: inline code spans, and lines of fenced code
/// blocks (with `\` continuations, shell comments and pipes cut). Usage synopses with
/// `[optional]` parts are not command lines and are skipped.
fn documented_commands(text: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut fenced = false;
    let mut pending = String::new();
    for line in text.lines() {
        if line.trim_start().starts_with("```") {
            fenced = !fenced;
            pending.clear();
            continue;
        }
        if fenced {
            let l = line.trim();
            let l = if pending.is_empty() {
                l.strip_prefix("cargo run --release -- ")
                    .map(|x| format!("momentlab {x}"))
                    .unwrap_or_else(|| l.to_string())
            } else {
                l.to_string()
            };
            if pending.is_empty() && !l.starts_with("momentlab ") {
                continue;
            }
            // A shell comment starts at " #".
            let l = l.split(" #").next().unwrap().trim_end().to_string();
            if let Some(cont) = l.strip_suffix('\\') {
                pending.push_str(cont);
                pending.push(' ');
                continue;
            }
            pending.push_str(&l);
            out.push(std::mem::take(&mut pending));
            continue;
        }
        let mut rest = line;
        while let Some(i) = rest.find("`momentlab ") {
            let after = &rest[i + 1..];
            let Some(e) = after.find('`') else { break };
            out.push(after[..e].to_string());
            rest = &after[e + 1..];
        }
    }
    out.into_iter()
        .map(|c| {
            let c = c.split(" | ").next().unwrap();
            let c = c.split(" && ").next().unwrap();
            let c = c.split(" > ").next().unwrap();
            c.trim().to_string()
        })
        // Synopses with [optional] parts, and bare command names in prose, are not command lines.
        .filter(|c| !c.contains('[') && c.split_whitespace().count() > 2)
        .collect()
}

/// The arguments of a documented command, placeholders (`DIR`, `M`, `FILES…`, `$s`) replaced
/// by a value every argument accepts at parse time.
fn command_args(cmd: &str) -> Vec<String> {
    crate::docs_figures::shell_words(cmd)
        .into_iter()
        .filter(|w| w != "…")
        .map(|w| {
            let placeholder = w.starts_with('$')
                || (w.chars().any(|c| c.is_ascii_uppercase())
                    && w.chars()
                        .all(|c| c.is_ascii_uppercase() || c.is_ascii_digit() || "_…".contains(c)));
            if placeholder {
                "1".to_string()
            } else {
                w
            }
        })
        .collect()
}

/// Parse a documented command with today's CLI; `--help` and `--version` count as parsed.
fn parse(cmd: &str) -> Result<(), clap::Error> {
    use clap::Parser;
    match crate::cli::Cli::try_parse_from(command_args(cmd)) {
        Ok(_) => Ok(()),
        Err(e)
            if matches!(
                e.kind(),
                clap::error::ErrorKind::DisplayHelp | clap::error::ErrorKind::DisplayVersion
            ) =>
        {
            Ok(())
        }
        Err(e) => Err(e),
    }
}

#[test]
fn every_documented_command_parses_with_todays_cli() {
    let mut bad = Vec::new();
    let mut count = 0;
    for f in doc_files() {
        for cmd in documented_commands(&std::fs::read_to_string(&f).unwrap()) {
            count += 1;
            if let Err(e) = parse(&cmd) {
                let first = e.to_string();
                let first = first.lines().next().unwrap_or("").to_string();
                bad.push(format!("{}: `{cmd}`: {first}", f.display()));
            }
        }
    }
    assert!(count >= 40, "only {count} documented commands found");
    assert!(
        bad.is_empty(),
        "documented commands that today's CLI rejects:\n{}",
        bad.join("\n")
    );
}

#[test]
fn an_invalid_flag_in_a_documented_command_is_found() {
    let text = "Run `momentlab evaluate --pictures DIR` and\n```sh\nmomentlab theta --m 6 \\\n  --restarts 200   # θ₆\n```\n";
    let cmds = documented_commands(text);
    assert_eq!(
        cmds,
        vec![
            "momentlab evaluate --pictures DIR".to_string(),
            "momentlab theta --m 6  --restarts 200".to_string()
        ]
    );
    assert!(parse(&cmds[0]).is_err());
    assert!(parse(&cmds[1]).is_ok());
    assert!(parse("momentlab shadow --help").is_ok());
}

/// Where `text` shows the LP solver API as it is not: a `make_solver(` whose first argument is
/// a string (solvers are named by `lp::SolverKind`), or a `SolverKind::…` that is no variant.
fn solver_api_findings(text: &str) -> Vec<String> {
    let variants: Vec<String> = momentlab::lp::SolverKind::ALL
        .iter()
        .map(|k| format!("{k:?}"))
        .collect();
    let mut out = Vec::new();
    for (at, _) in text.match_indices("make_solver(") {
        if text[at + "make_solver(".len()..]
            .trim_start()
            .starts_with('"')
        {
            let end = text[at..].find(')').map_or(text.len(), |e| at + e + 1);
            out.push(text[at..end].to_string());
        }
    }
    for (at, _) in text.match_indices("SolverKind::") {
        let name: String = text[at + "SolverKind::".len()..]
            .chars()
            .take_while(|c| c.is_alphanumeric() || *c == '_')
            .collect();
        if !variants.contains(&name) && name != "ALL" {
            out.push(format!("SolverKind::{name}"));
        }
    }
    out
}

#[test]
fn readme_and_docs_show_the_solver_api_as_it_is() {
    let mut bad = Vec::new();
    for f in doc_files() {
        for x in solver_api_findings(&std::fs::read_to_string(&f).unwrap()) {
            bad.push(format!("{}: {x}", f.display()));
        }
    }
    assert!(
        bad.is_empty(),
        "README/docs show an LP solver API that is not today's (make_solver takes a SolverKind):\n{}",
        bad.join("\n")
    );
    assert_eq!(
        solver_api_findings(
            "`make_solver( \"fast\", t)`, `SolverKind::Strict`; fine: \
             `lp::make_solver(SolverKind::Fast, table)`, `SolverKind::Reference`"
        ),
        vec!["make_solver( \"fast\", t)", "SolverKind::Strict"]
    );
}
