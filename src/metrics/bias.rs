//! The depth biases of the PCF reference and of the techniques (ε, the receiver plane, ε′).

use super::*;

/// Depth biases of the PCF reference and of the techniques (all in normalised depth [0,1]).
///
/// Defaults (see docs/evaluation.md): the PCF test uses the exact receiver plane (s = 1) plus
/// ε = 1e-4, so every front-layer fragment of a planar lit surface is lit (its neighbours lie
/// on its own plane) up to rounding of the f32 depths; techniques see z_f − ε′ with
/// ε′ = 1e-4 + 2·(|dz/du| + |dz/dv|): on a tilted plane the sharp bound of the four power
/// moments is 0 from 1.5·(|dz/du| + |dz/dv|) below z_f on (measured with the reference LP), so
/// front layers of lit planes come out lit; a larger slope scale (4 = kernel radius makes every
/// plane fragment trivial for every basis) doubles the light leaked on thin occluders' back
/// faces and contact shadows.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Bias {
    /// ε: constant bias of the PCF depth test.
    pub pcf_epsilon: f64,
    /// s: scale of the receiver-plane offset Δ_l in the PCF depth test.
    pub slope_scale: f64,
    /// Constant part of ε′, the bias subtracted from z_f before a technique is evaluated.
    pub technique_epsilon: f64,
    /// Slope part of ε′: ε′ += technique_slope_scale · (|dz/du| + |dz/dv|) (texels).
    pub technique_slope_scale: f64,
    /// Which receiver plane the PCF test extends to each tap (see [`Receiver`]).
    #[serde(default)]
    pub receiver: Receiver,
}

/// The receiver plane of the PCF test at tap l (offset o_l = (dx_l, dy_l) texels).
///
/// * `Fragment`: Δ_l = ∇z_f·o_l, the fragment's own tangent plane.
/// * `Lower` (default): Δ_l = min(∇z_f·o_l, min_j ∇z0(p_j)·o_l) over the front texels p_j the
///   straight path to the tap passes (at each step of the longer axis the floor and ceiling
///   texel of the path point, the tap included): the lowest tangent plane met on the way. The surface's own rise along the path is
///   z(t+l) − z_f = ∫₀¹ ∇z(t + τ·o_l)·o_l dτ ≥ min_τ ∇z·o_l, so a surface whose facets the path
///   samples never shadows itself (convex, concave or saddle); on a plane every slope agrees
///   and the test is the `Fragment` test (docs/evaluation.md).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Receiver {
    /// Δ_l = ∇z_f·o_l: the fragment's own tangent plane.
    Fragment,
    /// Δ_l = the lowest tangent plane met on the path to the tap (see above).
    #[default]
    Lower,
}

impl Receiver {
    /// Parses "fragment" or "lower".
    pub fn parse(s: &str) -> Result<Receiver> {
        match s {
            "fragment" => Ok(Receiver::Fragment),
            "lower" => Ok(Receiver::Lower),
            _ => bail!("receiver plane '{s}': expected 'fragment' or 'lower'"),
        }
    }
}

/// Factors of the PCF constant ε at which every error is also reported (reference
/// sensitivity): ε/3 and 3ε.
pub const EPSILON_FACTORS: [f64; 2] = [1.0 / 3.0, 3.0];

/// Largest slope scale of a bias, in texels (times |dz/du| + |dz/dv|).
pub const MAX_SLOPE_SCALE: f64 = 1e3;

impl Default for Bias {
    fn default() -> Self {
        Bias {
            pcf_epsilon: 1e-4,
            slope_scale: 1.0,
            technique_epsilon: 1e-4,
            technique_slope_scale: 2.0,
            receiver: Receiver::Lower,
        }
    }
}

impl Bias {
    /// Rejects values outside their range with a one-line error: the constants in [0, 1]
    /// (depths lie in [0, 1], so a larger offset moves every test past the depth range), the
    /// slope scales in [0, [`MAX_SLOPE_SCALE`]] texels.
    pub fn validate(&self) -> Result<()> {
        for (name, v, max) in [
            ("pcf_epsilon", self.pcf_epsilon, 1.0),
            ("slope_scale", self.slope_scale, MAX_SLOPE_SCALE),
            ("technique_epsilon", self.technique_epsilon, 1.0),
            (
                "technique_slope_scale",
                self.technique_slope_scale,
                MAX_SLOPE_SCALE,
            ),
        ] {
            if !(v.is_finite() && (0.0..=max).contains(&v)) {
                bail!("bias: {name} must be in [0, {max}], got {v:?}");
            }
        }
        Ok(())
    }

    /// ε′ for a fragment with receiver-plane slopes (dz/du, dz/dv).
    pub fn technique_offset(&self, dzdu: f64, dzdv: f64) -> f64 {
        self.technique_epsilon + self.technique_slope_scale * (dzdu.abs() + dzdv.abs())
    }
}
