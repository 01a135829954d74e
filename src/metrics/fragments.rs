//! The fragments of a depth stack (every layer of every texel, or a deterministic subsample)
//! with their PCF reference, and the depth a technique sees at each.

use super::*;

/// One fragment of a depth stack with its PCF reference.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Fragment {
    /// Index of the view (stack) in the evaluated list.
    pub view: usize,
    /// Texel index t = y·width + x.
    pub texel: usize,
    /// Layer k (0 = front).
    pub layer: usize,
    /// The depth a technique sees: z_f − ε′.
    pub zf: f64,
    /// The PCF reference shadow intensity ∈ [0,1].
    pub pcf: f64,
    /// PCF with the constant ε scaled by [`EPSILON_FACTORS`] (reference sensitivity).
    #[serde(default)]
    pub pcf_scaled: [f64; 2],
    /// F_Z(zf) = 0 (no kernel depth below zf): G = 0 for every sharp lower bound.
    pub trivial: bool,
}

/// A finite slope, or 0 (defensive: stacks are validated on load).
#[inline]
pub(super) fn slope(v: f32) -> f64 {
    if v.is_finite() {
        v as f64
    } else {
        0.0
    }
}

/// Checks the shape of a stack (so that indexing cannot panic) with a one-line error.
pub fn check_stack(stack: &DepthStack) -> Result<()> {
    let m = &stack.meta;
    let n = m.width * m.height;
    let name = format!("{}/{}", m.scene, m.view);
    if n == 0 {
        bail!("stack {name}: empty ({}×{})", m.width, m.height);
    }
    if stack.depth.len() != stack.dzdu.len() || stack.depth.len() != stack.dzdv.len() {
        bail!(
            "stack {name}: {} depth layers but {}/{} slope layers",
            stack.depth.len(),
            stack.dzdu.len(),
            stack.dzdv.len()
        );
    }
    for (l, ((d, u), v)) in stack
        .depth
        .iter()
        .zip(&stack.dzdu)
        .zip(&stack.dzdv)
        .enumerate()
    {
        if d.len() != n || u.len() != n || v.len() != n {
            bail!(
                "stack {name}: layer {l} has {}/{}/{} values, expected {n}",
                d.len(),
                u.len(),
                v.len()
            );
        }
        if let Some(t) = d
            .iter()
            .position(|z| z.is_nan() || *z < 0.0 || (*z > 1.0 && z.is_finite()))
        {
            bail!(
                "stack {name}: layer {l} texel ({}, {}) has depth {} outside [0,1]",
                t % m.width,
                t / m.width,
                d[t]
            );
        }
    }
    Ok(())
}

/// Which fragments of a view to evaluate.
#[derive(Clone, Copy, Debug, PartialEq, Default, Serialize, Deserialize)]
pub enum Subsample {
    /// Every fragment.
    #[default]
    All,
    /// Every k-th fragment in layer-major, texel order (k ≥ 1).
    Stride(usize),
    /// Each fragment independently with probability `fraction`, decided by a hash of
    /// (seed, view, layer, texel): deterministic and independent of thread timing.
    Random {
        /// Probability of keeping a fragment, in (0, 1].
        fraction: f64,
        /// Seed of the hash.
        seed: u64,
    },
}

impl Subsample {
    pub(super) fn validate(&self) -> Result<()> {
        match *self {
            Subsample::All => Ok(()),
            Subsample::Stride(0) => bail!("subsample: stride must be >= 1"),
            Subsample::Stride(_) => Ok(()),
            Subsample::Random { fraction, .. } => {
                if !(fraction > 0.0 && fraction <= 1.0) {
                    bail!("subsample: fraction must be in (0, 1], got {fraction}");
                }
                Ok(())
            }
        }
    }
}

pub(super) fn splitmix64(mut x: u64) -> u64 {
    x = x.wrapping_add(0x9E37_79B9_7F4A_7C15);
    x = (x ^ (x >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    x = (x ^ (x >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    x ^ (x >> 31)
}

/// (layer, texel) of the selected fragments of a view, layer-major.
pub(super) fn select(stack: &DepthStack, view: usize, sub: &Subsample) -> Vec<(usize, usize)> {
    let mut out = Vec::new();
    let mut i = 0usize;
    for (l, layer) in stack.depth.iter().enumerate() {
        for (t, z) in layer.iter().enumerate() {
            if !z.is_finite() {
                continue;
            }
            let keep = match *sub {
                Subsample::All => true,
                Subsample::Stride(k) => i.is_multiple_of(k),
                Subsample::Random { fraction, seed } => {
                    let h = splitmix64(
                        seed ^ splitmix64((view as u64) << 40 ^ (l as u64) << 32 ^ t as u64),
                    );
                    ((h >> 11) as f64) * (1.0 / (1u64 << 53) as f64) < fraction
                }
            };
            if keep {
                out.push((l, t));
            }
            i += 1;
        }
    }
    out
}

/// The fragments (layer, texel) of `picked` (as [`fragments`] returns them, in that order),
/// their PCF computed for these alone: a caller that needs the reference of a few fragments
/// of a stack does not pay for all of them.
pub fn fragments_at(
    stack: &DepthStack,
    view: usize,
    bias: &Bias,
    picked: &[(usize, usize)],
) -> Vec<Fragment> {
    let w = stack.meta.width;
    let h = stack.meta.height;
    let front = FrontMap::of(stack);
    let kern = Gaussian::paper();
    let min_map = kernel::min_filter(&front.depth, w, h, kern.radius());
    let e = bias.pcf_epsilon;
    let eps = [e, e * EPSILON_FACTORS[0], e * EPSILON_FACTORS[1]];
    picked
        .par_iter()
        .with_min_len(1024)
        .map(|&(layer, texel)| {
            let z = stack.depth[layer][texel] as f64;
            let (du, dv) = (
                slope(stack.dzdu[layer][texel]),
                slope(stack.dzdv[layer][texel]),
            );
            let p = pcf_at(&front, &kern, texel % w, texel / w, z, du, dv, bias, eps);
            let zf = technique_depth(stack, layer, texel, bias);
            Fragment {
                view,
                texel,
                layer,
                zf,
                pcf: p[0],
                pcf_scaled: [p[1], p[2]],
                trivial: min_map[texel] >= zf,
            }
        })
        .collect()
}

/// All fragments of a stack (every finite depth of every layer, layer-major, texel order) with
/// their PCF reference, biased technique depth and trivial flag. `view_index` is stored in each
/// fragment. Panics on a malformed stack; call [`check_stack`] first for user data.
pub fn fragments(stack: &DepthStack, view_index: usize, bias: &Bias) -> Vec<Fragment> {
    let picked = select(stack, view_index, &Subsample::All);
    fragments_at(stack, view_index, bias, &picked)
}

/// Every fragment of a stack as (layer, texel), in the order of [`fragments`].
pub fn fragment_positions(stack: &DepthStack) -> Vec<(usize, usize)> {
    select(stack, 0, &Subsample::All)
}

/// The depth a technique sees at fragment (layer, texel): z_f − ε′ ([`Bias::technique_offset`]).
pub fn technique_depth(stack: &DepthStack, layer: usize, texel: usize, bias: &Bias) -> f64 {
    let z = stack.depth[layer][texel] as f64;
    let (du, dv) = (
        slope(stack.dzdu[layer][texel]),
        slope(stack.dzdv[layer][texel]),
    );
    z - bias.technique_offset(du, dv)
}

/// Like [`fragments`] but only a subsample.
pub fn fragments_subsampled(
    stack: &DepthStack,
    view_index: usize,
    bias: &Bias,
    sub: &Subsample,
) -> Vec<Fragment> {
    let picked = select(stack, view_index, sub);
    fragments_at(stack, view_index, bias, &picked)
}

/// Index of the grid point nearest to z (ties to the lower point; outside the grid: an end).
pub fn snap_index(grid: &Grid, z: f64) -> usize {
    grid.nearest(z)
}

/// The grid point nearest to z ([`Grid::snap`]).
pub fn snap(grid: &Grid, z: f64) -> f64 {
    grid.snap(z)
}
