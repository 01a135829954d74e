//! Results files: one JSON line per candidate, appended and flushed per batch so that a run
//! killed at any moment (even mid-line) can be resumed; and `merge` of sharded runs.

use super::sweep::{SweepConfig, SweepSummary};
use anyhow::{bail, Context, Result};
use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};
use std::collections::BTreeSet;
use std::fs;
use std::io::Write;
use std::path::{Path, PathBuf};

/// Name of the per-candidate results file inside a results directory.
pub const RESULTS_FILE: &str = "results.jsonl";
/// Name of the run configuration file.
pub const CONFIG_FILE: &str = "config.json";
/// Written when a run (or merge) has finished.
pub const COMPLETE_FILE: &str = "complete.json";

/// One candidate's result.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Row {
    /// Candidate index (lexicographic rank of its function subset).
    pub index: u64,
    /// Function names b_1..b_m.
    pub functions: Vec<String>,
    /// Mean |G − PCF| over all fragments (trivial ones included) — exact when `full`, else
    /// estimated from the `fragments` non-trivial fragments sampled. None: not scored.
    pub error: Option<f64>,
    /// Standard error of `error` (sampling over fragments).
    pub stderr: Option<f64>,
    /// Non-trivial fragments solved for this candidate.
    pub fragments: u64,
    /// Numerically rank-deficient on the grid: not solved.
    pub degenerate: bool,
    /// Same span on the grid as this candidate index: scored there.
    pub duplicate_of: Option<u64>,
    /// Solver wall time (the only field that depends on timing).
    pub seconds: f64,
    /// Racing stage in which the candidate was eliminated (or the final stage).
    pub stage: usize,
    /// Scored on every fragment.
    pub full: bool,
    /// LPs that failed or were infeasible (counted as G = 0).
    pub lp_failures: u64,
}

/// Read a JSON-lines file. A last line without '\n' is a torn write: it is ignored and, with
/// `repair`, cut off the file. A missing file reads as empty.
pub fn read_jsonl<T: DeserializeOwned>(path: &Path, repair: bool) -> Result<Vec<T>> {
    let text = match fs::read(path) {
        Ok(t) => t,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(Vec::new()),
        Err(e) => return Err(e).with_context(|| format!("reading {}", path.display())),
    };
    let keep = text.iter().rposition(|&c| c == b'\n').map_or(0, |p| p + 1);
    if keep < text.len() && repair {
        let f = fs::OpenOptions::new()
            .write(true)
            .open(path)
            .with_context(|| format!("repairing {}", path.display()))?;
        f.set_len(keep as u64)
            .with_context(|| format!("repairing {}", path.display()))?;
    }
    let body = std::str::from_utf8(&text[..keep])
        .with_context(|| format!("{}: not UTF-8", path.display()))?;
    body.lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty())
        .map(|(i, l)| {
            serde_json::from_str(l)
                .with_context(|| format!("{}:{}: bad row", path.display(), i + 1))
        })
        .collect()
}

/// Append rows (one JSON line each) and flush.
pub fn append_jsonl<T: Serialize>(path: &Path, rows: &[T]) -> Result<()> {
    if rows.is_empty() {
        return Ok(());
    }
    let mut buf = Vec::new();
    for r in rows {
        serde_json::to_writer(&mut buf, r)?;
        buf.push(b'\n');
    }
    let mut f = fs::OpenOptions::new()
        .create(true)
        .append(true)
        .open(path)
        .with_context(|| format!("opening {}", path.display()))?;
    f.write_all(&buf)
        .and_then(|_| f.flush())
        .with_context(|| format!("writing {}", path.display()))
}

/// Write a JSON file atomically (temporary file + rename).
pub fn write_json<T: Serialize>(path: &Path, value: &T) -> Result<()> {
    let tmp = path.with_extension("tmp");
    fs::write(&tmp, serde_json::to_string_pretty(value)? + "\n")
        .with_context(|| format!("writing {}", tmp.display()))?;
    fs::rename(&tmp, path).with_context(|| format!("writing {}", path.display()))
}

/// Read a JSON file.
pub fn read_json<T: DeserializeOwned>(path: &Path) -> Result<T> {
    let text = fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
    serde_json::from_str(&text).with_context(|| format!("{}: invalid", path.display()))
}

/// The result rows of a results directory.
pub fn read_rows(dir: &Path) -> Result<Vec<Row>> {
    read_jsonl(&dir.join(RESULTS_FILE), false)
}

/// Rows sorted by error (scored ones only, duplicates resolved to their representative's
/// error; ties by index).
pub fn ranking(rows: &[Row]) -> Vec<Row> {
    let by_index: std::collections::HashMap<u64, &Row> =
        rows.iter().map(|r| (r.index, r)).collect();
    let mut out: Vec<Row> = rows
        .iter()
        .filter_map(|r| {
            let mut r = r.clone();
            if let Some(d) = r.duplicate_of {
                let rep = by_index.get(&d)?;
                r.error = rep.error;
                r.stderr = rep.stderr;
                r.full = rep.full;
            }
            r.error.map(|_| r)
        })
        .collect();
    out.sort_by(|a, b| {
        a.error
            .unwrap()
            .total_cmp(&b.error.unwrap())
            .then(a.index.cmp(&b.index))
    });
    out
}

/// Merge the results directories of the shards of one sweep into `out`: checks the configs
/// agree (except the shard), every shard 0..N is present once and complete, and no candidate
/// appears twice; writes the rows sorted by index. Returns the number of rows.
pub fn merge_dirs(dirs: &[PathBuf], out: &Path, allow_partial: bool) -> Result<usize> {
    if dirs.is_empty() {
        bail!("merge: no input directories");
    }
    let mut base: Option<SweepConfig> = None;
    let mut shards = BTreeSet::new();
    let mut count = None;
    let mut rows: Vec<Row> = Vec::new();
    for d in dirs {
        let cfg: SweepConfig = read_json(&d.join(CONFIG_FILE))?;
        let [i, n] = cfg.shard;
        if !d.join(COMPLETE_FILE).exists() && !allow_partial {
            bail!(
                "merge: {} (shard {i}/{n}) is not complete; rerun it or pass --allow-partial",
                d.display()
            );
        }
        if *count.get_or_insert(n) != n {
            bail!(
                "merge: {} is shard {i}/{n}, others are of {}",
                d.display(),
                count.unwrap()
            );
        }
        if !shards.insert(i) {
            bail!("merge: shard {i}/{n} given twice ({})", d.display());
        }
        let mut plain = cfg.clone();
        plain.shard = [0, 1];
        match &base {
            None => base = Some(plain),
            Some(b) => {
                if let Some(field) = b.first_difference(&plain) {
                    bail!(
                        "merge: {} was run with a different configuration ('{field}')",
                        d.display()
                    );
                }
            }
        }
        rows.extend(read_rows(d)?);
    }
    let n = count.unwrap();
    if let Some(missing) = (0..n).find(|i| !shards.contains(i)) {
        if !allow_partial {
            bail!("merge: shard {missing}/{n} is missing");
        }
    }
    rows.sort_by_key(|r| r.index);
    if let Some(w) = rows.windows(2).find(|w| w[0].index == w[1].index) {
        bail!("merge: candidate {} appears twice", w[0].index);
    }
    fs::create_dir_all(out).with_context(|| format!("creating {}", out.display()))?;
    let path = out.join(RESULTS_FILE);
    if path.exists() {
        bail!("merge: {} exists already", path.display());
    }
    write_json(&out.join(CONFIG_FILE), base.as_ref().unwrap())?;
    append_jsonl(&path, &rows)?;
    if shards.len() == n {
        write_json(
            &out.join(COMPLETE_FILE),
            &SweepSummary::merged(n, rows.len() as u64),
        )?;
    }
    Ok(rows.len())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn torn_last_line_is_dropped_and_repaired() {
        let dir = std::env::temp_dir().join(format!("momentlab-jsonl-{}", std::process::id()));
        fs::create_dir_all(&dir).unwrap();
        let p = dir.join("x.jsonl");
        let _ = fs::remove_file(&p);
        assert!(read_jsonl::<u32>(&p, true).unwrap().is_empty());
        append_jsonl(&p, &[1u32, 2, 3]).unwrap();
        fs::OpenOptions::new()
            .append(true)
            .open(&p)
            .unwrap()
            .write_all(b"4")
            .unwrap();
        assert_eq!(read_jsonl::<u32>(&p, false).unwrap(), vec![1, 2, 3]);
        assert_eq!(fs::read(&p).unwrap().len(), 7);
        assert_eq!(read_jsonl::<u32>(&p, true).unwrap(), vec![1, 2, 3]);
        assert_eq!(fs::read(&p).unwrap().len(), 6);
        fs::write(&p, "1\nx\n3\n").unwrap();
        let e = read_jsonl::<u32>(&p, true).unwrap_err();
        assert!(format!("{e:#}").contains("x.jsonl:2"), "{e:#}");
        fs::remove_dir_all(&dir).unwrap();
    }
}
