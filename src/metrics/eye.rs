//! Eye-view pictures (the paper's Fig. 6 way): an orthographic camera ray caster over the same
//! BVH as the light view, and per visible point the shadow intensity a GPU would compute from
//! the light's shadow map at the point's light-space position: a technique's filtered moments
//! bilinearly interpolated between the four nearest texel centres (clamped edges), evaluated at
//! the point's biased depth z − ε′; PCF at those four texels (the point's depth carried to each
//! texel centre along its receiver plane) blended with the same bilinear weights.

use crate::kernel::{self, Gaussian};
use crate::linalg::v3::{dot, norm, scale, sub};
use crate::metrics::{self, Bias, FrontMap, Subject};
use crate::render::{light_bvh, Light, LightFrame, Scene, Tri, V3};
use crate::stack::DepthStack;
use anyhow::{bail, Result};
use rayon::prelude::*;

/// Elevation of the default camera above the horizon, degrees.
pub const DEFAULT_ELEVATION_DEG: f64 = 40.0;

/// The default camera of a view: orthographic, looking down at [`DEFAULT_ELEVATION_DEG`] from
/// the side (azimuth of the light's horizontal travel + 90°), so cast shadows lie beside their
/// occluders in the picture. Returns the unit viewing direction.
pub fn default_camera(light_dir: V3) -> V3 {
    let h = [light_dir[0], 0.0, light_dir[2]];
    let n = norm(h);
    let (hx, hz) = if n > 1e-9 {
        (h[0] / n, h[2] / n)
    } else {
        (1.0, 0.0)
    };
    let el = DEFAULT_ELEVATION_DEG.to_radians();
    [-hz * el.cos(), -el.sin(), hx * el.cos()]
}

/// Eye-view resolution (pixels per side) of `evaluate --out` and the reproduce pipeline: a
/// 256² picture costs one ray cast and one shadow lookup per pixel per technique, a small
/// fraction of evaluating a 512² light view.
pub const DEFAULT_RESOLUTION: usize = 256;

/// The camera of a view: the scene file's `camera` of the light, else [`default_camera`].
pub fn camera_of(light: &Light) -> V3 {
    light.camera.unwrap_or_else(|| default_camera(light.dir))
}

/// The light of `scenes` that `stack` was rendered from: same scene and view names, and the
/// light frame [`LightFrame::fit`] gives for the scene's triangles at the stack's resolution
/// equals the stack's (so the eye view's geometry is the shadow map's). `Ok(None)` when no
/// scene has that name; an error when the names match but the frame does not.
pub fn light_of<'a>(scenes: &'a [Scene], stack: &DepthStack) -> Result<Option<(&'a Scene, usize)>> {
    let m = &stack.meta;
    let Some(sc) = scenes.iter().find(|s| s.name == m.scene) else {
        return Ok(None);
    };
    let Some(i) = sc.lights.iter().position(|l| l.name == m.view) else {
        bail!(
            "stack {}/{}: scene '{}' has no light '{}' (lights: {})",
            m.scene,
            m.view,
            sc.name,
            m.view,
            sc.lights
                .iter()
                .map(|l| l.name.as_str())
                .collect::<Vec<_>>()
                .join(", ")
        );
    };
    let f = LightFrame::fit(&sc.triangles, sc.lights[i].dir, m.width);
    let scale = (m.far - m.near)
        .abs()
        .max(m.texel_size * m.width as f64)
        .max(1e-300);
    let close = |a: f64, b: f64| (a - b).abs() <= 1e-6 * scale;
    let same = m.width == m.height
        && close(f.near, m.near)
        && close(f.far, m.far)
        && close(f.uv_origin[0], m.uv_origin[0])
        && close(f.uv_origin[1], m.uv_origin[1])
        && close(f.texel * m.width as f64, m.texel_size * m.width as f64)
        && (0..3).all(|k| (f.dir[k] - m.light_dir[k]).abs() <= 1e-6);
    if !same {
        bail!(
            "stack {}/{} was not rendered from scene '{}' as loaded (its light frame differs): \
             render the stacks from these scene files or pass the matching --scenes",
            m.scene,
            m.view,
            sc.name
        );
    }
    Ok(Some((sc, i)))
}

/// The surface point seen through one pixel: world position and unit normal facing the camera.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EyePoint {
    /// World position.
    pub world: V3,
    /// Unit normal, facing the camera.
    pub normal: V3,
}

/// The visible points of a `resolution`² orthographic camera fitted to the scene.
pub struct EyeView {
    /// Pixels per side.
    pub resolution: usize,
    /// Direction the camera looks along (unit, world space).
    pub camera: V3,
    /// Row-major, `None` where the ray hits nothing.
    pub points: Vec<Option<EyePoint>>,
}

/// Casts one ray per pixel along `camera` (unit) and keeps the nearest hit.
pub fn eye_view(tris: &[Tri], camera: V3, resolution: usize) -> Result<EyeView> {
    let n = norm(camera);
    if resolution == 0 || !(n.is_finite() && n > 0.0) {
        bail!("eye view: camera direction {camera:?} or resolution {resolution} invalid");
    }
    let camera = scale(camera, 1.0 / n);
    let frame = LightFrame::fit(tris, camera, resolution);
    let bvh = light_bvh(tris, &frame);
    let points = (0..resolution * resolution)
        .into_par_iter()
        .map(|i| {
            let (x, y) = (i % resolution, i / resolution);
            let u = frame.uv_origin[0] + (x as f64 + 0.5) * frame.texel;
            let v = frame.uv_origin[1] + (y as f64 + 0.5) * frame.texel;
            let mut best: Option<(f64, f64, f64)> = None;
            bvh.for_each_hit(u, v, |t, w| {
                if best.is_none_or(|b| w < b.0) {
                    best = Some((w, t.su, t.sv));
                }
            });
            best.map(|(w, su, sv)| {
                let world = std::array::from_fn(|k| {
                    u * frame.u_axis[k] + v * frame.v_axis[k] + w * frame.dir[k]
                });
                // plane w = su·u + sv·v + c: gradient (su, sv, −1) points at the camera
                let g = sub(
                    [
                        su * frame.u_axis[0] + sv * frame.v_axis[0],
                        su * frame.u_axis[1] + sv * frame.v_axis[1],
                        su * frame.u_axis[2] + sv * frame.v_axis[2],
                    ],
                    frame.dir,
                );
                EyePoint {
                    world,
                    normal: scale(g, 1.0 / norm(g)),
                }
            })
        })
        .collect();
    Ok(EyeView {
        resolution,
        camera,
        points,
    })
}

/// Bilinear interpolation of a row-major `width × height` map at texel coordinates (tx, ty)
/// (texel centres at integers), clamped edges: what a GPU returns for a filtered texture.
pub fn bilinear(map: &[f64], width: usize, height: usize, tx: f64, ty: f64) -> f64 {
    let (c, w) = bilinear_taps(width, height, tx, ty);
    (0..4).map(|i| w[i] * map[c[i].1 * width + c[i].0]).sum()
}

/// The four (clamped) texels and weights of a bilinear lookup at (tx, ty).
fn bilinear_taps(width: usize, height: usize, tx: f64, ty: f64) -> ([(usize, usize); 4], [f64; 4]) {
    let (x0, y0) = (tx.floor(), ty.floor());
    let (fx, fy) = (tx - x0, ty - y0);
    let cl = |v: f64, n: usize| (v.max(0.0) as usize).min(n - 1);
    let (xa, xb) = (cl(x0, width), cl(x0 + 1.0, width));
    let (ya, yb) = (cl(y0, height), cl(y0 + 1.0, height));
    (
        [(xa, ya), (xb, ya), (xa, yb), (xb, yb)],
        [
            (1.0 - fx) * (1.0 - fy),
            fx * (1.0 - fy),
            (1.0 - fx) * fy,
            fx * fy,
        ],
    )
}

/// Where a world point falls in a light view: texel coordinates (tx, ty) (centres at integers),
/// depth z and the receiver-plane slopes (dz/du, dz/dv) per texel of a surface with `normal`;
/// `None` if the stack has no light frame or the surface faces away from the light.
pub fn light_sample(stack: &DepthStack, p: &EyePoint) -> Option<(f64, f64, f64, f64, f64)> {
    let m = &stack.meta;
    if m.texel_size <= 0.0 || m.far <= m.near {
        return None;
    }
    let range = m.far - m.near;
    let tx = (dot(p.world, m.u_axis) - m.uv_origin[0]) / m.texel_size - 0.5;
    let ty = (dot(p.world, m.v_axis) - m.uv_origin[1]) / m.texel_size - 0.5;
    let z = (dot(p.world, m.light_dir) - m.near) / range;
    let nw = dot(p.normal, m.light_dir);
    if nw >= -1e-6 {
        return None;
    }
    let k = m.texel_size / range;
    let du = -dot(p.normal, m.u_axis) / nw * k;
    let dv = -dot(p.normal, m.v_axis) / nw * k;
    Some((tx, ty, z, du, dv))
}

/// Per pixel the shadow intensity of `subject` (1 = fully shadowed) from the light view
/// `stack`: NaN where no surface is seen, 1 where the surface faces away from the light.
pub fn shadows(
    view: &EyeView,
    stack: &DepthStack,
    subject: Subject,
    bias: &Bias,
) -> Result<Vec<f64>> {
    metrics::check_stack(stack)?;
    bias.validate()?;
    let (w, h) = (stack.meta.width, stack.meta.height);
    let kern = Gaussian::paper();
    let front = FrontMap::of(stack);
    let (maps, grid, min) = match subject {
        Subject::Technique(t) => {
            let grid = t.depth_grid();
            let snapped: Vec<f64> = match grid {
                Some(g) => front.depth.iter().map(|&z| metrics::snap(g, z)).collect(),
                None => front.depth.clone(),
            };
            let maps = kernel::moment_maps_of(&snapped, w, h, t.moment_count(), &kern, |z, o| {
                t.basis(z, o)
            });
            // Grid techniques (sharp bounds): no window depth below z_f ⇒ G = 0 (as
            // metrics::evaluate's trivial fragments), so no LP is solved there.
            let min = grid.map(|_| kernel::min_filter(&snapped, w, h, kern.radius()));
            (maps, grid, min)
        }
        Subject::Pcf => (Vec::new(), None, None),
        Subject::Cdf => bail!("eye view: the cdf subject has no shadow map"),
    };
    let out = view
        .points
        .par_chunks(view.resolution.max(1))
        .map_init(
            || match subject {
                Subject::Technique(t) => (Some(t.evaluator()), vec![0.0; t.moment_count()]),
                _ => (None, Vec::new()),
            },
            |(ev, buf), row| {
                row.iter()
                    .map(|p| {
                        let Some(p) = p else { return f64::NAN };
                        let Some((tx, ty, z, du, dv)) = light_sample(stack, p) else {
                            return 1.0;
                        };
                        match ev.as_mut() {
                            Some(e) => {
                                let mut zf = z - bias.technique_offset(du, dv);
                                if let Some(g) = grid {
                                    zf = metrics::snap(g, zf);
                                }
                                if let Some(min) = &min {
                                    // the bilinear mix of four windows has no depth below
                                    // zf iff none of the four has
                                    let (c, _) = bilinear_taps(w, h, tx, ty);
                                    if c.iter().all(|&(x, y)| min[y * w + x] >= zf) {
                                        return 0.0;
                                    }
                                }
                                for (j, m) in maps.iter().enumerate() {
                                    buf[j] = bilinear(m, w, h, tx, ty);
                                }
                                e.shadow(buf, zf)
                            }
                            None => {
                                let (c, wt) = bilinear_taps(w, h, tx, ty);
                                (0..4)
                                    .map(|i| {
                                        let (cx, cy) = c[i];
                                        let zc = z + du * (cx as f64 - tx) + dv * (cy as f64 - ty);
                                        wt[i]
                                            * metrics::pcf(&front, &kern, cx, cy, zc, du, dv, bias)
                                    })
                                    .sum()
                            }
                        }
                    })
                    .collect::<Vec<f64>>()
            },
        )
        .flatten()
        .collect();
    Ok(out)
}

/// One view seen by its eye camera: the visible points and their PCF shadow, shared by the
/// pictures of every technique of that view.
pub struct EyeComparison {
    /// The visible points.
    pub view: EyeView,
    /// Direction the light travels (world space).
    pub light_dir: V3,
    /// PCF shadow of each pixel's point, row-major (NaN where the ray hits nothing).
    pub pcf: Vec<f64>,
}

impl EyeComparison {
    /// The eye view of light `light` of `scene` (camera [`camera_of`]) at `resolution`² and
    /// its PCF shadows from `stack` (that light's view).
    pub fn new(
        scene: &Scene,
        light: usize,
        stack: &DepthStack,
        bias: &Bias,
        resolution: usize,
    ) -> Result<EyeComparison> {
        let view = eye_view(
            &scene.triangles,
            camera_of(&scene.lights[light]),
            resolution,
        )?;
        let pcf = shadows(&view, stack, Subject::Pcf, bias)?;
        Ok(EyeComparison {
            view,
            light_dir: stack.meta.light_dir,
            pcf,
        })
    }

    /// The shadows of `subject` in this view (PCF's are already computed).
    pub fn subject(&self, stack: &DepthStack, subject: Subject, bias: &Bias) -> Result<Vec<f64>> {
        match subject {
            Subject::Pcf => Ok(self.pcf.clone()),
            s => shadows(&self.view, stack, s, bias),
        }
    }
}

/// Lambert shading under the light with a shadow: 0.15 + 0.85·max(0, n·(−l))·(1 − shadow).
pub fn shade(p: &EyePoint, light_dir: V3, shadow: f64) -> f64 {
    let l = scale(light_dir, -1.0 / norm(light_dir));
    0.15 + 0.85 * dot(p.normal, l).max(0.0) * (1.0 - shadow.clamp(0.0, 1.0))
}
