//! The default dataset compiled into the binary, so `momentlab render` works from any
//! directory (`--scenes DIR` overrides). Sources: data/scenes/*.json, data/meshes/*.obj.

use super::Scene;
use anyhow::{bail, Context, Result};

/// File names of the embedded scenes, in dataset order.
pub const EMBEDDED_SCENE_NAMES: &[&str] = &["city.json", "stairs.json", "thin.json"];

const SCENES: &[&str] = &[
    include_str!("../../data/scenes/city.json"),
    include_str!("../../data/scenes/stairs.json"),
    include_str!("../../data/scenes/thin.json"),
];

/// Mesh paths as written in the scene files (relative to data/scenes/).
const MESHES: &[(&str, &[u8])] = &[(
    "../meshes/knot.obj",
    include_bytes!("../../data/meshes/knot.obj"),
)];

fn mesh(path: &str) -> Result<Vec<u8>> {
    match MESHES.iter().find(|(p, _)| *p == path) {
        Some((_, b)) => Ok(b.to_vec()),
        None => bail!("mesh '{path}' is not part of the embedded dataset"),
    }
}

/// Parses the embedded scenes (in [`EMBEDDED_SCENE_NAMES`] order).
pub fn embedded_scenes() -> Result<Vec<Scene>> {
    SCENES
        .iter()
        .zip(EMBEDDED_SCENE_NAMES)
        .map(|(text, name)| {
            Scene::from_json(text, &mesh).with_context(|| format!("embedded scene {name}"))
        })
        .collect()
}

/// A fingerprint of the embedded scene and mesh files (FNV-1a, 64 bits, in hex): equal
/// fingerprints, equal dataset.
pub fn embedded_fingerprint() -> String {
    let mut h: u64 = 0xcbf29ce484222325;
    let mut eat = |bytes: &[u8]| {
        for &b in bytes.iter().chain(&[0xff]) {
            h = (h ^ b as u64).wrapping_mul(0x100000001b3);
        }
    };
    for (name, text) in EMBEDDED_SCENE_NAMES.iter().zip(SCENES) {
        eat(name.as_bytes());
        eat(text.as_bytes());
    }
    for (path, bytes) in MESHES {
        eat(path.as_bytes());
        eat(bytes);
    }
    format!("{h:016x}")
}
