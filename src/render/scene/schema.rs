//! The scene file as written (format in docs/stacks.md): objects with their shapes and
//! transforms, lights and eye-view cameras (a direction, or azimuth and elevation in degrees),
//! and the light sidecar of a mesh file rendered directly.

use super::transform::{Transform, UpAxis};
use super::V3;
use crate::linalg::v3::norm;
use anyhow::{bail, Result};
use serde::Deserialize;

/// The light sidecar of a mesh file rendered directly (`<stem>.lights.json`): lights as in a
/// scene file and the mesh placement of [`orient_mesh`](super::orient_mesh).
#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub struct MeshSidecar {
    /// Scene name (default: the mesh file stem).
    pub name: Option<String>,
    /// The views' lights (replaced by lights given on the command line).
    #[serde(default)]
    pub lights: Vec<LightDesc>,
    /// Which axis of the mesh points up.
    #[serde(default)]
    pub up_axis: UpAxis,
    /// Euler rotation in degrees, X then Y then Z.
    pub rotate: Option<V3>,
    /// Uniform scale so that the largest extent is `fit`.
    pub fit: Option<f64>,
}

/// Smallest light elevation above the horizon, in degrees: a light must shine down onto the
/// receivers (y is up), so a direction of travel with y ≥ −sin 1° is rejected.
pub const MIN_ELEVATION_DEG: f64 = 1.0;

/// Largest |azimuth| in degrees of a light or camera: one turn either way (a NaN, infinite or
/// larger azimuth is an error naming the azimuth, not a direction computed from it).
pub const MAX_AZIMUTH_DEG: f64 = 360.0;

/// A light as written in a scene file: `dir` (direction of travel) or `azimuth_deg` +
/// `elevation_deg` (where it comes from), and optionally the `camera` of its eye view. On the
/// command line: `AZ,EL` or `X,Y,Z`.
#[derive(Deserialize, Clone, Debug, Default, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct LightDesc {
    /// View name (default `light<i>`, i the light's index).
    pub name: Option<String>,
    /// Direction the light travels (world space, any length).
    pub dir: Option<V3>,
    /// Azimuth the light comes from, degrees.
    pub azimuth_deg: Option<f64>,
    /// Elevation above the horizon the light comes from, degrees (at least [`MIN_ELEVATION_DEG`]).
    pub elevation_deg: Option<f64>,
    /// The eye-view camera of this view (default: derived from the light).
    pub camera: Option<CameraDesc>,
}

/// The eye-view camera of a view as written in a scene file (orthographic, fitted to the
/// scene): `dir` (the direction it looks along) or `azimuth_deg` + `elevation_deg` (where it
/// looks from), with the lights' conventions and limits.
#[derive(Deserialize, Clone, Debug, Default, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct CameraDesc {
    /// Direction the camera looks along (world space).
    pub dir: Option<V3>,
    /// Azimuth the camera looks from, degrees.
    pub azimuth_deg: Option<f64>,
    /// Elevation the camera looks from, degrees.
    pub elevation_deg: Option<f64>,
}

impl CameraDesc {
    /// The (unnormalized) viewing direction, checked to look down onto the receivers
    /// (elevation in [[`MIN_ELEVATION_DEG`], 90°]).
    pub fn direction(&self, light: &str) -> Result<V3> {
        downward(
            &format!("light '{light}': camera"),
            ("looks", "the camera looks along"),
            (self.dir, self.azimuth_deg, self.elevation_deg),
        )
    }
}

impl LightDesc {
    /// The (unnormalized) direction of travel, checked to point down onto the ground: the
    /// elevation asin(−d_y/|d|) must be in [`MIN_ELEVATION_DEG`], 90°].
    pub fn direction(&self, name: &str) -> Result<V3> {
        downward(
            &format!("light '{name}'"),
            ("travels", "the light travels"),
            (self.dir, self.azimuth_deg, self.elevation_deg),
        )
    }
}

/// A direction given as `dir` or as azimuth + elevation in degrees (where it comes from:
/// d = (−cos el·cos az, −sin el, −cos el·sin az)), checked to point down: elevation
/// asin(−d_y/|d|) in [[`MIN_ELEVATION_DEG`], 90°]. `what` names it in errors, `verb` and
/// `along` say what moves along it.
fn downward(
    what: &str,
    (verb, along): (&str, &str),
    given: (Option<V3>, Option<f64>, Option<f64>),
) -> Result<V3> {
    let d = match given {
        (Some(d), None, None) => d,
        (None, Some(az), Some(el)) => {
            if !(-MAX_AZIMUTH_DEG..=MAX_AZIMUTH_DEG).contains(&az) {
                // 1e308 as "1e308", not 309 digits
                let az = if az.abs() >= 1e9 {
                    format!("{az:e}")
                } else {
                    format!("{az}")
                };
                bail!("{what}: azimuth_deg {az} outside [-{MAX_AZIMUTH_DEG}, {MAX_AZIMUTH_DEG}]");
            }
            if !(MIN_ELEVATION_DEG..=90.0).contains(&el) {
                bail!(
                    "{what}: elevation_deg {el} outside [{MIN_ELEVATION_DEG}, 90] (it must look \
                     down onto the receivers)"
                );
            }
            let (az, el) = (az.to_radians(), el.to_radians());
            [-el.cos() * az.cos(), -el.sin(), -el.cos() * az.sin()]
        }
        _ => bail!("{what}: give either \"dir\" or both \"azimuth_deg\" and \"elevation_deg\""),
    };
    let n = norm(d);
    if !(n.is_finite() && n > 0.0) {
        bail!("{what}: direction {d:?} is zero or not finite");
    }
    let el = (-d[1] / n).clamp(-1.0, 1.0).asin().to_degrees();
    if el < MIN_ELEVATION_DEG {
        let how = if d[1] > 0.0 {
            format!("{verb} upward")
        } else {
            "is (nearly) horizontal".to_string()
        };
        bail!(
            "{what}: dir {d:?} {how} (elevation {el:.2}°); dir is the direction {along} and must \
             point down onto the receivers (y < 0, elevation ≥ {MIN_ELEVATION_DEG}°)"
        );
    }
    Ok(d)
}

impl std::str::FromStr for LightDesc {
    type Err = anyhow::Error;
    /// `AZ,EL` (degrees; where the light comes from) or `X,Y,Z` (direction of travel).
    fn from_str(s: &str) -> Result<LightDesc> {
        let v: Vec<f64> = s
            .split(',')
            .map(|t| t.trim().parse::<f64>())
            .collect::<std::result::Result<_, _>>()
            .map_err(|_| anyhow::anyhow!("light '{s}': expected AZ,EL or X,Y,Z (numbers)"))?;
        match v[..] {
            [az, el] => Ok(LightDesc {
                azimuth_deg: Some(az),
                elevation_deg: Some(el),
                ..Default::default()
            }),
            [x, y, z] => Ok(LightDesc {
                dir: Some([x, y, z]),
                ..Default::default()
            }),
            _ => bail!(
                "light '{s}': expected AZ,EL or X,Y,Z ({} numbers given)",
                v.len()
            ),
        }
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct SceneDesc {
    pub(super) name: String,
    #[serde(default)]
    #[allow(dead_code)]
    pub(super) description: String,
    pub(super) lights: Vec<LightDesc>,
    pub(super) objects: Vec<Object>,
}

#[derive(Deserialize)]
pub(super) struct Object {
    #[serde(flatten)]
    pub(super) shape: Shape,
    #[serde(default)]
    pub(super) transform: Transform,
}

/// Procedural primitives (local coordinates; y is up, solids stand on y = 0 unless noted).
#[derive(Deserialize)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
pub(super) enum Shape {
    /// Quad in the y = 0 plane, centred, size [x, z], normal +y.
    Plane { size: [f64; 2] },
    /// Axis-aligned box: x, z centred, y from 0 to size[1].
    Box { size: V3 },
    /// Capped cylinder about the y axis from y = 0 to height.
    Cylinder {
        radius: f64,
        height: f64,
        #[serde(default = "default_segments")]
        segments: usize,
    },
    /// Torus about the y axis centred at the origin: ring radius `radius`, tube radius `tube`,
    /// `segments` around the ring and `segments / 2` (at least 3) around the tube.
    Torus {
        radius: f64,
        tube: f64,
        #[serde(default = "default_segments")]
        segments: usize,
    },
    /// UV sphere centred at the origin.
    Sphere {
        radius: f64,
        #[serde(default = "default_segments")]
        segments: usize,
    },
    /// Solid staircase rising along +z (one closed surface, no interior faces): step i has
    /// its tread at y = (i+1)·step_height over z ∈ [i·step_depth, (i+1)·step_depth], x centred.
    Stairs {
        steps: usize,
        width: f64,
        step_depth: f64,
        step_height: f64,
    },
    /// Fence along x (centred), standing on y = 0: `bars` vertical boxes and `rails` horizontal
    /// rails, all of the given thickness (z).
    Fence {
        width: f64,
        height: f64,
        bars: usize,
        bar_width: f64,
        #[serde(default = "default_rails")]
        rails: usize,
        thickness: f64,
    },
    /// Horizontal grating (grid of crossing bars) centred, bars from y = 0 to thickness.
    Grating {
        size: [f64; 2],
        bars: [usize; 2],
        bar_width: f64,
        thickness: f64,
    },
    /// Random single-sided quads (foliage-like cards) of size [w, h] with random orientation,
    /// centres uniform in region [x0, y0, z0, x1, y1, z1]; deterministic in `seed`.
    Cards {
        count: usize,
        size: [f64; 2],
        region: [f64; 6],
        seed: u64,
    },
    /// Random city block: grid[0] × grid[1] boxes with footprint and height ranges on a grid of
    /// the given spacing (centred), plus `bridges` elevated slabs between neighbours.
    City {
        grid: [usize; 2],
        spacing: f64,
        footprint: [f64; 2],
        height: [f64; 2],
        #[serde(default)]
        bridges: usize,
        seed: u64,
    },
    /// Arcade along x: two rows (z = ±depth/2) of `columns` cylinders (radius, height) at the
    /// given spacing, centred, under a roof slab of thickness `roof`.
    Arcade {
        columns: usize,
        spacing: f64,
        radius: f64,
        height: f64,
        depth: f64,
        roof: f64,
    },
    /// Triangle mesh from an OBJ, glTF (.gltf/.glb), PLY or STL file (path relative to the
    /// scene file), placed by [`orient_mesh`]: `up_axis`, then `rotate`, then `fit`.
    Mesh {
        path: String,
        fit: Option<f64>,
        #[serde(default)]
        up_axis: UpAxis,
        rotate: Option<V3>,
    },
}

fn default_segments() -> usize {
    24
}
fn default_rails() -> usize {
    2
}

/// rings as fans.
fn sphere_triangles(n: u128) -> u128 {
    let rings = n.div_ceil(2).max(2);
    n.saturating_mul(2 * rings - 2)
}

impl Shape {
    /// The `type` name of the shape, for errors.
    pub(super) fn kind(&self) -> &'static str {
        match self {
            Shape::Plane { .. } => "plane",
            Shape::Box { .. } => "box",
            Shape::Cylinder { .. } => "cylinder",
            Shape::Torus { .. } => "torus",
            Shape::Sphere { .. } => "sphere",
            Shape::Stairs { .. } => "stairs",
            Shape::Fence { .. } => "fence",
            Shape::Grating { .. } => "grating",
            Shape::Cards { .. } => "cards",
            Shape::City { .. } => "city",
            Shape::Arcade { .. } => "arcade",
            Shape::Mesh { .. } => "mesh",
        }
    }

    /// The count fields of a procedural shape (as "field N, …", for errors) and the number of
    /// triangles [`Shape::triangles`] makes from them (saturating, so absurd counts stay
    /// absurd instead of wrapping); `None` for a mesh (bounded by the mesh loaders).
    pub(super) fn triangle_count(&self) -> Option<(String, u128)> {
        let w = |n: usize| n as u128;
        Some(match *self {
            Shape::Plane { .. } => ("a plane".into(), 2),
            Shape::Box { .. } => ("a box".into(), 12),
            Shape::Cylinder { segments, .. } => (
                format!("segments {segments}"),
                w(segments).saturating_mul(4),
            ),
            Shape::Torus { segments, .. } => (
                format!("segments {segments}"),
                w(segments)
                    .saturating_mul(w(segments / 2).max(3))
                    .saturating_mul(2),
            ),
            Shape::Sphere { segments, .. } => (
                format!("segments {segments}"),
                sphere_triangles(w(segments)),
            ),
            Shape::Stairs { steps, .. } => (
                format!("steps {steps}"),
                w(steps).saturating_mul(8) + if steps > 0 { 4 } else { 0 },
            ),
            Shape::Fence { bars, rails, .. } => (
                format!("bars {bars}, rails {rails}"),
                w(bars).saturating_add(w(rails)).saturating_mul(12),
            ),
            Shape::Grating { bars, .. } => (
                format!("bars [{}, {}]", bars[0], bars[1]),
                w(bars[0]).saturating_add(w(bars[1])).saturating_mul(12),
            ),
            Shape::Cards { count, .. } => (format!("count {count}"), w(count).saturating_mul(2)),
            Shape::City { grid, bridges, .. } => (
                format!("grid [{}, {}], bridges {bridges}", grid[0], grid[1]),
                w(grid[0])
                    .saturating_mul(w(grid[1]))
                    .saturating_add(w(bridges))
                    .saturating_mul(12),
            ),
            Shape::Arcade { columns, .. } => (
                format!("columns {columns}"),
                w(columns).saturating_mul(2 * 4 * 16).saturating_add(12),
            ),
            Shape::Mesh { .. } => return None,
        })
    }
}
