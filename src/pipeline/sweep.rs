//! Step 4: the candidate sweeps (racing) for each m of the plan, resumable through their
//! results folders `<results>/<run>/search-m<m>`; the report goes to `<reports>/<run>/search`.
//! A sweep that fails becomes a note in the report instead of stopping the study.

use super::progress::bar;
use super::Plan;
use crate::artefact::OutDir;
use crate::metrics::Bias;
use crate::report::sweep::{self as sweep_report, ReportOptions};
use crate::search::reference::ReferenceCache;
use crate::search::run::{ranking_lines, sweep_line};
use crate::search::{
    stacks_dataset, sweep_dataset, Dataset, FunctionTable, Progress, SweepOptions,
};
use crate::stack::DepthStack;
use anyhow::{Context, Result};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Where the sweeps read and write.
pub struct Folders<'a> {
    /// The stacks' folder (named in each sweep's configuration).
    pub stacks: &'a Path,
    /// `<results>/<run>`: one `search-m<m>` folder per m.
    pub data: &'a Path,
    /// The sweep report.
    pub report: &'a Path,
}

/// Run (or resume) the sweep for every m of the plan; returns one note per m for the report.
pub fn run_all(stacks: &[DepthStack], plan: &Plan, dirs: &Folders) -> Result<Vec<String>> {
    let mut notes = Vec::new();
    let mut compare: Vec<PathBuf> = Vec::new();
    // One dataset and one set of references for every m: neither depends on m.
    let mut data = Shared::default();
    let refs = ReferenceCache::new(Some(stacks));
    for &m in &plan.search_ms {
        let results = dirs.data.join(format!("search-m{m}"));
        let candidates = match (plan.search_subset, m >= 3) {
            (Some(k), true) => Some(subset(m, k)?),
            _ => None,
        };
        let opts = SweepOptions {
            m,
            max_fragments: (plan.search_max_fragments > 0).then_some(plan.search_max_fragments),
            dataset: format!("stacks:{}", dirs.stacks.display()),
            candidates,
            first_sample: plan.search_first_sample,
            ..SweepOptions::default()
        };
        let t0 = Instant::now();
        let done = data
            .get(stacks, &opts)
            .and_then(|(d, t)| sweep(d, t, &refs, &opts, &results, dirs.report, &compare));
        match done {
            Ok(()) => {
                let scope = match (plan.search_subset, m >= 3) {
                    (Some(k), true) => format!(
                        "a seeded subset of {k} candidates including the paper's bases \
                         (`--full` sweeps all C(37,{m}))"
                    ),
                    _ => format!("all C(37,{m}) candidates"),
                };
                notes.push(format!(
                    "m = {m}: {scope}, racing over at most {} non-trivial fragments, done in \
                     {:.0} s (results in {})",
                    plan.search_max_fragments,
                    t0.elapsed().as_secs_f64(),
                    results.display()
                ));
                compare.push(results);
            }
            Err(e) => notes.push(format!("m = {m}: not run: {e:#}")),
        }
    }
    Ok(notes)
}

/// The sweep's dataset and catalog table ([`stacks_dataset`]), built once for the sweeps of
/// every m (they share grid, bias, sample and catalog; rebuilt if those change).
#[derive(Default)]
struct Shared {
    built: Option<(DatasetKey, Dataset, FunctionTable)>,
}

/// What [`stacks_dataset`] reads from the options.
type DatasetKey = (usize, Option<usize>, u64, Bias, Option<PathBuf>);

impl Shared {
    fn get(
        &mut self,
        stacks: &[DepthStack],
        opts: &SweepOptions,
    ) -> Result<(&Dataset, &FunctionTable)> {
        let key = (
            opts.grid,
            opts.max_fragments,
            opts.seed,
            opts.bias,
            opts.catalog.clone(),
        );
        if self.built.as_ref().is_none_or(|b| b.0 != key) {
            let (data, table) = stacks_dataset(stacks, opts)?;
            self.built = Some((key, data, table));
        }
        let (_, data, table) = self.built.as_ref().expect("built above");
        Ok((data, table))
    }
}

/// One sweep with a progress bar and its summary lines on stderr; the report of a complete
/// sweep (the sweeps `compare` side by side) goes to `report`, replacing the run's own files.
fn sweep(
    data: &Dataset,
    table: &FunctionTable,
    refs: &ReferenceCache,
    opts: &SweepOptions,
    results: &Path,
    report: &Path,
    compare: &[PathBuf],
) -> Result<()> {
    eprintln!(
        "search: m = {}, {} views, results in {}",
        opts.m,
        refs.stacks().map_or(0, <[DepthStack]>::len),
        results.display()
    );
    let b = bar(0, &format!("sweep m = {}", opts.m));
    let progress = |p: Progress| match p {
        Progress::Phase { name, units } => {
            b.phase(&format!("  sweep m = {} {name}", opts.m), units)
        }
        Progress::Advance(u) => b.inc(u),
    };
    let r = sweep_dataset(data, table, refs, opts, results, Some(&progress))?;
    b.finish();
    if let Some(line) = sweep_line(&r) {
        eprintln!("{line}");
    }
    if let Some(s) = &r.ranking {
        let report_opts = ReportOptions {
            compare: compare.to_vec(),
            ..ReportOptions::of(opts, results)
        };
        let out = OutDir::new(report, true)?;
        sweep_report::write(&out, &r.rows, data, &r.references, &report_opts)?;
        for line in ranking_lines(s) {
            eprintln!("{line}");
        }
        eprintln!("report: written to {}", report.display());
    }
    Ok(())
}

/// A seeded random subset of `k` candidate indices of the embedded catalog for m functions,
/// always including the paper's polynomial basis (z, …, z^m) and, for m = 4, b_TMSM.
pub fn subset(m: usize, k: usize) -> Result<Vec<u64>> {
    use crate::basis::candidates;
    use rand::{Rng, SeedableRng};
    let cat = crate::basis::Catalog::embedded();
    let total = candidates::count(cat.len(), m);
    let mut pick: Vec<u64> = Vec::new();
    let mut named = vec![(1..=m)
        .map(|k| {
            if k == 1 {
                "z".to_string()
            } else {
                format!("z^{k}")
            }
        })
        .collect::<Vec<_>>()];
    if m == 4 {
        named.push(
            ["sin(2πz)", "cos(2πz)", "sin(4πz)", "cos(4πz)"]
                .iter()
                .map(|s| s.to_string())
                .collect(),
        );
    }
    for names in named {
        let mut idx: Vec<usize> = names
            .iter()
            .map(|n| {
                cat.position(n)
                    .with_context(|| format!("catalog has no '{n}'"))
            })
            .collect::<Result<_>>()?;
        idx.sort();
        pick.push(candidates::subset_to_index(&idx)?);
    }
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(2015 + m as u64);
    while pick.len() < k.min(total as usize) {
        let i = rng.gen_range(0..total);
        if !pick.contains(&i) {
            pick.push(i);
        }
    }
    pick.sort();
    Ok(pick)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn subsets_are_seeded_sorted_distinct_and_hold_the_paper_bases() {
        let a = subset(4, 30).unwrap();
        assert_eq!(a, subset(4, 30).unwrap());
        assert_eq!(a.len(), 30);
        assert!(a.windows(2).all(|w| w[0] < w[1]));
        let cat = crate::basis::Catalog::embedded();
        let msm: Vec<usize> = ["z", "z^2", "z^3", "z^4"]
            .iter()
            .map(|n| cat.position(n).unwrap())
            .collect();
        assert!(a.contains(&crate::basis::candidates::subset_to_index(&msm).unwrap()));
        // More than exist: all of them.
        assert_eq!(
            subset(2, 1 << 20).unwrap().len() as u64,
            crate::basis::candidates::count(cat.len(), 2)
        );
    }
}
