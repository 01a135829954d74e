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
                let n = (xx as i64 - x as i64)
                    .abs()
                    .max((yy as i64 - y as i64).abs());
                for j in 1..=n {
                    let f = j as f64 / n as f64;
                    let (px, py) = (x as f64 + dx * f, y as f64 + dy * f);
                    for (qx, qy) in [(px.floor(), py.floor()), (px.ceil(), py.ceil())] {
                        let k = qy as usize * width + qx as usize;
                        delta = delta.min(front.dzdu[k] * dx + front.dzdv[k] * dy);
                    }
                }
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
