//! The PCF reference: the 9×9 Gaussian depth test over the front layer with a receiver-plane
//! bias.

use super::*;

/// The front layer of a stack as the PCF test reads it: depth z0 (background = 1) and the
/// receiver-plane slopes of the front surface (0 where there is none).
#[derive(Clone, Debug, PartialEq)]
pub struct FrontMap {
    /// Texels per row.
    pub width: usize,
    /// Rows of texels.
    pub height: usize,
    /// Front depth z0 per texel, row-major (background = 1).
    pub depth: Vec<f64>,
    /// Receiver-plane slope dz/du per texel step in x.
    pub dzdu: Vec<f64>,
    /// Receiver-plane slope dz/dv per texel step in y.
    pub dzdv: Vec<f64>,
}

impl FrontMap {
    /// The tangent plane of texel k's front surface at the offset (dx, dy):
    /// dz/du·dx + dz/dv·dy.
    fn tangent(&self, k: usize, dx: f64, dy: f64) -> f64 {
        self.dzdu[k] * dx + self.dzdv[k] * dy
    }

    /// The front layer of `stack`.
    pub fn of(stack: &DepthStack) -> FrontMap {
        let n = stack.texel_count();
        let slopes = |s: &[Vec<f32>]| -> Vec<f64> {
            match (stack.depth.first(), s.first()) {
                (Some(d), Some(l)) => (0..n)
                    .map(|t| if d[t].is_finite() { slope(l[t]) } else { 0.0 })
                    .collect(),
                _ => vec![0.0; n],
            }
        };
        FrontMap {
            width: stack.meta.width,
            height: stack.meta.height,
            depth: kernel::front_map(stack),
            dzdu: slopes(&stack.dzdu),
            dzdv: slopes(&stack.dzdv),
        }
    }
}

/// PCF of a fragment at texel (x, y) with depth `zf` and receiver-plane slopes (dzdu, dzdv):
/// Σ_l w_l [z0(t+l) < zf + s·Δ_l − ε], Δ_l per [`Receiver`] with (dx, dy) the offset to the
/// (edge-clamped) neighbour texel actually read.
#[allow(clippy::too_many_arguments)]
pub fn pcf(
    front: &FrontMap,
    kernel: &Gaussian,
    x: usize,
    y: usize,
    zf: f64,
    dzdu: f64,
    dzdv: f64,
    bias: &Bias,
) -> f64 {
    pcf_at(
        front,
        kernel,
        x,
        y,
        zf,
        dzdu,
        dzdv,
        bias,
        [bias.pcf_epsilon],
    )[0]
}

/// [`pcf`] for N constants ε at once (one pass over the taps).
#[allow(clippy::too_many_arguments)]
pub fn pcf_at<const N: usize>(
    front: &FrontMap,
    kernel: &Gaussian,
    x: usize,
    y: usize,
    zf: f64,
    dzdu: f64,
    dzdv: f64,
    bias: &Bias,
    eps: [f64; N],
) -> [f64; N] {
    let (width, height) = (front.width, front.height);
    let r = kernel.radius() as i64;
    let g = kernel.weights_1d();
    let lower = bias.receiver == Receiver::Lower;
    let mut total = [0.0; N];
    for (iy, &wy) in g.iter().enumerate() {
        let yy = kernel::clamp_coord(y, iy as i64 - r, height);
        let dy = yy as f64 - y as f64;
        let row = yy * width;
        let mut s = [0.0; N];
        for (ix, &wx) in g.iter().enumerate() {
            let xx = kernel::clamp_coord(x, ix as i64 - r, width);
            let dx = xx as f64 - x as f64;
            let mut delta = dzdu * dx + dzdv * dy;
            if lower {
                // the lowest tangent plane met on the straight path to the tap: at each step
                // of the longer axis the (one or two) texels the path passes between
                let (ox, oy) = (xx as i64 - x as i64, yy as i64 - y as i64);
                delta = match path_offsets(ox, oy) {
                    Some(path) => delta.min(lowest_plane(front, x, y, path, dx, dy)),
                    None => path_texels(x, y, ox, oy).fold(delta, |d, (qx, qy)| {
                        d.min(front.tangent(qy * width + qx, dx, dy))
                    }),
                };
            }
            let plane = zf + bias.slope_scale * delta;
            let z0 = front.depth[row + xx];
            for k in 0..N {
                if z0 < plane - eps[k] {
                    s[k] += wx;
                }
            }
        }
        for k in 0..N {
            total[k] += wy * s[k];
        }
    }
    total
}

/// The texels the straight path from texel (x, y) to the tap at offset (ox, oy) passes
/// between: at each step j = 1..=n of the longer axis, n = max(|ox|, |oy|), the floor and the
/// ceiling of (x, y) + (ox, oy)·j/n (the same texel twice where that point is a texel).
fn path_texels(x: usize, y: usize, ox: i64, oy: i64) -> impl Iterator<Item = (usize, usize)> {
    let n = ox.abs().max(oy.abs());
    let (dx, dy) = (ox as f64, oy as f64);
    (1..=n).flat_map(move |j| {
        let f = j as f64 / n as f64;
        let (px, py) = (x as f64 + dx * f, y as f64 + dy * f);
        [(px.floor(), py.floor()), (px.ceil(), py.ceil())].map(|(a, b)| (a as usize, b as usize))
    })
}

/// min over the texels q = (x, y) + o, o in `path`, of the tangent plane of q at the offset
/// (dx, dy): dz/du(q)·dx + dz/dv(q)·dy (NaN for an empty path or only NaN planes: `f64::min`
/// then returns its other argument). Four independent minima, so the comparisons do not wait
/// on each other; a minimum does not depend on the order it is taken in (NaN planes are
/// skipped, as by `f64::min`; which zero a tie of ±0 keeps cannot change the depth it is
/// added to).
fn lowest_plane(front: &FrontMap, x: usize, y: usize, path: &[(i8, i8)], dx: f64, dy: f64) -> f64 {
    let w = front.width as isize;
    let base = (y * front.width + x) as isize;
    let plane = |&(qx, qy): &(i8, i8)| {
        front.tangent((base + qy as isize * w + qx as isize) as usize, dx, dy)
    };
    let mut lanes = [f64::NAN; 4];
    let chunks = path.chunks_exact(4);
    let tail = chunks.remainder();
    for c in chunks {
        for (m, o) in lanes.iter_mut().zip(c) {
            *m = m.min(plane(o));
        }
    }
    for (m, o) in lanes.iter_mut().zip(tail) {
        *m = m.min(plane(o));
    }
    lanes[0].min(lanes[1]).min(lanes[2].min(lanes[3]))
}

/// Largest tap offset whose path [`path_offsets`] tabulates (the paper's kernel radius).
const PATH_RADIUS: i64 = 4;

/// The distinct texels of [`path_texels`] as offsets from (x, y), in order of first
/// appearance, tabulated once for |ox|, |oy| ≤ [`PATH_RADIUS`] (None beyond). The same texels
/// for every (x, y): (ox, oy)·j/n with n ≤ 4 is an integer (computed exactly) or at least 1/4
/// from one, so ⌊x + v⌋ = x + ⌊v⌋ and ⌈x + v⌉ = x + ⌈v⌉ (test
/// `tabulated_paths_are_the_computed_ones`). A texel met twice (floor = ceil where the path
/// crosses a texel centre) is listed once: the lowest plane is a minimum.
fn path_offsets(ox: i64, oy: i64) -> Option<&'static [(i8, i8)]> {
    use std::sync::OnceLock;
    static TABLE: OnceLock<Vec<Vec<(i8, i8)>>> = OnceLock::new();
    if ox.abs() > PATH_RADIUS || oy.abs() > PATH_RADIUS {
        return None;
    }
    let side = 2 * PATH_RADIUS + 1;
    let table = TABLE.get_or_init(|| {
        let c = PATH_RADIUS as usize;
        (0..side * side)
            .map(|i: i64| {
                let (ox, oy) = (i % side - PATH_RADIUS, i / side - PATH_RADIUS);
                let mut path: Vec<(i8, i8)> = Vec::new();
                for (qx, qy) in path_texels(c, c, ox, oy) {
                    let o = ((qx as i64 - c as i64) as i8, (qy as i64 - c as i64) as i8);
                    if !path.contains(&o) {
                        path.push(o);
                    }
                }
                path
            })
            .collect()
    });
    Some(&table[((oy + PATH_RADIUS) * side + ox + PATH_RADIUS) as usize])
}

/// PCF of fragment (texel, layer) of a stack with the paper's kernel (see [`pcf`]).
pub fn pcf_of(
    stack: &DepthStack,
    front: &FrontMap,
    texel: usize,
    layer: usize,
    bias: &Bias,
) -> f64 {
    let w = stack.meta.width;
    let zf = stack.depth[layer][texel] as f64;
    pcf(
        front,
        &Gaussian::paper(),
        texel % w,
        texel / w,
        zf,
        slope(stack.dzdu[layer][texel]),
        slope(stack.dzdv[layer][texel]),
        bias,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The tabulated paths are the computed ones at every texel of a map, edges included, and
    /// at far coordinates; beyond the table's radius there is none.
    #[test]
    fn tabulated_paths_are_the_computed_ones() {
        for (x, y) in [(0, 0), (1, 3), (4, 4), (511, 0), (4095, 4093), (1 << 30, 7)] {
            for oy in -PATH_RADIUS..=PATH_RADIUS {
                for ox in -PATH_RADIUS..=PATH_RADIUS {
                    if (x as i64) + ox < 0 || (y as i64) + oy < 0 {
                        continue;
                    }
                    let table: Vec<(usize, usize)> = path_offsets(ox, oy)
                        .unwrap()
                        .iter()
                        .map(|&(qx, qy)| {
                            (
                                (x as i64 + qx as i64) as usize,
                                (y as i64 + qy as i64) as usize,
                            )
                        })
                        .collect();
                    let computed: Vec<(usize, usize)> = path_texels(x, y, ox, oy).collect();
                    assert_eq!(computed.len(), 2 * ox.abs().max(oy.abs()) as usize);
                    let mut distinct: Vec<(usize, usize)> = Vec::new();
                    for q in computed {
                        if !distinct.contains(&q) {
                            distinct.push(q);
                        }
                    }
                    assert_eq!(table, distinct, "({x}, {y}) + ({ox}, {oy})");
                }
            }
        }
        assert!(path_offsets(5, 0).is_none() && path_offsets(0, -5).is_none());
    }
}
