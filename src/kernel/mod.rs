//! Filter kernels over the front-layer depth map: the 9×9 Gaussian (σ = 2.4 texels) of the
//! paper's PCF reference (Section 3.2), depth distributions Z_t and filtered moment maps.
//!
//! OWNER: kernel/evaluate helper.
