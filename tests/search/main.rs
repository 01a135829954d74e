//! Candidate bases and the sweep: formulas, the catalog, candidates, LP candidates as
//! techniques, racing, plans, resume/shard/merge and the Slurm end-to-end run.

#[path = "../common/mod.rs"]
mod common;

mod basis_candidates;
mod basis_catalog;
mod basis_formula;
mod basis_lp_candidate;
mod consistency;
mod plan;
mod racing;
mod slurm_e2e;
mod sweep;
