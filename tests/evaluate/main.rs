//! Filtering and evaluation: the 9×9 kernel and moment maps, `metrics::evaluate` against
//! brute force, LP candidates evaluated, the PCF reference on curved surfaces, pictures.

#[path = "../common/mod.rs"]
mod common;

mod eye_view;
mod kernel_filter;
mod lp;
mod metrics;
mod pictures;
mod reference_curved;
