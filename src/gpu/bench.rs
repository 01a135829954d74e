//! `gpu bench`: time per pass (encode, the two filter passes, lookup) of the shadow-map
//! pipeline on the GPU, for every technique × storage, along three axes around a base point —
//! shadow-map size, filter size, output resolution (lookups) — the analogue of the paper's
//! Figure 7 (frame time against the same three, Peters & Klein 2015, Section 6.1).
//!
//! Times come from timestamp queries around each pass (GPU time) where the adapter has them,
//! else from the wall clock around a run (labelled "wall"). Each point is run `repeats` times
//! (`repeats_large` times where the map's edge is at least `large_from`) after one warm-up;
//! the median, mean and maximum are kept. A software adapter (lavapipe) is
//! labelled so: its figures are CPU figures and are never put beside hardware ones.

use super::pipeline::{Compiled, Program, Receivers};
use super::study;
use super::{Adapter, Gpu};
use crate::kernel::Gaussian;
use crate::quantize::pipeline as stored;
use crate::stack::DepthStack;
use crate::tune::export;
use crate::tune::space::Setting;
use anyhow::{bail, Result};
use serde::{Deserialize, Serialize};

/// The three sweeps and their base point.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Plan {
    /// Shadow-map edge lengths (texels).
    pub sizes: Vec<usize>,
    /// Filter taps per axis (odd): a Gaussian of radius (taps − 1)/2 and σ = 0.6·radius (the
    /// paper's 9 taps, σ = 2.4).
    pub filters: Vec<usize>,
    /// Output edge lengths: output² lookups.
    pub outputs: Vec<usize>,
    /// The base point (size, filter taps, output edge).
    pub base: (usize, usize, usize),
    /// Timed runs per point (after one warm-up run).
    pub repeats: usize,
    /// Timed runs per point whose shadow map has an edge of at least [`Plan::large_from`]
    /// texels (a 4096² map on a software rasterizer takes seconds per run).
    #[serde(default = "one")]
    pub repeats_large: usize,
    /// Shadow-map edge from which `repeats_large` applies (default: never).
    #[serde(default = "never")]
    pub large_from: usize,
}

fn one() -> usize {
    1
}

fn never() -> usize {
    usize::MAX
}

impl Plan {
    /// Timed runs at a shadow map of `size`² texels.
    pub fn repeats_at(&self, size: usize) -> usize {
        if size >= self.large_from {
            self.repeats_large
        } else {
            self.repeats
        }
    }
}

/// Median, mean and maximum of a time in milliseconds.
#[derive(Clone, Copy, Debug, Default, Serialize, Deserialize, PartialEq)]
pub struct Stat {
    /// Median, ms.
    pub median: f64,
    /// Mean, ms.
    pub mean: f64,
    /// Maximum, ms.
    pub max: f64,
}

impl Stat {
    fn of(mut v: Vec<f64>) -> Stat {
        v.sort_by(f64::total_cmp);
        let n = v.len().max(1);
        Stat {
            median: v.get(v.len() / 2).copied().unwrap_or(0.0),
            mean: v.iter().sum::<f64>() / n as f64,
            max: v.last().copied().unwrap_or(0.0),
        }
    }
}

/// One measured point.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Point {
    /// Technique name.
    pub technique: String,
    /// Storage format name.
    pub storage: String,
    /// Bits stored per texel.
    pub bits_per_texel: u32,
    /// "size", "filter" or "output": the axis this point belongs to.
    pub axis: String,
    /// Shadow-map edge length (texels).
    pub size: usize,
    /// Filter taps per axis.
    pub filter: usize,
    /// Output edge length (output² lookups).
    pub output: usize,
    /// Timed runs behind the statistics.
    #[serde(default)]
    pub runs: usize,
    /// Encode pass (depth to stored moments).
    pub encode_ms: Stat,
    /// Separable filter passes.
    pub filter_ms: Stat,
    /// Lookup pass (G per receiver).
    pub lookup_ms: Stat,
    /// The whole run.
    pub total_ms: Stat,
}

/// The artefact `reports/gpu/<adapter>.json`.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Report {
    /// The adapter measured on.
    pub adapter: Adapter,
    /// "timestamp" (GPU time per pass) or "wall" (whole run, passes not split).
    pub timer: String,
    /// The sweeps run.
    pub plan: Plan,
    /// Statements of each technique's lookup shader (`tunedShadow`, loops unrolled), the
    /// static size a cost model would use.
    pub shader_ops: Vec<(String, usize)>,
    /// Every measured point.
    pub points: Vec<Point>,
    /// Wall time of the bench, seconds.
    pub seconds: f64,
}

/// `src` scaled to `size`² by nearest texel, and `count` receivers spread over its fragments.
fn scene(src: &DepthStack, size: usize, count: usize) -> (Vec<f32>, Receivers) {
    let (w, h) = (src.meta.width, src.meta.height);
    let depth: Vec<f32> = (0..size * size)
        .map(|t| src.front((t / size) * h / size * w + (t % size) * w / size))
        .collect();
    let bias = study::DEPTH_BIAS;
    let all = study::receivers(src, bias, usize::MAX);
    let mut r = Receivers::default();
    for p in 0..count {
        let i = (p * 7919) % all.texel.len().max(1);
        let t = all.texel[i] as usize;
        let (x, y) = ((t % w) * size / w, (t / w) * size / h);
        r.texel.push((y * size + x) as u32);
        r.zf.push(all.zf[i]);
    }
    (depth, r)
}

/// The 1-D weights of a filter of `taps` taps.
pub fn weights(taps: usize) -> Result<Vec<f32>> {
    if taps.is_multiple_of(2) {
        bail!("filter taps must be odd, got {taps}");
    }
    let r = taps / 2;
    if r == 0 {
        return Ok(vec![1.0]);
    }
    Ok(stored::weights_f32(&Gaussian::new(r, 0.6 * r as f64)?))
}

/// Time one setting at one point.
fn measure(
    gpu: &Gpu,
    s: &Setting,
    src: &DepthStack,
    (size, taps, output): (usize, usize, usize),
    repeats: usize,
) -> Result<[Stat; 4]> {
    let Some(module) = export::module(s, vec![])? else {
        bail!("{}: no shader reconstruction", s.label());
    };
    let w = weights(taps)?;
    let program = Program {
        module: &module,
        wgsl: None,
        storage: s.family.storage.storage(),
        weights: &w,
    };
    let compiled = Compiled::new(gpu, &program)?;
    let (depth, receivers) = scene(src, size, output * output);
    let mut t = [vec![], vec![], vec![], vec![]];
    for k in 0..=repeats {
        let start = std::time::Instant::now();
        let out = compiled.run(gpu, &depth, (size, size), &receivers, false)?;
        let wall = start.elapsed().as_secs_f64() * 1e3;
        if k == 0 {
            continue; // warm-up
        }
        match out.times {
            Some(p) => {
                t[0].push(p.encode * 1e3);
                t[1].push(p.filter * 1e3);
                t[2].push(p.lookup * 1e3);
                t[3].push((p.encode + p.filter + p.lookup) * 1e3);
            }
            None => t[3].push(wall),
        }
    }
    let [a, b, c, d] = t;
    Ok([Stat::of(a), Stat::of(b), Stat::of(c), Stat::of(d)])
}

/// Run the plan for `settings` on the scene `src`; `progress` is told each point.
pub fn run(
    gpu: &Gpu,
    plan: &Plan,
    settings: &[Setting],
    src: &DepthStack,
    mut progress: impl FnMut(&str),
) -> Result<Report> {
    let max = gpu.device.limits().max_texture_dimension_2d as usize;
    if let Some(&s) = plan
        .sizes
        .iter()
        .chain([&plan.base.0])
        .find(|&&s| s > max || s == 0)
    {
        bail!("gpu bench: size {s} is outside 1..={max} (the adapter's largest texture)");
    }
    for &f in plan.filters.iter().chain([&plan.base.1]) {
        weights(f)?;
    }
    let start = std::time::Instant::now();
    let mut points = Vec::new();
    let mut shader_ops = Vec::new();
    for s in settings {
        if let Some(m) = export::module(s, vec![])? {
            let ops = m.func("tunedShadow").map_or(0, |f| f.n_ops());
            let name = s.family.technique.name().to_string();
            if !shader_ops.iter().any(|(n, _)| n == &name) {
                shader_ops.push((name, ops));
            }
        }
        let axes = [
            (
                "size",
                plan.sizes
                    .iter()
                    .map(|&v| (v, plan.base.1, plan.base.2))
                    .collect::<Vec<_>>(),
            ),
            (
                "filter",
                plan.filters
                    .iter()
                    .map(|&v| (plan.base.0, v, plan.base.2))
                    .collect(),
            ),
            (
                "output",
                plan.outputs
                    .iter()
                    .map(|&v| (plan.base.0, plan.base.1, v))
                    .collect(),
            ),
        ];
        for (axis, pts) in axes {
            for p in pts {
                progress(&format!("{} {axis} {:?}", s.family.label(), p));
                let runs = plan.repeats_at(p.0);
                let [e, f, l, t] = measure(gpu, s, src, p, runs)?;
                points.push(Point {
                    technique: s.family.technique.name().into(),
                    storage: s.family.storage.name().into(),
                    bits_per_texel: s.family.bits_per_texel(),
                    axis: axis.into(),
                    size: p.0,
                    filter: p.1,
                    output: p.2,
                    runs,
                    encode_ms: e,
                    filter_ms: f,
                    lookup_ms: l,
                    total_ms: t,
                });
            }
        }
    }
    Ok(Report {
        adapter: gpu.adapter.clone(),
        timer: if gpu.timestamps { "timestamp" } else { "wall" }.into(),
        plan: plan.clone(),
        shader_ops,
        points,
        seconds: start.elapsed().as_secs_f64(),
    })
}
