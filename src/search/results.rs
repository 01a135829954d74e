//! Results files: one JSON line per candidate, appended and flushed per batch so that a run
//! killed at any moment (even mid-line) can be resumed ([`merge`](super::merge) combines shards).

use super::race::Elimination;
use anyhow::Result;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// The JSON helpers of [`crate::artefact`], re-exported for the sweep's files.
pub use crate::artefact::{append_jsonl, read_json, read_jsonl, write_json};

/// Name of the per-candidate results file inside a results directory.
pub const RESULTS_FILE: &str = "results.jsonl";
/// Name of the run configuration file.
pub const CONFIG_FILE: &str = "config.json";
/// Written when a run (or merge) has finished.
pub const COMPLETE_FILE: &str = "complete.json";
/// Written by `merge --allow-partial` instead of [`COMPLETE_FILE`] when shards or candidates are
/// missing: what is missing ([`crate::search::merge::Partial`]).
pub const PARTIAL_FILE: &str = "partial.json";
/// Written into a shard's directory by a batch task that failed (scripts/slurm/search-array.sh):
/// one line saying how and where; removed when the task starts again.
pub const FAILED_FILE: &str = "FAILED";

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
    /// Racing: why the candidate left (None: it survived, or an exhaustive run).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub eliminated: Option<Elimination>,
    /// Racing survivor: statistically tied for first (not shown worse than any candidate).
    #[serde(default)]
    pub tied: bool,
    /// The candidate the evidence compares with: the stage reference (eliminated candidates)
    /// or the winner (survivors).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub versus: Option<u64>,
    /// Paired difference error − error(versus) on the same fragments (error units: the same
    /// scale as `error`) and its standard error.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub diff: Option<f64>,
    /// Standard error of `diff`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub diff_se: Option<f64>,
    /// Eliminated: the look of stage `stage` that removed it (0: the first or only look, j: the
    /// j-th look after it, the last being the whole block) and the one-sided lower confidence bound of `diff` at
    /// the stage's δ that was above 0 (the evidence: diff ∈ [diff_lower, ∞)).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub look: Option<usize>,
    /// The one-sided lower confidence bound of `diff` that eliminated it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub diff_lower: Option<f64>,
    /// Racing survivor when the LP budget ended the race: neither eliminated nor completed.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub unresolved: bool,
    /// Estimate on the common sample (racing stage 0's block, the same fragments for every
    /// candidate of the run): error, its standard error and the fragments (Fig. 4).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub common_error: Option<f64>,
    /// Standard error of `common_error`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub common_stderr: Option<f64>,
    /// Fragments of the common sample (0: none).
    #[serde(default, skip_serializing_if = "is_zero")]
    pub common_fragments: u64,
}

fn is_zero(n: &u64) -> bool {
    *n == 0
}

impl Row {
    /// A row with no racing evidence (flags, exhaustive scores).
    pub fn plain(index: u64, functions: Vec<String>) -> Row {
        Row {
            index,
            functions,
            error: None,
            stderr: None,
            fragments: 0,
            degenerate: false,
            duplicate_of: None,
            seconds: 0.0,
            stage: 0,
            full: false,
            lp_failures: 0,
            eliminated: None,
            tied: false,
            versus: None,
            diff: None,
            diff_se: None,
            look: None,
            diff_lower: None,
            unresolved: false,
            common_error: None,
            common_stderr: None,
            common_fragments: 0,
        }
    }
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
