//! Which candidates a run scores: the selection (`--candidates` or every m-subset), and the
//! flags that exclude some from solving (degenerate on the grid, or a duplicate span whose
//! representative is part of the run). Shared by the sweep and its plan (`search --plan`).

use super::config::SweepConfig;
use super::span::{Flag, SpanAnalyzer};
use super::Scorer;
use crate::basis::candidates as bc;
use anyhow::Result;
use rayon::prelude::*;
use std::collections::BTreeSet;

/// The `(index, subset)` pairs of a run before sharding: `cfg.candidates` (sorted, each once)
/// or every m-subset of the catalog.
pub fn selected(cfg: &SweepConfig) -> Result<Vec<(u64, Vec<usize>)>> {
    let nf = cfg.functions.len();
    Ok(match &cfg.candidates {
        None => all_subsets(nf, cfg.m),
        Some(list) => {
            let set: BTreeSet<u64> = list.iter().copied().collect();
            set.into_iter()
                .map(|i| Ok((i, bc::index_to_subset(nf, cfg.m, i)?)))
                .collect::<Result<_>>()?
        }
    })
}

/// `(degenerate, duplicate_of)` of each candidate of `cands`. Degenerate: the basis module's
/// check (σ_min/σ_max of the normalised [1, b] on the grid) or ours (Gram–Schmidt residual);
/// duplicates: the exact span comparison of [`super::span`], kept only when the representative
/// is in `in_run` (otherwise the candidate is scored itself).
pub fn flags(
    scorer: &Scorer,
    cands: &[(u64, Vec<usize>)],
    in_run: &BTreeSet<u64>,
    tol: f64,
) -> Result<Vec<(bool, Option<u64>)>> {
    let spans = SpanAnalyzer::new(scorer.table(), tol);
    let n_grid = scorer.table().grid().len();
    cands
        .par_iter()
        .map(|(_, c)| {
            let gt = scorer.table().grid_table(c)?;
            let info = bc::analyze_values(n_grid, c.len(), gt.values());
            if info.degenerate {
                return Ok((true, None));
            }
            Ok(match spans.flag(c) {
                Flag::Ok => (false, None),
                Flag::Degenerate => (true, None),
                Flag::DuplicateOf(rep) => {
                    let r = bc::subset_to_index(&rep)?;
                    (false, in_run.contains(&r).then_some(r))
                }
            })
        })
        .collect()
}

/// All `(index, subset)` pairs of m-subsets of 0..n in the catalog's colex order
/// ([`bc::next_subset`]: the index is the position in this enumeration).
pub fn all_subsets(n: usize, m: usize) -> Vec<(u64, Vec<usize>)> {
    let mut out = Vec::with_capacity(bc::count(n, m).min(1 << 24) as usize);
    if m == 0 || m > n {
        return out;
    }
    let mut c: Vec<usize> = (0..m).collect();
    let mut idx = 0u64;
    loop {
        out.push((idx, c.clone()));
        idx += 1;
        if !bc::next_subset(&mut c, n) {
            return out;
        }
    }
}
