//! The LP benchmarks' library (`momentlab bench lp`) and the test corpora: problem generators
//! ([`instances`]: built-in smooth functions, Dirac mixtures, 9×9 Gaussian kernel patches;
//! [`corpus`]: the adversarial set of bases over [`crate::lp::corpus`]'s problem kinds, the
//! moments-only corpus and real filter windows) and
//! the timing loops ([`kernels`]: reference, warm, cold and distribution start side by side;
//! [`timing`]: a corpus with mean and tail, microlp in the same run). The problems themselves are
//! [`crate::lp::corpus`], so the LP's unit tests draw them without this module.

pub mod corpus;
pub mod instances;
pub mod kernels;
pub mod timing;
