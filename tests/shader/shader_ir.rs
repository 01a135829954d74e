//! The shader representation: constants print to text that parses back to the same f32, the
//! interpreter applies each operation once in f32 (a loop body once per iteration, its
//! variables assigned in order at its end), malformed functions (including misused loops) are
//! refused, and a module using every operation and a loop compiles in all wrappers
//! (GLSL 3.30 / 4.50 / ES 3.00 / ES 3.10, HLSL, WGSL through naga) as printed, with
//! `MOMENTLAB_PRECISE` `precise` exactly where the GLSL version has it.

use crate::common::shader as shader_common;

use momentlab::shader::{self, Cmp, Func, Module, Shape};
use rand::{Rng, SeedableRng};

#[test]
fn literals_parse_back_to_the_same_f32() {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
    let mut specials = vec![
        0.0f32,
        -0.0,
        1.0,
        -1.0,
        f32::MIN_POSITIVE,
        f32::MAX,
        f32::MIN,
    ];
    specials.push(f32::from_bits(1)); // smallest subnormal
    specials.push(0.035_955_886);
    for _ in 0..20000 {
        let v = f32::from_bits(rng.gen());
        if v.is_finite() {
            specials.push(v);
        }
    }
    for v in specials {
        let t = shader::literal(v);
        let inner = t.trim_start_matches('(').trim_end_matches(')');
        // a compiler may parse as f64 and round, or parse as f32 directly: both give v
        let p64: f64 = inner.parse().unwrap();
        let p32: f32 = inner.parse().unwrap();
        assert_eq!((p64 as f32).to_bits(), v.to_bits(), "{v:e} -> {t}");
        assert_eq!(p32.to_bits(), v.to_bits(), "{v:e} -> {t}");
        assert!(inner.contains('e'), "{t} must be a float literal");
    }
}

/// (a·b) − c evaluated with one rounding per operation differs from a fused a·b − c here, so
/// the interpreter must not contract.
#[test]
fn interpreter_rounds_every_operation() {
    let mut f = Func::new("prod_minus");
    let a = f.input_scalar("a");
    let b = f.input_scalar("b");
    let c = f.input_scalar("c");
    let p = f.mul(a, b);
    let d = f.sub(p, c);
    f.ret(Shape::Scalar, &[d]);
    let x = 1.0f32 + f32::EPSILON;
    let prod = x * x; // rounded
    let got = f.eval(&[x, x, prod]).unwrap()[0];
    assert_eq!(got, 0.0);
    assert_ne!(x.mul_add(x, -prod), 0.0, "the fused result differs");
}

fn all_ops() -> Func {
    let mut f = Func::new("all_ops");
    let x = f.input_scalar("x");
    let arr = f.input("arr", Shape::Array(3));
    let v = f.input("v4", Shape::Vector(4));
    let half = f.c(0.5);
    let neg = f.c(-1.25);
    let s1 = f.add(x, arr[0]);
    let s2 = f.sub(s1, arr[1]);
    let s3 = f.mul(s2, v[2]);
    let s4 = f.div(s3, half);
    let s5 = f.neg(s4);
    let s6 = f.abs(s5);
    let s7 = f.sqrt(s6);
    let s8 = f.min(s7, arr[2]);
    let s9 = f.max(s8, neg);
    let s10 = f.clamp(s9, neg, half);
    let s11 = f.select(Cmp::Lt, s10, half, s7, s8);
    let s12 = f.select(Cmp::Ge, s10, half, s7, s8);
    let s13 = f.select(Cmp::Le, v[0], v[1], s11, s12);
    let s14 = f.select(Cmp::Gt, v[0], v[1], s11, s12);
    let s15 = f.cos(s13);
    let s16 = f.sin(s14);
    let s17 = f.acos(s10);
    let s18 = f.atan2(s15, s16);
    let s19 = f.exp(s18);
    let s20 = f.log(s19);
    f.note(s20, "log(exp(y))");
    f.ret(Shape::Vector(4), &[s17, s18, s19, s20]);
    f.output("extra", Shape::Array(2), &[s6, v[3]]);
    f.output("more", Shape::Vector(2), &[s9, x]);
    f.output("last", Shape::Scalar, &[s1]);
    f
}

#[test]
fn interpreter_matches_direct_f32_code() {
    let f = all_ops();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
    for _ in 0..2000 {
        let i: Vec<f32> = (0..8).map(|_| rng.gen_range(-2.0f32..2.0)).collect();
        let (x, arr, v) = (i[0], &i[1..4], &i[4..8]);
        let s1 = x + arr[0];
        let s2 = s1 - arr[1];
        let s3 = s2 * v[2];
        let s4 = s3 / 0.5;
        let s6 = (-s4).abs();
        let s7 = s6.sqrt();
        let s8 = s7.min(arr[2]);
        let s9 = s8.max(-1.25);
        #[allow(clippy::manual_clamp)] // clamp = min(max(x, lo), hi), NaN-propagation as in shaders
        let s10 = s9.max(-1.25).min(0.5);
        let s11 = if s10 < 0.5 { s7 } else { s8 };
        let s12 = if s10 >= 0.5 { s7 } else { s8 };
        let s13 = if v[0] <= v[1] { s11 } else { s12 };
        let s14 = if v[0] > v[1] { s11 } else { s12 };
        let s17 = s10.acos();
        let s18 = s13.cos().atan2(s14.sin());
        let s19 = s18.exp();
        let want = [s17, s18, s19, s19.ln(), s6, v[3], s9, x, s1];
        let got = f.eval(&i).unwrap();
        assert_eq!(got.len(), want.len());
        for (g, w) in got.iter().zip(want) {
            assert_eq!(g.to_bits(), w.to_bits(), "{got:?} vs {want:?}");
        }
    }
}

/// Heron's iteration for √s from x₀ = s with a counter of the steps taken before |Δx| ≤ 1e-6
/// (a flag carried by the loop freezes the state), and a value computed after the loop.
fn heron(steps: u32) -> Func {
    let mut f = Func::new("heron");
    let s = f.input_scalar("s");
    let zero = f.c(0.0);
    let out = f.repeat(steps, &[s, zero, zero], |f, v| {
        let (x, n, done) = (v[0], v[1], v[2]);
        let q = f.div(s, x);
        let t = f.add(x, q);
        let half = f.c(0.5);
        let nx = f.mul(t, half);
        let d = f.sub(nx, x);
        let ad = f.abs(d);
        let tol = f.c(1e-6);
        let one = f.c(1.0);
        let now = f.select(Cmp::Le, ad, tol, one, zero);
        let x = f.select(Cmp::Gt, done, zero, x, nx);
        let n1 = f.add(n, one);
        let n = f.select(Cmp::Gt, done, zero, n, n1);
        let done = f.max(done, now);
        vec![x, n, done]
    });
    let sq = f.mul(out[0], out[0]);
    f.ret(Shape::Vector(3), &[out[0], out[1], sq]);
    f
}

#[test]
fn loops_run_their_body_count_times_in_the_interpreter() {
    let f = heron(20);
    assert_eq!(f.n_statements(), 11);
    assert_eq!(f.n_ops(), 10 * 20 + 1);
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
    for _ in 0..2000 {
        let s: f32 = rng.gen_range(0.01f32..100.0);
        let (mut x, mut n, mut done) = (s, 0.0f32, false);
        for _ in 0..20 {
            if done {
                continue;
            }
            let nx = (x + s / x) * 0.5;
            done = (nx - x).abs() <= 1e-6;
            x = nx;
            n += 1.0;
        }
        let got = f.eval(&[s]).unwrap();
        assert_eq!(got[0].to_bits(), x.to_bits(), "{s}");
        assert_eq!(got[1], n, "{s}");
        assert_eq!(got[2].to_bits(), (x * x).to_bits(), "{s}");
    }
    // one iteration: the variables hold the first step after the loop
    assert_eq!(heron(1).eval(&[4.0]).unwrap()[0], 2.5);
}

#[test]
fn malformed_loops_are_refused() {
    let mut f = Func::new("body_value_outside");
    let x = f.input_scalar("x");
    let mut inner = None;
    let v = f.repeat(3, &[x], |f, v| {
        let y = f.add(v[0], v[0]);
        inner = Some(y);
        vec![y]
    });
    let z = f.add(v[0], inner.unwrap());
    f.ret(Shape::Scalar, &[z]);
    assert!(
        f.validate().is_err(),
        "a body statement used after the loop"
    );
    let mut f = Func::new("body_value_returned");
    let x = f.input_scalar("x");
    let mut inner = None;
    f.repeat(3, &[x], |f, v| {
        let y = f.mul(v[0], v[0]);
        inner = Some(y);
        vec![y]
    });
    f.ret(Shape::Scalar, &[inner.unwrap()]);
    assert!(f.validate().is_err(), "a body statement returned");
    let mut f = Func::new("swap");
    let x = f.input_scalar("x");
    let y = f.input_scalar("y");
    let v = f.repeat(2, &[x, y], |_, v| vec![v[1], v[0]]);
    f.ret(Shape::Vector(2), &[v[0], v[1]]);
    assert!(
        f.validate().is_err(),
        "a variable assigned from another one"
    );
    let mut f = Func::new("nested");
    let x = f.input_scalar("x");
    let v = f.repeat(2, &[x], |f, v| {
        let w = f.repeat(2, &[v[0]], |f, w| vec![f.add(w[0], w[0])]);
        vec![w[0]]
    });
    f.ret(Shape::Scalar, &[v[0]]);
    assert!(f.validate().is_err(), "nested loops");
    assert!(f.eval(&[1.0]).is_err(), "nested loops");
    let mut f = Func::new("never");
    let x = f.input_scalar("x");
    let v = f.repeat(0, &[x], |f, v| vec![f.add(v[0], v[0])]);
    f.ret(Shape::Scalar, &[v[0]]);
    assert!(f.validate().is_err(), "zero iterations");
    assert!(f.eval(&[1.0]).is_err(), "zero iterations");
    assert!(heron(3).validate().is_ok());
}

#[test]
fn malformed_functions_are_refused() {
    let mut f = Func::new("f");
    let x = f.input_scalar("x");
    f.ret(Shape::Scalar, &[x]);
    assert!(f.eval(&[1.0, 2.0]).is_err(), "wrong input count");
    let mut g = Func::new("g");
    let _ = g.input_scalar("x");
    assert!(g.validate().is_err(), "no outputs");
    let mut h = Func::new("h");
    let y = h.input_scalar("y");
    h.output("y", Shape::Scalar, &[y]);
    assert!(h.validate().is_err(), "duplicate parameter name");
    let mut k = Func::new("2bad");
    let y = k.input_scalar("y");
    k.ret(Shape::Scalar, &[y]);
    assert!(shader::glsl(&Module {
        header: vec![],
        funcs: vec![k]
    })
    .is_err());
    let mut v = Func::new("v");
    let y = v.input_scalar("y");
    v.ret(Shape::Vector(5), &[y, y, y, y, y]);
    assert!(v.validate().is_err(), "vector of 5");
    let mut n = Func::new("n");
    let y = n.input_scalar("y");
    let c = n.c(f32::NAN);
    let s = n.add(y, c);
    n.ret(Shape::Scalar, &[s]);
    assert!(shader::hlsl(&Module {
        header: vec![],
        funcs: vec![n]
    })
    .is_err());
    let mut a = Func::new("a");
    let y = a.input_scalar("y");
    let mut b = Func::new("b");
    b.input_scalar("y");
    let s = b.add(y, y);
    let far = b.mul(s, s);
    a.ret(Shape::Scalar, &[far]);
    assert!(a.validate().is_err(), "value of another function");
}

#[test]
fn every_operation_compiles_in_all_wrappers() {
    let glslang = shader_common::tools_present("every_operation_compiles_in_all_wrappers");
    let m = Module {
        header: vec!["all operations".into()],
        funcs: vec![all_ops(), heron(20)],
    };
    let g = shader::glsl(&m).unwrap();
    assert!(g.contains("atan(") && !g.contains("atan2("));
    assert!(g.contains("for (int t_loop") && g.contains("< 20;"));
    assert!(shader::hlsl(&m).unwrap().contains("atan2("));
    assert!(shader::wgsl(&m).unwrap().contains("atan2("));
    shader_common::check("all_ops", &m, glslang).unwrap_or_else(|e| panic!("{e}"));
    // the check itself rejects broken code, in every language
    let mut bad = all_ops();
    bad.name = "main".into(); // clashes with the wrappers' entry point
    let m = Module {
        header: vec![],
        funcs: vec![bad],
    };
    let e = shader_common::check("clash", &m, glslang).unwrap_err();
    assert!(e.contains("WGSL (naga"), "{e}");
    if glslang {
        for what in [
            "GLSL 3.30",
            "GLSL 4.50",
            "GLSL ES 3.00",
            "GLSL ES 3.10",
            "HLSL",
        ] {
            assert!(e.contains(&format!("clash: {what}")), "{what}: {e}");
        }
    }
    // a WGSL type error (f32 + i32) is caught by naga's parser
    let e =
        shader_common::naga_check("typed", "fn f(x: f32) -> f32 { return x + 1i; }").unwrap_err();
    assert!(e.contains("typed: WGSL"), "{e}");
}

/// The GLSL version guard: `MOMENTLAB_PRECISE` is `precise` in GLSL ≥ 4.00 and GLSL ES ≥ 3.20,
/// empty before, and a definition made before the text wins.
#[test]
fn precise_is_guarded_by_glsl_version() {
    if !shader_common::tools_present("precise_is_guarded_by_glsl_version") {
        return;
    }
    let m = Module {
        header: vec![],
        funcs: vec![heron(2)],
    };
    for (version, es, precise) in shader_common::GLSL_VERSIONS {
        let pp = shader_common::glsl_preprocessed("guard", &m, version, es);
        let declared = pp.lines().filter(|l| l.contains("float t_")).count();
        let with = pp
            .lines()
            .filter(|l| l.contains("precise float t_"))
            .count();
        assert!(declared > 0, "{version}: {pp}");
        assert_eq!(with, if precise { declared } else { 0 }, "{version}: {pp}");
    }
    // HLSL keeps `precise`; an earlier definition overrides the default
    let h = shader::hlsl(&m).unwrap();
    assert!(h.contains("#define MOMENTLAB_PRECISE precise\n#endif"));
    assert!(!h.contains("__VERSION__"));
    let g = shader::glsl(&m).unwrap();
    assert!(g.contains("#ifndef MOMENTLAB_PRECISE\n#if"), "{g}");
}
