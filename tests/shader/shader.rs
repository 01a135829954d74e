//! The emitted θ shader code, run by the f32 interpreter of the shader representation (the same
//! operations in the same order as the GLSL/HLSL/WGSL), in both of its orders (every operation
//! rounded, as with `precise`; every a·b ± c fused, as a driver may without it): encode each
//! depth, mix with the window's weights in f32, decode. On 10 000 windows of the embedded default stacks plus adversarial
//! windows, for θ₂…θ₈ (ours; θ₅/θ₇ from a short seeded search), the published θ₂/θ₄/θ₆ and two
//! catalog-basis θ:
//! * f32 round trip ≤ 3e-6 against the exact f64 pipeline with the same inputs,
//! * stored values inside [0,1],
//! * through 16-bit UNORM storage, max error ≤ 1.5 × that of the exact pipeline with the same
//!   16-bit rounding,
//! * the vector (float4) variants compute bit for bit what the array variants compute.
//!
//! Also: the default θ₂/θ₄ are the published ones up to rounding (paper channel order), and
//! every emitted snippet compiles (tests/common/shader.rs).

use crate::common::shader as shader_common;

use momentlab::artefact::read_json;
use momentlab::quantize::codegen::{self, ChannelOrder, EncoderForm, Layout};
use momentlab::quantize::theta::{paper_order, published, Theta};
use momentlab::quantize::{curve, optimize, Curve};
use momentlab::shader::{Func, Order};
use rand::{Rng, SeedableRng};
use std::path::Path;
use std::sync::OnceLock;

/// (depth, weight) windows: 10 000 from the default stacks, then adversarial ones.
/// Windows of (depth, weight) and how many of them (the first) are real.
type Windows = (Vec<Vec<(f32, f32)>>, usize);

fn windows() -> &'static Windows {
    static W: OnceLock<Windows> = OnceLock::new();
    W.get_or_init(|| {
        let stacks = momentlab::render::default_dataset(96).unwrap();
        let c = momentlab::metrics::windows::stacks_corpus(&stacks, 10_000, 31).unwrap();
        assert_eq!(c.dists.len(), 10_000);
        let mut out: Vec<Vec<(f32, f32)>> = c
            .dists
            .iter()
            .map(|d| {
                let tot: f64 = d.iter().map(|p| p.1).sum();
                d.iter()
                    .map(|&(z, w)| (z as f32, (w / tot) as f32))
                    .collect()
            })
            .collect();
        assert!(out.iter().flatten().all(|p| (0.0..=1.0).contains(&p.0)));
        let real = out.len();
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
        let dirac = |z: f32| vec![(z, 1.0f32)];
        for z in [0.0f32, 1.0, 0.5, 1e-7, 1.0 - 1e-7] {
            out.push(dirac(z));
        }
        out.push(vec![(0.0, 0.5), (1.0, 0.5)]);
        out.push(vec![(0.0, 0.999), (1.0, 0.001)]);
        out.push(vec![(0.0, 0.001), (1.0, 0.999)]);
        for _ in 0..300 {
            out.push(dirac(rng.gen()));
        }
        for _ in 0..300 {
            // 81 depths clustered within 1e-4 (or 1e-6) of a centre, some at the ends
            let c: f32 = match rng.gen_range(0..4) {
                0 => 0.0,
                1 => 1.0,
                _ => rng.gen(),
            };
            let spread = if rng.gen() { 1e-4 } else { 1e-6 };
            let w: Vec<f32> = (0..81).map(|_| rng.gen_range(0.1f32..1.0)).collect();
            let tot: f32 = w.iter().sum();
            out.push(
                w.iter()
                    .map(|&wi| {
                        let z: f32 = c + rng.gen_range(-spread..spread);
                        (z.clamp(0.0, 1.0), wi / tot)
                    })
                    .collect(),
            );
        }
        for _ in 0..300 {
            // two clusters at 0 and 1 with random split, and a few uniform depths
            let a: f32 = rng.gen();
            out.push(vec![(0.0, a), (1.0, 1.0 - a)]);
            let n = rng.gen_range(2..6);
            let w: Vec<f32> = (0..n).map(|_| rng.gen_range(0.01f32..1.0)).collect();
            let tot: f32 = w.iter().sum();
            out.push(w.iter().map(|&wi| (rng.gen(), wi / tot)).collect());
        }
        (out, real)
    })
}

struct Case {
    label: String,
    theta: Theta,
    curve: Box<dyn Curve>,
    tag: String,
}

fn theta_from_json(path: &Path) -> Theta {
    let v: serde_json::Value = read_json(path).unwrap();
    Theta::new(
        serde_json::from_value(v["basis"].clone()).unwrap(),
        serde_json::from_value(v["matrix"].clone()).unwrap(),
        serde_json::from_value(v["offset"].clone()).unwrap(),
    )
    .unwrap()
}

fn short_search(m: usize) -> Theta {
    let c = curve::MonomialCurve::power(m).unwrap();
    let opts = optimize::Options {
        restarts: 1,
        max_sweeps: 60,
        ..Default::default()
    };
    optimize::optimize(&c, &opts, &|_, _| {}).unwrap().theta
}

fn cases() -> Vec<Case> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("reports/theta");
    let mut v = Vec::new();
    for m in 2..=8 {
        let theta = match m {
            5 | 7 => short_search(m),
            _ => theta_from_json(&dir.join(format!("theta{m}.json"))),
        };
        v.push(Case {
            label: format!("ours θ{m}"),
            curve: Box::new(curve::MonomialCurve::power(m).unwrap()),
            theta,
            tag: m.to_string(),
        });
    }
    for m in [2, 4, 6] {
        v.push(Case {
            label: format!("published θ{m}"),
            curve: Box::new(curve::MonomialCurve::power(m).unwrap()),
            theta: published(m).unwrap(),
            tag: format!("{m}p"),
        });
    }
    for f in ["theta_3eae1070", "theta_ad920539"] {
        let theta = theta_from_json(&dir.join(format!("basis/{f}.json")));
        v.push(Case {
            label: format!("basis θ {}", theta.basis.join(",")),
            curve: curve::from_names(&theta.basis).unwrap(),
            tag: f.trim_start_matches("theta").to_string(),
            theta,
        });
    }
    v
}

fn unorm16(s: f64) -> f64 {
    (s.clamp(0.0, 1.0) * 65535.0).round() / 65535.0
}

/// Max errors over all windows: (f32 round trip, max |f32 stored − exact θ∘b|, stored outside
/// [0,1] count, f32 16-bit pipeline, exact 16-bit pipeline).
fn measure(case: &Case, enc: &Func, dec: &Func, ws: &[Vec<(f32, f32)>], order: Order) -> [f64; 5] {
    let th = &case.theta;
    let m = th.m();
    let mut sc = Vec::new();
    let (mut s32, mut b32) = (vec![0f32; m], vec![0f32; m]);
    let (mut bz, mut sz) = (vec![0f64; m], vec![0f64; m]);
    let mut res = [0.0f64; 5];
    for w in ws {
        let (mut mix32, mut mix16_32) = (vec![0f32; m], vec![0f32; m]);
        let (mut mix64, mut mix16_64) = (vec![0f64; m], vec![0f64; m]);
        for &(z, wt) in w {
            enc.eval_order_into(order, &[z], &mut sc, &mut s32).unwrap();
            case.curve.eval(z as f64, &mut bz);
            th.encode(&bz, &mut sz);
            for i in 0..m {
                if !(0.0..=1.0).contains(&s32[i]) {
                    res[2] += 1.0;
                }
                res[1] = res[1].max((s32[i] as f64 - sz[i]).abs());
                mix32[i] += wt * s32[i];
                mix16_32[i] += wt * (unorm16(s32[i] as f64) as f32);
                mix64[i] += wt as f64 * sz[i];
                mix16_64[i] += wt as f64 * unorm16(sz[i]);
            }
        }
        let mut exact = vec![0f64; m];
        th.decode(&mix64, &mut exact);
        dec.eval_order_into(order, &mix32, &mut sc, &mut b32)
            .unwrap();
        for i in 0..m {
            res[0] = res[0].max((b32[i] as f64 - exact[i]).abs());
        }
        dec.eval_order_into(order, &mix16_32, &mut sc, &mut b32)
            .unwrap();
        let mut q64 = vec![0f64; m];
        th.decode(&mix16_64, &mut q64);
        for i in 0..m {
            res[3] = res[3].max((b32[i] as f64 - exact[i]).abs());
            res[4] = res[4].max((q64[i] - exact[i]).abs());
        }
    }
    res
}

#[test]
fn emitted_theta_round_trips_in_f32_on_real_and_adversarial_windows() {
    let (ws, real) = windows();
    for case in cases() {
        // the search's own θ₂/θ₄ too (the default emits the published ones, tested as such)
        let sn = codegen::snippet(
            &case.theta,
            case.curve.as_ref(),
            &case.tag,
            ChannelOrder::Search,
        )
        .unwrap();
        assert!(
            matches!(sn.form, EncoderForm::Chebyshev(_)),
            "{}: no Chebyshev encoder",
            case.label
        );
        let (e, d) = codegen::names(&case.tag, Layout::Array, false);
        let enc = sn.glsl.func(&e).unwrap();
        let dec = sn.glsl.func(&d).unwrap();
        let emitted = Case {
            label: case.label.clone(),
            theta: sn.theta.clone(),
            curve: case.curve,
            tag: case.tag.clone(),
        };
        for order in [Order::Unfused, Order::Fused] {
            for (what, set) in [("real", &ws[..*real]), ("adversarial", &ws[*real..])] {
                let [rt, enc_err, outside, q32, q64] = measure(&emitted, enc, dec, set, order);
                eprintln!(
                    "{} ({what}, {} windows, {order:?}): f32 round trip {rt:.2e}, encode {enc_err:.2e}, 16-bit f32 {q32:.3e} vs exact {q64:.3e} ({:.3}x)",
                    case.label,
                    set.len(),
                    q32 / q64
                );
                assert!(
                    rt <= 3e-6,
                    "{} {what} {order:?}: f32 round trip {rt:.3e}",
                    case.label
                );
                assert_eq!(
                    outside, 0.0,
                    "{} {what} {order:?}: stored values outside [0,1]",
                    case.label
                );
                assert!(
                    q32 <= 1.5 * q64,
                    "{} {what} {order:?}: 16-bit f32 pipeline {q32:.3e} vs {q64:.3e}",
                    case.label
                );
            }
        }
        // the same θ₈ in monomial form (z, z², … by products, then A·b + t) fails the bound:
        // the measurement can tell a well-conditioned encoder from an ill-conditioned one
        if case.tag == "8" {
            let mut f = Func::new("monomial");
            let z = f.input_scalar("z");
            let mut pw = vec![z];
            for _ in 1..8 {
                let p = f.mul(pw[pw.len() - 1], z);
                pw.push(p);
            }
            let s = codegen::encode_matrix_into(&mut f, &emitted.theta, &pw);
            f.output("s", momentlab::shader::Shape::Array(8), &s);
            for order in [Order::Unfused, Order::Fused] {
                let [rt, ..] = measure(&emitted, &f, dec, &ws[..*real], order);
                eprintln!("θ8 in monomial form ({order:?}): f32 round trip {rt:.2e}");
                assert!(rt > 1e-4, "monomial θ8 round trip {rt:.3e} ({order:?})");
            }
        }
    }
}

#[test]
fn vector_variants_equal_array_variants_bit_for_bit() {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(9);
    for case in cases() {
        let sn = codegen::snippet(
            &case.theta,
            case.curve.as_ref(),
            &case.tag,
            ChannelOrder::Paper,
        )
        .unwrap();
        for module in [&sn.glsl, &sn.hlsl] {
            let hl = module == &sn.hlsl;
            let (ea, da) = codegen::names(&case.tag, Layout::Array, hl);
            let (ev, dv) = codegen::names(&case.tag, Layout::Vectors, hl);
            let f = |n: &str| module.func(n).unwrap();
            for _ in 0..500 {
                let z: f32 = rng.gen();
                for order in [Order::Unfused, Order::Fused] {
                    let a = f(&ea).eval_in(order, &[z]).unwrap();
                    assert_eq!(a, f(&ev).eval_in(order, &[z]).unwrap(), "{}", case.label);
                    assert_eq!(
                        f(&da).eval_in(order, &a).unwrap(),
                        f(&dv).eval_in(order, &a).unwrap(),
                        "{} {order:?}",
                        case.label
                    );
                }
            }
        }
    }
}

#[test]
fn default_theta2_theta4_are_the_published_ones_in_paper_order() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("reports/theta");
    for m in [2, 4] {
        let ours = theta_from_json(&dir.join(format!("theta{m}.json")));
        let p = published(m).unwrap();
        let (ordered, diff) = paper_order(&ours).unwrap();
        // the search's θ lies on the published optimum: rows permuted/reflected, equal up to the
        // flat directions of det A (θ₄: 7e-4 relative) and the same gain
        assert!(diff < 2e-3, "θ{m}: relative difference {diff:e}");
        assert!((ordered.gain_bits() - p.gain_bits()).abs() < 1e-6, "θ{m}");
        assert!(
            (ours.gain_bits() - ordered.gain_bits()).abs() < 1e-12,
            "θ{m}"
        );
        // the search's own order differs (so the reordering is doing something) ...
        assert_ne!(ours.matrix, ordered.matrix);
        // ... and the emitted default snippet uses the paper's order
        let c = curve::MonomialCurve::power(m).unwrap();
        let sn = codegen::snippet(&ours, &c, &m.to_string(), ChannelOrder::Paper).unwrap();
        assert_eq!(sn.order, "paper");
        assert_eq!(sn.theta, p, "the default is the published transform");
        let sn = codegen::snippet(&ours, &c, &m.to_string(), ChannelOrder::Search).unwrap();
        assert_eq!(sn.theta, ours);
        // an engine's decoder (published θ₄, MJP's offset 0.035955884801) reads our texel
        if m == 4 {
            let (e, _) = codegen::names("4", Layout::Vectors, true);
            let enc = sn_paper(&ours).hlsl.func(&e).unwrap().clone();
            for (k, order) in (0..=100).flat_map(|k| [(k, Order::Unfused), (k, Order::Fused)]) {
                let z = k as f32 / 100.0;
                let s = enc.eval_in(order, &[z]).unwrap();
                let mut d: Vec<f64> = s.iter().map(|&v| v as f64).collect();
                d[0] -= 0.035955884801;
                let b: Vec<f64> = p
                    .inverse
                    .iter()
                    .map(|row| row.iter().zip(&d).map(|(a, x)| a * x).sum())
                    .collect();
                for (j, bj) in b.iter().enumerate() {
                    let want = (z as f64).powi(j as i32 + 1);
                    assert!((bj - want).abs() < 2e-6, "z={z} b{j}: {bj} vs {want}");
                }
            }
        }
    }
}

fn sn_paper(th: &Theta) -> codegen::Snippet {
    let c = curve::MonomialCurve::power(th.m()).unwrap();
    codegen::snippet(th, &c, &th.m().to_string(), ChannelOrder::Paper).unwrap()
}

#[test]
fn emitted_snippets_compile() {
    let glslang = shader_common::tools_present("emitted_snippets_compile");
    for case in cases() {
        for order in [ChannelOrder::Paper, ChannelOrder::Search] {
            let sn = codegen::snippet(&case.theta, case.curve.as_ref(), &case.tag, order).unwrap();
            // the GLSL-named module is the one printed as GLSL and WGSL
            for (lang, module) in [("glsl", &sn.glsl), ("hlsl", &sn.hlsl)] {
                shader_common::check(&format!("theta{}-{lang}", case.tag), module, glslang)
                    .unwrap_or_else(|e| panic!("{}: {e}", case.label));
            }
        }
    }
}
