//! The GPU path: a headless wgpu device ([`device`]), the shadow-map pipeline of a setting's
//! emitted shader code — encode, the separable 9×9 Gaussian as two passes, the lookup of every
//! fragment — run by a real driver ([`pipeline`], its WGSL generated in [`passes`], results
//! read back in [`readback`]), and the check of that pipeline against its CPU model
//! ([`check`], the model is [`crate::quantize::pipeline`]).
//!
//! Without an adapter (no GPU, no driver, no Vulkan loader) [`Gpu::new`] fails with one line;
//! the CPU study never needs one.

pub mod bench;
pub mod call;
pub mod check;
pub mod cost;
pub mod device;
pub mod passes;
pub mod pipeline;
pub mod readback;
pub mod study;

pub use device::{Adapter, Gpu};
