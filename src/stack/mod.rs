//! Depth stacks: every surface seen from the light, per shadow-map texel (all layers, sorted),
//! with receiver-plane depth slopes for biasing. Stored as one OpenEXR file per view plus a JSON
//! sidecar; also the import format for stacks from other renderers (layout: docs/stacks.md).
//!
//! Other modules rely on [`DepthStack`] and [`StackMeta`] as below
//! and on `stack::read(path)` / `stack::write(path, &stack)` / `stack::load_dir(dir)`.

pub mod deep;
mod io;

pub use io::{channel_name, exr_files, file_names, is_deep_file, load_dir, read, write, write_to};

use anyhow::{bail, Result};
use serde::{Deserialize, Serialize};

/// Relative widening of the fitted depth range and (u, v) window on each side.
pub const MARGIN: f64 = 0.01;
/// Hits closer than this in depth z are one surface (shared edges, coincident faces); it also
/// guarantees strictly increasing f32 depths.
pub const DEDUP_EPS: f64 = 1e-6;

/// Largest width or height of a stack.
pub const MAX_SIDE: usize = 16384;
/// Largest layer count of a stack.
pub const MAX_LAYERS: usize = 4096;
/// Largest in-memory size of one stack (3 f32 channels per layer and texel).
pub const MAX_STACK_BYTES: u64 = 4 << 30;

/// The sidecar's size fields within the limits, checked before anything is allocated.
pub(crate) fn check_size(m: &StackMeta) -> Result<()> {
    if m.width == 0 || m.height == 0 || m.width > MAX_SIDE || m.height > MAX_SIDE {
        bail!(
            "{}x{} texels: width and height must be in 1..={MAX_SIDE}",
            m.width,
            m.height
        );
    }
    if m.layers == 0 || m.layers > MAX_LAYERS {
        bail!("layers = {}: must be in 1..={MAX_LAYERS}", m.layers);
    }
    let bytes = (m.width * m.height) as u64 * m.layers as u64 * 12;
    if bytes > MAX_STACK_BYTES {
        bail!(
            "{}x{} texels × {} layers need {:.1} GiB, more than the {} GiB limit per stack",
            m.width,
            m.height,
            m.layers,
            bytes as f64 / (1u64 << 30) as f64,
            MAX_STACK_BYTES >> 30
        );
    }
    Ok(())
}

/// The sidecar of `path`: same name with extension `.json`.
pub fn sidecar_path(path: &std::path::Path) -> std::path::PathBuf {
    path.with_extension("json")
}

/// The JSON sidecar of a depth-stack file. Unknown fields are refused (a copy would drop them).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StackMeta {
    /// Scene name (e.g. "stairs").
    pub scene: String,
    /// View name within the scene (e.g. "light0").
    pub view: String,
    /// Direction the light travels (unit vector, world space).
    pub light_dir: [f64; 3],
    /// Near and far plane distances along the light direction (depth 0 and 1).
    pub near: f64,
    /// Far plane distance along the light direction (depth 1).
    pub far: f64,
    /// Texels per row.
    pub width: usize,
    /// Rows of texels.
    pub height: usize,
    /// Number of depth layers (the most surfaces any texel has, at least 1).
    pub layers: usize,
    /// World-space unit vector of the texel x axis (+x texel step); optional (0 = unknown).
    #[serde(default)]
    pub u_axis: [f64; 3],
    /// World-space unit vector of the texel y axis (+y texel step = next row); optional.
    #[serde(default)]
    pub v_axis: [f64; 3],
    /// Light-space (u, v) coordinates of the corner of texel (0, 0); optional.
    #[serde(default)]
    pub uv_origin: [f64; 2],
    /// Edge length of a (square) texel in world units; optional (0 = unknown).
    #[serde(default)]
    pub texel_size: f64,
}

/// A depth stack in memory.
#[derive(Clone, Debug, PartialEq)]
pub struct DepthStack {
    /// The sidecar: scene, view, light frame and size.
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
    /// FNV-1a (64 bits, per 32-bit word) of the stack: its metadata as JSON, then the bits of
    /// every depth and slope value. A fingerprint of the data (what a checkpoint of a run on the
    /// stack is valid for), as 16 hex digits.
    pub fn digest(&self) -> String {
        let mut h: u64 = 0xcbf2_9ce4_8422_2325;
        let mut eat = |w: u32| h = (h ^ w as u64).wrapping_mul(0x0100_0000_01b3);
        for b in serde_json::to_vec(&self.meta).unwrap_or_default() {
            eat(b as u32);
        }
        for layer in self.depth.iter().chain(&self.dzdu).chain(&self.dzdv) {
            eat(layer.len() as u32);
            for v in layer {
                eat(v.to_bits());
            }
        }
        format!("{h:016x}")
    }

    /// width · height.
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
    /// Number of surfaces (finite depths) at texel `t`.
    pub fn layer_count_at(&self, t: usize) -> usize {
        self.depth.iter().take_while(|l| l[t].is_finite()).count()
    }
    /// `(file stem)` used for files of this stack: `<scene>_<view>`.
    pub fn file_stem(&self) -> String {
        format!("{}_{}", self.meta.scene, self.meta.view)
    }
}

/// A scene or light (view) name becomes part of a file name (`<scene>_<light>.exr`, the
/// pictures): it must be a plain name — not empty, no '/', '\\', control characters or leading
/// '.', at most 100 bytes.
pub fn check_plain_name(what: &str, name: &str) -> Result<()> {
    let bad = name.is_empty()
        || name.starts_with('.')
        || name.len() > 100
        || name
            .chars()
            .any(|c| c == '/' || c == '\\' || c.is_control());
    if bad {
        bail!(
            "{what} name '{}' is not a plain name (1 to 100 bytes; no '/', '\\', control \
             characters or leading '.')",
            name.escape_debug()
        );
    }
    Ok(())
}

/// Checks every invariant of a depth stack; the error names the first violation (layer, texel
/// x/y). Invariants: width, height ≥ 1; `layers` ≥ 1 and equal to the number of depth, dzdu and
/// dzdv channels, each of width·height values; near < far finite; light_dir finite and of unit
/// length (±1e-3); per texel, depths are finite values in [0,1] followed only by +inf ("no
/// surface"), strictly increasing over the finite ones; no NaN or −inf anywhere; slopes finite.
pub fn validate(stack: &DepthStack) -> Result<()> {
    let m = &stack.meta;
    if m.width == 0 || m.height == 0 {
        bail!("empty resolution {}x{}", m.width, m.height);
    }
    if m.layers == 0 {
        bail!("layer count is 0 (need at least one layer)");
    }
    if !(m.near.is_finite() && m.far.is_finite() && m.near < m.far) {
        bail!("near/far planes invalid: near={} far={}", m.near, m.far);
    }
    if m.light_dir.iter().any(|c| !c.is_finite()) {
        bail!("light_dir is not finite: {:?}", m.light_dir);
    }
    check_plain_name("scene", &m.scene)?;
    check_plain_name("view", &m.view)?;
    let norm = m.light_dir.iter().map(|c| c * c).sum::<f64>().sqrt();
    if (norm - 1.0).abs() > 1e-3 {
        bail!(
            "light_dir {:?} is not a unit vector (length {norm})",
            m.light_dir
        );
    }
    let n = m.width * m.height;
    for (what, ch) in [
        ("depth", &stack.depth),
        ("dzdu", &stack.dzdu),
        ("dzdv", &stack.dzdv),
    ] {
        if ch.len() != m.layers {
            bail!(
                "{} {what} channels but the sidecar says {} layers",
                ch.len(),
                m.layers
            );
        }
        for (l, c) in ch.iter().enumerate() {
            if c.len() != n {
                bail!(
                    "layer {l} {what} channel has {} values, expected {}x{} = {n}",
                    c.len(),
                    m.width,
                    m.height
                );
            }
        }
    }
    let at = |t: usize| (t % m.width, t / m.width);
    for t in 0..n {
        let mut prev = f32::NEG_INFINITY;
        for l in 0..m.layers {
            let d = stack.depth[l][t];
            let (x, y) = at(t);
            if d.is_nan() {
                bail!("layer {l} texel (x={x}, y={y}): depth is NaN");
            }
            if d == f32::INFINITY {
                prev = d;
            } else {
                if !(0.0..=1.0).contains(&d) {
                    bail!("layer {l} texel (x={x}, y={y}): depth {d} outside [0,1]");
                }
                if d <= prev {
                    if prev == f32::INFINITY {
                        bail!(
                            "layer {l} texel (x={x}, y={y}): depth {d} after a missing surface \
                             (+inf) in layer {}: layers not strictly increasing",
                            l - 1
                        );
                    }
                    bail!(
                        "layer {l} texel (x={x}, y={y}): depth {d} not greater than layer {} \
                         depth {prev}: layers not strictly increasing",
                        l - 1
                    );
                }
                prev = d;
            }
            for (what, ch) in [("dzdu", &stack.dzdu), ("dzdv", &stack.dzdv)] {
                let s = ch[l][t];
                if !s.is_finite() {
                    bail!("layer {l} texel (x={x}, y={y}): slope {what} = {s} is not finite");
                }
            }
        }
    }
    Ok(())
}
