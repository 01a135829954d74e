//! `merge` of sharded runs: the results directories of the shards of one sweep into one.

use super::results::{
    append_jsonl, read_json, read_rows, write_json, Row, COMPLETE_FILE, CONFIG_FILE, FAILED_FILE,
    RESULTS_FILE,
};
use super::sweep::{SweepConfig, SweepSummary};
use anyhow::{bail, Context, Result};
use std::collections::BTreeSet;
use std::fs;
use std::path::{Path, PathBuf};

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
        check_not_failed(d)?;
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

/// Refuse a shard directory whose task recorded a failure, or that was never started.
fn check_not_failed(d: &Path) -> Result<()> {
    let failed = d.join(FAILED_FILE);
    if failed.exists() {
        let text = fs::read_to_string(&failed).unwrap_or_default();
        let why = text
            .lines()
            .find(|l| !l.trim().is_empty())
            .unwrap_or("no details");
        bail!(
            "merge: {} failed: {}; fix the cause and resubmit that task \
             (scripts/slurm/resubmit.sh, docs/search.md)",
            d.display(),
            why.trim()
        );
    }
    if !d.join(CONFIG_FILE).exists() {
        bail!(
            "merge: {} has no {CONFIG_FILE}: that shard never started \
             (not submitted, still pending, or failed before writing; check its log)",
            d.display()
        );
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn merge_refuses_failed_and_never_started_shards() {
        let root = std::env::temp_dir().join(format!("momentlab-merge-{}", std::process::id()));
        let (a, b) = (root.join("shard-0"), root.join("shard-1"));
        fs::create_dir_all(&a).unwrap();
        fs::create_dir_all(&b).unwrap();
        let out = root.join("merged");
        let e = merge_dirs(&[a.clone(), b.clone()], &out, false).unwrap_err();
        assert!(
            e.to_string().contains("shard-0 has no config.json")
                && e.to_string().contains("never started"),
            "{e}"
        );
        fs::write(
            b.join(FAILED_FILE),
            "\nshard 1/2: exit status 1 in Slurm job 7_1: error: unknown solver 'x'\n",
        )
        .unwrap();
        // The failure is reported even with --allow-partial, and before the missing config.
        for partial in [false, true] {
            let e = merge_dirs(&[b.clone(), a.clone()], &out, partial).unwrap_err();
            let e = e.to_string();
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
