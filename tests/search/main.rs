//! The sweep: racing, plans, agreement with `evaluate`, resume/shard/merge and the Slurm
//! end-to-end run.

#[path = "../common/mod.rs"]
mod common;

mod consistency;
mod plan;
mod racing;
mod slurm_e2e;
mod sweep;
