//! The typed configuration of a study run: which preset, where its artefacts go, and the
//! sizes ([`Plan`]) every step uses.

use anyhow::{bail, Result};
use std::path::PathBuf;

/// The three configurations of the study.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Preset {
    /// Tests and smoke runs: 64² stacks, small samples (about a minute).
    Tiny,
    /// The default study (512² stacks, subsets of the m = 3, 4 sweeps).
    Default,
    /// Every fragment for the LP candidates, θ₆, all candidates for m = 2, 3, 4 (hours).
    Full,
}

impl Preset {
    /// The preset's name ("tiny", "default", "full").
    pub fn name(self) -> &'static str {
        match self {
            Preset::Tiny => "tiny",
            Preset::Default => "default",
            Preset::Full => "full",
        }
    }
}

/// A study run.
#[derive(Clone, Debug)]
pub struct Config {
    /// Name of the run: the report goes to `<reports>/<run>/`, bulky data to `<results>/<run>/`.
    pub run: String,
    /// Sizes preset, see [`Plan`].
    pub preset: Preset,
    /// Shadow-map resolution of the rendered views (None: the preset's, 512 or 64 for tiny).
    pub resolution: Option<usize>,
    /// Recommendation tolerance: absolute error above the best technique that is acceptable.
    pub tolerance: f64,
    /// Folder of reports (default `results/reports`, untracked; the committed report is
    /// `reports`).
    pub reports: PathBuf,
    /// Folder of bulky results (stacks, sweep rows).
    pub results: PathBuf,
    /// Leave out the candidate sweep (the slowest step).
    pub skip_search: bool,
    /// Delete the run's previous artefacts first.
    pub fresh: bool,
}

impl Default for Config {
    fn default() -> Self {
        Config {
            run: "default".into(),
            preset: Preset::Default,
            resolution: None,
            tolerance: 0.002,
            reports: "results/reports".into(),
            results: "results".into(),
            skip_search: false,
            fresh: false,
        }
    }
}

/// Largest shadow-map resolution of a run (12 views × layers × res² fragments must fit).
pub const MAX_RESOLUTION: usize = 4096;

impl Config {
    /// Check the configuration and return the sizes of its steps.
    pub fn plan(&self) -> Result<Plan> {
        if self.run.is_empty() || self.run.contains(['/', '\\']) || self.run.starts_with('.') {
            bail!("--run '{}': expected a plain folder name", self.run);
        }
        if !(self.tolerance.is_finite() && self.tolerance >= 0.0) {
            bail!(
                "--tolerance must be a finite number ≥ 0, got {}",
                self.tolerance
            );
        }
        let plan = Plan::of(self.preset, self.resolution);
        if plan.resolution < 16 {
            bail!("--resolution must be at least 16, got {}", plan.resolution);
        }
        if plan.resolution > MAX_RESOLUTION {
            bail!(
                "--resolution must be at most {MAX_RESOLUTION}, got {}",
                plan.resolution
            );
        }
        Ok(plan)
    }

    /// `<reports>/<run>`: the report and its figures.
    pub fn report_dir(&self) -> PathBuf {
        self.reports.join(&self.run)
    }

    /// `<results>/<run>`: stacks and sweep rows.
    pub fn data_dir(&self) -> PathBuf {
        self.results.join(&self.run)
    }
}

/// Sizes of one configuration.
#[derive(Clone, Debug, PartialEq)]
pub struct Plan {
    /// Shadow-map resolution of the rendered views.
    pub resolution: usize,
    /// Every k-th fragment for the LP candidates (closed forms see every fragment).
    pub lp_stride: usize,
    /// LP grid sizes n of the refinement step.
    pub grid_sizes: Vec<usize>,
    /// Fragments (sampled from the stacks) of the speed measurement of closed forms and of LP
    /// candidates.
    pub speed_inputs: usize,
    /// Fragments of the speed measurement of LP candidates.
    pub lp_speed_inputs: usize,
    /// θ_m computed for these m, with this many random starts.
    pub theta_moments: Vec<usize>,
    /// Random starts of each θ_m search.
    pub theta_restarts: usize,
    /// θ_m by re-running only start k of the recorded seed-1 search with R starts (m, R, k):
    /// the start that reached the best basin (docs/theta.md), seconds instead of minutes,
    /// same result as the full search.
    pub theta_best_starts: Vec<(usize, usize, usize)>,
    /// Every k-th fragment in the quantization study.
    pub quantize_stride: usize,
    /// Inputs of the stability study.
    pub stability_samples: usize,
    /// Candidate sweeps for these m.
    pub search_ms: Vec<usize>,
    /// Fragments of racing stage 0, the common sample of every candidate.
    pub search_first_sample: usize,
    /// Candidates per m ≥ 3 sweep (a seeded random subset plus the paper's bases); None = all.
    pub search_subset: Option<usize>,
    /// Cap on the sweep's non-trivial fragments.
    pub search_max_fragments: usize,
    /// Shadow pictures in the report.
    pub pictures: usize,
    /// `tune`: fragments per scene, and per scene in the screening pass.
    pub tune_fragments: usize,
    /// Fragments per scene in the screening pass of `tune`.
    pub tune_screen: usize,
}

/// (m, restarts, start) of the recorded seed-1 searches at the start that reached the best
/// basin (reports/theta/theta6.json; re-checked by tests/quantize/optimum.rs).
pub const THETA_BEST_STARTS: [(usize, usize, usize); 1] = [(6, 200, 17)];

impl Plan {
    /// The sizes of a preset, with an optional resolution override.
    pub fn of(preset: Preset, resolution: Option<usize>) -> Plan {
        let mut p = match preset {
            Preset::Tiny => Plan {
                resolution: 64,
                lp_stride: 4,
                grid_sizes: vec![64, 128, 256],
                speed_inputs: 20_000,
                lp_speed_inputs: 200,
                theta_moments: vec![2, 3],
                theta_restarts: 2,
                theta_best_starts: vec![],
                quantize_stride: 4,
                stability_samples: 120,
                search_ms: vec![2],
                search_first_sample: 128,
                search_subset: Some(20),
                search_max_fragments: 4096,
                pictures: 1,
                tune_fragments: 1024,
                tune_screen: 256,
            },
            Preset::Full => Plan {
                resolution: 512,
                lp_stride: 1,
                grid_sizes: vec![64, 128, 256, 512, 1024, 2048, 4096],
                speed_inputs: 1_000_000,
                lp_speed_inputs: 20_000,
                theta_moments: vec![2, 3, 4],
                theta_restarts: 8,
                theta_best_starts: THETA_BEST_STARTS.to_vec(),
                quantize_stride: 1,
                stability_samples: 5000,
                search_ms: vec![2, 3, 4],
                // The `momentlab search` defaults: the full sweeps measured in README.
                search_first_sample: crate::search::config::DEFAULT_FIRST_SAMPLE,
                search_subset: None,
                search_max_fragments: 131_072,
                pictures: 12,
                tune_fragments: 32_768,
                tune_screen: 4096,
            },
            Preset::Default => Plan {
                resolution: 512,
                lp_stride: 16,
                grid_sizes: vec![64, 128, 256, 512, 1024, 2048, 4096],
                speed_inputs: 200_000,
                lp_speed_inputs: 3000,
                theta_moments: vec![2, 3, 4],
                theta_restarts: 4,
                theta_best_starts: THETA_BEST_STARTS.to_vec(),
                quantize_stride: 4,
                stability_samples: 1200,
                search_ms: vec![2, 3, 4],
                search_first_sample: 1024,
                search_subset: Some(150),
                search_max_fragments: 32_768,
                pictures: 4,
                tune_fragments: 8192,
                tune_screen: 1024,
            },
        };
        if let Some(r) = resolution {
            p.resolution = r;
        }
        p
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bad_configurations_are_named() {
        let bad = |c: Config, what: &str| {
            let e = format!("{:#}", c.plan().unwrap_err());
            assert!(e.contains(what), "{e}");
        };
        for run in ["", "../x", ".hidden", "a/b"] {
            bad(
                Config {
                    run: run.into(),
                    ..Config::default()
                },
                "--run",
            );
        }
        for t in [-1.0, f64::NAN, f64::INFINITY] {
            bad(
                Config {
                    tolerance: t,
                    ..Config::default()
                },
                "--tolerance",
            );
        }
        for r in [4, 1 << 20] {
            bad(
                Config {
                    resolution: Some(r),
                    ..Config::default()
                },
                "--resolution",
            );
        }
        let tiny = Config {
            preset: Preset::Tiny,
            ..Config::default()
        };
        assert_eq!(tiny.plan().unwrap().resolution, 64);
        assert_eq!(
            Config {
                resolution: Some(128),
                ..tiny
            }
            .plan()
            .unwrap()
            .resolution,
            128
        );
    }
}
