//! Optimal affine quantization transforms θ (Peters & Klein 2015, Section 4.3; supplementary
//! Section 3 for θ₆), bit depths and the quantized moment-shadow-map study.
//!
//! OWNER: theta helper.
