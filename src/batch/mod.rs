//! The JSON batches of `momentlab lp` and `momentlab shadow`: parse and validate a whole batch
//! (one error naming the problem and field), then answer every problem.

pub mod lp;
pub mod shadow;
