//! Optimal affine quantization transforms θ (Peters & Klein 2015, Section 4.3; supplementary
//! of Peters et al. 2016, Section 3 for θ₆), the volume bound of the moment space, the Fig. 5
//! analogue, shader code generation, and the quantized moment-shadow-map study.
//!
//! * [`theta::Theta`]: s = A·b + t, encode/decode, gain log₂|det A|; published θ₂, θ₄, θ₆.
//! * [`theta::verify`]: containment θ(b([0,1])) ⊆ [0,1]^m (exact for polynomial bases).
//! * [`optimize::optimize`]: row-wise LP ascent with cutting planes and random restarts.
//! * [`volume`]: ∏ ((j−1)!)²/(2j−1)! and convex hulls of curves in 3D (Fig. 5).
//! * [`codegen`]: θ encoders (Chebyshev series, Clenshaw) and decoders as shader functions
//!   ([`crate::shader`]): GLSL, HLSL and their f32 interpreter.

// NaN-aware comparisons are intentional; index loops mirror the matrix formulas.
#![allow(clippy::neg_cmp_op_on_partial_ord, clippy::needless_range_loop)]

pub mod codegen;
pub mod curve;
pub mod fig5;
pub mod linalg;
pub mod lpsmall;
pub mod optimize;
pub mod pipeline;
pub mod poly;
pub mod study;
pub mod theta;
pub mod volume;

pub use curve::{Curve, MonomialCurve, SampledCurve};
pub use theta::{verify, Theta, Verification};
