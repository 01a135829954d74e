//! The LP benchmarks' library (`momentlab bench lp`) and the test corpora: problem generators
//! ([`instances`]: built-in smooth functions, Dirac mixtures, 9×9 Gaussian kernel patches;
//! [`corpus`]: the adversarial corpus, the moments-only corpus and real filter windows) and
//! the timing loops ([`kernels`]: reference, warm, cold and distribution start side by side;
//! [`timing`]: a corpus with mean and tail, microlp in the same run). Kept out of [`crate::lp`],
//! which solves and certifies and needs none of this.

pub mod corpus;
pub mod instances;
pub mod kernels;
pub mod timing;
