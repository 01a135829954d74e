//! The procedural shapes of a scene file as triangles (local coordinates; y is up).

use super::schema::Shape;
use super::transform::orient_mesh;
use super::{pos, Tri, V3};
use crate::linalg::v3::{add, cross, dot, norm, scale, sub};
use crate::render::mesh::{load_mesh_from, MeshFiles};
use anyhow::{bail, Context, Result};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

impl Shape {
    /// The shape's triangles in its local frame, after checking its numbers (sizes positive
    /// and finite, at least 3 segments).
    pub(super) fn triangles(&self, mesh: &dyn MeshFiles) -> Result<Vec<Tri>> {
        let mut out = Vec::new();
        match *self {
            Shape::Plane { size } => plane(&mut out, size)?,
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
            } => fence(&mut out, [width, height, bar_width, thickness], bars, rails)?,
            Shape::Grating {
                size,
                bars,
                bar_width,
                thickness,
            } => grating(&mut out, size, bars, bar_width, thickness)?,
            Shape::Cards {
                count,
                size,
                region,
                seed,
            } => cards(&mut out, count, size, region, seed)?,
            Shape::City {
                grid,
                spacing,
                footprint,
                height,
                bridges,
                seed,
            } => city(&mut out, grid, spacing, [footprint, height], bridges, seed)?,
            Shape::Arcade {
                columns,
                spacing,
                radius,
                height,
                depth,
                roof,
            } => arcade(&mut out, columns, [spacing, radius, height, depth, roof])?,
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

/// Quad in the y = 0 plane, centred, of size [x, z], normal +y.
fn plane(out: &mut Vec<Tri>, size: [f64; 2]) -> Result<()> {
    pos("plane size", size[0])?;
    pos("plane size", size[1])?;
    let (x, z) = (size[0] / 2.0, size[1] / 2.0);
    quad(out, [-x, 0.0, -z], [-x, 0.0, z], [x, 0.0, z], [x, 0.0, -z]);
    Ok(())
}

/// Fence along x of `[width, height, bar_width, thickness]`: `bars` vertical boxes, then
/// `rails` horizontal rails half again as thick (so faces do not coincide).
fn fence(out: &mut Vec<Tri>, dims: [f64; 4], bars: usize, rails: usize) -> Result<()> {
    let [width, height, bar_width, thickness] = dims;
    pos("fence width", width)?;
    pos("fence height", height)?;
    pos("fence bar_width", bar_width)?;
    pos("fence thickness", thickness)?;
    let t = thickness / 2.0;
    for i in 0..bars {
        let x = -width / 2.0 + (i as f64 + 0.5) * width / bars as f64;
        boxed(
            out,
            [x - bar_width / 2.0, 0.0, -t],
            [x + bar_width / 2.0, height, t],
        );
    }
    for r in 0..rails {
        let y = height * (r as f64 + 0.5) / rails as f64;
        // rails slightly thicker than the bars so faces do not coincide
        boxed(
            out,
            [-width / 2.0, y - bar_width / 2.0, -t * 1.5],
            [width / 2.0, y + bar_width / 2.0, t * 1.5],
        );
    }
    Ok(())
}

/// Grating of `bars[0]` bars along z and `bars[1]` crossing bars along x, half a thickness
/// lower (so top faces do not coincide).
fn grating(
    out: &mut Vec<Tri>,
    size: [f64; 2],
    bars: [usize; 2],
    bar_width: f64,
    thickness: f64,
) -> Result<()> {
    pos("grating size", size[0])?;
    pos("grating size", size[1])?;
    pos("grating bar_width", bar_width)?;
    pos("grating thickness", thickness)?;
    let (hx, hz) = (size[0] / 2.0, size[1] / 2.0);
    for i in 0..bars[0] {
        let x = -hx + (i as f64 + 0.5) * size[0] / bars[0] as f64;
        boxed(
            out,
            [x - bar_width / 2.0, 0.0, -hz],
            [x + bar_width / 2.0, thickness, hz],
        );
    }
    for i in 0..bars[1] {
        let z = -hz + (i as f64 + 0.5) * size[1] / bars[1] as f64;
        // crossing bars sit half a thickness lower so top faces do not coincide
        boxed(
            out,
            [-hx, -thickness / 2.0, z - bar_width / 2.0],
            [hx, thickness / 2.0, z + bar_width / 2.0],
        );
    }
    Ok(())
}

/// `count` single-sided quads of size [w, h]: centre uniform in the region
/// [x0, y0, z0, x1, y1, z1], edges along a random unit a and a random unit b ⟂ a.
fn cards(
    out: &mut Vec<Tri>,
    count: usize,
    size: [f64; 2],
    region: [f64; 6],
    seed: u64,
) -> Result<()> {
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
            out,
            sub(sub(c, ha), hb),
            add(sub(c, ha), hb),
            add(add(c, ha), hb),
            sub(add(c, ha), hb),
        );
    }
    Ok(())
}

/// City block: a grid of boxes with random footprint and height (`ranges` = [footprint,
/// height], each [min, max]), then `bridges` slabs between random neighbours.
fn city(
    out: &mut Vec<Tri>,
    grid: [usize; 2],
    spacing: f64,
    ranges: [[f64; 2]; 2],
    bridges: usize,
    seed: u64,
) -> Result<()> {
    let [footprint, height] = ranges;
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
            boxed(out, [x - fx, 0.0, z - fz], [x + fx, h, z + fz]);
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
        boxed(out, lo, hi);
    }
    Ok(())
}

/// Arcade of `[spacing, radius, height, depth, roof]`: two rows of 16-segment columns under a
/// roof slab.
fn arcade(out: &mut Vec<Tri>, columns: usize, dims: [f64; 5]) -> Result<()> {
    let [spacing, radius, height, depth, roof] = dims;
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
        out,
        [-half - m, height, -depth / 2.0 - m],
        [half + m, height + roof, depth / 2.0 + m],
    );
    Ok(())
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
