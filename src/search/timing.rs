//! Where a sweep's time went: per racing stage and candidate family, the LPs solved, the mean
//! CPU µs per LP, the unsettled LPs and the share of all LP time, read from the per-candidate
//! statistics of the stage files (`stage{k}.jsonl` and the later looks' `stage{k}.look{j}.jsonl`:
//! fragments and CPU seconds per candidate).
//!
//! A candidate's family is its steepest exponential exp(c·z) (|c| ≥ 40, ≥ 20, smaller), else
//! "no exponential": the escalation to the double-double simplex concentrates in steep
//! exponentials (docs/lp.md).

use super::FunctionTable;
use crate::basis::candidates::index_to_subset;
use anyhow::{Context, Result};
use std::collections::BTreeMap;
use std::path::Path;

/// The family of a candidate from its function names.
pub fn family_of(names: &[String]) -> &'static str {
    let steepest = names.iter().filter_map(|n| exp_rate(n)).fold(0.0, f64::max);
    if steepest >= 40.0 {
        "exp(±40z)"
    } else if steepest >= 20.0 {
        "exp(±20z)"
    } else if steepest > 0.0 {
        "exp(c·z), |c| < 20"
    } else {
        "no exponential"
    }
}

/// |c| of a name of the form exp(cz) (c a signed number), e.g. "exp(-40z)" → 40.
fn exp_rate(name: &str) -> Option<f64> {
    let inner = name.strip_prefix("exp(")?.strip_suffix("z)")?;
    inner.parse::<f64>().ok().map(f64::abs)
}

/// One stage's time for one family.
#[derive(Clone, Debug, PartialEq)]
pub struct FamilyTime {
    /// "stage k".
    pub stage: String,
    /// The family ([`family_of`]).
    pub family: &'static str,
    /// Candidates of the family in the stage.
    pub candidates: u64,
    /// LPs solved (fragments × candidates).
    pub lps: u64,
    /// CPU seconds in the LPs.
    pub seconds: f64,
    /// LPs nothing certified (scored G = 0).
    pub failures: u64,
}

/// The fields of a stage row this table needs.
#[derive(serde::Deserialize)]
struct StageTime {
    index: u64,
    n: u64,
    seconds: f64,
    failures: u64,
}

/// The per-stage, per-family time of the sweep in `dir` with m functions per candidate from
/// `table`'s catalog; stages in order, families in a fixed order within each.
pub fn stage_family_times(dir: &Path, table: &FunctionTable, m: usize) -> Result<Vec<FamilyTime>> {
    let mut out = Vec::new();
    for k in 0.. {
        if !super::sweep::stage_file(dir, k, 0).exists() {
            break;
        }
        let mut by: BTreeMap<&'static str, FamilyTime> = BTreeMap::new();
        // The later looks' files hold the same candidates again (fewer): LPs and time add up,
        // candidates are counted once.
        for look in 0..=super::race::EARLY_LOOKS {
            let path = super::sweep::stage_file(dir, k, look);
            if !path.exists() {
                continue;
            }
            for row in crate::artefact::read_jsonl::<StageTime>(&path, false)? {
                let cols = index_to_subset(table.len(), m, row.index)
                    .with_context(|| format!("{}: candidate {}", path.display(), row.index))?;
                let family = family_of(&table.names_of(&cols));
                let e = by.entry(family).or_insert_with(|| FamilyTime {
                    stage: format!("stage {k}"),
                    family,
                    candidates: 0,
                    lps: 0,
                    seconds: 0.0,
                    failures: 0,
                });
                e.candidates += (look == 0) as u64;
                e.lps += row.n;
                e.seconds += row.seconds;
                e.failures += row.failures;
            }
        }
        out.extend(by.into_values());
    }
    Ok(out)
}

/// The table as text: stage, family, candidates, LPs, mean µs per LP, unsettled LPs, share of
/// all LP CPU time.
pub fn render(rows: &[FamilyTime]) -> String {
    let total: f64 = rows.iter().map(|r| r.seconds).sum();
    let mut s = format!(
        "{:<8} {:<20} {:>10} {:>13} {:>9} {:>10} {:>7}\n",
        "stage", "family", "candidates", "LPs", "mean µs", "unsettled", "share"
    );
    for r in rows {
        s += &format!(
            "{:<8} {:<20} {:>10} {:>13} {:>9.1} {:>10} {:>6.1}%\n",
            r.stage,
            r.family,
            r.candidates,
            r.lps,
            1e6 * r.seconds / r.lps.max(1) as f64,
            r.failures,
            100.0 * r.seconds / total.max(f64::MIN_POSITIVE)
        );
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn families_by_steepest_exponential() {
        let f = |v: &[&str]| family_of(&v.iter().map(|s| s.to_string()).collect::<Vec<_>>());
        assert_eq!(f(&["z", "exp(-40z)", "exp(5z)"]), "exp(±40z)");
        assert_eq!(f(&["z^2", "exp(20z)"]), "exp(±20z)");
        assert_eq!(f(&["exp(2z)", "sin(πz)"]), "exp(c·z), |c| < 20");
        // A Gaussian bump is not exp(c·z).
        assert_eq!(f(&["exp(-10(z-0.5)^2)", "z"]), "no exponential");
    }

    /// Stage files are read per stage, grouped by family; seconds and LPs add up, shares sum
    /// to 100 %.
    #[test]
    fn stage_files_grouped_by_family() {
        let grid = crate::Grid::uniform(5).unwrap();
        let names: Vec<String> = ["z", "exp(40z)", "exp(20z)"].map(String::from).to_vec();
        let table = FunctionTable::new(&grid, names, |_, z| z).unwrap();
        let dir = std::env::temp_dir().join(format!("momentlab-timing-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        // m = 2 candidates in colex order: 0 = {z, exp(40z)}, 1 = {z, exp(20z)},
        // 2 = {exp(40z), exp(20z)}.
        let row = |i: u64, n: u64, s: f64, f: u64| {
            format!("{{\"index\":{i},\"n\":{n},\"seconds\":{s},\"failures\":{f}}}\n")
        };
        let stage0 = row(0, 100, 0.004, 1) + &row(1, 100, 0.001, 0) + &row(2, 100, 0.003, 0);
        std::fs::write(dir.join("stage0.jsonl"), stage0).unwrap();
        std::fs::write(dir.join("stage1.jsonl"), row(1, 400, 0.002, 0)).unwrap();
        // A later look of stage 1: LPs and time add, the candidate once.
        std::fs::write(dir.join("stage1.look1.jsonl"), row(1, 400, 0.002, 0)).unwrap();
        let rows = stage_family_times(&dir, &table, 2).unwrap();
        std::fs::remove_dir_all(&dir).unwrap();
        assert_eq!(rows.len(), 3);
        let steep = rows
            .iter()
            .find(|r| r.stage == "stage 0" && r.family == "exp(±40z)");
        let steep = steep.unwrap();
        assert_eq!((steep.candidates, steep.lps, steep.failures), (2, 200, 1));
        assert!((steep.seconds - 0.007).abs() < 1e-15);
        let later = &rows[2];
        assert_eq!(
            (
                later.stage.as_str(),
                later.family,
                later.candidates,
                later.lps
            ),
            ("stage 1", "exp(±20z)", 1, 800)
        );
        let text = render(&rows);
        assert!(text.contains("35.0") && text.contains("58.3%"), "{text}");
    }
}
