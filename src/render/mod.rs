//! The reference renderer: a CPU ray caster for a directional light (orthographic projection
//! fitted to the scene bounds) recording every surface along each texel's ray.
//!
//! OWNER: render/stack helper.

pub mod rectified;
