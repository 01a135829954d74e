//! `momentlab candidates`: count, list and index candidates (m-subsets of the catalog).
//!
//! * `count [--m 4]` → `66045`
//! * `list [--m 4] [--from i] [--count k] [--grid N]` → one line per candidate:
//!   `index<TAB>f1,f2,…`; with `--grid N` two more columns: `degenerate|ok` and the span key
//!   (hex, `-` when degenerate) on N uniform points.
//! * `index <i> [--m 4]` → `f1,f2,…`
//! * `subset <f1,f2,…>` → the index (m is the number of names).
//!
//! `--json` prints JSON instead (objects with "index", "functions", "positions", and with
//! `--grid` "degenerate", "sigma_ratio", "span_key"); `--catalog FILE` uses a user catalog.

use super::common::{usize_in, MAX_GRID};
use anyhow::{bail, Context, Result};
use momentlab::basis::candidates::MAX_M;
use momentlab::basis::candidates::{
    analyze, check_m, checked_count, index_to_subset, next_subset, subset_to_index, DEFAULT_M,
};
use momentlab::basis::{split_list, Catalog, Function};
use momentlab::Grid;
use std::io::Write;
use std::path::PathBuf;

#[derive(clap::Args, Debug)]
pub struct Args {
    #[command(subcommand)]
    pub action: Action,
    /// Catalog file (default: the embedded basis_functions/catalog.json).
    #[arg(long, global = true)]
    pub catalog: Option<PathBuf>,
    /// Print JSON instead of plain lines.
    #[arg(long, global = true)]
    pub json: bool,
}

#[derive(clap::Subcommand, Debug)]
pub enum Action {
    /// Number of candidates C(N, m).
    Count {
        /// Functions per candidate (1..=8).
        #[arg(long, default_value_t = DEFAULT_M, value_parser = usize_in(1, MAX_M as u64))]
        m: usize,
    },
    /// Candidates in index order.
    List {
        /// Functions per candidate (1..=8).
        #[arg(long, default_value_t = DEFAULT_M, value_parser = usize_in(1, MAX_M as u64))]
        m: usize,
        /// First index.
        #[arg(long, default_value_t = 0)]
        from: u64,
        /// Number of candidates (default: all from `--from`).
        #[arg(long)]
        count: Option<u64>,
        /// Also report degeneracy and span key on this many uniform grid points (2..=1048576).
        #[arg(long, value_parser = usize_in(2, MAX_GRID))]
        grid: Option<usize>,
    },
    /// The functions of candidate number i.
    Index {
        /// Candidate index (0 ≤ i < C(N, m)).
        i: u64,
        /// Functions per candidate (1..=8).
        #[arg(long, default_value_t = DEFAULT_M, value_parser = usize_in(1, MAX_M as u64))]
        m: usize,
    },
    /// The index of a comma-separated list of catalog names.
    Subset {
        /// Comma-separated catalog function names, e.g. "z,z^2,z^3,z^4" (m = their number).
        names: String,
    },
}

fn names_of(catalog: &Catalog, subset: &[usize]) -> Vec<String> {
    subset
        .iter()
        .map(|&i| catalog.functions()[i].name().to_string())
        .collect()
}

pub fn run(args: Args) -> Result<()> {
    let catalog = match &args.catalog {
        Some(p) => Catalog::load(p)?,
        None => Catalog::embedded(),
    };
    let n = catalog.len();
    let stdout = std::io::stdout();
    let mut out = std::io::BufWriter::new(stdout.lock());
    match args.action {
        Action::Count { m } => {
            check_m(n, m)?;
            let c = checked_count(n, m).ok_or_else(|| anyhow::anyhow!("C({n},{m}) overflows"))?;
            if args.json {
                writeln!(out, "{}", serde_json::json!({"n": n, "m": m, "count": c}))?;
            } else {
                writeln!(out, "{c}")?;
            }
        }
        Action::List {
            m,
            from,
            count,
            grid,
        } => {
            check_m(n, m)?;
            let total =
                checked_count(n, m).ok_or_else(|| anyhow::anyhow!("C({n},{m}) overflows"))?;
            if from > total {
                bail!("--from {from} out of range: C({n},{m}) = {total} candidates");
            }
            let end = match count {
                Some(k) => from.saturating_add(k).min(total),
                None => total,
            };
            let grid = grid.map(Grid::uniform).transpose()?;
            if from < end {
                let mut subset = index_to_subset(n, m, from)?;
                for index in from..end {
                    let names = names_of(&catalog, &subset);
                    let info = grid.as_ref().map(|g| {
                        let fs: Vec<&Function> =
                            subset.iter().map(|&i| &catalog.functions()[i]).collect();
                        analyze(&fs, g)
                    });
                    if args.json {
                        let mut v = serde_json::json!({
                            "index": index, "functions": names, "positions": subset,
                        });
                        if let Some(info) = &info {
                            v["degenerate"] = info.degenerate.into();
                            v["sigma_ratio"] = info.sigma_ratio.into();
                            v["span_key"] = info.key.map(|k| format!("{k:016x}")).into();
                        }
                        writeln!(out, "{v}")?;
                    } else {
                        write!(out, "{index}\t{}", names.join(","))?;
                        if let Some(info) = &info {
                            let key = info.key.map_or("-".to_string(), |k| format!("{k:016x}"));
                            let d = if info.degenerate { "degenerate" } else { "ok" };
                            write!(out, "\t{d}\t{key}")?;
                        }
                        writeln!(out)?;
                    }
                    next_subset(&mut subset, n);
                }
            }
        }
        Action::Index { i, m } => {
            check_m(n, m)?;
            let subset = index_to_subset(n, m, i)?;
            let names = names_of(&catalog, &subset);
            if args.json {
                writeln!(
                    out,
                    "{}",
                    serde_json::json!({"index": i, "functions": names, "positions": subset})
                )?;
            } else {
                writeln!(out, "{}", names.join(","))?;
            }
        }
        Action::Subset { names } => {
            let list = split_list(&names);
            let mut positions = Vec::with_capacity(list.len());
            for name in &list {
                match catalog.position(name) {
                    Some(p) => positions.push(p),
                    None => bail!("subset: '{name}' is not a catalog function name"),
                }
            }
            check_m(n, positions.len())?;
            let index = subset_to_index(&positions)
                .map_err(|e| anyhow::anyhow!("subset '{names}': {e}"))?;
            positions.sort_unstable();
            if args.json {
                writeln!(
                    out,
                    "{}",
                    serde_json::json!({
                        "index": index,
                        "functions": names_of(&catalog, &positions),
                        "positions": positions,
                    })
                )?;
            } else {
                writeln!(out, "{index}")?;
            }
        }
    }
    out.flush().context("writing stdout")?;
    Ok(())
}
