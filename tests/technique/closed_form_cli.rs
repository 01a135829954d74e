//! `momentlab shadow` batch parsing: results and one-line errors naming what and where.

use momentlab::batch::shadow::evaluate_batch;

#[test]
fn shadow_batch_results() {
    let out = evaluate_batch(
        r#"{"technique":"hamburger4","alpha":0,"problems":[
            {"moments":[0.5,0.25,0.125,0.0625],"zf":0.6},
            {"moments":[0.5,0.25,0.125,0.0625],"zf":0.4}]}"#,
        "t",
    )
    .unwrap();
    let r = out["results"].as_array().unwrap();
    assert_eq!(r.len(), 2);
    assert!((r[0]["g"].as_f64().unwrap() - 1.0).abs() < 1e-9);
    assert!(r[1]["g"].as_f64().unwrap().abs() < 1e-9);
    // "hamburger" takes m from the moment count (m = 2 is VSM).
    let out = evaluate_batch(
        r#"{"technique":"hamburger","alpha":0,"problems":[{"moments":[0.5,0.3],"zf":0.9}]}"#,
        "t",
    )
    .unwrap();
    let g = out["results"][0]["g"].as_f64().unwrap();
    let (mu, var) = (0.5f64, 0.3 - 0.25);
    let t = 0.9 - mu;
    assert!((g - t * t / (var + t * t)).abs() < 1e-12);
}

#[test]
fn shadow_batch_errors_are_one_line_and_specific() {
    let cases = [
        (
            r#"{"technique":"hamburger4","problems":[{"moments":[1,2],"zf":0.5}]"#,
            "line 1",
        ),
        (
            r#"{"technique":"nope","problems":[]}"#,
            "unknown technique 'nope'",
        ),
        (
            r#"{"technique":"vsm","problems":[{"moments":[0.5,0.3],"zf":0.5},{"moments":[0.5],"zf":0.5}]}"#,
            "problem 1",
        ),
        (
            r#"{"technique":"vsm","problems":[{"moments":[0.5,0.3]}]}"#,
            "zf",
        ),
        (r#"{"technique":"vsm","alpha":2,"problems":[]}"#, "alpha"),
        (r#"{"technique":"vsm","wat":2,"problems":[]}"#, "wat"),
        (r#"{"problems":[]}"#, "technique"),
    ];
    for (input, needle) in cases {
        let e = format!("{:#}", evaluate_batch(input, "in.json").unwrap_err());
        assert!(e.contains(needle) && e.contains("in.json"), "{e}");
        assert!(!e.contains('\n'), "{e}");
    }
}

/// Moments of a few Diracs in [0,1] (one at 0, one at 1, the rest random) for `t`'s basis.
fn moments_of(t: &dyn momentlab::technique::Technique, seed: &mut u64) -> Vec<f64> {
    let mut next = || {
        *seed ^= *seed << 13;
        *seed ^= *seed >> 7;
        *seed ^= *seed << 17;
        (*seed >> 11) as f64 / (1u64 << 53) as f64
    };
    let mut depths = vec![0.0, 1.0];
    for _ in 0..(1 + (next() * 3.0) as usize) {
        depths.push(next());
    }
    let w: Vec<f64> = depths.iter().map(|_| 0.05 + next()).collect();
    let total: f64 = w.iter().sum();
    let m = t.moment_count();
    let (mut b, mut row) = (vec![0.0; m], vec![0.0; m]);
    for (z, wz) in depths.iter().zip(&w) {
        t.basis(*z, &mut row);
        for j in 0..m {
            b[j] += wz / total * row[j];
        }
    }
    b
}

/// Cantelli's one-sided bound on P(X ≥ mean + t), t > 0, for X with mean μ and variance σ².
fn cantelli(mu: f64, var: f64, x: f64) -> f64 {
    let t = x - mu;
    if t <= 0.0 {
        0.0
    } else {
        t * t / (var.max(0.0) + t * t)
    }
}

/// Receiver depths outside [0,1] (engines pass the biased z − ε): every closed-form technique
/// answers every problem of one batch. Techniques on [0,1] give exactly G = 0 below 0 and
/// G = 1 above 1; techniques on R give their formula there, checked against an independent
/// evaluation (Hamburger MSM: the general Algorithm 2; VSM: Cantelli; ESM: Markov; EVSM:
/// Cantelli on both warps); sharp bounds are non-decreasing in z_f.
#[test]
fn shadow_answers_receiver_depths_outside_the_unit_interval() {
    use momentlab::technique::registry::{build, Params, CLOSED_FORM_NAMES};
    use momentlab::technique::DepthDomain;
    let zfs = [-0.002, 1.003, 0.0, 0.5, 1.0, -0.5, 1.05];
    let mut seed = 0x2545_f491_4f6c_dd1d_u64;
    for name in CLOSED_FORM_NAMES {
        for precision in ["f64", "f32"] {
            let params: Params =
                serde_json::from_str(&format!(r#"{{"alpha":0,"precision":"{precision}"}}"#))
                    .unwrap();
            let t = build(name, &params).unwrap();
            let domain = t.depth_domain();
            let real = matches!(
                *name,
                "hamburger" | "hamburger4" | "hamburger6" | "vsm" | "esm" | "evsm"
            );
            assert_eq!(domain == DepthDomain::Real, real, "{name}: depth domain");
            for _ in 0..50 {
                let b = moments_of(t.as_ref(), &mut seed);
                let problems: Vec<String> = zfs
                    .iter()
                    .map(|zf| format!(r#"{{"moments":{b:?},"zf":{zf}}}"#))
                    .collect();
                let batch = format!(
                    r#"{{"technique":"{name}","alpha":0,"precision":"{precision}","problems":[{}]}}"#,
                    problems.join(",")
                );
                let out =
                    evaluate_batch(&batch, "batch").unwrap_or_else(|e| panic!("{name}: {e:#}"));
                let g: Vec<f64> = out["results"]
                    .as_array()
                    .unwrap()
                    .iter()
                    .map(|r| r["g"].as_f64().unwrap_or_else(|| panic!("{name}: {r}")))
                    .collect();
                assert_eq!(g.len(), zfs.len());
                let mut ev = t.evaluator();
                for (k, &zf) in zfs.iter().enumerate() {
                    assert!(
                        (0.0..=1.0).contains(&g[k]),
                        "{name} {precision} zf={zf}: G={}",
                        g[k]
                    );
                    if !real && zf < 0.0 {
                        assert_eq!(g[k], 0.0, "{name} {precision} zf={zf}");
                    } else if !real && zf > 1.0 {
                        assert_eq!(g[k], 1.0, "{name} {precision} zf={zf}");
                    } else {
                        assert_eq!(g[k], ev.shadow(&b, zf), "{name} {precision} zf={zf}");
                    }
                }
                if *name != "csm" && precision == "f64" {
                    // A sharp (or valid) lower bound of P(Z < z_f) never decreases with z_f
                    // (in f64; the f32 paths round).
                    let order = [5, 0, 2, 3, 4, 1, 6];
                    for w in order.windows(2) {
                        assert!(g[w[0]] <= g[w[1]] + 1e-6, "{name} {precision}: {g:?}");
                    }
                }
                if precision == "f32" || !real {
                    continue;
                }
                for (k, &zf) in zfs.iter().enumerate() {
                    let want = match *name {
                        "hamburger" | "hamburger4" | "hamburger6" => {
                            let p = Params {
                                moment_count: Some(b.len()),
                                ..params.clone()
                            };
                            build("hamburger", &p).unwrap().evaluator().shadow(&b, zf)
                        }
                        "vsm" => cantelli(b[0], b[1] - b[0] * b[0], zf),
                        "esm" => (1.0 - b[0] * (-80.0 * zf).exp()).max(0.0),
                        "evsm" => {
                            let (cp, cn) = (40.0f64, 5.0f64);
                            let pos = cantelli(b[0], b[1] - b[0] * b[0], (cp * zf).exp());
                            let neg = cantelli(b[2], b[3] - b[2] * b[2], -(-cn * zf).exp());
                            pos.max(neg)
                        }
                        _ => unreachable!(),
                    };
                    let tol = if *name == "evsm" { 1e-6 } else { 1e-7 };
                    assert!(
                        (g[k] - want.clamp(0.0, 1.0)).abs() < tol,
                        "{name} zf={zf}: {} vs {want}",
                        g[k]
                    );
                }
            }
        }
    }
}

/// The binary answers the engine's batch (z − ε slightly below 0) instead of rejecting it.
#[test]
fn shadow_binary_accepts_biased_receiver_depths() {
    let (code, out, err) = crate::common::run(
        &["shadow"],
        Some(
            r#"{"technique":"hausdorff4","problems":[
                {"moments":[0.5,0.3,0.2,0.15],"zf":-0.002},
                {"moments":[0.5,0.3,0.2,0.15],"zf":1.003}]}"#,
        ),
    );
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(v["results"][0]["g"], 0.0);
    assert_eq!(v["results"][1]["g"], 1.0);
}
