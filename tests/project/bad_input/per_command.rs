//! The bad-input corpus per subcommand: each case is (arguments, stdin, exit code, a part of
//! the one-line error).

use super::*;

/// `momentlab candidates`: its hostile and edge inputs.
#[test]
fn candidates() {
    let c = Ctx::new();
    check(vec![
        // Sizes that used to panic (capacity overflow) or run away (allocation failure).
        (
            args(&["candidates", "list", "--grid", c.big]),
            None,
            2,
            "--grid",
        ),
        (
            args(&["candidates", "list", "--grid", "100000000"]),
            None,
            2,
            "not in 2..=1048576",
        ),
        (
            args(&["candidates", "index", "99999999"]),
            None,
            1,
            "99999999",
        ),
        (args(&["candidates", "count", "--m", "0"]), None, 2, "--m"),
        (args(&["candidates", "subset", "z,nope"]), None, 1, "nope"),
    ]);
}

/// `momentlab stability`: its hostile and edge inputs.
#[test]
fn stability() {
    let c = Ctx::new();
    check(vec![
        (args(&["stability", "--grid", c.big]), None, 2, "--grid"),
        (
            args(&["stability", "--grid", "100000000"]),
            None,
            2,
            "not in 2..=65536",
        ),
        (args(&["stability", "--inputs", "0"]), None, 2, "--inputs"),
        (
            args(&["stability", "--inputs", "5", "--technique", "vsm,hamburgr4"]),
            None,
            1,
            "--technique hamburgr4",
        ),
    ]);
}

/// `momentlab bench`: its hostile and edge inputs.
#[test]
fn bench() {
    check(vec![
        // Flags the command would have ignored, and checks that used to wait for the dataset.
        (
            args(&["bench", "lp", "--corpus", "adversarial", "--n", "64"]),
            None,
            1,
            "--n does not apply to --corpus adversarial",
        ),
        (
            args(&["bench", "lp", "--corpus", "moments", "--large"]),
            None,
            1,
            "--large does not apply to --corpus moments",
        ),
        (
            args(&["bench", "lp", "--basis", "z,z^2", "--m", "3"]),
            None,
            1,
            "--basis and --m both choose the functions",
        ),
        (
            args(&["bench", "shadow", "--inputs", "1e12"]),
            None,
            2,
            "--inputs",
        ),
        (
            args(&["bench", "shadow", "--inputs", "1000000000000"]),
            None,
            2,
            "not in 1..=10000000",
        ),
        (
            args(&["bench", "shadow", "--repeats", "0"]),
            None,
            2,
            "--repeats",
        ),
        (
            args(&["bench", "lp", "--repeats", "0"]),
            None,
            2,
            "--repeats",
        ),
        (args(&["bench", "lp", "--n", "1"]), None, 2, "--n"),
    ]);
}

/// `momentlab search`: its hostile and edge inputs.
#[test]
fn search() {
    check(vec![
        (
            args(&["search", "--synthetic", "100", "--max-fragments", "10"]),
            None,
            2,
            "--max-fragments",
        ),
        (args(&["search", "--plan", "--json"]), None, 2, "--json"),
        (
            args(&["search", "--solver", "foo"]),
            None,
            1,
            "--solver: unknown LP solver 'foo'",
        ),
        (
            args(&[
                "search",
                "--report-only",
                "--compare",
                "/nonexistent-momentlab",
            ]),
            None,
            1,
            "--compare /nonexistent-momentlab",
        ),
        (args(&["search", "--grid", "1e11"]), None, 2, "--grid"),
        (
            args(&["search", "--grid", "100000000000"]),
            None,
            2,
            "--grid",
        ),
        (
            args(&["search", "--lp-budget", "x"]),
            None,
            2,
            "--lp-budget",
        ),
        (args(&["search", "--growth", "1"]), None, 2, "--growth"),
        // Rejected before any rendering.
        (args(&["search", "--m", "0"]), None, 2, "--m"),
        (args(&["search", "--m", "9"]), None, 2, "--m"),
    ]);
}

/// `momentlab shadow`: its hostile and edge inputs.
#[test]
fn shadow() {
    let c = Ctx::new();
    check(vec![
        (
            args(&["shadow"]),
            Some(
                r#"{"technique": "vsm", "esm_c": 5, "problems": [{"moments": [0.5, 0.3], "zf": 0.5}]}"#
                    .to_string(),
            ),
            1,
            "\"esm_c\" does not apply to vsm",
        ),
        (
            args(&["shadow"]),
            Some(c.shadow_huge.clone()),
            1,
            "moment 1 = 1e308 is outside",
        ),
        (
            args(&["shadow"]),
            Some(c.shadow_nan.clone()),
            1,
            "needs 4 moments, got 3",
        ),
        (args(&["shadow"]), Some(String::new()), 1, "malformed JSON"),
    ]);
}

/// `momentlab theta`: its hostile and edge inputs.
#[test]
fn theta() {
    check(vec![(
        args(&["theta", "--summary", "/nonexistent-momentlab-summary"]),
        None,
        1,
        "--summary /nonexistent-momentlab-summary: no such folder",
    )]);
}

/// `momentlab evaluate`: its hostile and edge inputs.
#[test]
fn evaluate() {
    let c = Ctx::new();
    check(vec![
        // A bias beyond the depth range made every output non-finite (scored as 0 % error).
        (
            args(&[
                "evaluate",
                "--technique",
                "hamburger4",
                "--technique-epsilon",
                "1e300",
            ]),
            None,
            1,
            "technique_epsilon must be in [0, 1], got 1e300",
        ),
        (
            args(&["evaluate", "--technique", "vsm", "--slope-scale", "1e9"]),
            None,
            1,
            "slope_scale must be in [0, 1000]",
        ),
        // Silently wrong: empty inputs, out-of-range z_f and moments, lossy EXR.
        (
            args(&[
                "evaluate",
                "--technique",
                "vsm",
                "--stacks",
                &c.f.p("empty"),
            ]),
            None,
            1,
            "0 fragments",
        ),
        // Negative numbers without '=' reach the range check.
        (
            args(&["evaluate", "--technique", "vsm", "--pcf-epsilon", "-1"]),
            None,
            2,
            "-1 is negative",
        ),
        (
            args(&["evaluate", "--technique", "vsm", "--stride", "0"]),
            None,
            2,
            "--stride",
        ),
        (
            args(&["evaluate", "--technique", "vsm", "--sample", "0"]),
            None,
            2,
            "not in (0, 1]",
        ),
        (
            args(&["evaluate", "--technique", "nope", "--stacks", &c.f.p("a")]),
            None,
            1,
            "nope",
        ),
        (
            args(&["evaluate", "--technique", "vsm", "--resolution", "100000"]),
            None,
            2,
            "--resolution",
        ),
        (args(&["evaluate"]), None, 2, "--technique"),
    ]);
}

/// `momentlab import`: its hostile and edge inputs.
#[test]
fn import() {
    let c = Ctx::new();
    check(vec![
        (
            args(&["import", &c.f.p("huge/v.exr")]),
            None,
            1,
            "layers = 1000000000000000",
        ),
        (
            args(&["import", &c.f.p("wide/v.exr")]),
            None,
            1,
            "width and height",
        ),
        // Silent data loss: two inputs with one file name.
        (
            args(&[
                "import",
                &c.f.p("a/v.exr"),
                &c.f.p("b/v.exr"),
                "--out",
                &c.out_x,
            ]),
            None,
            1,
            "would both be written",
        ),
        (
            args(&["import", &c.f.p("lossy/v.exr")]),
            None,
            1,
            "PXR24 is lossy",
        ),
        (args(&["import", "-"]), None, 1, "stdin"),
        (
            args(&["import", &c.f.p("nothing.exr")]),
            None,
            1,
            "no such file",
        ),
    ]);
    // Nothing was written by the refused import.
    assert!(!Path::new(&c.out_x).join("v.exr").exists());
}

/// `momentlab recommend`: its hostile and edge inputs.
#[test]
fn tune_and_recommend() {
    let c = Ctx::new();
    check(vec![
        (
            args(&[
                "recommend",
                "--stacks",
                &c.f.p("empty"),
                "--fragments",
                "10",
            ]),
            None,
            1,
            "0 fragments",
        ),
        (
            args(&["recommend", "--technique", "lp:z,z^2"]),
            None,
            1,
            "unknown 'lp:z'",
        ),
        (
            args(&["recommend", "--technique", "nope", "--stacks", &c.f.p("a")]),
            None,
            1,
            "'nope'",
        ),
        (
            args(&["recommend", "--tolerance", "-1"]),
            None,
            2,
            "-1 is negative",
        ),
    ]);
}

/// `momentlab quantize`: its hostile and edge inputs.
#[test]
fn quantize() {
    let c = Ctx::new();
    check(vec![(
        args(&[
            "quantize",
            "--stacks",
            &c.f.p("empty"),
            "--theta-dir",
            &c.theta_dir,
            "--technique",
            "vsm",
            "--out",
            &c.out_q,
        ]),
        None,
        1,
        "0 fragments",
    )]);
}

/// `momentlab lp`: its hostile and edge inputs.
#[test]
fn lp() {
    let c = Ctx::new();
    check(vec![
        (
            args(&["lp"]),
            Some(r#"{"basis": ["z"], "problems": [{"moments": [0.5], "zf": 7}]}"#.into()),
            1,
            "outside [0,1]",
        ),
        (
            args(&["lp", "-"]),
            Some("{".into()),
            1,
            "malformed input JSON",
        ),
        (
            args(&["lp"]),
            Some(r#"{"basis": ["z"], "grid": {"points": 100000000000}, "problems": []}"#.into()),
            1,
            "more than the supported",
        ),
        (
            args(&["lp", &c.f.p("missing.json")]),
            None,
            1,
            "missing.json: no such file",
        ),
        (args(&["lp", "--frobnicate"]), None, 2, "--frobnicate"),
    ]);
}

/// `momentlab reproduce`: its hostile and edge inputs.
#[test]
fn reproduce() {
    check(vec![
        (
            args(&["reproduce", "--tolerance", "-1"]),
            None,
            2,
            "-1 is negative",
        ),
        (args(&["reproduce", "--run", "../x"]), None, 1, "--run"),
        (
            args(&["reproduce", "--tiny", "--resolution", "4"]),
            None,
            2,
            "--resolution",
        ),
    ]);
}

/// `momentlab render`: its hostile and edge inputs.
#[test]
fn render() {
    check(vec![
        (
            args(&["render", "--resolution", "0"]),
            None,
            2,
            "--resolution",
        ),
        (
            args(&["render", "--resolution", "100000"]),
            None,
            2,
            "--resolution",
        ),
    ]);
}

/// `momentlab merge`: its hostile and edge inputs.
#[test]
fn merge() {
    let c = Ctx::new();
    check(vec![(
        args(&["merge", &c.f.p("nothing"), "--out", &c.out_x]),
        None,
        1,
        "nothing",
    )]);
}

/// Unknown subcommands and flags.
#[test]
fn unknown_commands_and_flags() {
    check(vec![(args(&["frobnicate"]), None, 2, "frobnicate")]);
}
