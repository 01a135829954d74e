//! Every emitted program runs under wgpu (lavapipe in CI) and computes what momentlab's f32
//! interpreter computes: every function of
//! * the θ snippets — θ₂, θ₃, θ₄, θ₆, θ₈ and the basis θ (`reports/theta`,
//!   `reports/theta/basis`, `reports/default/theta`: the module `momentlab theta --snippets`
//!   prints, array and vector variants of encoder and decoder);
//! * every technique × storage of `gpu::study::settings()` (`tune::export::module`:
//!   `tunedEncode`, `tunedDecode`, `tunedShadow`);
//! * the committed tune exports (`reports/default/tune/export/*/setting.json`, the module
//!   regenerated, whose WGSL equals the committed `shadow.wgsl`),
//!
//! run through [`momentlab::gpu::call::call`] on real filter windows: [`WINDOWS`] fragments of
//! `render::default_dataset(64)` with their 9×9 Gaussian windows (`stacks_corpus`), the same
//! windows for every program (TMSM's included). An encoder gets the
//! fragment's depth z_f (or, taking moments, the window's filtered moments); a decoder or
//! reconstruction gets the window's filtered stored values Σ w·encode(z_tap) (f64 sum rounded
//! to f32, the interpreter's encoder on each tap depth) and z_f.
//!
//! Agreement, for every output of every call: the GPU value g against the interpreter's value
//! in the closer of its two orders (every operation rounded; every a·b ± c fused),
//! |g − r| ≤ [`ABS`] + [`REL`]·|r| (NaN equals NaN only). Where a reconstruction is
//! ill-conditioned a one-ulp change of its inputs moves the result visibly; a call beyond that
//! bound then passes when |g − r| ≤ ABS + REL·|r| + 4·σ, σ being the largest change of the
//! unfused interpreter's output when every input moves by one f32 ulp ([`PERTURBATIONS`] sign
//! patterns, as `gpu check` does), and at most [`OUTLIER_SHARE`] of a program's calls may be
//! beyond even that.

use crate::common::gpu::gpu_or_skip;
use momentlab::gpu::{call::call, study, Gpu};
use momentlab::metrics::windows::stacks_corpus;
use momentlab::quantize::codegen::{self, ChannelOrder};
use momentlab::quantize::{curve, theta::Theta};
use momentlab::shader::{self, Module, Order};
use momentlab::technique::timing::Corpus;
use momentlab::tune::export;
use momentlab::tune::space::{Setting, TechniqueKind};
use std::collections::HashMap;
use std::path::{Path, PathBuf};

/// Windows (calls) per program.
const WINDOWS: usize = 10_000;
/// Absolute part of the tolerance.
const ABS: f64 = 2e-6;
/// Relative part of the tolerance (≈ 34 ulp of f32).
const REL: f64 = 4e-6;
/// Share of a program's calls allowed beyond tolerance + 4σ.
const OUTLIER_SHARE: f64 = 1e-3;
/// Sign patterns of the one-ulp input perturbations.
const PERTURBATIONS: usize = 4;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn read(p: &Path) -> String {
    std::fs::read_to_string(p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

/// |a − b| with NaN equal to NaN only, equal infinities 0.
fn diff(a: f32, b: f32) -> f64 {
    if a == b || (a.is_nan() && b.is_nan()) {
        0.0
    } else if a.is_nan() || b.is_nan() {
        f64::INFINITY
    } else {
        (a as f64 - b as f64).abs()
    }
}

/// The interpreter's outputs of `name` on every row, in `order`.
fn eval_all(module: &Module, name: &str, inputs: &[f32], order: Order) -> Vec<f32> {
    let f = module.func(name).unwrap();
    let (n_in, n_out) = (f.n_inputs(), f.n_outputs());
    let mut out = vec![0.0f32; inputs.len() / n_in * n_out];
    let mut scratch = Vec::new();
    for (row, o) in inputs.chunks_exact(n_in).zip(out.chunks_exact_mut(n_out)) {
        f.eval_order_into(order, row, &mut scratch, o).unwrap();
    }
    out
}

/// What one program's run measured.
#[derive(Default)]
struct Agreement {
    calls: usize,
    /// Seconds of the GPU run (compile, dispatch, readback).
    gpu_s: f64,
    /// Largest |g − r| (closer order) and the largest (|g − r| − ABS)/|r| over all outputs.
    max_abs: f64,
    max_rel: f64,
    /// Calls beyond ABS + REL·|r| that needed the sensitivity, and calls beyond it too.
    sensitive: usize,
    outliers: usize,
    worst: String,
}

/// Run `name` of `on_gpu` on the GPU and compare with the interpreter running `name` of
/// `module` (the same module, except in the check that a changed constant is caught).
fn agree(gpu: &Gpu, on_gpu: &Module, module: &Module, name: &str, inputs: &[f32]) -> Agreement {
    let f = module.func(name).unwrap();
    let (n_in, n_out) = (f.n_inputs(), f.n_outputs());
    let t = std::time::Instant::now();
    let g = call(gpu, on_gpu, name, inputs).unwrap_or_else(|e| panic!("{name}: {e}"));
    let gpu_s = t.elapsed().as_secs_f64();
    // the two orders on two threads (TMSM's reconstruction is ~10⁴ interpreted operations)
    let (u, fu) = std::thread::scope(|sc| {
        let fused = sc.spawn(|| eval_all(module, name, inputs, Order::Fused));
        let u = eval_all(module, name, inputs, Order::Unfused);
        (u, fused.join().expect("interpreter thread"))
    });
    assert_eq!(g.len(), u.len(), "{name}: output length");
    let mut a = Agreement {
        calls: inputs.len() / n_in,
        gpu_s,
        ..Default::default()
    };
    let mut scratch = Vec::new();
    let mut moved = vec![0.0f32; n_in];
    let mut out = vec![0.0f32; n_out];
    let mut worst_excess = 0.0f64;
    for i in 0..a.calls {
        let row = &inputs[i * n_in..(i + 1) * n_in];
        let mut sens: Option<Vec<f64>> = None;
        let mut beyond = false;
        let mut needed = false;
        for j in 0..n_out {
            let k = i * n_out + j;
            let (d, r) = {
                let (du, df) = (diff(g[k], u[k]), diff(g[k], fu[k]));
                if du <= df {
                    (du, u[k])
                } else {
                    (df, fu[k])
                }
            };
            let r = if r.is_finite() { r.abs() as f64 } else { 0.0 };
            a.max_abs = a.max_abs.max(d);
            if r > 0.0 {
                a.max_rel = a.max_rel.max((d - ABS).max(0.0) / r);
            }
            let tol = ABS + REL * r;
            if d <= tol {
                continue;
            }
            needed = true;
            let s = sens.get_or_insert_with(|| {
                let mut s = vec![0.0f64; n_out];
                for p in 0..PERTURBATIONS {
                    for (c, (v, &x)) in moved.iter_mut().zip(row).enumerate() {
                        let h = ((c as u64) ^ ((p as u64) << 40) ^ ((i as u64) << 20))
                            .wrapping_mul(0x9E37_79B9_7F4A_7C15)
                            >> 63;
                        *v = if h == 1 { x.next_up() } else { x.next_down() };
                    }
                    f.eval_order_into(Order::Unfused, &moved, &mut scratch, &mut out)
                        .unwrap();
                    for (sj, (&o, &b)) in s.iter_mut().zip(out.iter().zip(&u[i * n_out..])) {
                        *sj = sj.max(diff(o, b));
                    }
                }
                s
            });
            let excess = d - (tol + 4.0 * s[j]);
            if excess > 0.0 {
                beyond = true;
                if excess > worst_excess {
                    worst_excess = excess;
                    a.worst = format!(
                        "call {i} output {j}: GPU {} vs interpreter {} / {} (σ {:.2e}), inputs {row:?}",
                        g[k], u[k], fu[k], s[j]
                    );
                }
            }
        }
        a.sensitive += needed as usize;
        a.outliers += beyond as usize;
    }
    a
}

/// Real windows: fragments of the default scenes with their filter windows.
fn corpus() -> Corpus {
    let stacks = momentlab::render::default_dataset(64).unwrap();
    let c = stacks_corpus(&stacks, WINDOWS, 51).unwrap();
    assert!(c.zfs.len() >= 9_000, "{} windows", c.zfs.len());
    c
}

/// Σ w·enc(z_tap) over each window, in f64, rounded to f32: `enc` gives the m values a texel
/// stores for a depth (cached per depth).
fn filtered(c: &Corpus, m: usize, mut enc: impl FnMut(f64) -> Vec<f32>) -> Vec<f32> {
    let mut cache: HashMap<u64, Vec<f32>> = HashMap::new();
    let mut out = Vec::with_capacity(c.zfs.len() * m);
    let mut acc = vec![0.0f64; m];
    for d in &c.dists {
        acc.iter_mut().for_each(|a| *a = 0.0);
        for &(z, w) in d {
            let s = cache.entry(z.to_bits()).or_insert_with(|| enc(z));
            for (a, &v) in acc.iter_mut().zip(s.iter()) {
                *a += w * v as f64;
            }
        }
        out.extend(acc.iter().map(|&a| a as f32));
    }
    out
}

/// The inputs of every function of a tune module: (name, inputs).
fn setting_programs(module: &Module, m: usize, c: &Corpus) -> Vec<(String, Vec<f32>)> {
    let enc = module.func("tunedEncode").unwrap();
    let stored = filtered(c, m, |z| enc.eval(&[z as f32]).unwrap());
    let depths: Vec<f32> = c.zfs.iter().map(|&z| z as f32).collect();
    let mut with_zf = Vec::with_capacity(depths.len() * (m + 1));
    for (s, &z) in stored.chunks_exact(m).zip(&depths) {
        with_zf.extend_from_slice(s);
        with_zf.push(z);
    }
    vec![
        ("tunedEncode".into(), depths),
        ("tunedDecode".into(), stored),
        ("tunedShadow".into(), with_zf),
    ]
}

/// The inputs of every function of a θ snippet module: encoders get z_f (Chebyshev form) or
/// the window's filtered moments b (matrix form); decoders the filtered stored values.
fn theta_programs(
    module: &Module,
    th: &Theta,
    curve: &dyn momentlab::quantize::Curve,
    c: &Corpus,
) -> Vec<(String, Vec<f32>)> {
    let m = th.m();
    let basis = |z: f64| {
        let mut b = vec![0.0f64; m];
        curve.eval(z, &mut b);
        b.iter().map(|&v| v as f32).collect::<Vec<f32>>()
    };
    let moments = filtered(c, m, basis);
    // the first function is the array-layout encoder: stored values of one depth
    let enc = &module.funcs[0];
    assert!(enc.name.starts_with("encode"), "{}", enc.name);
    let stored = filtered(c, m, |z| {
        if enc.n_inputs() == 1 {
            enc.eval(&[z as f32]).unwrap()
        } else {
            enc.eval(&basis(z)).unwrap()
        }
    });
    module
        .funcs
        .iter()
        .map(|f| {
            let inputs = if f.name.starts_with("encode") {
                if f.n_inputs() == 1 {
                    c.zfs.iter().map(|&z| z as f32).collect()
                } else {
                    moments.clone()
                }
            } else {
                stored.clone()
            };
            (f.name.clone(), inputs)
        })
        .collect()
}

/// Run the programs of one module; a line per function, failures collected.
fn run_module(
    gpu: &Gpu,
    label: &str,
    module: &Module,
    programs: &[(String, Vec<f32>)],
    failures: &mut Vec<String>,
    summary: &mut (f64, f64, usize, usize),
) {
    for (name, inputs) in programs {
        let t = std::time::Instant::now();
        let a = agree(gpu, module, module, name, inputs);
        eprintln!(
            "{label:<44} {name:<26} {} calls in {:.2} s (GPU {:.2} s): max |Δ| {:.2e}, max rel {:.2e}, beyond ABS+REL {} ({:.3} %), beyond +4σ {}",
            a.calls,
            t.elapsed().as_secs_f64(),
            a.gpu_s,
            a.max_abs,
            a.max_rel,
            a.sensitive,
            100.0 * a.sensitive as f64 / a.calls as f64,
            a.outliers
        );
        summary.0 = summary.0.max(a.max_abs);
        summary.1 = summary.1.max(a.max_rel);
        summary.2 += a.sensitive;
        summary.3 += a.calls;
        if a.outliers as f64 > OUTLIER_SHARE * a.calls as f64 {
            failures.push(format!(
                "{label} {name}: {} of {} calls beyond tolerance + 4σ; worst {}",
                a.outliers, a.calls, a.worst
            ));
        }
    }
}

fn theta_jsons(dir: &Path) -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| {
            p.extension().is_some_and(|e| e == "json")
                && p.file_name()
                    .and_then(|n| n.to_str())
                    .is_some_and(|n| n.starts_with("theta"))
        })
        .collect();
    v.sort();
    v
}

#[test]
fn every_emitted_program_agrees_with_the_interpreter() {
    let Some(gpu) = gpu_or_skip("every_emitted_program_agrees_with_the_interpreter") else {
        return;
    };
    let t0 = std::time::Instant::now();
    let all = corpus();
    let mut failures = Vec::new();
    let mut summary = (0.0f64, 0.0f64, 0usize, 0usize);
    let mut modules = 0;

    // θ snippets
    for rel in [
        "reports/theta",
        "reports/theta/basis",
        "reports/default/theta",
    ] {
        for p in theta_jsons(&root().join(rel)) {
            let v: serde_json::Value = serde_json::from_str(&read(&p)).unwrap();
            let th = Theta::new(
                serde_json::from_value(v["basis"].clone()).unwrap(),
                serde_json::from_value(v["matrix"].clone()).unwrap(),
                serde_json::from_value(v["offset"].clone()).unwrap(),
            )
            .unwrap();
            let c = curve::from_names(&th.basis).unwrap();
            let tag = momentlab::pipeline::theta::snippet_tag(c.as_ref());
            let order = match v["snippet_channel_order"].as_str() {
                Some("search") => ChannelOrder::Search,
                _ => ChannelOrder::Paper,
            };
            let sn = codegen::snippet(&th, c.as_ref(), &tag, order).unwrap();
            // the module theta{tag}.wgsl is printed from
            let programs = theta_programs(&sn.glsl, &sn.theta, c.as_ref(), &all);
            let label = format!("{rel}/theta{tag}");
            run_module(
                gpu,
                &label,
                &sn.glsl,
                &programs,
                &mut failures,
                &mut summary,
            );
            modules += 1;
        }
    }
    assert!(modules >= 11, "{modules} θ snippets");

    // every technique × storage, and the committed exports
    let mut settings: Vec<(String, Setting, Option<String>)> = study::settings()
        .into_iter()
        .map(|s| (s.label(), s, None))
        .collect();
    let base = root().join("reports/default/tune/export");
    let mut dirs: Vec<PathBuf> = std::fs::read_dir(&base)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.is_dir())
        .collect();
    dirs.sort();
    assert!(dirs.len() >= 2, "{}: no exports", base.display());
    for d in &dirs {
        let v: serde_json::Value = serde_json::from_str(&read(&d.join("setting.json"))).unwrap();
        let s: Setting = serde_json::from_value(v["setting"].clone()).unwrap();
        let label = format!("export/{}", d.file_name().unwrap().to_string_lossy());
        settings.push((label, s, Some(read(&d.join("shadow.wgsl")))));
    }
    for (label, s, committed) in &settings {
        let Some(module) = export::module(s, export::header(s)).unwrap() else {
            continue;
        };
        if let Some(text) = committed {
            assert_eq!(
                &shader::wgsl(&module).unwrap(),
                text,
                "{label}: the committed shadow.wgsl is not what the setting emits"
            );
        }
        let m = s.family.technique.moment_count();
        let programs = setting_programs(&module, m, &all);
        run_module(gpu, label, &module, &programs, &mut failures, &mut summary);
        modules += 1;
    }
    eprintln!(
        "{modules} modules in {:.1} s: max |Δ| {:.2e}, max rel {:.2e}, {} of {} calls beyond ABS + REL·|r| (sensitivity used)",
        t0.elapsed().as_secs_f64(),
        summary.0,
        summary.1,
        summary.2,
        summary.3
    );
    assert!(failures.is_empty(), "{}", failures.join("\n"));

    // The comparison catches a changed constant: Hamburger 4MSM's α moved by 10 % in the
    // program the GPU runs.
    let s = study::settings()
        .into_iter()
        .find(|s| s.family.technique == TechniqueKind::Hamburger4)
        .unwrap();
    let mut changed = s;
    changed.alpha *= 1.1;
    let module = export::module(&s, export::header(&s)).unwrap().unwrap();
    let wrong = export::module(&changed, export::header(&changed))
        .unwrap()
        .unwrap();
    let (name, inputs) = &setting_programs(&module, 4, &all)[2];
    let a = agree(gpu, &wrong, &module, name, inputs);
    eprintln!(
        "α × 1.1 on the GPU: {} of {} calls beyond tolerance + 4σ, max |Δ| {:.2e}",
        a.outliers, a.calls, a.max_abs
    );
    assert!(
        a.outliers as f64 > 10.0 * OUTLIER_SHARE * a.calls as f64,
        "a 10 % change of α went unnoticed: {} of {} calls beyond",
        a.outliers,
        a.calls
    );
}
