//! Candidate bases: formulas, the catalog, m-subsets (candidates) and LP candidates as
//! techniques.

#[path = "../common/mod.rs"]
mod common;

mod candidates;
mod catalog;
mod formula;
mod lp_candidate;
