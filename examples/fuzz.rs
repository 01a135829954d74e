//! The offline fuzz budget: `cargo run --release --example fuzz -- [--inputs N] [--seconds S]
//! [--seed K] [--parsers a,b] [--out reports/fuzz/fuzz.json]`. Runs N inputs per parser (or
//! until S seconds per parser), two parsers at a time, and writes the figures (parser, inputs,
//! failures, the command) as JSON through the artefact writer; findings go to
//! `reports/fuzz/findings/`. Exit status 1 when any input failed.

#[path = "../tests/fuzz/harness.rs"]
mod harness;

#[global_allocator]
static ALLOC: harness::Counting = harness::Counting;

use std::time::{Duration, Instant};

#[derive(serde::Serialize)]
struct Report {
    command: String,
    seed: u64,
    time_limit_seconds: f64,
    alloc_bound: String,
    parsers: Vec<harness::ParserRun>,
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let get = |k: &str| {
        args.iter()
            .position(|a| a == k)
            .and_then(|i| args.get(i + 1).cloned())
    };
    let inputs: u64 = get("--inputs").map_or(1_000_000, |s| s.parse().expect("--inputs"));
    let seconds: Option<f64> = get("--seconds").map(|s| s.parse().expect("--seconds"));
    let seed: u64 = get("--seed").map_or(1, |s| s.parse().expect("--seed"));
    let out = get("--out").unwrap_or_else(|| "reports/fuzz/fuzz.json".into());
    let parsers: Vec<String> = get("--parsers").map_or(
        harness::PARSERS.iter().map(|s| s.to_string()).collect(),
        |s| s.split(',').map(str::to_string).collect(),
    );
    let findings = std::path::PathBuf::from("reports/fuzz/findings");
    let next = std::sync::atomic::AtomicUsize::new(0);
    let runs = std::sync::Mutex::new(Vec::new());
    std::thread::scope(|s| {
        for _ in 0..2 {
            s.spawn(|| loop {
                let i = next.fetch_add(1, std::sync::atomic::Ordering::SeqCst);
                let Some(p) = parsers.get(i) else { break };
                let t = Instant::now();
                // In slices of 10 000 inputs, so that --seconds can end a parser's run.
                let mut total = harness::ParserRun {
                    parser: p.clone(),
                    ..Default::default()
                };
                let mut k = 0u64;
                while total.inputs < inputs && seconds.is_none_or(|s| t.elapsed().as_secs_f64() < s)
                {
                    let opts = harness::Options {
                        inputs: (inputs - total.inputs).min(10_000),
                        seed: seed.wrapping_mul(1_000_003).wrapping_add(k),
                        limit: Duration::from_secs(2),
                        findings: findings.clone(),
                    };
                    let r = harness::run_parser(p, &opts);
                    total.inputs += r.inputs;
                    total.failures += r.failures;
                    total.panics += r.panics;
                    total.hangs += r.hangs;
                    total.over_allocations += r.over_allocations;
                    total.max_seconds = total.max_seconds.max(r.max_seconds);
                    total.max_peak_bytes = total.max_peak_bytes.max(r.max_peak_bytes);
                    total.findings.extend(r.findings);
                    k += 1;
                }
                eprintln!(
                    "fuzz: {p}: {} inputs, {} failures in {:.0} s",
                    total.inputs,
                    total.failures,
                    t.elapsed().as_secs_f64()
                );
                runs.lock().unwrap().push(total);
            });
        }
    });
    let mut runs = runs.into_inner().unwrap();
    runs.sort_by_key(|r| {
        harness::PARSERS
            .iter()
            .position(|p| *p == r.parser)
            .unwrap_or(usize::MAX)
    });
    let failed = runs.iter().any(|r| r.failures > 0);
    let report = Report {
        command: format!("cargo run --release --example fuzz -- {}", args.join(" "))
            .trim()
            .to_string(),
        seed,
        time_limit_seconds: 2.0,
        alloc_bound: format!(
            "{} MiB + {} × input bytes",
            harness::ALLOC_BASE >> 20,
            harness::ALLOC_PER_BYTE
        ),
        parsers: runs,
    };
    if let Err(e) = momentlab::artefact::write_json(std::path::Path::new(&out), &report) {
        eprintln!("fuzz: writing {out}: {e:#}");
        std::process::exit(2);
    }
    std::process::exit(failed as i32);
}
