//! Scenes: a list of triangles (world space) and the directional lights (views) to render.
//! Loaded from JSON (procedural primitives and OBJ meshes with transforms; format in
//! docs/stacks.md) or built in code.

pub use super::mesh::load_obj_bytes;
use super::mesh::{load_mesh_from, MeshFiles};
use crate::stack::check_plain_name;
use anyhow::{bail, Context, Result};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::Deserialize;
use std::path::Path;

pub use super::{Tri, V3};

/// One view of a scene: a directional light.
#[derive(Clone, Debug, PartialEq)]
pub struct Light {
    /// View name, e.g. "light0".
    pub name: String,
    /// Unit direction the light travels (world space).
    pub dir: V3,
    /// Viewing direction (unit) of this view's eye-view camera from the scene file; `None`:
    /// [`crate::render::eye::default_camera`] of `dir`.
    pub camera: Option<V3>,
}

/// A scene ready to render: world-space triangles and its lights.
#[derive(Clone, Debug)]
pub struct Scene {
    pub name: String,
    pub lights: Vec<Light>,
    pub triangles: Vec<Tri>,
}

impl Scene {
    /// A scene built in code. Light directions are normalized; zero/non-finite ones are errors.
    pub fn new(name: &str, triangles: Vec<Tri>, lights: Vec<(String, V3)>) -> Result<Scene> {
        check_plain_name("scene", name)?;
        let mut seen = std::collections::BTreeSet::new();
        for (l, _) in &lights {
            check_plain_name("light", l)?;
            if !seen.insert(l.as_str()) {
                bail!("scene '{name}': two lights named '{l}' (each view is one file)");
            }
        }
        let lights = lights
            .into_iter()
            .map(|(name, d)| {
                let n = norm(d);
                if !(n.is_finite() && n > 0.0) {
                    bail!("light '{name}': direction {d:?} is zero or not finite");
                }
                Ok(Light {
                    name,
                    dir: scale(d, 1.0 / n),
                    camera: None,
                })
            })
            .collect::<Result<Vec<_>>>()?;
        if let Some((i, _)) = triangles
            .iter()
            .enumerate()
            .find(|(_, t)| t.iter().flatten().any(|c| !c.is_finite()))
        {
            bail!("scene '{name}': triangle {i} has a non-finite vertex");
        }
        check_extent(name, &triangles)?;
        Ok(Scene {
            name: name.to_string(),
            lights,
            triangles,
        })
    }

    /// Loads a scene from a JSON file; mesh paths are relative to the file's directory.
    pub fn load(path: &Path) -> Result<Scene> {
        use crate::artefact::input::{read_text, Limit};
        let text = read_text(path, Limit::SCENE)?;
        let files = DirFiles(path.parent().unwrap_or(Path::new(".")).to_path_buf());
        let desc: SceneDesc = serde_json::from_str(&text)
            .context("malformed scene JSON")
            .with_context(|| format!("scene {}", path.display()))?;
        Scene::from_desc(desc, &files).with_context(|| format!("scene {}", path.display()))
    }

    /// Parses a scene from JSON text; `mesh` returns the bytes of a mesh file given its path
    /// as written in the JSON.
    pub fn from_json(text: &str, mesh: &dyn Fn(&str) -> Result<Vec<u8>>) -> Result<Scene> {
        let desc: SceneDesc = serde_json::from_str(text).context("malformed scene JSON")?;
        Scene::from_desc(desc, &mesh)
    }

    /// A scene made of one mesh file (OBJ, glTF, PLY, STL) rendered directly. Its lights and
    /// placement come from the sidecar `<stem>.lights.json` next to it (a [`MeshSidecar`]) if
    /// there is one, and from `lights` / `up_axis` (command line), which replace the sidecar's.
    pub fn load_mesh_file(
        path: &Path,
        lights: &[LightDesc],
        up_axis: Option<UpAxis>,
    ) -> Result<Scene> {
        let side = mesh_sidecar_path(path);
        let mut sc: MeshSidecar = if side.is_file() {
            let text = crate::artefact::read_text(&side, crate::artefact::Limit::SCENE)?;
            serde_json::from_str(&text)
                .with_context(|| format!("malformed light sidecar {}", side.display()))?
        } else {
            MeshSidecar::default()
        };
        if !lights.is_empty() {
            sc.lights = lights.to_vec();
        }
        if let Some(u) = up_axis {
            sc.up_axis = u;
        }
        if sc.lights.is_empty() {
            bail!(
                "{}: no lights; give --light AZIMUTH,ELEVATION (degrees) or --light X,Y,Z, or \
                 write {}",
                path.display(),
                side.display()
            );
        }
        let file = path
            .file_name()
            .with_context(|| format!("{}: no file name", path.display()))?
            .to_string_lossy()
            .to_string();
        let name = sc.name.clone().unwrap_or_else(|| {
            path.file_stem()
                .map_or("mesh".into(), |s| s.to_string_lossy().to_string())
        });
        let desc = SceneDesc {
            name,
            description: String::new(),
            lights: sc.lights,
            objects: vec![Object {
                shape: Shape::Mesh {
                    path: file,
                    fit: sc.fit,
                    up_axis: sc.up_axis,
                    rotate: sc.rotate,
                },
                transform: Transform::default(),
            }],
        };
        let files = DirFiles(path.parent().unwrap_or(Path::new(".")).to_path_buf());
        Scene::from_desc(desc, &files).with_context(|| format!("{}", path.display()))
    }

    fn from_desc(desc: SceneDesc, mesh: &dyn MeshFiles) -> Result<Scene> {
        // Every procedural object's triangle count, and their sum, before anything is built.
        let mut planned: u128 = 0;
        for (i, obj) in desc.objects.iter().enumerate() {
            if let Some((fields, n)) = obj.shape.triangle_count() {
                let kind = obj.shape.kind();
                if n > MAX_TRIANGLES as u128 {
                    bail!(
                        "object {i} ({kind}): {fields} makes {n} triangles, more than the \
                         {MAX_TRIANGLES} a scene may hold"
                    );
                }
                planned += n;
                if planned > MAX_TRIANGLES as u128 {
                    bail!(
                        "object {i} ({kind}): {fields} brings the scene to {planned} triangles, \
                         more than the {MAX_TRIANGLES} a scene may hold"
                    );
                }
            }
        }
        let mut tris = Vec::new();
        for (i, obj) in desc.objects.iter().enumerate() {
            let mut local = obj
                .shape
                .triangles(mesh)
                .with_context(|| format!("object {i}"))?;
            if tris.len() + local.len() > MAX_TRIANGLES {
                bail!(
                    "object {i} ({}): brings the scene to {} triangles, more than the \
                     {MAX_TRIANGLES} a scene may hold",
                    obj.shape.kind(),
                    tris.len() + local.len()
                );
            }
            let m = obj.transform.matrix();
            check_affine(&m).with_context(|| format!("object {i}: transform"))?;
            for t in &mut local {
                for v in t.iter_mut() {
                    *v = m.apply(*v);
                    if let Some(c) = v.iter().find(|c| c.is_nan() || c.abs() > MAX_COORD) {
                        bail!(
                            "object {i}: transform puts a vertex at coordinate {c:e}, beyond \
                             ±{MAX_COORD:e}"
                        );
                    }
                }
            }
            tris.extend(local);
        }
        let lights = desc
            .lights
            .iter()
            .enumerate()
            .map(|(i, l)| {
                let name = l.name.clone().unwrap_or_else(|| format!("light{i}"));
                Ok((name.clone(), l.direction(&name)?))
            })
            .collect::<Result<Vec<_>>>()?;
        if lights.is_empty() {
            bail!("scene '{}' has no lights", desc.name);
        }
        if tris.is_empty() {
            bail!("scene '{}' has no triangles", desc.name);
        }
        let cameras = desc
            .lights
            .iter()
            .zip(&lights)
            .map(|(l, (name, _))| match &l.camera {
                Some(c) => c.direction(name).map(Some),
                None => Ok(None),
            })
            .collect::<Result<Vec<_>>>()?;
        let mut scene = Scene::new(&desc.name, tris, lights)?;
        for (l, c) in scene.lights.iter_mut().zip(cameras) {
            l.camera = c.map(|d| scale(d, 1.0 / norm(d)));
        }
        Ok(scene)
    }
}

/// Mesh files in a folder (paths relative to it), read through the bounded reader
/// ([`Limit::MESH`](crate::artefact::Limit::MESH)). A glTF buffer must be a file in or below the
/// `.gltf`'s folder once links are followed.
struct DirFiles(std::path::PathBuf);

impl MeshFiles for DirFiles {
    fn read(&self, rel: &str) -> Result<Vec<u8>> {
        crate::artefact::read_bytes(&self.0.join(rel), crate::artefact::Limit::MESH)
            .context("reading mesh")
    }

    fn read_beside(&self, mesh: &str, name: &str) -> Result<Vec<u8>> {
        let mesh = self.0.join(mesh);
        let folder = match mesh.parent() {
            Some(f) if !f.as_os_str().is_empty() => f,
            _ => Path::new("."),
        };
        let p = folder.join(name);
        let Ok(t) = p.canonicalize() else {
            // missing (or a dangling link): the bounded reader's "no such file"
            return crate::artefact::read_bytes(&p, crate::artefact::Limit::MESH);
        };
        let f = folder
            .canonicalize()
            .with_context(|| format!("{}: cannot resolve", folder.display()))?;
        if !t.starts_with(&f) {
            bail!(
                "{} leads to {}, outside the folder of the .gltf",
                p.display(),
                t.display()
            );
        }
        crate::artefact::read_bytes(&t, crate::artefact::Limit::MESH)
    }
}

/// The light sidecar of a mesh file rendered directly: `<stem>.lights.json`.
pub fn mesh_sidecar_path(path: &Path) -> std::path::PathBuf {
    let stem = path.file_stem().unwrap_or_default().to_string_lossy();
    path.with_file_name(format!("{stem}.lights.json"))
}

/// The light sidecar of a mesh file rendered directly (`<stem>.lights.json`): lights as in a
/// scene file and the mesh placement of [`orient_mesh`].
#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub struct MeshSidecar {
    pub name: Option<String>,
    #[serde(default)]
    pub lights: Vec<LightDesc>,
    #[serde(default)]
    pub up_axis: UpAxis,
    pub rotate: Option<V3>,
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
    pub name: Option<String>,
    pub dir: Option<V3>,
    pub azimuth_deg: Option<f64>,
    pub elevation_deg: Option<f64>,
    pub camera: Option<CameraDesc>,
}

/// The eye-view camera of a view as written in a scene file (orthographic, fitted to the
/// scene): `dir` (the direction it looks along) or `azimuth_deg` + `elevation_deg` (where it
/// looks from), with the lights' conventions and limits.
#[derive(Deserialize, Clone, Debug, Default, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct CameraDesc {
    pub dir: Option<V3>,
    pub azimuth_deg: Option<f64>,
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

pub use super::mesh::MAX_TRIANGLES;

/// Largest |coordinate| of a scene vertex (world units): depths and their differences stay
/// well inside f64 and the f32 depth maps keep their resolution.
pub const MAX_COORD: f64 = 1e9;

/// A transform must be invertible with a finite, not vanishing scale: |det A| in
/// [1e-30, 1e30] and every entry finite (scale 0 or 1e300 are errors, not an empty stack).
fn check_affine(m: &Affine) -> Result<()> {
    let a = &m.a;
    if a.iter().flatten().chain(m.t.iter()).any(|v| !v.is_finite()) {
        bail!("not finite");
    }
    let det = a[0][0] * (a[1][1] * a[2][2] - a[1][2] * a[2][1])
        - a[0][1] * (a[1][0] * a[2][2] - a[1][2] * a[2][0])
        + a[0][2] * (a[1][0] * a[2][1] - a[1][1] * a[2][0]);
    if !(det.abs() >= 1e-30 && det.abs() <= 1e30) {
        bail!("degenerate (determinant {det:e}): a scale must be finite and not 0");
    }
    Ok(())
}

/// Axis-aligned bounding box (lo, hi) of the triangles' vertices (±∞ when there are none).
fn bounds(tris: &[Tri]) -> ([f64; 3], [f64; 3]) {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for v in tris.iter().flatten() {
        for k in 0..3 {
            lo[k] = lo[k].min(v[k]);
            hi[k] = hi[k].max(v[k]);
        }
    }
    (lo, hi)
}

/// The scene must have an extent: its bounding box is not a single point.
fn check_extent(name: &str, tris: &[Tri]) -> Result<()> {
    let (lo, hi) = bounds(tris);
    let ext = (0..3).map(|k| hi[k] - lo[k]).fold(0.0, f64::max);
    if !(ext.is_finite() && ext > 0.0) {
        bail!("scene '{name}' has no extent (every vertex at one point)");
    }
    Ok(())
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SceneDesc {
    name: String,
    #[serde(default)]
    #[allow(dead_code)]
    description: String,
    lights: Vec<LightDesc>,
    objects: Vec<Object>,
}

#[derive(Deserialize)]
struct Object {
    #[serde(flatten)]
    shape: Shape,
    #[serde(default)]
    transform: Transform,
}

/// Scale: uniform or per axis.
#[derive(Deserialize, Clone, Copy)]
#[serde(untagged)]
enum Scale {
    Uniform(f64),
    Axes(V3),
}

#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct Transform {
    /// Applied last.
    #[serde(default)]
    translate: Option<V3>,
    /// Euler angles in degrees, applied about X, then Y, then Z (after scaling).
    #[serde(default)]
    rotate: Option<V3>,
    /// Applied first.
    #[serde(default)]
    scale: Option<Scale>,
}

/// Affine map x ↦ A x + t.
#[derive(Clone, Copy, Debug)]
pub struct Affine {
    pub a: [[f64; 3]; 3],
    pub t: V3,
}

impl Affine {
    pub fn apply(&self, p: V3) -> V3 {
        let mut r = self.t;
        for (i, ri) in r.iter_mut().enumerate() {
            *ri += self.a[i][0] * p[0] + self.a[i][1] * p[1] + self.a[i][2] * p[2];
        }
        r
    }
}

fn matmul(x: [[f64; 3]; 3], y: [[f64; 3]; 3]) -> [[f64; 3]; 3] {
    let mut r = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            r[i][j] = (0..3).map(|k| x[i][k] * y[k][j]).sum();
        }
    }
    r
}

impl Transform {
    fn matrix(&self) -> Affine {
        let s = match self.scale {
            None => [1.0; 3],
            Some(Scale::Uniform(s)) => [s; 3],
            Some(Scale::Axes(s)) => s,
        };
        let a = [[s[0], 0.0, 0.0], [0.0, s[1], 0.0], [0.0, 0.0, s[2]]];
        Affine {
            a: matmul(euler(self.rotate.unwrap_or([0.0; 3])), a),
            t: self.translate.unwrap_or([0.0; 3]),
        }
    }
}

/// R = R_z · R_y · R_x for Euler angles `r` in degrees (about X first, then Y, then Z).
fn euler(r: V3) -> [[f64; 3]; 3] {
    let (sx, cx) = r[0].to_radians().sin_cos();
    let (sy, cy) = r[1].to_radians().sin_cos();
    let (sz, cz) = r[2].to_radians().sin_cos();
    let rx = [[1.0, 0.0, 0.0], [0.0, cx, -sx], [0.0, sx, cx]];
    let ry = [[cy, 0.0, sy], [0.0, 1.0, 0.0], [-sy, 0.0, cy]];
    let rz = [[cz, -sz, 0.0], [sz, cz, 0.0], [0.0, 0.0, 1.0]];
    matmul(rz, matmul(ry, rx))
}

/// Which axis of a mesh file points up. momentlab's world is y-up; a z-up mesh (common for
/// STL and PLY scans) is turned by −90° about X, which maps (x, y, z) to (x, z, −y).
#[derive(Deserialize, Clone, Copy, Debug, Default, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub enum UpAxis {
    #[default]
    Y,
    Z,
}

impl std::str::FromStr for UpAxis {
    type Err = anyhow::Error;
    fn from_str(s: &str) -> Result<UpAxis> {
        match s {
            "y" | "Y" => Ok(UpAxis::Y),
            "z" | "Z" => Ok(UpAxis::Z),
            _ => bail!("up axis '{s}': expected y or z"),
        }
    }
}

/// Places a loaded mesh in its object's local frame, in this order: `up_axis` (z-up → y-up),
/// then `rotate` (Euler degrees, X then Y then Z), then `fit` (uniform scale so the largest
/// extent is `fit`, centred in x/z, lowest point at y = 0). The object's `transform` is applied
/// after this, so a fitted mesh always stands on the ground before it is moved.
pub fn orient_mesh(
    tris: &mut [Tri],
    up_axis: UpAxis,
    rotate: Option<V3>,
    fit: Option<f64>,
) -> Result<()> {
    let mut r = euler(rotate.unwrap_or([0.0; 3]));
    if up_axis == UpAxis::Z {
        r = matmul(r, euler([-90.0, 0.0, 0.0]));
    }
    if up_axis != UpAxis::Y || rotate.is_some() {
        let m = Affine { a: r, t: [0.0; 3] };
        for v in tris.iter_mut().flatten() {
            *v = m.apply(*v);
        }
    }
    if let Some(f) = fit {
        pos("mesh fit", f)?;
        fit_mesh(tris, f);
    }
    Ok(())
}

/// Procedural primitives (local coordinates; y is up, solids stand on y = 0 unless noted).
#[derive(Deserialize)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
enum Shape {
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

fn pos(what: &str, v: f64) -> Result<()> {
    if !(v.is_finite() && v > 0.0) {
        bail!("{what} must be positive and finite, got {v}");
    }
    Ok(())
}

/// Triangles of a sphere of `n` segments: ⌈n/2⌉ (at least 2) rings of n quads, the two pole
/// rings as fans.
fn sphere_triangles(n: u128) -> u128 {
    let rings = n.div_ceil(2).max(2);
    n.saturating_mul(2 * rings - 2)
}

impl Shape {
    /// The `type` name of the shape, for errors.
    fn kind(&self) -> &'static str {
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
    fn triangle_count(&self) -> Option<(String, u128)> {
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

    fn triangles(&self, mesh: &dyn MeshFiles) -> Result<Vec<Tri>> {
        let mut out = Vec::new();
        match *self {
            Shape::Plane { size } => {
                pos("plane size", size[0])?;
                pos("plane size", size[1])?;
                let (x, z) = (size[0] / 2.0, size[1] / 2.0);
                quad(
                    &mut out,
                    [-x, 0.0, -z],
                    [-x, 0.0, z],
                    [x, 0.0, z],
                    [x, 0.0, -z],
                );
            }
            Shape::Box { size } => {
                for s in size {
                    pos("box size", s)?;
                }
                boxed(
                    &mut out,
                    [-size[0] / 2.0, 0.0, -size[2] / 2.0],
                    [size[0] / 2.0, size[1], size[2] / 2.0],
                );
            }
            Shape::Cylinder {
                radius,
                height,
                segments,
            } => {
                pos("cylinder radius", radius)?;
                pos("cylinder height", height)?;
                if segments < 3 {
                    bail!("cylinder segments must be ≥ 3");
                }
                cylinder(&mut out, radius, height, segments);
            }
            Shape::Torus {
                radius,
                tube,
                segments,
            } => {
                pos("torus radius", radius)?;
                pos("torus tube", tube)?;
                if segments < 3 {
                    bail!("torus segments must be ≥ 3");
                }
                torus(&mut out, radius, tube, segments, (segments / 2).max(3));
            }
            Shape::Sphere { radius, segments } => {
                pos("sphere radius", radius)?;
                if segments < 3 {
                    bail!("sphere segments must be ≥ 3");
                }
                sphere(&mut out, radius, segments);
            }
            Shape::Stairs {
                steps,
                width,
                step_depth,
                step_height,
            } => {
                pos("stairs width", width)?;
                pos("stairs step_depth", step_depth)?;
                pos("stairs step_height", step_height)?;
                stairs(&mut out, steps, width, step_depth, step_height);
            }
            Shape::Fence {
                width,
                height,
                bars,
                bar_width,
                rails,
                thickness,
            } => {
                pos("fence width", width)?;
                pos("fence height", height)?;
                pos("fence bar_width", bar_width)?;
                pos("fence thickness", thickness)?;
                let t = thickness / 2.0;
                for i in 0..bars {
                    let x = -width / 2.0 + (i as f64 + 0.5) * width / bars as f64;
                    boxed(
                        &mut out,
                        [x - bar_width / 2.0, 0.0, -t],
                        [x + bar_width / 2.0, height, t],
                    );
                }
                for r in 0..rails {
                    let y = height * (r as f64 + 0.5) / rails as f64;
                    // rails slightly thicker than the bars so faces do not coincide
                    boxed(
                        &mut out,
                        [-width / 2.0, y - bar_width / 2.0, -t * 1.5],
                        [width / 2.0, y + bar_width / 2.0, t * 1.5],
                    );
                }
            }
            Shape::Grating {
                size,
                bars,
                bar_width,
                thickness,
            } => {
                pos("grating size", size[0])?;
                pos("grating size", size[1])?;
                pos("grating bar_width", bar_width)?;
                pos("grating thickness", thickness)?;
                let (hx, hz) = (size[0] / 2.0, size[1] / 2.0);
                for i in 0..bars[0] {
                    let x = -hx + (i as f64 + 0.5) * size[0] / bars[0] as f64;
                    boxed(
                        &mut out,
                        [x - bar_width / 2.0, 0.0, -hz],
                        [x + bar_width / 2.0, thickness, hz],
                    );
                }
                for i in 0..bars[1] {
                    let z = -hz + (i as f64 + 0.5) * size[1] / bars[1] as f64;
                    // crossing bars sit half a thickness lower so top faces do not coincide
                    boxed(
                        &mut out,
                        [-hx, -thickness / 2.0, z - bar_width / 2.0],
                        [hx, thickness / 2.0, z + bar_width / 2.0],
                    );
                }
            }
            Shape::Cards {
                count,
                size,
                region,
                seed,
            } => {
                pos("cards size", size[0])?;
                pos("cards size", size[1])?;
                let mut rng = ChaCha8Rng::seed_from_u64(seed);
                for _ in 0..count {
                    let c: V3 = std::array::from_fn(|k| {
                        let (lo, hi) = (region[k], region[k + 3]);
                        if hi > lo {
                            rng.gen_range(lo..hi)
                        } else {
                            lo
                        }
                    });
                    let a = random_unit(&mut rng);
                    let mut b = random_unit(&mut rng);
                    b = sub(b, scale(a, dot(a, b)));
                    let nb = norm(b);
                    let b = if nb > 1e-6 {
                        scale(b, 1.0 / nb)
                    } else {
                        perpendicular(a)
                    };
                    let (ha, hb) = (scale(a, size[0] / 2.0), scale(b, size[1] / 2.0));
                    quad(
                        &mut out,
                        sub(sub(c, ha), hb),
                        add(sub(c, ha), hb),
                        add(add(c, ha), hb),
                        sub(add(c, ha), hb),
                    );
                }
            }
            Shape::City {
                grid,
                spacing,
                footprint,
                height,
                bridges,
                seed,
            } => {
                pos("city spacing", spacing)?;
                if !(0.0 < footprint[0] && footprint[0] <= footprint[1] && footprint[1] < spacing) {
                    bail!("city footprint range must satisfy 0 < min ≤ max < spacing");
                }
                if !(0.0 < height[0] && height[0] <= height[1]) {
                    bail!("city height range must satisfy 0 < min ≤ max");
                }
                let mut rng = ChaCha8Rng::seed_from_u64(seed);
                let mut tops = vec![0.0; grid[0] * grid[1]];
                let cx = |i: usize, n: usize| (i as f64 - (n as f64 - 1.0) / 2.0) * spacing;
                for j in 0..grid[1] {
                    for i in 0..grid[0] {
                        let fx = rng.gen_range(footprint[0]..=footprint[1]) / 2.0;
                        let fz = rng.gen_range(footprint[0]..=footprint[1]) / 2.0;
                        let h = rng.gen_range(height[0]..=height[1]);
                        let (x, z) = (cx(i, grid[0]), cx(j, grid[1]));
                        boxed(&mut out, [x - fx, 0.0, z - fz], [x + fx, h, z + fz]);
                        tops[j * grid[0] + i] = h;
                    }
                }
                for _ in 0..bridges {
                    if grid[0] < 2 || grid[1] < 1 {
                        break;
                    }
                    let along_x = grid[1] < 2 || rng.gen_bool(0.5);
                    let (i, j) = if along_x {
                        (rng.gen_range(0..grid[0] - 1), rng.gen_range(0..grid[1]))
                    } else {
                        (rng.gen_range(0..grid[0]), rng.gen_range(0..grid[1] - 1))
                    };
                    let (i2, j2) = if along_x { (i + 1, j) } else { (i, j + 1) };
                    let top = tops[j * grid[0] + i].min(tops[j2 * grid[0] + i2]);
                    let y = rng.gen_range(0.3 * top..0.8 * top);
                    let th = 0.04 * spacing;
                    let w = 0.15 * spacing;
                    let (x0, z0) = (cx(i, grid[0]), cx(j, grid[1]));
                    let (x1, z1) = (cx(i2, grid[0]), cx(j2, grid[1]));
                    let lo = [x0.min(x1) - w, y, z0.min(z1) - w];
                    let hi = [x0.max(x1) + w, y + th, z0.max(z1) + w];
                    boxed(&mut out, lo, hi);
                }
            }
            Shape::Arcade {
                columns,
                spacing,
                radius,
                height,
                depth,
                roof,
            } => {
                for (w, v) in [
                    ("spacing", spacing),
                    ("radius", radius),
                    ("height", height),
                    ("depth", depth),
                    ("roof", roof),
                ] {
                    pos(&format!("arcade {w}"), v)?;
                }
                let half = (columns.max(1) as f64 - 1.0) / 2.0 * spacing;
                for i in 0..columns {
                    let x = i as f64 * spacing - half;
                    for z in [-depth / 2.0, depth / 2.0] {
                        let mut c = Vec::new();
                        cylinder(&mut c, radius, height, 16);
                        out.extend(c.into_iter().map(|t| t.map(|p| [p[0] + x, p[1], p[2] + z])));
                    }
                }
                let m = 2.0 * radius;
                boxed(
                    &mut out,
                    [-half - m, height, -depth / 2.0 - m],
                    [half + m, height + roof, depth / 2.0 + m],
                );
            }
            Shape::Mesh {
                ref path,
                fit,
                up_axis,
                rotate,
            } => {
                let bytes = mesh.read(path)?;
                let mut tris =
                    load_mesh_from(path, &bytes, mesh).with_context(|| format!("mesh '{path}'"))?;
                orient_mesh(&mut tris, up_axis, rotate, fit)?;
                out = tris;
            }
        }
        Ok(out)
    }
}

fn fit_mesh(tris: &mut [Tri], fit: f64) {
    let (lo, hi) = bounds(tris);
    let ext = (0..3).map(|k| hi[k] - lo[k]).fold(0.0, f64::max);
    let s = if ext > 0.0 { fit / ext } else { 1.0 };
    let c = [(lo[0] + hi[0]) / 2.0, lo[1], (lo[2] + hi[2]) / 2.0];
    for v in tris.iter_mut().flatten() {
        *v = scale(sub(*v, c), s);
    }
}

pub(crate) fn add(a: V3, b: V3) -> V3 {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}
pub(crate) fn sub(a: V3, b: V3) -> V3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
pub(crate) fn scale(a: V3, s: f64) -> V3 {
    [a[0] * s, a[1] * s, a[2] * s]
}
pub(crate) fn dot(a: V3, b: V3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
pub(crate) fn cross(a: V3, b: V3) -> V3 {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}
pub(crate) fn norm(a: V3) -> f64 {
    dot(a, a).sqrt()
}
fn perpendicular(a: V3) -> V3 {
    let h = if a[0].abs() < 0.9 {
        [1.0, 0.0, 0.0]
    } else {
        [0.0, 1.0, 0.0]
    };
    let c = cross(a, h);
    scale(c, 1.0 / norm(c))
}
fn random_unit(rng: &mut ChaCha8Rng) -> V3 {
    loop {
        let v = [
            rng.gen_range(-1.0..1.0),
            rng.gen_range(-1.0..1.0),
            rng.gen_range(-1.0..1.0),
        ];
        let n = norm(v);
        if n > 1e-3 && n <= 1.0 {
            return scale(v, 1.0 / n);
        }
    }
}

/// Quad a-b-c-d as two triangles.
pub fn quad(out: &mut Vec<Tri>, a: V3, b: V3, c: V3, d: V3) {
    out.push([a, b, c]);
    out.push([a, c, d]);
}

/// Axis-aligned box from `lo` to `hi` (12 triangles).
pub fn boxed(out: &mut Vec<Tri>, lo: V3, hi: V3) {
    let p = |i: usize| -> V3 {
        [
            if i & 1 == 0 { lo[0] } else { hi[0] },
            if i & 2 == 0 { lo[1] } else { hi[1] },
            if i & 4 == 0 { lo[2] } else { hi[2] },
        ]
    };
    for f in [
        [0, 2, 6, 4],
        [1, 5, 7, 3],
        [0, 4, 5, 1],
        [2, 3, 7, 6],
        [0, 1, 3, 2],
        [4, 6, 7, 5],
    ] {
        quad(out, p(f[0]), p(f[1]), p(f[2]), p(f[3]));
    }
}

fn stairs(out: &mut Vec<Tri>, n: usize, width: f64, d: f64, h: f64) {
    let (x0, x1) = (-width / 2.0, width / 2.0);
    let top = n as f64 * h;
    let back = n as f64 * d;
    for i in 0..n {
        let (z0, z1) = (i as f64 * d, (i + 1) as f64 * d);
        let (y0, y1) = (i as f64 * h, (i + 1) as f64 * h);
        // riser (facing −z) and tread (facing +y)
        quad(out, [x0, y0, z0], [x0, y1, z0], [x1, y1, z0], [x1, y0, z0]);
        quad(out, [x0, y1, z0], [x0, y1, z1], [x1, y1, z1], [x1, y1, z0]);
        // the two side faces of this column of the profile
        for x in [x0, x1] {
            quad(out, [x, 0.0, z0], [x, y1, z0], [x, y1, z1], [x, 0.0, z1]);
        }
    }
    if n > 0 {
        quad(
            out,
            [x0, 0.0, back],
            [x1, 0.0, back],
            [x1, top, back],
            [x0, top, back],
        );
        quad(
            out,
            [x0, 0.0, 0.0],
            [x1, 0.0, 0.0],
            [x1, 0.0, back],
            [x0, 0.0, back],
        );
    }
}

fn cylinder(out: &mut Vec<Tri>, r: f64, h: f64, n: usize) {
    let pt = |i: usize, y: f64| {
        let a = std::f64::consts::TAU * (i % n) as f64 / n as f64;
        [r * a.cos(), y, r * a.sin()]
    };
    for i in 0..n {
        quad(out, pt(i, 0.0), pt(i, h), pt(i + 1, h), pt(i + 1, 0.0));
        out.push([[0.0, 0.0, 0.0], pt(i + 1, 0.0), pt(i, 0.0)]);
        out.push([[0.0, h, 0.0], pt(i, h), pt(i + 1, h)]);
    }
}

/// Torus about the y axis: ring radius `big`, tube radius `small`, `n` ring and `m` tube
/// segments (quads split into two triangles).
pub fn torus(out: &mut Vec<Tri>, big: f64, small: f64, n: usize, m: usize) {
    let pt = |i: usize, j: usize| {
        let ph = std::f64::consts::TAU * (i % n) as f64 / n as f64;
        let th = std::f64::consts::TAU * (j % m) as f64 / m as f64;
        let r = big + small * th.cos();
        [r * ph.cos(), small * th.sin(), r * ph.sin()]
    };
    for i in 0..n {
        for j in 0..m {
            quad(out, pt(i, j), pt(i + 1, j), pt(i + 1, j + 1), pt(i, j + 1));
        }
    }
}

/// UV sphere of radius `r` with `n` segments around and ⌈n/2⌉ rings (pole caps as fans).
pub fn sphere(out: &mut Vec<Tri>, r: f64, n: usize) {
    let rings = n.div_ceil(2).max(2);
    let pt = |i: usize, j: usize| {
        let th = std::f64::consts::PI * j as f64 / rings as f64;
        let ph = std::f64::consts::TAU * (i % n) as f64 / n as f64;
        [
            r * th.sin() * ph.cos(),
            r * th.cos(),
            r * th.sin() * ph.sin(),
        ]
    };
    for j in 0..rings {
        for i in 0..n {
            let (a, b, c, d) = (pt(i, j), pt(i + 1, j), pt(i + 1, j + 1), pt(i, j + 1));
            if j > 0 {
                out.push([a, b, c]);
            }
            if j + 1 < rings {
                out.push([a, c, d]);
            }
        }
    }
}
