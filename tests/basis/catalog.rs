//! The basis catalog: the embedded file loads, has ≥ 37 unique, finite functions including the
//! MSM/TMSM/ESM ones, names agree with formulas, and bad files give one-line errors.

use momentlab::basis::{split_list, Catalog};
use std::collections::HashSet;

#[test]
fn embedded_catalog_is_complete() {
    let c = Catalog::embedded();
    assert!(c.len() >= 37, "{} functions", c.len());
    let names: HashSet<&str> = c.functions().iter().map(|f| f.name()).collect();
    assert_eq!(names.len(), c.len(), "names must be unique");
    for required in [
        "z",
        "z^2",
        "z^3",
        "z^4",
        "sin(2πz)",
        "cos(2πz)",
        "sin(4πz)",
        "cos(4πz)",
        "exp(20z)",
        "exp(-20z)",
    ] {
        assert!(names.contains(required), "missing {required}");
    }
    for f in c.functions() {
        assert!(!f.family().is_empty(), "{} has no family", f.name());
    }
}

#[test]
fn all_functions_finite_on_a_dense_grid() {
    let c = Catalog::embedded();
    for f in c.functions() {
        for i in 0..=100_000 {
            let z = i as f64 / 100_000.0;
            assert!(f.eval(z).is_finite(), "{} at {z}", f.name());
        }
    }
}

/// Each name is itself a formula; it must agree with the stored (explicit) formula, and with
/// an independent std evaluation for the required entries.
#[test]
fn names_agree_with_formulas() {
    let c = Catalog::embedded();
    for f in c.functions() {
        let by_name = momentlab::basis::Function::parse(f.name())
            .unwrap_or_else(|e| panic!("name {} does not parse: {e:#}", f.name()));
        for i in 0..=1000 {
            let z = i as f64 / 1000.0;
            let (a, b) = (f.eval(z), by_name.eval(z));
            assert!(
                (a - b).abs() <= 1e-12 * a.abs().max(1.0),
                "{}: formula {} gives {a}, name gives {b} at z = {z}",
                f.name(),
                f.formula()
            );
        }
    }
    type Known = (&'static str, fn(f64) -> f64);
    let known: [Known; 7] = [
        ("z^4", |z| z * z * z * z),
        ("sin(2πz)", |z| (2.0 * std::f64::consts::PI * z).sin()),
        ("cos(4πz)", |z| (4.0 * std::f64::consts::PI * z).cos()),
        ("exp(20z)", |z| (20.0 * z).exp()),
        ("exp(-20z)", |z| (-20.0 * z).exp()),
        ("z^(1/2)", f64::sqrt),
        ("log(1+10z)", |z| (1.0 + 10.0 * z).ln()),
    ];
    for (name, g) in known {
        let f = c.resolve(name).unwrap();
        for i in 0..=64 {
            let z = i as f64 / 64.0;
            assert!(
                (f.eval(z) - g(z)).abs() <= 1e-12 * g(z).abs().max(1.0),
                "{name}"
            );
        }
    }
}

#[test]
fn resolve_prefers_names_then_parses() {
    let c = Catalog::embedded();
    let f = c.resolve("z^(1/2)").unwrap();
    assert_eq!(f.formula(), "sqrt(z)");
    assert_eq!(f.family(), "root");
    let g = c.resolve(" 3z+1 ").unwrap();
    assert_eq!(g.name(), "3z+1");
    assert_eq!(g.eval(0.5), 2.5);
    assert!(c.resolve("blorp(z)").is_err());
    assert!(c.resolve("log(z)").is_err());
    let b = c.basis(&["z", "z^2"]).unwrap();
    let mut out = [0.0; 2];
    b.eval(0.5, &mut out);
    assert_eq!(out, [0.5, 0.25]);
    assert_eq!(b.names(), vec!["z", "z^2"]);
}

#[test]
fn split_list_respects_parentheses() {
    assert_eq!(
        split_list("z, tanh(10(z-0.5)),exp(20z)"),
        vec!["z", "tanh(10(z-0.5))", "exp(20z)"]
    );
    assert_eq!(split_list("z"), vec!["z"]);
    assert_eq!(split_list("a,,b"), vec!["a", "", "b"]);
}

fn load_err(text: &str) -> String {
    let dir = crate::common::tmp("cat");
    let path = dir.join(format!(
        "{:x}.json",
        text.len() * 7919 + text.as_bytes()[1] as usize
    ));
    std::fs::write(&path, text).unwrap();
    let e = match Catalog::load(&path) {
        Ok(_) => panic!("loaded: {text}"),
        Err(e) => format!("{e:#}"),
    };
    assert!(e.contains(&path.display().to_string()), "{e}");
    assert!(!e.contains('\n'), "{e}");
    e
}

#[test]
fn user_catalogs_load_and_bad_ones_fail_clearly() {
    let dir = crate::common::tmp("cat-ok");
    let path = dir.join("mine.json");
    std::fs::write(
        &path,
        r#"{"functions": [{"name": "z"}, {"name": "wave", "formula": "sin(3πz)", "family": "x"}]}"#,
    )
    .unwrap();
    let c = Catalog::load(&path).unwrap();
    assert_eq!(c.len(), 2);
    assert_eq!(c.functions()[1].name(), "wave");
    assert!((c.resolve("wave").unwrap().eval(0.5) + 1.0).abs() < 1e-15);

    let e = load_err(r#"{"functions": [{"name": "z"}, ]}"#);
    assert!(e.contains("malformed JSON") && e.contains("line 1"), "{e}");
    let e = load_err(r#"{"functions": [{"name": "z"}, {"name": "z"}]}"#);
    assert!(e.contains("entry 1: duplicate name 'z'"), "{e}");
    let e = load_err(r#"{"functions": [{"name": "a", "formula": "sin(z"}]}"#);
    assert!(
        e.contains("entry 0") && e.contains("formula 'sin(z'"),
        "{e}"
    );
    let e = load_err(r#"{"functions": [{"name": "a", "formula": "log(z)"}]}"#);
    assert!(
        e.contains("function 'a'") && e.contains("not finite"),
        "{e}"
    );
    let e = load_err(r#"{"functions": [{"name": "a", "fromula": "z"}]}"#);
    assert!(e.contains("unknown field"), "{e}");
    let e = load_err(r#"{"functions": []}"#);
    assert!(e.contains("no functions"), "{e}");
    let missing = dir.join("does-not-exist.json");
    let e = format!("{:#}", Catalog::load(&missing).unwrap_err());
    assert!(
        e.contains("does-not-exist.json") && e.contains("no such file"),
        "{e}"
    );
}
