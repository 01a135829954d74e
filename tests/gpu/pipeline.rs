//! The shadow-map pipeline of every technique × storage on the GPU equals its CPU model
//! (`quantize::pipeline`) on the embedded scenes' fragments, and so does `tune`'s model
//! (`tune::score`).

use crate::common::gpu::gpu_or_skip;
use momentlab::gpu::check;
use momentlab::gpu::pipeline::{Compiled, Program, Receivers};
use momentlab::gpu::study;
use momentlab::kernel::{clamp_coord, Gaussian};
use momentlab::quantize::pipeline::{filtered_map, weights_f32, HalfRounding};
use momentlab::quantize::study::Storage;
use momentlab::shader::{Module, Order};
use momentlab::tune::export;
use momentlab::tune::sample::Sample;
use momentlab::tune::score::Moments;

#[test]
fn every_technique_and_storage_matches_the_model() {
    let Some(gpu) = gpu_or_skip("every_technique_and_storage_matches_the_model") else {
        return;
    };
    let stacks = momentlab::render::default_dataset(64).unwrap();
    let mut failures = Vec::new();
    // every setting on one view, the views taken in turn
    for (i, s) in study::settings().iter().enumerate() {
        {
            let stack = &stacks[(3 * i) % stacks.len()];
            let v = study::check_setting(gpu, s, None, stack, 10_000).unwrap();
            eprintln!(
                "{}: map {:.2} steps ({:.3} % inexact), G max {:.2e} excess {:.2e} outliers {:.4} %, whole max {:.2e} mean {:.2e} >1/255 {:.3} %",
                v.label, v.map_steps, 100.0 * v.map_inexact, v.g_max, v.g_excess, 100.0 * v.g_outliers, v.pipeline_max, v.pipeline_mean, 100.0 * v.pipeline_above_8bit
            );
            if let Some(f) = v.failure() {
                failures.push(f);
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// Per receiver, the largest |G(s′) − G(s)| of the shader model (unfused) when every stored
/// value moves by one f32 ulp (four fixed sign patterns), and the spread of its two orders.
fn sensitivity(module: &Module, map: &[f32], m: usize, r: &Receivers) -> Vec<f64> {
    let base = check::model_shadow(module, Order::Unfused, map, m, r).unwrap();
    let fused = check::model_shadow(module, Order::Fused, map, m, r).unwrap();
    let mut out: Vec<f64> = base
        .iter()
        .zip(&fused)
        .map(|(&a, &b)| diff(a, b).min(1.0))
        .collect();
    let mut moved = map.to_vec();
    for k in 0..4u64 {
        for (i, (v, &x)) in moved.iter_mut().zip(map).enumerate() {
            let h = (i as u64 ^ k << 40).wrapping_mul(0x9E37_79B9_7F4A_7C15) >> 63;
            *v = if h == 1 { x.next_up() } else { x.next_down() };
        }
        let g = check::model_shadow(module, Order::Unfused, &moved, m, r).unwrap();
        for ((o, &a), &b) in out.iter_mut().zip(&g).zip(&base) {
            *o = o.max(diff(a, b).min(1.0));
        }
    }
    out
}

/// |a − b| with NaN equal to NaN only.
fn diff(a: f32, b: f32) -> f64 {
    match (a.is_nan(), b.is_nan()) {
        (true, true) => 0.0,
        (false, false) => (a as f64 - b as f64).abs(),
        _ => f64::INFINITY,
    }
}

/// `tune`'s model of the pipeline (`tune::score::Moments`: θ(b(z)) per texel rounded to the
/// storage format, the two f32 filter passes through `quantize::pipeline::filtered_window`,
/// θ⁻¹ in f32, the technique's f32 reconstruction) equals the GPU pipeline fragment by fragment
/// for every technique × storage, 16-bit UNORM (with and without θ) and binary16 included:
/// |G_tune − G_gpu| ≤ [`check::G_TOLERANCE`] + 4·σ on all but [`check::G_OUTLIER_SHARE`] of the
/// receivers — the criterion of `gpu check` — with σ the receiver's rounding sensitivity (one
/// f32 ulp on every stored value, and the two operation orders) plus the change of G when the
/// stored values move by one storage step where the two encoders (f64 θ rounded once, and the
/// shader's f32 encoder) may round a texel differently.
///
/// `tune` stores binary16 rounded to nearest even, as IEEE and hardware GPUs do; a driver that
/// rounds toward zero (lavapipe; Vulkan allows both) runs a different pipeline there. For f16 on
/// such a driver the reference is the CPU model of the pipeline (`quantize::pipeline`, which the
/// test above holds equal to the GPU under the driver's rounding) with nearest-even stores.
#[test]
fn the_tune_model_matches_the_gpu_pipeline() {
    let Some(gpu) = gpu_or_skip("the_tune_model_matches_the_gpu_pipeline") else {
        return;
    };
    let half = check::half_rounding(gpu).unwrap();
    let stacks = momentlab::render::default_dataset(64).unwrap();
    let weights = weights_f32(&Gaussian::paper());
    let taps = Gaussian::paper().taps();
    let mut failures = Vec::new();
    for (i, s) in study::settings().iter().enumerate() {
        let stack = &stacks[(3 * i + 1) % stacks.len()];
        let (w, h) = (stack.meta.width, stack.meta.height);
        let depth = study::depth_map(stack);
        let r = study::receivers(stack, s.depth_bias, 3_000);
        let module = export::module(s, export::header(s)).unwrap().unwrap();
        let compiled = Compiled::new(
            gpu,
            &Program {
                module: &module,
                wgsl: None,
                storage: s.family.storage.storage(),
                weights: &weights,
            },
        )
        .unwrap();
        let m = compiled.channels();
        let out = compiled.run(gpu, &depth, (w, h), &r, true).unwrap();
        // the receivers as tune's sample: the window of front depths, z = z_f, no further bias
        let mut sample = Sample {
            scenes: vec![stack.meta.scene.clone()],
            weights: taps.iter().map(|t| t.2).collect(),
            ..Default::default()
        };
        for (&t, &zf) in r.texel.iter().zip(&r.zf) {
            let (x, y) = (t as usize % w, t as usize / w);
            for &(dx, dy, _) in &taps {
                sample
                    .window
                    .push(depth[clamp_coord(y, dy, h) * w + clamp_coord(x, dx, w)]);
            }
            sample.scene.push(0);
            sample.z.push(zf as f64);
            sample.slope.push(0.0);
            sample.pcf.push(0.0);
        }
        let moments = Moments::compute(&s.family, &sample).unwrap();
        let t = s.family.build(s.alpha).unwrap();
        let mut ev = t.evaluator();
        let tune_g: Vec<f32> = (0..sample.len())
            .map(|k| ev.shadow(&moments.stored[k * m..(k + 1) * m], sample.z[k]) as f32)
            .collect();
        // the pipeline tune models: the GPU's, or for binary16 on a driver that does not round
        // to nearest even, the CPU model of the same passes with nearest-even stores
        let nearest =
            s.family.storage.storage() == Storage::Half && half != HalfRounding::NearestEven;
        let (map, reference, against) = if nearest {
            let enc = module.func("tunedEncode").unwrap();
            let map = filtered_map(
                enc,
                Order::Unfused,
                (Storage::Half, HalfRounding::NearestEven),
                &Gaussian::paper(),
                &depth,
                (w, h),
            )
            .unwrap();
            let g = check::model_shadow(&module, Order::Unfused, &map, m, &r).unwrap();
            (map, g, "CPU pipeline model, binary16 to nearest even")
        } else {
            (out.filtered.clone(), out.shadow.clone(), "GPU")
        };
        let sens = sensitivity(&module, &map, m, &r);
        // one storage step on every stored value (UNORM: 1/65535; binary16: one code; f32: as
        // the ulp sensitivity), four sign patterns
        let step = |v: f32, up: bool| -> f32 {
            match s.family.storage.storage() {
                Storage::Unorm(bits) => {
                    let q = ((1u64 << bits) - 1) as f32;
                    let c = (v * q).round() + if up { 1.0 } else { -1.0 };
                    c.clamp(0.0, q) / q
                }
                Storage::Half => {
                    let b = half::f16::from_f32(v);
                    let n = if (b.to_f32() >= 0.0) == up {
                        b.to_bits() + 1
                    } else {
                        b.to_bits().saturating_sub(1)
                    };
                    half::f16::from_bits(n).to_f32()
                }
                _ => {
                    if up {
                        v.next_up()
                    } else {
                        v.next_down()
                    }
                }
            }
        };
        let base = check::model_shadow(&module, Order::Unfused, &map, m, &r).unwrap();
        let mut step_sens = vec![0.0f64; r.texel.len()];
        let mut moved = map.clone();
        for k in 0..4u64 {
            for (j, (v, &x)) in moved.iter_mut().zip(&map).enumerate() {
                let hb = (j as u64 ^ k << 40).wrapping_mul(0x9E37_79B9_7F4A_7C15) >> 63;
                *v = step(x, hb == 1);
            }
            let g = check::model_shadow(&module, Order::Unfused, &moved, m, &r).unwrap();
            for ((o, &a), &b) in step_sens.iter_mut().zip(&g).zip(&base) {
                *o = o.max(diff(a, b).min(1.0));
            }
        }
        let (mut worst, mut beyond, mut exact) = (0.0f64, 0usize, 0usize);
        for (k, (&g, &tg)) in reference.iter().zip(&tune_g).enumerate() {
            let d = diff(g, tg);
            exact += (d <= check::G_TOLERANCE) as usize;
            worst = worst.max(d);
            beyond += (d > check::G_TOLERANCE + 4.0 * sens[k].max(step_sens[k])) as usize;
        }
        let n = r.texel.len();
        let share = beyond as f64 / n as f64;
        eprintln!(
            "{} on {} against the {against} (driver's binary16: {half:?}): {n} receivers, {:.2} % within {:.0e}, max |ΔG| {worst:.2e}, {:.3} % beyond tolerance",
            s.label(),
            stack.file_stem(),
            100.0 * exact as f64 / n as f64,
            check::G_TOLERANCE,
            100.0 * share
        );
        if share > check::G_OUTLIER_SHARE {
            failures.push(format!(
                "{}: {beyond} of {n} receivers beyond tolerance, max |ΔG| {worst:.3e}",
                s.label()
            ));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
