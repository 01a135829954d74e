//! Triangle meshes from files: OBJ, glTF 2.0 (.gltf, .glb), PLY (ASCII, binary little and big
//! endian) and STL (ASCII, binary). The format is chosen by the file extension and checked
//! against the first bytes (magic), so a misnamed file is a one-line error naming both formats;
//! any other extension is a one-line error naming the format. Every count and offset read from
//! a file is checked against the file's length before anything is allocated.

mod gltf;
mod ply;
mod stl;

use super::scene::Tri;
use anyhow::{anyhow, bail, Result};
use std::path::Path;

pub use self::gltf::load_gltf_bytes;
pub use self::ply::load_ply_bytes;
pub use self::stl::load_stl_bytes;

/// Largest triangle count of a scene, and so of one mesh file (each triangle takes 72 bytes,
/// so a scene holds at most 3.6 GB of triangles before its BVH). Checked before the triangles
/// are built: from the counts of procedural objects, from the face and index counts of mesh
/// files as they are read.
pub const MAX_TRIANGLES: usize = 50_000_000;

/// Error unless `have` triangles and `more` to come stay within [`MAX_TRIANGLES`].
pub(crate) fn check_triangles(what: &dyn Fn() -> String, have: usize, more: usize) -> Result<()> {
    if more > MAX_TRIANGLES.saturating_sub(have) {
        bail!(
            "{}: more than {MAX_TRIANGLES} triangles (the limit of a scene)",
            what()
        );
    }
    Ok(())
}

/// The mesh formats read.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MeshFormat {
    /// Wavefront OBJ.
    Obj,
    /// glTF 2.0 JSON (`.gltf`; buffers embedded as data URIs or external files).
    Gltf,
    /// glTF 2.0 binary container (`.glb`).
    Glb,
    /// Stanford PLY (ASCII or binary).
    Ply,
    /// STL (ASCII or binary).
    Stl,
}

impl MeshFormat {
    /// Human-readable format name for messages.
    pub fn name(self) -> &'static str {
        match self {
            MeshFormat::Obj => "OBJ",
            MeshFormat::Gltf => "glTF (JSON)",
            MeshFormat::Glb => "glTF (binary .glb)",
            MeshFormat::Ply => "PLY",
            MeshFormat::Stl => "STL",
        }
    }

    /// The format of a file name by its extension (case-insensitive).
    pub fn from_path(path: &str) -> Result<MeshFormat> {
        let ext = Path::new(path)
            .extension()
            .map(|e| e.to_string_lossy().to_ascii_lowercase())
            .unwrap_or_default();
        Ok(match ext.as_str() {
            "obj" => MeshFormat::Obj,
            "gltf" => MeshFormat::Gltf,
            "glb" => MeshFormat::Glb,
            "ply" => MeshFormat::Ply,
            "stl" => MeshFormat::Stl,
            "" => bail!(
                "'{path}' has no file extension; mesh formats read: .obj, .gltf, .glb, .ply, .stl"
            ),
            other => {
                let known = match other {
                    "fbx" => "FBX",
                    "dae" => "COLLADA",
                    "3ds" => "3DS",
                    "blend" => "Blender",
                    "usd" | "usda" | "usdc" | "usdz" => "USD",
                    "abc" => "Alembic",
                    "off" => "OFF",
                    "x3d" | "wrl" => "VRML/X3D",
                    _ => "",
                };
                let what = if known.is_empty() {
                    format!("the .{other} format")
                } else {
                    format!("{known} (.{other})")
                };
                bail!(
                    "'{path}': {what} is not a supported mesh format; mesh formats read: OBJ \
                     (.obj), glTF 2.0 (.gltf, .glb), PLY (.ply), STL (.stl)"
                )
            }
        })
    }
}

/// The format the bytes look like, from their first bytes; `None` for plain text that matches
/// no magic (an OBJ file has none).
pub fn sniff(bytes: &[u8]) -> Option<MeshFormat> {
    let head = &bytes[..bytes.len().min(512)];
    let text_start = head
        .iter()
        .position(|b| !b.is_ascii_whitespace())
        .map_or(&head[..0], |i| &head[i..]);
    if head.starts_with(b"glTF") {
        Some(MeshFormat::Glb)
    } else if head.starts_with(b"ply\n") || head.starts_with(b"ply\r\n") {
        Some(MeshFormat::Ply)
    } else if stl::is_binary_stl(bytes) || text_start.starts_with(b"solid") {
        Some(MeshFormat::Stl)
    } else if text_start.starts_with(b"{") {
        Some(MeshFormat::Gltf)
    } else {
        None
    }
}

/// Where a mesh and the files it refers to (external glTF buffers) are read from.
pub trait MeshFiles {
    /// The bytes of the file at `rel` (relative to the scene's base).
    fn read(&self, rel: &str) -> Result<Vec<u8>>;
    /// The bytes of file `name` beside the mesh `mesh` (a path as given to [`MeshFiles::read`]);
    /// `name` is a relative path already checked by [`check_beside`]. A reader of real folders
    /// also checks that the file it opens, links followed, lies in the mesh's folder.
    fn read_beside(&self, mesh: &str, name: &str) -> Result<Vec<u8>> {
        let base = Path::new(mesh).parent().unwrap_or(Path::new(""));
        self.read(&base.join(name).to_string_lossy())
    }
}

impl<F: Fn(&str) -> Result<Vec<u8>>> MeshFiles for F {
    fn read(&self, rel: &str) -> Result<Vec<u8>> {
        self(rel)
    }
}

/// `name` (a glTF buffer URI that is not a data URI) as a path in or below the mesh's folder:
/// relative, no `..`, no backslash, no URI scheme, no control characters.
pub fn check_beside(name: &str) -> Result<()> {
    use std::path::Component;
    let p = Path::new(name);
    let plain = !name.is_empty()
        && !name.contains('\\')
        && !name.chars().any(char::is_control)
        && !name.split('/').next().unwrap_or("").contains(':')
        && p.components()
            .all(|c| matches!(c, Component::Normal(_) | Component::CurDir));
    if !plain {
        bail!(
            "uri '{}' is not a file in the folder of the .gltf (only data URIs and relative \
             paths without '..' are read)",
            name.escape_debug()
        );
    }
    Ok(())
}

/// Triangles of the mesh file `path` (format by extension, checked by magic). `bytes` is the
/// file's content; `resolve` reads a file given its path relative to the same base as `path`
/// (external glTF buffers are resolved next to the `.gltf`).
pub fn load_mesh(
    path: &str,
    bytes: &[u8],
    resolve: &dyn Fn(&str) -> Result<Vec<u8>>,
) -> Result<Vec<Tri>> {
    load_mesh_from(path, bytes, &resolve)
}

/// [`load_mesh`] reading external glTF buffers through `files` ([`MeshFiles::read_beside`]).
pub fn load_mesh_from(path: &str, bytes: &[u8], files: &dyn MeshFiles) -> Result<Vec<Tri>> {
    let fmt = MeshFormat::from_path(path)?;
    let seen = sniff(bytes);
    let mismatch = match (fmt, seen) {
        (MeshFormat::Obj, None) => false,
        (MeshFormat::Obj, Some(_)) => true,
        (f, Some(s)) => f != s,
        (_, None) => {
            bail!(
                "'{path}' is not a {} file (its first bytes match no mesh format)",
                fmt.name()
            )
        }
    };
    if mismatch {
        let s = seen.map_or("unknown", MeshFormat::name);
        bail!(
            "'{path}' is named as {} but its content is {s}; rename it to match its format",
            fmt.name()
        );
    }
    let tris = match fmt {
        MeshFormat::Obj => {
            if bytes[..bytes.len().min(4096)].contains(&0) {
                bail!("'{path}' is not a text OBJ file (binary content)");
            }
            load_obj_bytes(bytes)?
        }
        MeshFormat::Gltf | MeshFormat::Glb => load_gltf_bytes(bytes, &|uri: &str| {
            check_beside(uri)?;
            files.read_beside(path, uri)
        })?,
        MeshFormat::Ply => load_ply_bytes(bytes)?,
        MeshFormat::Stl => load_stl_bytes(bytes)?,
    };
    check_finite(&tris, fmt.name())?;
    Ok(tris)
}

fn check_finite(tris: &[Tri], what: &str) -> Result<()> {
    if tris.is_empty() {
        bail!("{what} mesh has no triangles");
    }
    if let Some(i) = tris
        .iter()
        .position(|t| t.iter().flatten().any(|c| !c.is_finite()))
    {
        bail!("{what} mesh: triangle {i} has a non-finite vertex coordinate");
    }
    Ok(())
}

/// Triangles of an OBJ file (all models, faces triangulated).
pub fn load_obj_bytes(bytes: &[u8]) -> Result<Vec<Tri>> {
    let opts = tobj::LoadOptions {
        triangulate: true,
        single_index: true,
        ..Default::default()
    };
    let mut reader = std::io::BufReader::new(bytes);
    let (models, _) =
        tobj::load_obj_buf(&mut reader, &opts, |_| Err(tobj::LoadError::OpenFileFailed))
            .map_err(|e| anyhow!("OBJ parse error: {e}"))?;
    let faces = models
        .iter()
        .fold(0usize, |a, m| a.saturating_add(m.mesh.indices.len() / 3));
    check_triangles(&|| "OBJ".to_string(), 0, faces)?;
    let mut tris = Vec::with_capacity(faces);
    for m in &models {
        let p = &m.mesh.positions;
        let idx = &m.mesh.indices;
        let vert = |i: u32| -> Result<[f64; 3]> {
            let i = i as usize * 3;
            if i + 2 >= p.len() {
                bail!("OBJ index out of range in model '{}'", m.name);
            }
            Ok([p[i] as f64, p[i + 1] as f64, p[i + 2] as f64])
        };
        for f in idx.chunks_exact(3) {
            tris.push([vert(f[0])?, vert(f[1])?, vert(f[2])?]);
        }
    }
    if tris.is_empty() {
        bail!("OBJ has no triangles");
    }
    if tris.iter().flatten().flatten().any(|c| !c.is_finite()) {
        bail!("OBJ has non-finite vertex coordinates");
    }
    Ok(tris)
}

/// Fan-triangulates polygon `idx` (vertex indices into `verts`), checking every index.
pub(crate) fn fan(
    verts: &[[f64; 3]],
    idx: &[usize],
    what: &dyn Fn() -> String,
    out: &mut Vec<Tri>,
) -> Result<()> {
    if idx.len() < 3 {
        bail!("{}: a face has {} vertices (need ≥ 3)", what(), idx.len());
    }
    let v = |i: usize| -> Result<[f64; 3]> {
        verts.get(i).copied().ok_or_else(|| {
            anyhow!(
                "{}: vertex index {i} out of range ({} vertices)",
                what(),
                verts.len()
            )
        })
    };
    check_triangles(what, out.len(), idx.len() - 2)?;
    let a = v(idx[0])?;
    for k in 1..idx.len() - 1 {
        out.push([a, v(idx[k])?, v(idx[k + 1])?]);
    }
    Ok(())
}
