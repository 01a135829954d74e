//! Where a report or artefact comes from: crate version, git commit of the build, CPU model,
//! worker threads, UTC date and the command line that ran.

use serde::Serialize;

/// The git commit the binary was built from (`build.rs`; "unknown" outside a git checkout).
pub const COMMIT: &str = env!("MOMENTLAB_GIT_COMMIT");

/// The provenance of one run.
#[derive(Clone, Debug, Serialize)]
pub struct Provenance {
    /// momentlab's version (Cargo.toml).
    pub version: String,
    /// The git commit of the build ([`COMMIT`]).
    pub commit: String,
    /// CPU model name from /proc/cpuinfo.
    pub cpu: String,
    /// Worker threads of the run.
    pub threads: usize,
    /// UTC, `YYYY-MM-DD HH:MM`.
    pub date: String,
    /// The command line of the run.
    pub command: String,
}

impl Provenance {
    /// The provenance of this process, now.
    pub fn current() -> Provenance {
        let secs = std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map_or(0, |d| d.as_secs());
        Provenance {
            version: env!("CARGO_PKG_VERSION").to_string(),
            commit: COMMIT.to_string(),
            cpu: cpu_model(
                &crate::artefact::read_text(
                    std::path::Path::new("/proc/cpuinfo"),
                    crate::artefact::Limit::CONFIG,
                )
                .unwrap_or_default(),
            ),
            threads: rayon::current_num_threads(),
            date: utc_date(secs),
            command: command_line(),
        }
    }

    /// One line: "momentlab 0.1.0, commit …, `command`".
    pub fn line(&self) -> String {
        format!(
            "momentlab {} (commit {}); command `{}`",
            self.version, self.commit, self.command
        )
    }

    /// (field, value) rows for a table.
    pub fn rows(&self) -> Vec<Vec<String>> {
        vec![
            vec!["momentlab".into(), self.version.clone()],
            vec!["git commit".into(), self.commit.clone()],
            vec!["command".into(), self.command.clone()],
            vec!["CPU".into(), self.cpu.clone()],
            vec!["threads".into(), self.threads.to_string()],
            vec!["date (UTC)".into(), self.date.clone()],
        ]
    }
}

/// The command line of this process with the program named `momentlab` (not the path of the
/// binary, which may be a temporary copy); arguments with spaces are quoted.
pub fn command_line() -> String {
    command_of(std::env::args().skip(1))
}

/// `momentlab` followed by `args`, quoting those that contain spaces or are empty.
pub fn command_of(args: impl IntoIterator<Item = String>) -> String {
    let mut s = String::from("momentlab");
    for a in args {
        s.push(' ');
        if a.is_empty() || a.contains(char::is_whitespace) {
            s.push('\'');
            s.push_str(&a);
            s.push('\'');
        } else {
            s.push_str(&a);
        }
    }
    s
}

/// The first `model name` of a /proc/cpuinfo text ("unknown" when there is none).
pub fn cpu_model(cpuinfo: &str) -> String {
    cpuinfo
        .lines()
        .find_map(|l| {
            let (k, v) = l.split_once(':')?;
            (k.trim() == "model name").then(|| v.trim().to_string())
        })
        .filter(|v| !v.is_empty())
        .unwrap_or_else(|| "unknown".into())
}

/// `YYYY-MM-DD HH:MM` (UTC) of a Unix time: days to the proleptic Gregorian calendar by
/// H. Hinnant's `civil_from_days`.
pub fn utc_date(unix_secs: u64) -> String {
    let days = (unix_secs / 86_400) as i64;
    let rem = unix_secs % 86_400;
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = doy - (153 * mp + 2) / 5 + 1;
    let m = if mp < 10 { mp + 3 } else { mp - 9 };
    let y = yoe + era * 400 + i64::from(m <= 2);
    format!(
        "{y:04}-{m:02}-{d:02} {:02}:{:02}",
        rem / 3600,
        (rem % 3600) / 60
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dates_match_known_unix_times() {
        assert_eq!(utc_date(0), "1970-01-01 00:00");
        assert_eq!(utc_date(951_782_400), "2000-02-29 00:00");
        assert_eq!(utc_date(1_700_000_000), "2023-11-14 22:13");
        assert_eq!(utc_date(4_107_542_399), "2100-02-28 23:59");
        // Every day boundary over 400 years: the date advances by exactly one day.
        let mut prev = utc_date(0);
        for d in 1..146_097u64 {
            let cur = utc_date(d * 86_400);
            assert!(cur > prev, "{prev} then {cur}");
            assert!(cur.ends_with("00:00"));
            prev = cur;
        }
    }

    #[test]
    fn cpu_model_and_command_line() {
        let info = "processor\t: 0\nvendor_id\t: X\nmodel name\t: Some CPU @ 2.0GHz\n";
        assert_eq!(cpu_model(info), "Some CPU @ 2.0GHz");
        assert_eq!(cpu_model("processor : 0\n"), "unknown");
        assert_eq!(
            command_of(["theta".into(), "--basis".into(), "a, b".into()]),
            "momentlab theta --basis 'a, b'"
        );
        let p = Provenance::current();
        assert!(p.threads >= 1);
        assert!(p.command.starts_with("momentlab"));
        assert!(!p.commit.is_empty());
    }
}
