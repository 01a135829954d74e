//! Error of a technique against the PCF reference: mean |G − PCF| over all fragments of all
//! layers (Peters & Klein 2015, Section 3.2).
//!
//! A *fragment* is one surface seen from the light: texel t, layer k, depth z_f = depth[k][t].
//! Its reference is PCF with the paper's 9×9 Gaussian (σ = 2.4) over the front-layer depths z0
//! and a receiver-plane bias (see [`Bias`], [`pcf`]):
//!
//! PCF(t, k) = Σ_l w_l [ z0(t+l) < z_f + s·Δ_l − ε ],  Δ_l = dz/du·dx_l + dz/dv·dy_l,
//!
//! and every technique is evaluated from the filtered moments b_t at the biased depth
//! z_f − ε′ (ε′ = technique_epsilon + technique_slope_scale·(|dz/du| + |dz/dv|)).
//! The error of a technique is mean_{fragments} |G − PCF| (for a directional light this is the
//! L¹ error of the irradiance field divided by the total radiant power, Section 3.2).

mod bias;
mod evaluate;
pub mod eye;
mod fragments;
mod pcf;
mod report;
pub mod windows;

pub use bias::*;
pub use evaluate::*;
pub use fragments::*;
pub use pcf::*;
pub use report::*;

use crate::kernel::{self, Gaussian};
use crate::stack::DepthStack;
use crate::technique::{Evaluator, Technique};
use crate::Grid;
use anyhow::{bail, Result};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Arc;
use std::time::Instant;

#[cfg(test)]
mod tests {
    use super::*;

    /// No fragments: 0; every output non-finite: NaN (never a perfect score); else the mean
    /// over the finite ones.
    #[test]
    fn means_over_finite_outputs() {
        assert_eq!(finite_mean(0.0, 0, 0), 0.0);
        assert!(finite_mean(0.0, 0, 5).is_nan());
        assert_eq!(finite_mean(3.0, 4, 6), 0.75);
    }

    #[test]
    fn biases_beyond_the_depth_range_are_refused() {
        let ok = Bias::default();
        assert!(ok.validate().is_ok());
        for bad in [
            Bias {
                technique_epsilon: 1e300,
                ..ok
            },
            Bias {
                pcf_epsilon: 1.5,
                ..ok
            },
            Bias {
                slope_scale: f64::INFINITY,
                ..ok
            },
            Bias {
                technique_slope_scale: 1e4,
                ..ok
            },
            Bias {
                pcf_epsilon: -1e-9,
                ..ok
            },
        ] {
            let e = bad.validate().unwrap_err().to_string();
            assert!(
                e.starts_with("bias: ") && e.contains("must be in [0, "),
                "{e}"
            );
        }
    }
}
