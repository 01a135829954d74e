//! `tune`: technique × storage × biases on the pipeline model with noise as error, on
//! constructed stacks where the answer is known, and its shader export.

#[path = "../common/mod.rs"]
mod common;

mod tune;
mod tune_export;
