//! `momentlab shadow` batch parsing: results and one-line errors naming what and where.

use momentlab::cli::shadow::evaluate_batch;

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
