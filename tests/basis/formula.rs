//! The formula parser: exact values, grammar corner cases, errors with positions, and a
//! property test against directly evaluated random expression trees.

use momentlab::basis::formula::parse;
use momentlab::basis::Function;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::f64::consts::{E, PI};

fn ev(s: &str, z: f64) -> f64 {
    parse(s).unwrap_or_else(|e| panic!("{s}: {e:#}")).eval(z)
}

#[test]
fn exact_values() {
    let cases: &[(&str, f64, f64)] = &[
        ("z", 0.3, 0.3),
        ("1e-3", 0.0, 0.001),
        ("2.5E+2", 0.0, 250.0),
        (".5", 0.0, 0.5),
        ("5.", 0.0, 5.0),
        ("1+2*3", 0.0, 7.0),
        ("(1+2)*3", 0.0, 9.0),
        ("10-4-3", 0.0, 3.0),
        ("64/4/2", 0.0, 8.0),
        ("2^3^2", 0.0, 512.0),
        ("2**3", 0.0, 8.0),
        ("-z^2", 3.0, -9.0),
        ("(-z)^2", 3.0, 9.0),
        ("--z", 2.0, 2.0),
        ("+z", 2.0, 2.0),
        ("2^-1", 0.0, 0.5),
        ("20z", 0.5, 10.0),
        ("2z^2", 3.0, 18.0),
        ("1/2z", 4.0, 2.0),
        ("2 -z", 0.5, 1.5),
        ("(1+z)(2-z)", 1.0, 2.0),
        ("10(z-0.5)", 0.7, 2.0),
        ("z·2", 0.25, 0.5),
        ("3×z", 2.0, 6.0),
        ("1−z", 0.25, 0.75),
        ("abs(z-1)", 0.25, 0.75),
        ("sqrt(z)", 0.25, 0.5),
        ("cbrt(z)", 0.125, 0.5),
        ("log2(z)", 0.25, -2.0),
        ("log10(z)", 0.001, -3.0),
        ("exp(0)", 0.0, 1.0),
        ("z^(1/2)", 0.25, 0.5),
        ("e", 0.0, E),
        ("pi", 0.0, PI),
        ("π", 0.0, PI),
    ];
    for &(s, z, want) in cases {
        let got = ev(s, z);
        assert!(
            (got - want).abs() <= 1e-15 * want.abs().max(1.0),
            "{s} at {z}: got {got}, want {want}"
        );
    }
}

#[test]
fn constants_and_functions_match_std() {
    for &z in &[0.0, 0.1, 0.37, 0.5, 0.999, 1.0] {
        let pairs: &[(&str, f64)] = &[
            ("sin(2πz)", (2.0 * PI * z).sin()),
            ("cos(4 pi z)", (4.0 * PI * z).cos()),
            ("2πz", 2.0 * PI * z),
            ("piz", PI * z),
            ("ez", E * z),
            ("exp(20z)", (20.0 * z).exp()),
            ("exp(-20z)", (-20.0 * z).exp()),
            ("e^(2z)", (2.0 * z).exp()),
            ("log(1+z)", (1.0 + z).ln()),
            ("ln(1+10z)", (1.0 + 10.0 * z).ln()),
            ("1/(1+100z)", 1.0 / (1.0 + 100.0 * z)),
            ("tanh(10(z-0.5))", (10.0 * (z - 0.5)).tanh()),
            ("atan(z)", z.atan()),
            ("tan(z)", z.tan()),
            ("sinh(z)+cosh(z)", z.sinh() + z.cosh()),
            ("asinh(z)", z.asinh()),
            ("asin(z)+acos(z)", z.asin() + z.acos()),
            ("sigmoid(z)", 1.0 / (1.0 + (-z).exp())),
            ("gauss(z)", (-z * z).exp()),
        ];
        for &(s, want) in pairs {
            let got = ev(s, z);
            assert!(
                (got - want).abs() <= 1e-13 * want.abs().max(1.0),
                "{s} at {z}: got {got}, want {want}"
            );
        }
    }
}

fn err(s: &str) -> String {
    match parse(s) {
        Ok(e) => panic!("'{s}' parsed as {e:?}"),
        Err(e) => format!("{e:#}"),
    }
}

#[test]
fn errors_name_formula_and_position() {
    let cases: &[(&str, &str)] = &[
        ("", "empty formula at position 1"),
        ("   ", "empty formula"),
        (
            "sin(2πz",
            "expected ')' to close '(' at position 4, found end of formula at position 8",
        ),
        ("z+", "found end of formula at position 3"),
        ("z)", "unmatched ')' at position 2"),
        ("foo(z)", "unknown name 'foo' at position 1"),
        ("2*y", "unknown name 'y' at position 3"),
        ("z $ 2", "unexpected character '$' at position 3"),
        (
            "sin z",
            "expected '(' after function 'sin', found 'z' at position 5",
        ),
        ("1..2", "malformed number '1..2' at position 1"),
        ("*z", "found '*' at position 1"),
        ("()", "found ')' at position 2"),
        ("z^", "found end of formula at position 3"),
    ];
    let deep = format!("{}z{}", "(".repeat(2000), ")".repeat(2000));
    assert!(err(&deep).contains("nested more than 200 levels deep"));
    let negs = format!("{}z", "-".repeat(300));
    assert!(err(&negs).contains("nested more than 200 levels deep"));
    let long = "z+".repeat(3000) + "z";
    assert!(err(&long).contains("formula too long"));
    assert_eq!(
        ev(&format!("{}z{}", "(".repeat(150), ")".repeat(150)), 0.5),
        0.5
    );
    for &(s, want) in cases {
        let e = err(s);
        assert!(e.contains(want), "'{s}': error '{e}' lacks '{want}'");
        assert!(e.starts_with(&format!("formula '{s}'")), "'{s}': {e}");
        assert!(!e.contains('\n'));
    }
}

#[test]
fn not_finite_on_unit_interval_is_rejected() {
    for s in [
        "log(z)",
        "1/z",
        "1/(z-0.5)",
        "z^(-1)",
        "sqrt(z-0.5)",
        "log(1-z)",
        "exp(1000z)",
    ] {
        let e = format!("{:#}", Function::parse(s).unwrap_err());
        assert!(e.contains(&format!("function '{s}'")), "{e}");
        assert!(e.contains("not finite on [0,1]"), "{e}");
    }
    // Named functions name both.
    let e = format!("{:#}", Function::new("bad", "1/z").unwrap_err());
    assert!(
        e.contains("'bad'") && e.contains("'1/z'") && e.contains("z = 0"),
        "{e}"
    );
    // Finite everywhere on [0,1] even if not outside it.
    assert!(Function::parse("log(1.001-z)").is_ok());
    assert!(Function::parse("sqrt(z)").is_ok());
}

/// A random expression tree, printed fully parenthesised and evaluated directly.
enum T {
    Num(f64),
    Z,
    Bin(char, Box<T>, Box<T>),
    Neg(Box<T>),
    Call(&'static str, Box<T>),
}

const FUNCS: &[&str] = &["exp", "sin", "cos", "tanh", "atan", "abs", "sqrt"];

fn gen(rng: &mut ChaCha8Rng, depth: u32) -> T {
    if depth == 0 || rng.gen_bool(0.25) {
        return if rng.gen_bool(0.5) {
            T::Z
        } else {
            T::Num((rng.gen_range(-50.0f64..50.0) * 100.0).round() / 100.0)
        };
    }
    match rng.gen_range(0..8) {
        0 => T::Neg(Box::new(gen(rng, depth - 1))),
        1 => T::Call(
            FUNCS[rng.gen_range(0..FUNCS.len())],
            Box::new(gen(rng, depth - 1)),
        ),
        2 => T::Bin(
            '^',
            Box::new(T::Call("abs", Box::new(gen(rng, depth - 1)))),
            Box::new(T::Num(rng.gen_range(0..4) as f64)),
        ),
        k => T::Bin(
            ['+', '-', '*', '/', '+'][k - 3],
            Box::new(gen(rng, depth - 1)),
            Box::new(gen(rng, depth - 1)),
        ),
    }
}

/// Fully parenthesised text; `implicit` writes products as juxtaposition "(a)(b)".
fn show(t: &T, implicit: bool) -> String {
    match t {
        T::Num(v) => format!("({v})"),
        T::Z => "z".to_string(),
        T::Neg(a) => format!("(-{})", show(a, implicit)),
        T::Call(f, a) => format!("{f}({})", show(a, implicit)),
        T::Bin('*', a, b) if implicit => {
            format!("(({})({}))", show(a, implicit), show(b, implicit))
        }
        T::Bin(op, a, b) => format!("({} {op} {})", show(a, implicit), show(b, implicit)),
    }
}

fn direct(t: &T, z: f64) -> f64 {
    match t {
        T::Num(v) => *v,
        T::Z => z,
        T::Neg(a) => -direct(a, z),
        T::Call(f, a) => {
            let x = direct(a, z);
            match *f {
                "exp" => x.exp(),
                "sin" => x.sin(),
                "cos" => x.cos(),
                "tanh" => x.tanh(),
                "atan" => x.atan(),
                "abs" => x.abs(),
                _ => x.sqrt(),
            }
        }
        T::Bin(op, a, b) => {
            let (x, y) = (direct(a, z), direct(b, z));
            match op {
                '+' => x + y,
                '-' => x - y,
                '*' => x * y,
                '/' => x / y,
                // The parser compiles constant integer exponents to powi.
                _ => x.powi(y as i32),
            }
        }
    }
}

#[test]
fn random_expressions_match_direct_evaluation() {
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let mut compared = 0;
    for _ in 0..3000 {
        let t = gen(&mut rng, 5);
        for implicit in [false, true] {
            let s = show(&t, implicit);
            let e = parse(&s).unwrap_or_else(|e| panic!("{s}: {e:#}"));
            for &z in &[0.0, 0.21, 0.5, 0.77, 1.0] {
                let (a, b) = (e.eval(z), direct(&t, z));
                if a.is_nan() || b.is_nan() {
                    assert!(a.is_nan() && b.is_nan(), "{s} at {z}: {a} vs {b}");
                    continue;
                }
                // Constant folding and powi may reassociate nothing, but powi ≠ powf in the
                // last bits: compare relatively.
                assert!(
                    a == b || (a - b).abs() <= 1e-12 * a.abs().max(b.abs()).max(1e-300),
                    "{s} at {z}: parsed {a}, direct {b}"
                );
                compared += 1;
            }
        }
    }
    assert!(compared > 20000, "{compared}");
}
