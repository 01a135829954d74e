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
