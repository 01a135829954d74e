//! `momentlab lp` and `momentlab candidates`, run as the binary: happy paths checked against
//! known answers (single Diracs, moments reproduced by the support, G ≤ true CDF) and every
//! kind of bad input (exit 1, one-line error naming the problem).

use crate::common::lp::{check_points, Tol};
use serde_json::{json, Value};

/// `momentlab args` with `stdin` piped in: (exit code, stdout, stderr).
fn run(args: &[&str], stdin: &str) -> (i32, String, String) {
    crate::common::run(args, Some(stdin))
}

fn lp(input: &Value) -> Vec<Value> {
    let (code, out, err) = run(&["lp"], &input.to_string());
    assert_eq!(code, 0, "stderr: {err}");
    let v: Value = serde_json::from_str(&out).unwrap();
    v["results"].as_array().unwrap().clone()
}

fn moments(basis: &[fn(f64) -> f64], diracs: &[(f64, f64)]) -> Vec<f64> {
    basis
        .iter()
        .map(|b| diracs.iter().map(|&(z, w)| w * b(z)).sum())
        .collect()
}

const MSM: [fn(f64) -> f64; 4] = [|z| z, |z| z * z, |z| z * z * z, |z| z * z * z * z];

/// A result of `momentlab lp` is optimal and its support checks out ([`check_points`]) on the
/// uniform grid of `grid_n` points, to 1e-7.
fn check_result(r: &Value, basis: &[fn(f64) -> f64], b: &[f64], grid_n: usize, zf: f64) {
    assert_eq!(r["status"], "optimal", "{r}");
    let support: Vec<(f64, f64)> = r["support"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| (p[0].as_f64().unwrap(), p[1].as_f64().unwrap()))
        .collect();
    let row = |z: f64| {
        let k = z * (grid_n - 1) as f64;
        ((k - k.round()).abs() < 1e-9).then(|| basis.iter().map(|f| f(z)).collect())
    };
    let tol = Tol {
        mass: 1e-7,
        moment: 1e-7,
    };
    let g = r["g"].as_f64().unwrap();
    check_points(&support, g, b, zf, row, &vec![1.0; basis.len()], tol)
        .unwrap_or_else(|e| panic!("{e}: {r}"));
}

#[test]
fn single_diracs_give_zero_or_one() {
    let n = 33;
    let mut problems = Vec::new();
    let mut expect = Vec::new();
    for k in [0usize, 5, 16, 31, 32] {
        let z0 = k as f64 / (n - 1) as f64;
        let b = moments(&MSM, &[(z0, 1.0)]);
        for zf in [0.0, z0, (z0 + 0.01).min(1.0), 1.0] {
            problems.push(json!({"moments": b, "zf": zf}));
            expect.push((b.clone(), zf, if z0 < zf { 1.0 } else { 0.0 }));
        }
    }
    let input = json!({"basis": ["z", "z^2", "z^3", "z^4"], "grid": {"points": n},
                       "solver": "reference", "problems": problems});
    let results = lp(&input);
    assert_eq!(results.len(), expect.len());
    for (r, (b, zf, want)) in results.iter().zip(&expect) {
        let g = r["g"].as_f64().unwrap();
        assert!(
            (g - want).abs() < 1e-7,
            "zf {zf}, b {b:?}: g = {g}, want {want}"
        );
        check_result(r, &MSM, b, n, *zf);
    }
}

#[test]
fn mixtures_batch_with_infeasible_entries_and_explicit_grid() {
    let n = 41;
    let grid: Vec<f64> = (0..n).map(|i| i as f64 / (n - 1) as f64).collect();
    let mixtures: Vec<Vec<(f64, f64)>> = vec![
        vec![(0.25, 0.5), (0.75, 0.5)],
        vec![(0.1, 0.2), (0.4, 0.3), (0.9, 0.5)],
        vec![(0.0, 0.6), (1.0, 0.4)],
    ];
    let mut problems = Vec::new();
    let mut cases = Vec::new();
    for mix in &mixtures {
        let b = moments(&MSM, mix);
        for zf in [0.3, 0.5, 0.95] {
            problems.push(json!({"moments": b, "zf": zf}));
            let cdf: f64 = mix.iter().filter(|d| d.0 < zf).map(|d| d.1).sum();
            cases.push(Some((b.clone(), zf, cdf)));
        }
        // Not a moment vector of any distribution: E[z²] < E[z]².
        problems.push(json!({"moments": [0.5, 0.1, 0.05, 0.01], "zf": 0.5}));
        cases.push(None);
    }
    let input = json!({"basis": ["z", "z^2", "z^3", "z^4"], "grid": {"values": grid},
                       "solver": "reference", "problems": problems});
    let results = lp(&input);
    assert_eq!(results.len(), cases.len());
    for (r, c) in results.iter().zip(&cases) {
        match c {
            None => assert_eq!(r, &json!({"status": "infeasible"})),
            Some((b, zf, cdf)) => {
                check_result(r, &MSM, b, n, *zf);
                // G is a lower bound over all distributions with these moments.
                let g = r["g"].as_f64().unwrap();
                assert!(g <= cdf + 1e-7, "g {g} > true CDF {cdf} at zf {zf}");
            }
        }
    }
}

#[test]
fn formulas_user_catalogs_and_pretty_output() {
    let dir = crate::common::tmp("cli-lp");
    let cat = dir.join("cat.json");
    std::fs::write(
        &cat,
        r#"{"functions": [{"name": "wave", "formula": "sin(2πz)"}]}"#,
    )
    .unwrap();
    let z0: f64 = 0.25;
    let b = [(2.0 * std::f64::consts::PI * z0).sin(), (3.0 * z0).exp()];
    let input = json!({"basis": ["wave", "exp(3z)"], "grid": {"points": 5}, "solver": "reference",
                       "problems": [{"moments": b, "zf": 0.5}]});
    let file = dir.join("in.json");
    std::fs::write(&file, input.to_string()).unwrap();
    let (code, out, err) = run(
        &[
            "lp",
            file.to_str().unwrap(),
            "--catalog",
            cat.to_str().unwrap(),
            "--pretty",
        ],
        "",
    );
    assert_eq!(code, 0, "{err}");
    assert!(out.lines().count() > 3, "pretty output spans lines");
    let v: Value = serde_json::from_str(&out).unwrap();
    assert_eq!(v["results"][0]["g"].as_f64().unwrap().round(), 1.0);
    // Without the user catalog "wave" is unknown.
    let (code, _, err) = run(&["lp", file.to_str().unwrap()], "");
    assert_eq!(code, 1);
    assert!(err.contains("'wave' is not in the catalog"), "{err}");
}

fn bad(input: &str, want: &str) {
    let (code, out, err) = run(&["lp"], input);
    assert_eq!(code, 1, "input {input}: stdout {out}");
    assert!(out.is_empty(), "no partial output: {out}");
    assert_eq!(err.trim_end().lines().count(), 1, "one line: {err}");
    assert!(err.starts_with("error: "), "{err}");
    assert!(
        err.contains(want),
        "input {input}: error '{err}' lacks '{want}'"
    );
    assert!(!err.contains("panicked"), "{err}");
}

#[test]
fn bad_input_gives_one_line_errors() {
    let ok_problem = r#"{"moments": [0.5, 0.25], "zf": 0.5}"#;
    let with = |basis: &str, extra: &str, problems: &str| {
        format!(r#"{{"basis": {basis}, {extra} "solver": "reference", "problems": [{problems}]}}"#)
    };
    bad(
        "{\"basis\": [\"z\"],\n \"problems\": [}",
        "malformed input JSON",
    );
    bad("{\"basis\": [\"z\"],\n \"problems\": [}", "line 2 column");
    bad("", "malformed input JSON");
    bad(r#"{"basis": ["z"]}"#, "missing field `problems`");
    bad(
        r#"{"basis": ["z"], "problems": [], "colour": 1}"#,
        "unknown field `colour`",
    );
    bad(
        &with(r#"["z", "blorp(z)"]"#, "", ok_problem),
        "basis entry 1: 'blorp(z)' is not in the catalog: formula 'blorp(z)': unknown name 'blorp' at position 1",
    );
    bad(
        &with(r#"["z", "sin(2z"]"#, "", ok_problem),
        "formula 'sin(2z': expected ')'",
    );
    bad(
        &with(r#"["z", "log(z)"]"#, "", ok_problem),
        "function 'log(z)' is not finite on [0,1]",
    );
    bad(&with("[]", "", ok_problem), "need at least one function");
    bad(
        &with(
            r#"["z", "z^2"]"#,
            "",
            r#"{"moments": [NaN, 0.1], "zf": 0.5}"#,
        ),
        "malformed input JSON",
    );
    bad(
        &with(
            r#"["z", "z^2"]"#,
            "",
            r#"{"moments": [1e999, 0.1], "zf": 0.5}"#,
        ),
        "number out of range",
    );
    bad(
        &with(
            r#"["z", "z^2"]"#,
            "",
            r#"{"moments": [null, 0.1], "zf": 0.5}"#,
        ),
        "invalid type: null",
    );
    bad(
        &with(
            r#"["z", "z^2"]"#,
            "",
            &format!(r#"{ok_problem}, {ok_problem}, {{"moments": [0.5], "zf": 0.5}}"#),
        ),
        "problem 2: expected 2 moments (one per basis function), got 1",
    );
    bad(
        &with(
            r#"["z", "z^2"]"#,
            "",
            &format!(r#"{ok_problem}, {{"moments": [0.5, 0.25], "zf": 1.5}}"#),
        ),
        "problem 1: zf = 1.5 is outside [0,1]",
    );
    bad(
        &with(
            r#"["z", "z^2"]"#,
            "",
            r#"{"moments": [0.5, 0.25], "zf": -0.1}"#,
        ),
        "problem 0: zf = -0.1 is outside [0,1]",
    );
    bad(
        &with(r#"["z"]"#, r#""grid": {"points": 1},"#, ""),
        "grid: need at least 2 points, got 1",
    );
    bad(
        &with(r#"["z"]"#, r#""grid": {"points": 1000000000},"#, ""),
        "grid: 1000000000 points is more than the supported",
    );
    bad(
        &with(r#"["z"]"#, r#""grid": {"points": -3},"#, ""),
        "invalid value: integer `-3`",
    );
    bad(
        &with(r#"["z"]"#, r#""grid": {"values": [0.5, 0.5]},"#, ""),
        "grid: need at least 2 distinct points",
    );
    bad(
        &with(r#"["z"]"#, r#""grid": {"values": [0.5, 2.0]},"#, ""),
        "grid: value 1 (2) is outside [0,1]",
    );
    bad(
        &with(
            r#"["z"]"#,
            r#""grid": {"points": 5, "values": [0.5, 1.0]},"#,
            "",
        ),
        "grid: give exactly one of",
    );
    bad(
        r#"{"basis": ["z"], "solver": "simplex9000", "problems": []}"#,
        "unknown LP solver 'simplex9000'",
    );
    let (code, _, err) = run(&["lp", "/nonexistent/batch.json"], "");
    assert_eq!(code, 1);
    assert!(
        err.contains("/nonexistent/batch.json: no such file"),
        "{err}"
    );
    let (code, _, err) = run(&["lp", "--catalog", "/nonexistent/cat.json"], "{}");
    assert_eq!(code, 1);
    assert!(
        err.contains("catalog: /nonexistent/cat.json: no such file"),
        "{err}"
    );
}

/// The fast solver, once merged, must answer like the reference through the CLI.
#[test]
fn fast_solver_matches_reference_when_available() {
    let n = 64;
    let mut problems = Vec::new();
    for (i, zf) in [0.1, 0.33, 0.5, 0.77, 1.0].iter().enumerate() {
        let a = 0.1 + 0.15 * i as f64;
        let b = moments(&MSM, &[(a, 0.5), (0.9, 0.3), (0.2, 0.2)]);
        problems.push(json!({"moments": b, "zf": zf}));
    }
    let mk = |solver: &str| {
        json!({"basis": ["z", "z^2", "z^3", "z^4"], "grid": {"points": n}, "solver": solver,
               "problems": problems})
        .to_string()
    };
    let (code, out, err) = run(&["lp"], &mk("fast"));
    if code != 0 {
        // Not merged yet: a one-line error saying so.
        assert_eq!(err.trim_end().lines().count(), 1, "{err}");
        assert!(err.contains("fast"), "{err}");
        return;
    }
    let fast: Value = serde_json::from_str(&out).unwrap();
    let (code, out, err) = run(&["lp"], &mk("reference"));
    assert_eq!(code, 0, "{err}");
    let reference: Value = serde_json::from_str(&out).unwrap();
    for (f, r) in fast["results"]
        .as_array()
        .unwrap()
        .iter()
        .zip(reference["results"].as_array().unwrap())
    {
        assert_eq!(f["status"], r["status"]);
        let (gf, gr) = (f["g"].as_f64().unwrap(), r["g"].as_f64().unwrap());
        assert!((gf - gr).abs() < 1e-7, "fast {gf} vs reference {gr}");
    }
}

#[test]
fn candidates_subcommands() {
    let (code, out, _) = run(&["candidates", "count"], "");
    assert_eq!((code, out.trim()), (0, "66045"));
    let (code, out, _) = run(&["candidates", "count", "--m", "2", "--json"], "");
    assert_eq!(code, 0);
    assert_eq!(
        serde_json::from_str::<Value>(&out).unwrap(),
        json!({"n": 37, "m": 2, "count": 666})
    );
    let (_, out, _) = run(&["candidates", "subset", "z,z^2,z^3,z^4"], "");
    assert_eq!(out.trim(), "0");
    let (_, out, _) = run(&["candidates", "subset", "z^4, z^3,z,z^2"], "");
    assert_eq!(out.trim(), "0");
    let (_, out, _) = run(
        &[
            "candidates",
            "subset",
            "sin(2πz),cos(2πz),sin(4πz),cos(4πz)",
        ],
        "",
    );
    let tmsm: u64 = out.trim().parse().unwrap();
    let (_, out, _) = run(&["candidates", "index", &tmsm.to_string()], "");
    assert_eq!(out.trim(), "sin(2πz),cos(2πz),sin(4πz),cos(4πz)");
    let (_, out, _) = run(
        &["candidates", "list", "--from", "66043", "--grid", "64"],
        "",
    );
    let lines: Vec<&str> = out.lines().collect();
    assert_eq!(lines.len(), 2);
    assert!(lines[0].starts_with("66043\t"), "{}", lines[0]);
    assert_eq!(lines[1].split('\t').nth(2), Some("ok"));
    let (_, out, _) = run(
        &["candidates", "list", "--m", "1", "--count", "3", "--json"],
        "",
    );
    let first: Value = serde_json::from_str(out.lines().next().unwrap()).unwrap();
    assert_eq!(
        first,
        json!({"index": 0, "functions": ["z"], "positions": [0]})
    );
    for (args, want) in [
        (vec!["candidates", "index", "66045"], "out of range"),
        // Usage errors (exit 2) are tested in tests/project/bad_input/per_command.rs.
        (
            vec!["candidates", "subset", "z,blorp"],
            "'blorp' is not a catalog function name",
        ),
        (vec!["candidates", "subset", "z,z"], "appears twice"),
        (
            vec!["candidates", "list", "--from", "70000"],
            "out of range",
        ),
    ] {
        let (code, _, err) = run(&args, "");
        assert_eq!(code, 1, "{args:?}");
        assert_eq!(err.trim_end().lines().count(), 1, "{err}");
        assert!(err.contains(want), "{args:?}: {err}");
    }
}

/// m = 2 with (z, z²): G equals the one-tailed Chebyshev (Cantelli) bound
/// (z_f−μ)²/(σ²+(z_f−μ)²) for z_f > μ when the extremal two-point distribution lies on the
/// grid, and approaches it from above, monotonically over nested grids, otherwise.
#[test]
fn vsm_basis_gives_the_cantelli_bound() {
    let cantelli = |mu: f64, var: f64, zf: f64| {
        let d: f64 = zf - mu;
        d * d / (var + d * d)
    };
    // μ = 0.5, σ² = 0.01: extremal points {0.4, 0.6} for z_f = 0.6, {0.3, 0.55} for 0.55.
    let input = json!({"basis": ["z", "z^2"], "grid": {"points": 21}, "solver": "reference",
        "problems": [{"moments": [0.5, 0.26], "zf": 0.6}, {"moments": [0.5, 0.26], "zf": 0.55}]});
    let r = lp(&input);
    for (res, zf) in r.iter().zip([0.6, 0.55]) {
        let g = res["g"].as_f64().unwrap();
        assert!((g - cantelli(0.5, 0.01, zf)).abs() < 1e-9, "zf {zf}: {g}");
    }
    // Diracs at 0.375 and 0.625 (on every grid below); z_f off every grid; the extremal
    // point μ − σ²/(z_f − μ) ≈ 0.336 lies inside [0,1], so the bound is approached.
    let zf = 0.5 + 0.3 / std::f64::consts::PI;
    let want = cantelli(0.5, 0.015625, zf);
    let mut prev = f64::INFINITY;
    for n in [9, 33, 129, 513, 1025] {
        let input = json!({"basis": ["z", "z^2"], "grid": {"points": n}, "solver": "reference",
            "problems": [{"moments": [0.5, 0.265625], "zf": zf}]});
        let g = lp(&input)[0]["g"].as_f64().unwrap();
        assert!(g >= want - 1e-9, "n {n}: {g} below Cantelli {want}");
        assert!(
            g <= prev + 1e-9,
            "n {n}: {g} not monotone (previous {prev})"
        );
        prev = g;
        // The upper Dirac can only sit at the first grid point z₊ ≥ z_f: Cantelli at z₊,
        // plus a gap (the lower point off the grid) that shrinks like h².
        let zp = (zf * (n - 1) as f64).ceil() / (n - 1) as f64;
        let at_zp = cantelli(0.5, 0.015625, zp);
        assert!(g >= at_zp - 1e-9, "n {n}: {g} below Cantelli at z+ {at_zp}");
        if n >= 129 {
            let tol = 0.1 / ((n - 1) as f64).powi(2) * 128.0;
            assert!(g - at_zp < tol, "n {n}: {g} vs Cantelli at z+ {at_zp}");
        }
    }
    assert!(prev - want < 2e-3, "n 1025: {prev} vs Cantelli {want}");
}

/// A batch mixing ordinary problems with flat-receiver problems the fast solver may not be able
/// to certify (three adjacent grid points at n = 1024, z_f on the middle one: the f64 moments
/// determine the distribution only to ~1e-5 there) and an infeasible one: exit 0, one answer per
/// problem in order, the ordinary ones exact, every other one `optimal` with a support that
/// reproduces the moments or `failed` / `infeasible` with nothing claimed.
#[test]
fn batch_with_unsettled_problems_answers_every_other_problem() {
    let n = 1024usize;
    let z = |i: usize| i as f64 / (n - 1) as f64;
    let mut problems = Vec::new();
    let mut want: Vec<Option<f64>> = Vec::new();
    for c in [300usize, 721, 900] {
        // Ordinary: a single Dirac on the grid, z_f above it (G = 1).
        problems.push(json!({"moments": moments(&MSM, &[(z(c), 1.0)]), "zf": z(c + 5)}));
        want.push(Some(1.0));
        // Flat receiver: weights on c, c+1, c+2, z_f = z(c+1).
        let b = moments(&MSM, &[(z(c), 0.146), (z(c + 1), 0.649), (z(c + 2), 0.205)]);
        problems.push(json!({"moments": b, "zf": z(c + 1)}));
        want.push(None);
    }
    // Clearly infeasible: E[z²] < E[z]².
    problems.push(json!({"moments": [0.5, 0.1, 0.05, 0.02], "zf": 0.5}));
    want.push(None);
    let input = json!({"basis": ["z", "z^2", "z^3", "z^4"], "grid": {"points": n},
                       "problems": problems});
    let results = lp(&input);
    assert_eq!(results.len(), problems.len());
    let mut failed = 0;
    for (k, (r, w)) in results.iter().zip(&want).enumerate() {
        match (r["status"].as_str().unwrap(), w) {
            ("optimal", Some(g)) => {
                assert!((r["g"].as_f64().unwrap() - g).abs() < 1e-9, "{k}: {r}")
            }
            ("optimal", None) => {
                let b: Vec<f64> = serde_json::from_value(problems[k]["moments"].clone()).unwrap();
                check_result(r, &MSM, &b, n, problems[k]["zf"].as_f64().unwrap());
            }
            ("failed", None) => {
                failed += 1;
                assert!(
                    r.get("g").is_none() && r.get("support").is_none(),
                    "{k}: {r}"
                );
                assert!(!r["reason"].as_str().unwrap().is_empty(), "{k}: {r}");
            }
            ("infeasible", None) => assert_eq!(k, problems.len() - 1, "{r}"),
            (s, w) => panic!("problem {k}: status {s}, expected {w:?}: {r}"),
        }
    }
    eprintln!("{failed} of 3 flat-receiver problems failed (unsettled), the rest answered");
}
