//! The fuzz harness (`harness.rs`) on a short budget: a few thousand inputs per parser, none of
//! which may panic, hang or allocate beyond the input bound. The offline budget is
//! `cargo run --release --example fuzz` (reports/fuzz/fuzz.json, docs/files.md).

mod harness;

#[global_allocator]
static ALLOC: harness::Counting = harness::Counting;

use std::time::Duration;

/// Inputs per parser in CI.
const CI_INPUTS: u64 = 2000;

#[test]
fn every_parser_survives_a_short_fuzz_budget() {
    let findings = std::env::temp_dir().join(format!("momentlab-fuzz-ci-{}", std::process::id()));
    let opts = harness::Options {
        inputs: CI_INPUTS,
        seed: 1,
        limit: Duration::from_secs(2),
        findings: findings.clone(),
    };
    // Two workers over the parsers.
    let next = std::sync::atomic::AtomicUsize::new(0);
    let runs = std::sync::Mutex::new(Vec::new());
    std::thread::scope(|s| {
        for _ in 0..2 {
            s.spawn(|| loop {
                let i = next.fetch_add(1, std::sync::atomic::Ordering::SeqCst);
                let Some(p) = harness::PARSERS.get(i) else {
                    break;
                };
                let r = harness::run_parser(p, &opts);
                runs.lock().unwrap().push(r);
            });
        }
    });
    let runs = runs.into_inner().unwrap();
    assert_eq!(runs.len(), harness::PARSERS.len());
    for r in &runs {
        assert_eq!(r.inputs, CI_INPUTS, "{}", r.parser);
        assert_eq!(r.failures, 0, "{}: {r:?}", r.parser);
    }
    let _ = std::fs::remove_dir_all(findings);
}

/// Every committed finding (tests/fuzz/findings/<parser>/) parses without a panic within the
/// bounds: the regression fixtures of earlier findings.
#[test]
fn findings_are_regression_fixtures() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fuzz/findings");
    let findings = std::env::temp_dir().join(format!("momentlab-fuzz-reg-{}", std::process::id()));
    for p in harness::PARSERS {
        if !dir.join(p).is_dir() {
            continue;
        }
        // The seeds include every finding; a run of 0 generated inputs is not enough, so each
        // seed is run unmutated first.
        let r = harness::run_seeds(p, &findings);
        assert_eq!(r.failures, 0, "{p}: {r:?}");
    }
    let _ = std::fs::remove_dir_all(findings);
}

/// The fuzz figures of docs/files.md (block `fuzz`) as rendered from reports/fuzz/fuzz.json.
fn render_figures(artefact: &serde_json::Value) -> String {
    let mut s = String::from(
        "| parser | inputs | failures | slowest input | largest heap peak |\n| --- | ---: | ---: | ---: | ---: |\n",
    );
    for p in artefact["parsers"].as_array().unwrap() {
        s += &format!(
            "| {} | {} | {} | {:.0} ms | {:.1} MiB |\n",
            p["parser"].as_str().unwrap(),
            p["inputs"].as_u64().unwrap(),
            p["failures"].as_u64().unwrap(),
            p["max_seconds"].as_f64().unwrap() * 1e3,
            p["max_peak_bytes"].as_f64().unwrap() / (1u64 << 20) as f64
        );
    }
    s += &format!(
        "\nCommand: `{}` (seed {}); time limit {} s per input; allocation bound {}.\n",
        artefact["command"].as_str().unwrap(),
        artefact["seed"],
        artefact["time_limit_seconds"],
        artefact["alloc_bound"].as_str().unwrap()
    );
    s
}

/// docs/files.md states the offline figures as rendered from the committed artefact, which
/// covers every parser with a million inputs and no failure. `MOMENTLAB_UPDATE_DOCS=1`
/// rewrites the block.
#[test]
fn docs_fuzz_figures_are_rendered_from_the_artefact() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let artefact: serde_json::Value =
        serde_json::from_slice(&std::fs::read(root.join("reports/fuzz/fuzz.json")).unwrap())
            .unwrap();
    let parsers: Vec<&str> = artefact["parsers"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| p["parser"].as_str().unwrap())
        .collect();
    assert_eq!(parsers, harness::PARSERS.to_vec());
    for p in artefact["parsers"].as_array().unwrap() {
        assert_eq!(p["failures"], 0, "{p}");
        assert!(p["inputs"].as_u64().unwrap() >= 1_000_000, "{p}");
    }
    let docs = root.join("docs/files.md");
    let text = std::fs::read_to_string(&docs).unwrap();
    let want = render_figures(&artefact);
    if std::env::var("MOMENTLAB_UPDATE_DOCS").as_deref() == Ok("1") {
        let new = momentlab::report::readme::splice(&text, |n| {
            anyhow::ensure!(n == "fuzz", "unknown block {n}");
            Ok(want.clone())
        })
        .unwrap();
        std::fs::write(&docs, new).unwrap();
        return;
    }
    let blocks = momentlab::report::readme::blocks(&text).unwrap();
    let block = blocks
        .iter()
        .find(|b| b.0 == "fuzz")
        .expect("docs/files.md has no fuzz block");
    assert_eq!(
        block.1, want,
        "docs/files.md: rerun with MOMENTLAB_UPDATE_DOCS=1"
    );
    // The check can fail: a changed figure renders a different block.
    let mut changed = artefact.clone();
    changed["parsers"][0]["inputs"] = serde_json::json!(1);
    assert_ne!(render_figures(&changed), want);
}
