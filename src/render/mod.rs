//! The reference renderer: a CPU ray caster for a directional light (orthographic projection
//! fitted to the scene bounds) recording every surface along each texel's ray.
//!
//! Light space: w = p·d along the light direction d, u = p·u_axis, v = p·v_axis with
//! (u_axis, v_axis, d) right-handed orthonormal and v_axis the negated projection of world up
//! (+y texel rows go "down"). Depth z = (w − near)/(far − near) ∈ [0,1], with near/far the
//! scene's w range widened by 1 % on each side; the square (u, v) window is the scene's
//! projected bounds widened by 1 %. Texel (x, y) casts one ray through its centre
//! (u0 + (x+½)·s, v0 + (y+½)·s). Per surface the receiver-plane slopes are analytic from the
//! triangle's geometric normal n in light space: ∂z/∂x = −(n_u/n_w)·s/(far−near),
//! ∂z/∂y = −(n_v/n_w)·s/(far−near) (per texel step).

pub mod bvh;
mod embedded;
pub mod mesh;
pub mod scene;

pub use embedded::{embedded_fingerprint, embedded_scenes, EMBEDDED_SCENE_NAMES};
pub use scene::{Light, Scene};

use crate::stack::{DepthStack, StackMeta};

/// A point / vector in world space.
pub type V3 = [f64; 3];
/// A triangle (three world-space vertices).
pub type Tri = [V3; 3];
use crate::linalg::v3::{cross, dot, norm, scale, sub};
use anyhow::{bail, Context, Result};
use bvh::{Bvh, LTri};
use rayon::prelude::*;
use std::path::Path;

pub use crate::stack::{DEDUP_EPS, MARGIN};

/// The orthographic light frame of one view.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightFrame {
    /// Unit direction the light travels (the depth axis w).
    pub dir: V3,
    /// Unit texel x axis (u), orthogonal to `dir`.
    pub u_axis: V3,
    /// Unit texel y axis (v), orthogonal to `dir` and `u_axis`.
    pub v_axis: V3,
    /// w of depth 0.
    pub near: f64,
    /// w of depth 1.
    pub far: f64,
    /// (u, v) of the corner of texel (0, 0).
    pub uv_origin: [f64; 2],
    /// Texel edge length (world units).
    pub texel: f64,
    /// Texels per side (square shadow map).
    pub resolution: usize,
}

impl LightFrame {
    /// Fits the frame for light direction `dir` (unit) to the bounds of `tris`.
    pub fn fit(tris: &[Tri], dir: V3, resolution: usize) -> LightFrame {
        let hint = if dir[1].abs() < 0.9 {
            [0.0, 1.0, 0.0]
        } else {
            [0.0, 0.0, 1.0]
        };
        let up = sub(hint, scale(dir, dot(hint, dir)));
        let v_axis = scale(up, -1.0 / norm(up));
        let u_axis = cross(v_axis, dir);
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for p in tris.iter().flatten() {
            let q = [dot(*p, u_axis), dot(*p, v_axis), dot(*p, dir)];
            for k in 0..3 {
                lo[k] = lo[k].min(q[k]);
                hi[k] = hi[k].max(q[k]);
            }
        }
        if tris.is_empty() {
            lo = [-1.0; 3];
            hi = [1.0; 3];
        }
        let ext = (hi[0] - lo[0]).max(hi[1] - lo[1]);
        let ext = if ext > 0.0 { ext } else { 1.0 };
        let side = ext * (1.0 + 2.0 * MARGIN);
        let mut dr = hi[2] - lo[2];
        if dr <= 0.0 {
            dr = ext;
        }
        LightFrame {
            dir,
            u_axis,
            v_axis,
            near: lo[2] - MARGIN * dr,
            far: hi[2] + MARGIN * dr,
            uv_origin: [
                (lo[0] + hi[0]) / 2.0 - side / 2.0,
                (lo[1] + hi[1]) / 2.0 - side / 2.0,
            ],
            texel: side / resolution as f64,
            resolution,
        }
    }

    /// Light-space (u, v, w) of a world point.
    pub fn to_light(&self, p: V3) -> V3 {
        [dot(p, self.u_axis), dot(p, self.v_axis), dot(p, self.dir)]
    }

    /// World-space origin (on the near plane) of the ray of texel (x, y).
    pub fn ray_origin(&self, x: usize, y: usize) -> V3 {
        let u = self.uv_origin[0] + (x as f64 + 0.5) * self.texel;
        let v = self.uv_origin[1] + (y as f64 + 0.5) * self.texel;
        std::array::from_fn(|k| u * self.u_axis[k] + v * self.v_axis[k] + self.near * self.dir[k])
    }
}

/// One surface along a texel's ray.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// Depth (w − near)/(far − near) ∈ [0,1].
    pub z: f32,
    /// Slope dz/du per texel step in x.
    pub dzdu: f32,
    /// Slope dz/dv per texel step in y.
    pub dzdv: f32,
}

/// Sorts raw hits (w, ∂w/∂u, ∂w/∂v) front to back, converts them to depth/slopes per texel
/// step and merges hits closer than [`DEDUP_EPS`] (the front-most is kept).
pub fn finish_hits(frame: &LightFrame, raw: &mut [(f64, f64, f64)], out: &mut Vec<Hit>) {
    raw.sort_by(|a, b| a.0.total_cmp(&b.0));
    let range = frame.far - frame.near;
    let k = frame.texel / range;
    let mut last = f64::NEG_INFINITY;
    for &(w, su, sv) in raw.iter() {
        let z = ((w - frame.near) / range).clamp(0.0, 1.0);
        if z - last <= DEDUP_EPS {
            continue;
        }
        last = z;
        out.push(Hit {
            z: z as f32,
            dzdu: (su * k) as f32,
            dzdv: (sv * k) as f32,
        });
    }
}

/// The scene's triangles in the frame's light space, ready for ray casting.
pub fn light_bvh(tris: &[Tri], frame: &LightFrame) -> Bvh {
    let lt: Vec<LTri> = tris
        .iter()
        .filter_map(|t| {
            LTri::new(
                frame.to_light(t[0]),
                frame.to_light(t[1]),
                frame.to_light(t[2]),
            )
        })
        .collect();
    Bvh::build(lt)
}

/// Renders view `light_index` of `scene` at `resolution`² (see module docs). Panics if
/// `light_index` is out of range or `resolution` is 0, or if the view has more layers than a
/// stack may hold (for scenes built in code and tests; user scenes go through
/// [`try_render_view`]).
pub fn render_view(scene: &Scene, light_index: usize, resolution: usize) -> DepthStack {
    try_render_view(scene, light_index, resolution).unwrap_or_else(|e| panic!("{e:#}"))
}

/// [`render_view`], with an error when the view would be a stack its reader refuses (more than
/// [`MAX_LAYERS`](crate::stack::MAX_LAYERS) layers, or more than
/// [`MAX_STACK_BYTES`](crate::stack::MAX_STACK_BYTES)), found before the layers are allocated.
pub fn try_render_view(scene: &Scene, light_index: usize, resolution: usize) -> Result<DepthStack> {
    render_view_with(scene, light_index, resolution, &|_| {})
}

/// [`try_render_view`] calling `row_done(1)` after each finished row (for progress bars).
pub fn render_view_with(
    scene: &Scene,
    light_index: usize,
    resolution: usize,
    row_done: &(dyn Fn(u64) + Sync),
) -> Result<DepthStack> {
    assert!(resolution > 0, "resolution must be positive");
    let light = &scene.lights[light_index];
    let frame = LightFrame::fit(&scene.triangles, light.dir, resolution);
    let bvh = light_bvh(&scene.triangles, &frame);
    let n = resolution;
    let rows: Vec<(Vec<u32>, Vec<Hit>)> = (0..n)
        .into_par_iter()
        .map(|y| {
            let mut counts = Vec::with_capacity(n);
            let mut hits = Vec::new();
            let mut raw = Vec::new();
            let v = frame.uv_origin[1] + (y as f64 + 0.5) * frame.texel;
            for x in 0..n {
                let u = frame.uv_origin[0] + (x as f64 + 0.5) * frame.texel;
                raw.clear();
                bvh.for_each_hit(u, v, |t, w| raw.push((w, t.su, t.sv)));
                let before = hits.len();
                finish_hits(&frame, &mut raw, &mut hits);
                counts.push((hits.len() - before) as u32);
            }
            row_done(1);
            (counts, hits)
        })
        .collect();
    let layers = rows
        .iter()
        .flat_map(|r| r.0.iter())
        .copied()
        .max()
        .unwrap_or(0)
        .max(1) as usize;
    if layers > crate::stack::MAX_LAYERS {
        bail!(
            "scene '{}' view '{}' at {n}×{n}: {layers} surfaces along one texel's ray, more than \
             the {} layers a stack may hold",
            scene.name,
            light.name,
            crate::stack::MAX_LAYERS
        );
    }
    let meta = StackMeta {
        scene: scene.name.clone(),
        view: light.name.clone(),
        light_dir: light.dir,
        near: frame.near,
        far: frame.far,
        width: n,
        height: n,
        layers,
        u_axis: frame.u_axis,
        v_axis: frame.v_axis,
        uv_origin: frame.uv_origin,
        texel_size: frame.texel,
    };
    // the reader's limits, before the layers are allocated
    crate::stack::check_size(&meta)
        .with_context(|| format!("scene '{}' view '{}'", scene.name, light.name))?;
    let mut depth = vec![vec![f32::INFINITY; n * n]; layers];
    let mut dzdu = vec![vec![0.0f32; n * n]; layers];
    let mut dzdv = vec![vec![0.0f32; n * n]; layers];
    for (y, (counts, hits)) in rows.iter().enumerate() {
        let mut i = 0;
        for (x, &c) in counts.iter().enumerate() {
            let t = y * n + x;
            for l in 0..c as usize {
                let h = hits[i];
                depth[l][t] = h.z;
                dzdu[l][t] = h.dzdu;
                dzdv[l][t] = h.dzdv;
                i += 1;
            }
        }
    }
    Ok(DepthStack {
        meta,
        depth,
        dzdu,
        dzdv,
    })
}

/// The scenes of `path`: a folder gives all its `*.json` scene files (sorted by file name;
/// `*.lights.json` mesh sidecars skipped); a `.json` file is one scene file; a mesh file
/// (.obj, .gltf, .glb, .ply, .stl) is rendered directly ([`Scene::load_mesh_file`], with
/// `lights` and `up_axis` from the command line). `lights`/`up_axis` only apply to a mesh file.
pub fn load_scenes(
    path: &Path,
    lights: &[scene::LightDesc],
    up_axis: Option<scene::UpAxis>,
) -> Result<Vec<Scene>> {
    let mesh_only = |what: &str| -> Result<()> {
        if !lights.is_empty() || up_axis.is_some() {
            bail!(
                "{}: --light and --up-axis apply to a mesh file given to --scenes, not to {what}",
                path.display()
            );
        }
        Ok(())
    };
    if path.is_dir() {
        mesh_only("a folder of scene files")?;
        let mut files = Vec::new();
        for e in std::fs::read_dir(path).with_context(|| format!("reading {}", path.display()))? {
            let p = e?.path();
            let name = p.file_name().unwrap_or_default().to_string_lossy();
            if p.is_file() && name.ends_with(".json") && !name.ends_with(".lights.json") {
                files.push(p);
            }
        }
        files.sort();
        if files.is_empty() {
            bail!("no *.json scenes in {}", path.display());
        }
        return files.iter().map(|p| Scene::load(p)).collect();
    }
    if std::fs::symlink_metadata(path).is_err() {
        bail!("{}: no such file or folder", path.display());
    }
    crate::artefact::check_regular(path)?;
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    if ext == "json" {
        mesh_only("a scene file")?;
        return Ok(vec![Scene::load(path)?]);
    }
    // any other extension: a mesh file (an unsupported format is a one-line error naming it)
    mesh::MeshFormat::from_path(&path.to_string_lossy())?;
    Ok(vec![Scene::load_mesh_file(path, lights, up_axis)?])
}

/// The embedded default dataset (every view of every embedded scene), rendered at
/// `resolution`², in scene-file then light order.
pub fn default_dataset(resolution: usize) -> Result<Vec<DepthStack>> {
    if resolution == 0 {
        bail!("resolution must be positive");
    }
    let scenes = embedded_scenes()?;
    scenes
        .iter()
        .flat_map(|s| (0..s.lights.len()).map(move |i| (s, i)))
        .map(|(s, i)| try_render_view(s, i, resolution))
        .collect()
}

/// The views of the default dataset as (scene, light) names, in the order [`default_dataset`]
/// renders them; nothing is rendered.
pub fn default_dataset_views() -> Result<Vec<(String, String)>> {
    Ok(embedded_scenes()?
        .iter()
        .flat_map(|s| s.lights.iter().map(|l| (s.name.clone(), l.name.clone())))
        .collect())
}

pub mod rectified;
