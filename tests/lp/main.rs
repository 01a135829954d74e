//! Algorithm 1, the LP: the solvers' correctness contract, the fast solver against the
//! reference and exact certificates, known answers, solver names and `momentlab lp`.

#[path = "../common/mod.rs"]
mod common;

mod cli;
mod contract;
mod distribution;
mod equivalence;
mod exact;
mod known;
mod markov;
mod strict;
