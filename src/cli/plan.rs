//! The output of `momentlab search --plan`: what the sweep will cost, to size a Slurm job array
//! (`--array`, `--cpus-per-task`, `--time`) before submitting (docs/search.md).

use momentlab::search::plan::{Plan, Schedule};
use momentlab::search::SweepOptions;

/// Calibration sample: candidates (stratified by family), solved on all threads on stage 0's
/// block size of fragments (≈ 1 s; [`calibration`]).
pub const CALIBRATION_CANDIDATES: usize = 64;

/// The calibration sample of `opts`: [`CALIBRATION_CANDIDATES`] × the first `first_sample`
/// fragments of the racing order, as dense in the sorted order as stage 0's block (a sparser
/// block costs more per LP: fewer neighbours share a distribution or a warm start).
pub fn calibration(opts: &SweepOptions) -> [usize; 2] {
    [CALIBRATION_CANDIDATES, opts.first_sample.max(1)]
}

/// Safety factor on the estimated time of a task for `--time`.
const TIME_MARGIN: f64 = 1.5;

/// Print the plan to stdout. `setup` is the seconds it took to build the dataset (each task
/// pays it again).
pub fn print(plan: &Plan, opts: &SweepOptions, setup: f64) {
    print_calibration(plan, opts);
    let expected_seconds = print_costs(plan, opts, setup);
    if let (Some(p), Some(secs)) = (plan.proxy.as_ref(), expected_seconds) {
        print_proxy(p, opts, secs);
    }
    print_schedule(plan, opts, setup);
}

/// The candidates and the calibration sample's rate.
fn print_calibration(plan: &Plan, opts: &SweepOptions) {
    let c = &plan.calibration;
    println!(
        "plan: m = {}, {} candidates: {} scored, {} degenerate, {} duplicate spans; {} kept non-trivial fragments",
        opts.m,
        count(plan.candidates),
        count(plan.candidates - plan.degenerate - plan.duplicates),
        count(plan.degenerate),
        count(plan.duplicates),
        count(plan.fragments)
    );
    let strata: Vec<String> = c
        .strata
        .iter()
        .map(|(family, sampled, all)| {
            let us = c.family_us.iter().find(|f| f.0 == *family);
            format!(
                "{family} {sampled} of {}{}",
                count(*all as u64),
                us.map_or(String::new(), |f| format!(" at {:.1} µs", f.1))
            )
        })
        .collect();
    println!(
        "plan: calibration: {} candidates ({}) × {} fragments = {} LP solves in {:.2} s on {} threads ({} unsettled) → {} LP solves/s per core",
        c.candidates,
        strata.join(", "),
        count(c.fragments as u64),
        count(c.lp_solves),
        c.seconds,
        c.threads,
        c.failures,
        count(c.rate().round() as u64)
    );
}

/// The cost table (LP solves, core-hours, wall time per row; the chosen row starred); returns
/// the expected seconds of one shard's race where a proxy race ran and the sweep races.
fn print_costs(plan: &Plan, opts: &SweepOptions, setup: f64) -> Option<f64> {
    let c = &plan.calibration;
    let threads = rayon::current_num_threads();
    let shards = opts.shard[1].max(1);
    println!(
        "plan: {:<28} {:>12} {:>11} {:>18}",
        "",
        "LP solves",
        "core-hours",
        format!("wall, {threads} threads")
    );
    // The chosen row is starred: racing's expected cost when a proxy race ran.
    let expected = plan.proxy.as_ref().filter(|_| !opts.exhaustive);
    let mut rows: Vec<(String, &[Schedule])> =
        vec![("racing (at most)".to_string(), plan.racing.as_slice())];
    rows.push(("exhaustive".to_string(), plan.exhaustive.as_slice()));
    // One shard's proxy race; the rows are totals over the shards, like the others.
    let expected_seconds = expected.map(|p| {
        let (_, by_family, other) = p.expected();
        c.seconds_for(by_family, other, threads)
    });
    if let (Some(p), Some(secs)) = (expected, expected_seconds) {
        let all = secs * shards as f64;
        println!(
            "plan: {:<28} {:>12} {:>11} {:>18}",
            "* racing (expected)",
            big(p.expected().0 * shards as u64),
            format!("{:.3}", all * threads as f64 / 3600.0),
            duration(setup + plan.references_seconds + all)
        );
    }
    for (name, per) in &rows {
        let total: u64 = per.iter().map(|s| s.lp_solves).sum();
        let hours = c.core_hours(total);
        let chosen = (name == "exhaustive") == opts.exhaustive && expected.is_none();
        println!(
            "plan: {:<28} {:>12} {:>11} {:>18}",
            format!("{}{name}", if chosen { "* " } else { "  " }),
            big(total),
            format!("{hours:.3}"),
            duration(setup + plan.references_seconds + hours * 3600.0 / threads as f64)
        );
    }
    expected_seconds
}

/// The proxy race and the expected cost drawn from it (`secs`: one shard's expected seconds).
fn print_proxy(p: &momentlab::search::plan::Proxy, opts: &SweepOptions, secs: f64) {
    let shards = opts.shard[1].max(1);
    let stages = |s: &mut dyn Iterator<Item = String>| s.collect::<Vec<_>>().join(", ");
    let families = |f: &[(&str, u64)]| {
        f.iter()
            .map(|(f, n)| format!("{f} {}", big(*n)))
            .collect::<Vec<_>>()
            .join(", ")
    };
    println!(
        "plan: proxy race{} on 1/{} of the fragments ({} fragments, {:.1} s, every half-width × 1/√{}): stages {}; {} tied; its LP solves × {} = {}",
        if shards > 1 {
            format!(" of shard {}/{shards} (the expected row: × {shards})", opts.shard[0])
        } else {
            String::new()
        },
        p.share,
        count(p.fragments),
        p.seconds,
        p.share,
        stages(&mut p.stages.iter().map(|(c, f)| format!("{} × {}", count(*c), count(*f)))),
        p.tied,
        p.share,
        count(p.lp_solves),
    );
    let (lps, cost_by_family, _) = p.expected();
    if let Some(r) = p.forecast.as_ref().and_then(|f| f.refinement.as_ref()) {
        println!(
            "plan: estimates refined on {} fresh fragments ({} LP solves, {:.1} s): the {} candidates nearest the proxy's winner pool their gaps and spreads there with the proxy's; {} drawn over the rest calibrate the others' gaps towards {:+.5} + {:.3}·gap and their spreads towards × {:.3} (each by its share of the fragments)",
            count(r.fragments as u64),
            count(r.lp_solves),
            r.seconds,
            r.closest,
            r.drawn,
            r.line.0,
            r.line.1,
            r.spread
        );
    }
    match &p.forecast {
        Some(f) => println!(
            "plan: expected from {} runs of the race simulated on the proxy's estimates (gaps to its winner, spreads, refined; the proxy's winner as the reference of a stage whose earlier blocks lie in its fragments): stages {}; {} LP solves (80 % of the runs between {} and {}; {}), {} at the calibrated µs per LP of each family, each candidate weighted by its cost relative to its family's in the proxy",
            f.runs,
            stages(&mut f.stages.iter().map(|c| count(c.round() as u64))),
            count(lps),
            big(f.range.0),
            big(f.range.1),
            families(&f.by_family),
            duration(secs)
        ),
        None => println!(
            "plan: expected from the proxy race: {} LP solves ({}), {} at the calibrated µs per LP of each family",
            count(lps),
            families(cost_by_family),
            duration(secs)
        ),
    }
}

/// The racing stages, the largest task and the Slurm line.
fn print_schedule(plan: &Plan, opts: &SweepOptions, setup: f64) {
    let c = &plan.calibration;
    let threads = rayon::current_num_threads();
    let shards = opts.shard[1].max(1);
    if let Some(s) = plan.racing.first().filter(|_| shards == 1) {
        let stages: Vec<String> = s
            .stages
            .iter()
            .map(|(c, f)| format!("{} × {}", count(*c), count(*f)))
            .collect();
        println!(
            "plan: racing stages (candidates × fragments): {}; then {} on all {} fragments",
            if stages.is_empty() {
                "none".to_string()
            } else {
                stages.join(", ")
            },
            s.full,
            count(plan.fragments)
        );
    }
    let per = if opts.exhaustive {
        &plan.exhaustive
    } else {
        &plan.racing
    };
    let largest = per.iter().map(|s| s.lp_solves).max().unwrap_or(0);
    let hours = c.core_hours(largest);
    if shards > 1 {
        println!(
            "plan: {shards} shards ({}): the largest task has {} LP solves = {:.3} core-hours (+ {:.0} s setup)",
            if opts.exhaustive { "exhaustive" } else { "racing, each shard on its own" },
            big(largest),
            hours,
            setup
        );
    }
    if plan.references_seconds > 0.0 {
        println!(
            "plan: wall times include the dataset ({}) and the references after the race ({}: the winner and {} LP references on every kept fragment, and the closed forms)",
            duration(setup),
            duration(plan.references_seconds),
            momentlab::search::reference::LP_REFERENCES
        );
    }
    let time = TIME_MARGIN * (setup + plan.references_seconds + hours * 3600.0 / threads as f64);
    println!(
        "plan: Slurm: --array=0-{} --cpus-per-task={threads} --time={} ({TIME_MARGIN}× the estimate at this machine's speed per core)",
        shards - 1,
        slurm_time(time)
    );
}

/// 1234567 → "1 234 567".
fn count(n: u64) -> String {
    let d = n.to_string();
    let mut out = String::new();
    for (i, ch) in d.chars().enumerate() {
        if i > 0 && (d.len() - i).is_multiple_of(3) {
            out.push(' ');
        }
        out.push(ch);
    }
    out
}

/// LP counts as "38.5 M", "1.01 G".
fn big(n: u64) -> String {
    let x = n as f64;
    match n {
        0..=99_999 => count(n),
        100_000..=999_999_999 => format!("{:.3} M", x / 1e6),
        _ => format!("{:.3} G", x / 1e9),
    }
}

fn duration(secs: f64) -> String {
    let s = secs.max(0.0).round() as u64;
    match s {
        0..=119 => format!("{s} s"),
        120..=7199 => format!("{} min {} s", s / 60, s % 60),
        _ => format!("{} h {} min", s / 3600, (s % 3600) / 60),
    }
}

/// Seconds as Slurm's D-HH:MM:SS, rounded up to whole minutes (at least one).
fn slurm_time(secs: f64) -> String {
    let m = ((secs / 60.0).ceil() as u64).max(1);
    let (d, h, mm) = (m / 1440, (m % 1440) / 60, m % 60);
    if d > 0 {
        format!("{d}-{h:02}:{mm:02}:00")
    } else {
        format!("{h:02}:{mm:02}:00")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn formats() {
        assert_eq!(big(38_500_000), "38.500 M");
        assert_eq!(big(1_010_000_000), "1.010 G");
        assert_eq!(big(4_096), "4 096");
        assert_eq!(slurm_time(1.0), "00:01:00");
        assert_eq!(slurm_time(3601.0), "01:01:00");
        assert_eq!(slurm_time(90_000.0), "1-01:00:00");
        assert_eq!(duration(3725.0), "62 min 5 s");
    }
}
