//! `merge` of sharded runs: the results directories of the shards of one sweep into one.

use super::config::SweepConfig;
use super::results::{
    read_json, read_rows, Row, COMPLETE_FILE, CONFIG_FILE, FAILED_FILE, PARTIAL_FILE, RESULTS_FILE,
};
use super::sweep::SweepSummary;
use crate::artefact::{read_bytes, Limit, OutDir};
use anyhow::{bail, Context, Result};
use serde::{Deserialize, Serialize};
use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

/// A results directory checked to be whole: its configuration, its rows, and whether it is
/// complete.
pub struct Verified {
    /// The run's configuration.
    pub config: SweepConfig,
    /// Its rows.
    pub rows: Vec<Row>,
    /// Whether the run finished (its completion marker is present).
    pub complete: bool,
}

/// Check the results directory `d` before its rows are trusted (by `merge` and by
/// `search --report-only` alike): the rows file has no torn last line, no candidate twice, and
/// only candidates of its shard; a directory with its completion marker has exactly as many
/// rows as the marker says. Without the marker: an error unless `allow_partial`.
pub fn verify_results(d: &Path, allow_partial: bool) -> Result<Verified> {
    check_not_failed(d)?;
    let config: SweepConfig = read_json(&d.join(CONFIG_FILE))?;
    let [i, n] = config.shard;
    let marker = d.join(COMPLETE_FILE);
    let complete = std::fs::symlink_metadata(&marker).is_ok();
    if !complete && !allow_partial {
        bail!(
            "{} (shard {i}/{n}) is not complete (no {COMPLETE_FILE}); rerun the search to \
             finish it (`momentlab merge --allow-partial` merges unfinished shards)",
            d.display()
        );
    }
    let rows_path = d.join(RESULTS_FILE);
    let rows: Vec<Row> = if std::fs::symlink_metadata(&rows_path).is_err() {
        if complete {
            bail!(
                "{} is marked complete but has no {RESULTS_FILE}",
                d.display()
            );
        }
        Vec::new()
    } else {
        let bytes = read_bytes(&rows_path, Limit::ROWS)?;
        if bytes.last().is_some_and(|&c| c != b'\n') {
            let line = bytes.iter().filter(|&&c| c == b'\n').count() + 1;
            bail!(
                "{}: line {line} is a torn row (the run was killed while writing); rerun that \
                 shard to repair it",
                rows_path.display()
            );
        }
        read_rows(d)?
    };
    let mut seen = BTreeSet::new();
    for r in &rows {
        if !seen.insert(r.index) {
            bail!(
                "{}: candidate {} appears twice (two runs wrote into one folder?)",
                rows_path.display(),
                r.index
            );
        }
        if n > 1 && r.index % n as u64 != i as u64 {
            bail!(
                "{}: candidate {} does not belong to shard {i}/{n}",
                rows_path.display(),
                r.index
            );
        }
    }
    if complete {
        let summary: SweepSummary = read_json(&marker)?;
        if summary.candidates != rows.len() as u64 {
            bail!(
                "{}: {} rows, but {COMPLETE_FILE} says {} candidates (rows lost or added after \
                 the run)",
                rows_path.display(),
                rows.len(),
                summary.candidates
            );
        }
    }
    Ok(Verified {
        config,
        rows,
        complete,
    })
}

/// What a merge lacks (`partial.json` of a partial merge; also in `merge --json`): the shards
/// not given, the shards given but unfinished, and the candidates of the sweep without a row.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Partial {
    /// Always true: the merged folder is not the whole sweep.
    pub partial: bool,
    /// Shard count N of the sweep.
    pub shards: usize,
    /// Shards i of 0..N not among the inputs.
    pub missing_shards: Vec<usize>,
    /// Shards given without their completion marker.
    pub incomplete_shards: Vec<usize>,
    /// Candidates of the sweep's selection (all shards).
    pub candidates: u64,
    /// Candidates of the sweep's selection with no row.
    pub missing_candidates: u64,
    /// The first [`Partial::LISTED`] of them, by index.
    pub missing_candidate_list: Vec<u64>,
}

impl Partial {
    /// How many missing candidate indices are listed.
    pub const LISTED: usize = 100;

    /// One line: "partial: shards 2/6, 5/6 missing; shard 1/6 unfinished; 12 of 40 candidates
    /// missing (3, 7, …)".
    pub fn line(&self) -> String {
        let n = self.shards;
        let list = |v: &[usize]| {
            v.iter()
                .map(|i| format!("{i}/{n}"))
                .collect::<Vec<_>>()
                .join(", ")
        };
        let mut parts = Vec::new();
        if !self.missing_shards.is_empty() {
            parts.push(format!("shards {} missing", list(&self.missing_shards)));
        }
        if !self.incomplete_shards.is_empty() {
            parts.push(format!(
                "shards {} unfinished",
                list(&self.incomplete_shards)
            ));
        }
        let mut idx: Vec<String> = self
            .missing_candidate_list
            .iter()
            .map(|i| i.to_string())
            .collect();
        if self.missing_candidates > self.missing_candidate_list.len() as u64 {
            idx.push("…".into());
        }
        parts.push(format!(
            "{} of {} candidates missing ({})",
            self.missing_candidates,
            self.candidates,
            idx.join(", ")
        ));
        format!("partial: {}", parts.join("; "))
    }
}

/// What [`merge_dirs`] wrote.
#[derive(Clone, Debug, PartialEq)]
pub struct Merged {
    /// Rows written.
    pub rows: usize,
    /// Candidates of the sweep's selection (all shards).
    pub candidates: u64,
    /// None: complete (`complete.json` written); else what is missing (`partial.json`).
    pub partial: Option<Partial>,
}

/// Merge the results directories of the shards of one sweep into `out`: every shard verified
/// ([`verify_results`]), the configs agree (except the shard), every shard 0..N is present
/// once, and no candidate appears twice; writes the rows sorted by index through the output
/// writer (existing files refused unless `force`). The completion marker `complete.json` is
/// written only when every shard is present and complete and every candidate of the selection
/// has its row; otherwise (`allow_partial`) `partial.json` names what is missing and no
/// completion marker exists in `out`.
pub fn merge_dirs(
    dirs: &[PathBuf],
    out: &Path,
    allow_partial: bool,
    force: bool,
) -> Result<Merged> {
    if dirs.is_empty() {
        bail!("merge: no input directories");
    }
    let od = OutDir::new(out, force).context("merge --out")?;
    od.reserve([CONFIG_FILE, RESULTS_FILE, COMPLETE_FILE, PARTIAL_FILE])
        .context("merge --out")?;
    // A folder that exists may be in use by another writer: refuse that first. A new one is
    // created (and locked) only after every shard passed.
    if std::fs::symlink_metadata(out).is_ok() {
        od.lock().context("merge --out")?;
    }
    let mut base: Option<SweepConfig> = None;
    let mut shards = BTreeSet::new();
    let mut incomplete = Vec::new();
    let mut count = None;
    let mut rows: Vec<Row> = Vec::new();
    for d in dirs {
        let v = verify_results(d, allow_partial).context("merge")?;
        let cfg = v.config;
        let [i, n] = cfg.shard;
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
        if !v.complete {
            incomplete.push(i);
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
        rows.extend(v.rows);
    }
    let n = count.unwrap();
    let missing_shards: Vec<usize> = (0..n).filter(|i| !shards.contains(i)).collect();
    if let Some(missing) = missing_shards.first() {
        if !allow_partial {
            bail!("merge: shard {missing}/{n} is missing");
        }
    }
    rows.sort_by_key(|r| r.index);
    if let Some(w) = rows.windows(2).find(|w| w[0].index == w[1].index) {
        bail!("merge: candidate {} appears twice", w[0].index);
    }
    let base = base.unwrap();
    let selection = super::select::selected(&base).context("merge: the sweep's candidates")?;
    let have: BTreeSet<u64> = rows.iter().map(|r| r.index).collect();
    let missing: Vec<u64> = selection
        .iter()
        .map(|c| c.0)
        .filter(|i| !have.contains(i))
        .collect();
    let partial = (!missing_shards.is_empty() || !incomplete.is_empty() || !missing.is_empty())
        .then(|| Partial {
            partial: true,
            shards: n,
            missing_shards,
            incomplete_shards: incomplete,
            candidates: selection.len() as u64,
            missing_candidates: missing.len() as u64,
            missing_candidate_list: missing.iter().take(Partial::LISTED).copied().collect(),
        });
    od.lock().context("merge --out")?;
    // Neither marker of an earlier merge into this folder (--force) may outlive this one.
    od.remove(COMPLETE_FILE)?;
    od.remove(PARTIAL_FILE)?;
    od.write_json(CONFIG_FILE, &base)?;
    let mut text = Vec::new();
    for r in &rows {
        serde_json::to_writer(&mut text, r)?;
        text.push(b'\n');
    }
    od.write(RESULTS_FILE, &text)?;
    match &partial {
        None => od.write_json(COMPLETE_FILE, &SweepSummary::merged(n, rows.len() as u64))?,
        Some(p) => od.write_json(PARTIAL_FILE, p)?,
    };
    Ok(Merged {
        rows: rows.len(),
        candidates: selection.len() as u64,
        partial,
    })
}

/// Refuse a shard directory whose task recorded a failure, or that was never started.
fn check_not_failed(d: &Path) -> Result<()> {
    let failed = d.join(FAILED_FILE);
    if failed.exists() {
        let text = crate::artefact::read_text(&failed, Limit::CONFIG).unwrap_or_default();
        let why = text
            .lines()
            .find(|l| !l.trim().is_empty())
            .unwrap_or("no details");
        bail!(
            "{} failed: {}; fix the cause and resubmit that task \
             (scripts/slurm/resubmit.sh, docs/search.md)",
            d.display(),
            why.trim()
        );
    }
    if !d.join(CONFIG_FILE).exists() {
        bail!(
            "{} has no {CONFIG_FILE}: that shard never started \
             (not submitted, still pending, or failed before writing; check its log)",
            d.display()
        );
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::fs;

    #[test]
    fn merge_refuses_failed_and_never_started_shards() {
        let root = std::env::temp_dir().join(format!("momentlab-merge-{}", std::process::id()));
        let (a, b) = (root.join("shard-0"), root.join("shard-1"));
        fs::create_dir_all(&a).unwrap();
        fs::create_dir_all(&b).unwrap();
        let out = root.join("merged");
        let e = format!(
            "{:#}",
            merge_dirs(&[a.clone(), b.clone()], &out, false, false).unwrap_err()
        );
        assert!(
            e.contains("shard-0 has no config.json") && e.contains("never started"),
            "{e}"
        );
        fs::write(
            b.join(FAILED_FILE),
            "\nshard 1/2: exit status 1 in Slurm job 7_1: error: unknown solver 'x'\n",
        )
        .unwrap();
        // The failure is reported even with --allow-partial, and before the missing config.
        for partial in [false, true] {
            let e = merge_dirs(&[b.clone(), a.clone()], &out, partial, false).unwrap_err();
            let e = format!("{e:#}");
            assert!(
                e.contains("shard-1 failed: shard 1/2: exit status 1"),
                "{e}"
            );
            assert!(
                e.contains("unknown solver 'x'") && e.contains("resubmit"),
                "{e}"
            );
        }
        assert!(!out.exists(), "nothing written");
        fs::remove_dir_all(&root).unwrap();
    }
}
