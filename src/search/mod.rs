//! The candidate sweep (Peters & Klein 2015, Section 3.2, Fig. 4): every m-subset of the catalog
//! scored by Algorithm 1 over the depth stacks, with racing, shards and resumable results.
//!
//! Pieces:
//! * [`FunctionTable`]: every catalog function tabulated on the LP grid once (n × N).
//! * [`span`]: numerical rank (degenerate candidates) and span keys (duplicate candidates).
//! * candidates ↔ indices: [`crate::basis::candidates`] (colex numbering, as `momentlab candidates`).
//! * [`dataset`]: the sampled fragments with their depth distributions on the grid.
//! * [`score`]: Algorithm 1 errors |G − PCF| of one candidate over a list of fragments.
//! * [`plan`], [`forecast`] and [`refine`]: what a race will cost (`search --plan`), from a
//!   proxy race whose estimates are refined on fresh fragments and the run simulated on them.
//! * [`race`]: the racing statistics (paired tests with a stated confidence, the cap, the plan).
//! * [`sweep`]: racing with elimination by evidence, resumable results files, shards.
//! * [`tieset`]: the race's answer as sets (winner, tied for first, eliminated) and its check
//!   against an exhaustive run.
//! * [`results`]: the results rows, reading/writing them.
//! * [`merge`]: combining the results of sharded runs.
//! * [`reference`]: the paper's bases and the closed forms scored as references, the ranking,
//!   the Fig. 3 curves (the report's charts and text: `crate::report::sweep`).
//! * [`run`]: the whole sweep on depth stacks ([`stacks_dataset`], [`sweep_dataset`]) for the
//!   CLI and `reproduce`.

pub mod config;
pub mod dataset;
pub mod forecast;
pub mod merge;
pub mod plan;
pub mod race;
pub mod reference;
pub mod refine;
pub mod results;
pub mod run;
pub mod score;
pub mod select;
pub mod span;
pub mod sweep;
pub mod tieset;
pub mod timing;

pub use config::{Parameters, SweepConfig};
pub use dataset::{Dataset, DatasetBuilder, Fragment, SamplePlan, DEFAULT_MAX_FRAGMENTS};
pub use merge::merge_dirs;
pub use results::{read_rows, Row};
pub use run::{stacks_dataset, sweep_dataset, SweepOptions, SweepResult};
pub use score::Scorer;
pub use sweep::{run_sweep, Hooks, Outcome, Progress, RaceSummary, SweepSummary};

use crate::lp::GridTable;
use crate::Grid;
use anyhow::{bail, Result};

/// N functions tabulated on a grid with their names: an [`lp::GridTable`] of any width (a
/// catalog), from which each candidate's LP table is gathered.
#[derive(Clone, Debug)]
pub struct FunctionTable {
    table: GridTable,
    names: Vec<String>,
}

impl FunctionTable {
    /// Tabulate `f(j, z)` for j = 0..names.len() on every grid point; a non-finite value is an
    /// error naming the function and the depth.
    pub fn new(grid: &Grid, names: Vec<String>, f: impl Fn(usize, f64) -> f64) -> Result<Self> {
        let nf = names.len();
        if nf == 0 {
            bail!("function table: no functions");
        }
        let mut values = Vec::with_capacity(grid.len() * nf);
        for &z in grid.points() {
            for (j, name) in names.iter().enumerate() {
                let v = f(j, z);
                if !v.is_finite() {
                    bail!("function '{name}' is not finite at z = {z} ({v})");
                }
                values.push(v);
            }
        }
        Ok(FunctionTable {
            table: GridTable::wide(grid, nf, values)?,
            names,
        })
    }

    /// Every function of a catalog on `grid`.
    pub fn from_functions(grid: &Grid, functions: &[crate::basis::Function]) -> Result<Self> {
        let names = functions.iter().map(|f| f.name().to_string()).collect();
        FunctionTable::new(grid, names, |j, z| functions[j].eval(z))
    }

    /// The depth grid the functions are tabulated on.
    pub fn grid(&self) -> &Grid {
        self.table.grid()
    }
    /// Number of functions N.
    pub fn len(&self) -> usize {
        self.names.len()
    }
    /// True when N = 0.
    pub fn is_empty(&self) -> bool {
        self.names.is_empty()
    }
    /// The function names, in column order.
    pub fn names(&self) -> &[String] {
        &self.names
    }
    /// f_j(z_i).
    pub fn value(&self, i: usize, j: usize) -> f64 {
        self.table.row(i)[j]
    }
    /// Row i: all N function values at z_i.
    pub fn row(&self, i: usize) -> &[f64] {
        self.table.row(i)
    }
    /// The Algorithm 1 constraint table of the candidate `cols` (a gather of m columns).
    pub fn grid_table(&self, cols: &[usize]) -> Result<GridTable> {
        Ok(self.table.columns(cols)?)
    }
    /// The names of the functions `cols`.
    pub fn names_of(&self, cols: &[usize]) -> Vec<String> {
        cols.iter().map(|&c| self.names[c].clone()).collect()
    }
    /// A 64-bit fingerprint of names and tabulated values (FNV-1a), to refuse resuming a run
    /// with a different catalog or grid.
    pub fn fingerprint(&self) -> u64 {
        let mut h = Fnv::new();
        for n in &self.names {
            h.bytes(n.as_bytes());
            h.bytes(&[0]);
        }
        for z in self.table.grid().points() {
            h.u64(z.to_bits());
        }
        for v in self.table.values() {
            h.u64(v.to_bits());
        }
        h.finish()
    }
}

/// FNV-1a, 64 bit: a stable (platform independent) fingerprint for configs.
pub(crate) struct Fnv(u64);

impl Fnv {
    pub(crate) fn new() -> Fnv {
        Fnv(0xcbf29ce484222325)
    }
    pub(crate) fn bytes(&mut self, b: &[u8]) {
        for &x in b {
            self.0 ^= x as u64;
            self.0 = self.0.wrapping_mul(0x100000001b3);
        }
    }
    pub(crate) fn u64(&mut self, v: u64) {
        self.bytes(&v.to_le_bytes());
    }
    pub(crate) fn finish(&self) -> u64 {
        self.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn grid_table_gathers_columns() {
        let g = Grid::uniform(5).unwrap();
        let t = FunctionTable::new(&g, vec!["z".into(), "z^2".into(), "z^3".into()], |j, z| {
            z.powi(j as i32 + 1)
        })
        .unwrap();
        let gt = t.grid_table(&[2, 0]).unwrap();
        assert_eq!(gt.m(), 2);
        for (i, &z) in g.points().iter().enumerate() {
            assert_eq!(gt.row(i), &[z.powi(3), z]);
        }
        assert!(t.grid_table(&[3]).is_err());
        assert_eq!(t.names_of(&[1]), vec!["z^2".to_string()]);
    }

    #[test]
    fn non_finite_function_is_an_error() {
        let g = Grid::uniform(5).unwrap();
        let e = FunctionTable::new(&g, vec!["1/z".into()], |_, z| 1.0 / z).unwrap_err();
        assert!(e.to_string().contains("1/z"), "{e}");
    }
}
