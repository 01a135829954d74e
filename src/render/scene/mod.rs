//! Scenes: a list of triangles (world space) and the directional lights (views) to render.
//! Loaded from JSON (procedural primitives and OBJ meshes with transforms; format in
//! docs/stacks.md) or built in code.
//!
//! * [`schema`]: the scene file as written — objects, shapes, lights, cameras, the light
//!   sidecar of a mesh file — and the checks on its numbers.
//! * [`transform`]: the affine maps of objects and the placement of meshes.
//! * [`triangulate`]: the procedural shapes as triangles.

mod schema;
#[cfg(test)]
mod tests;
mod transform;
mod triangulate;

pub use super::mesh::load_obj_bytes;
use super::mesh::MeshFiles;
use crate::linalg::v3::{norm, scale};
use crate::stack::check_plain_name;
use anyhow::{bail, Context, Result};
use schema::{Object, SceneDesc, Shape};
use std::path::Path;
use transform::{check_affine, Transform};

pub use super::{Tri, V3};
pub use schema::{CameraDesc, LightDesc, MeshSidecar, MAX_AZIMUTH_DEG, MIN_ELEVATION_DEG};
pub use transform::{orient_mesh, Affine, UpAxis};
pub use triangulate::{boxed, quad, sphere, torus};

/// One view of a scene: a directional light.
#[derive(Clone, Debug, PartialEq)]
pub struct Light {
    /// View name, e.g. "light0".
    pub name: String,
    /// Unit direction the light travels (world space).
    pub dir: V3,
    /// Viewing direction (unit) of this view's eye-view camera from the scene file; `None`:
    /// [`crate::metrics::eye::default_camera`] of `dir`.
    pub camera: Option<V3>,
}

/// A scene ready to render: world-space triangles and its lights.
#[derive(Clone, Debug)]
pub struct Scene {
    /// Scene name.
    pub name: String,
    /// Its views, one per light.
    pub lights: Vec<Light>,
    /// World-space triangles.
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
        let mut sc: MeshSidecar = if std::fs::symlink_metadata(&side).is_ok() {
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

pub use super::mesh::MAX_TRIANGLES;

/// Largest |coordinate| of a scene vertex (world units): depths and their differences stay
/// well inside f64 and the f32 depth maps keep their resolution.
pub const MAX_COORD: f64 = 1e9;

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

fn pos(what: &str, v: f64) -> Result<()> {
    if !(v.is_finite() && v > 0.0) {
        bail!("{what} must be positive and finite, got {v}");
    }
    Ok(())
}
