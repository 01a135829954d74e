//! Depth stacks: every surface seen from the light, per shadow-map texel (all layers, sorted),
//! with receiver-plane depth slopes for biasing. Stored as one OpenEXR file per view plus a JSON
//! sidecar; also the import format for stacks from other renderers.
//!
//! OWNER: render/stack helper. Other modules rely on [`DepthStack`] and [`StackMeta`] as below
//! and on `stack::read(path)` / `stack::write(path, &stack)` / `stack::load_dir(dir)`.

use serde::{Deserialize, Serialize};

/// The JSON sidecar of a depth-stack file.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct StackMeta {
    /// Scene name (e.g. "stairs").
    pub scene: String,
    /// View name within the scene (e.g. "light0").
    pub view: String,
    /// Direction the light travels (unit vector, world space).
    pub light_dir: [f64; 3],
    /// Near and far plane distances along the light direction (depth 0 and 1).
    pub near: f64,
    pub far: f64,
    pub width: usize,
    pub height: usize,
    pub layers: usize,
}

/// A depth stack in memory.
#[derive(Clone, Debug, PartialEq)]
pub struct DepthStack {
    pub meta: StackMeta,
    /// `depth[l][y * width + x]`: depth of the l-th surface hit (front first) in [0,1];
    /// `f32::INFINITY` where the texel has fewer than l+1 surfaces. Strictly increasing in l.
    pub depth: Vec<Vec<f32>>,
    /// Receiver-plane slope dz/du (per texel step in x) of that surface; 0 where no surface.
    pub dzdu: Vec<Vec<f32>>,
    /// Receiver-plane slope dz/dv (per texel step in y) of that surface; 0 where no surface.
    pub dzdv: Vec<Vec<f32>>,
}

impl DepthStack {
    pub fn texel_count(&self) -> usize {
        self.meta.width * self.meta.height
    }
    /// Front-layer depth of texel `t`, background (no surface) = 1.
    pub fn front(&self, t: usize) -> f32 {
        let d = self.depth.first().map_or(f32::INFINITY, |l| l[t]);
        if d.is_finite() {
            d
        } else {
            1.0
        }
    }
    /// Number of fragments: finite depths over all layers.
    pub fn fragment_count(&self) -> usize {
        self.depth
            .iter()
            .map(|l| l.iter().filter(|d| d.is_finite()).count())
            .sum()
    }
}
