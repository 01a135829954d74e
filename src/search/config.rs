//! The configuration of a sweep: [`SweepConfig`], everything that determines the rows of a run
//! (stored as `config.json`), and [`Parameters`], its racing and sharding parameters with their
//! one validation.

use super::race::{Bound, Correction};
use super::Scorer;
use anyhow::{bail, Result};
use serde::{Deserialize, Serialize};

/// Fragments in racing stage 0 by default, the *common sample* every candidate is scored on
/// (Fig. 4); then ×`growth` per stage: 4096, 16384, 65536, the rest of the 131 072-fragment
/// sample.
pub const DEFAULT_FIRST_SAMPLE: usize = 4096;

/// Early looks by default on prefixes of at least 1024 fragments: a block of 2 × 1024 or more
/// after stage 0 is tested on its prefixes of 1/8, 1/4, 1/2 that hold as many, then whole (the
/// normal approximation is used on ≥ 1024 fragments only).
pub const DEFAULT_EARLY_LOOK: usize = 1024;

/// Everything that determines the rows of a run (stored as `config.json`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SweepConfig {
    /// Functions per candidate.
    pub m: usize,
    /// Catalog function names, in catalog order.
    pub functions: Vec<String>,
    /// Fingerprint of the catalog tabulated on the grid.
    pub table_fingerprint: String,
    /// Grid size n.
    pub grid: usize,
    /// Description of the dataset (e.g. "stacks:data/stacks").
    pub dataset: String,
    /// Fingerprint of the dataset's fragments.
    pub dataset_fingerprint: String,
    /// Seed of the fragment sample and of the racing order.
    pub seed: u64,
    /// LP solves after which no further look starts (0: none). It never eliminates anyone:
    /// the race ends with its survivors *unresolved*.
    #[serde(default)]
    pub lp_budget: u64,
    /// Every candidate on every fragment, no racing.
    pub exhaustive: bool,
    /// Restrict to these candidate indices (None: all C(N, m)).
    pub candidates: Option<Vec<u64>>,
    /// [i, N]: this run scores the candidates with index % N == i.
    pub shard: [usize; 2],
    /// LP solver ("fast" or "reference").
    pub solver: String,
    /// Fragments in racing stage 0.
    pub first_sample: usize,
    /// Sample growth factor per stage.
    pub growth: usize,
    /// Early looks: a stage block after stage 0 is first tested on its prefixes of 1/8, 1/4 and
    /// 1/2 that hold at least this many fragments, by confidence only (0: never;
    /// [`super::race::looks`]).
    #[serde(default)]
    pub early_look: usize,
    /// Early looks per stage block after stage 0 at most ([`super::race::EARLY_LOOKS`]; rows
    /// of a run with another number are not resumed: a folder from before the geometric looks
    /// reads as 1).
    #[serde(default = "one")]
    pub early_looks: usize,
    /// Confidence 1 − α of the elimination tests: that the best candidate survives, or with
    /// [`Correction::All`] that no elimination anywhere is false.
    pub confidence: f64,
    /// What the confidence covers ([`super::race::stage_delta`]; a folder from before the
    /// choice reads as `all`).
    #[serde(default = "Correction::legacy")]
    pub correction: Correction,
    /// One-sided bound of the tests (normal approximation or empirical Bernstein).
    pub bound: Bound,
    /// Paired differences to the reference (true) or independent intervals (comparison only).
    pub paired: bool,
    /// Candidates tried to pick the stage-0 reference.
    pub pilot: usize,
    /// Relative tolerance of the rank / span decisions.
    pub tol: f64,
    /// Fragments per solver instance (warm-start chain).
    pub chunk: usize,
    /// Candidates per flushed batch.
    pub batch: usize,
}

/// Serde default of [`SweepConfig::early_looks`] for folders written before it existed.
fn one() -> usize {
    1
}

/// The racing and sharding parameters of a sweep, as given (flags or a configuration).
#[derive(Clone, Copy, Debug)]
pub struct Parameters {
    /// [i, N]: this run scores the candidates with index % N == i.
    pub shard: [usize; 2],
    /// Fragments in racing stage 0.
    pub first_sample: usize,
    /// Sample growth factor per stage.
    pub growth: usize,
    /// Candidates per flushed batch.
    pub batch: usize,
    /// Confidence 1 − α of the elimination tests.
    pub confidence: f64,
}

impl Parameters {
    /// The one validation of a sweep's parameters: shard i/N with i < N, positive sizes,
    /// `confidence` in (0, 1). [`super::run_sweep`] calls it, and
    /// `momentlab search` before any work.
    pub fn check(&self) -> Result<()> {
        let [i, n] = self.shard;
        if n == 0 || i >= n {
            bail!("shard {i}/{n}: need 0 ≤ i < N");
        }
        for (name, v) in [
            ("first-sample", self.first_sample),
            ("growth", self.growth),
            ("batch", self.batch),
        ] {
            if v == 0 {
                bail!("{name} 0: must be at least 1");
            }
        }
        if !(self.confidence > 0.0 && self.confidence < 1.0) {
            bail!(
                "confidence {}: must be in (0, 1), e.g. 0.99",
                self.confidence
            );
        }
        Ok(())
    }
}

impl SweepConfig {
    /// The parameters [`Parameters::check`] validates.
    pub fn parameters(&self) -> Parameters {
        Parameters {
            shard: self.shard,
            first_sample: self.first_sample,
            growth: self.growth,
            batch: self.batch,
            confidence: self.confidence,
        }
    }

    /// Defaults for a sweep of m-subsets of `scorer`'s table on its dataset.
    pub fn new(m: usize, scorer: &Scorer, dataset: &str) -> SweepConfig {
        SweepConfig {
            m,
            functions: scorer.table().names().to_vec(),
            table_fingerprint: format!("{:016x}", scorer.table().fingerprint()),
            grid: scorer.table().grid().len(),
            dataset: dataset.to_string(),
            dataset_fingerprint: format!("{:016x}", scorer.data().fingerprint()),
            seed: 1,
            lp_budget: 0,
            exhaustive: false,
            candidates: None,
            shard: [0, 1],
            solver: scorer.solver().to_string(),
            first_sample: DEFAULT_FIRST_SAMPLE,
            growth: 4,
            early_look: DEFAULT_EARLY_LOOK,
            early_looks: super::race::EARLY_LOOKS,
            confidence: 0.99,
            correction: Correction::Best,
            bound: Bound::Normal,
            paired: true,
            pilot: 32,
            tol: 1e-9,
            chunk: scorer.chunk(),
            batch: 64,
        }
    }

    /// Name of the first field that differs, if any.
    pub fn first_difference(&self, other: &SweepConfig) -> Option<String> {
        let a = serde_json::to_value(self).ok()?;
        let b = serde_json::to_value(other).ok()?;
        let (a, b) = (a.as_object()?, b.as_object()?);
        a.keys().find(|k| a.get(*k) != b.get(*k)).cloned()
    }
}
