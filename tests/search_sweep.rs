//! The candidate sweep on a tiny synthetic dataset (reference LP, small grid): racing equals the
//! exhaustive ranking, interrupted runs resume to the same file, shards merge to the single run,
//! degenerate and duplicate-span candidates are flagged.

use momentlab::search::{
    merge_dirs, read_rows, run_sweep, Dataset, FunctionTable, Hooks, Outcome, Row, Scorer,
    SweepConfig,
};
use momentlab::Grid;
use std::f64::consts::PI;
use std::path::{Path, PathBuf};

/// 0 z, 1 z^2, 2 z^3, 3 sin(2πz), 4 cos(2πz), 5 exp(2z), 6 1−z (degenerate with z),
/// 7 2z^2+1 (same span as z^2).
fn table(grid: &Grid) -> FunctionTable {
    let names = [
        "z",
        "z^2",
        "z^3",
        "sin(2pi z)",
        "cos(2pi z)",
        "exp(2z)",
        "1-z",
        "2z^2+1",
    ];
    FunctionTable::new(
        grid,
        names.iter().map(|s| s.to_string()).collect(),
        |j, z| match j {
            0 => z,
            1 => z * z,
            2 => z * z * z,
            3 => (2.0 * PI * z).sin(),
            4 => (2.0 * PI * z).cos(),
            5 => (2.0 * z).exp(),
            6 => 1.0 - z,
            _ => 2.0 * z * z + 1.0,
        },
    )
    .unwrap()
}

struct Fixture {
    data: Dataset,
    table: FunctionTable,
}

fn fixture() -> Fixture {
    let grid = Grid::uniform(24).unwrap();
    Fixture {
        data: Dataset::synthetic(11, &grid, 3, 60, 3).unwrap(),
        table: table(&grid),
    }
}

fn config(s: &Scorer, m: usize) -> SweepConfig {
    let mut c = SweepConfig::new(m, s, "synthetic");
    c.top = 4;
    c.first_sample = 40;
    c.growth = 2;
    c.pilot = 4;
    c.batch = 3;
    // Exercise the z-test extension of the promotion rule (off by default: max_keep = keep).
    c.max_keep = 0.5;
    c
}

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("momentlab-search-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

/// Rows without the timing field, sorted by index.
fn rows(dir: &Path) -> Vec<Row> {
    let mut r = read_rows(dir).unwrap();
    r.iter_mut().for_each(|r| r.seconds = 0.0);
    r.sort_by_key(|r| r.index);
    r
}

fn file_without_seconds(dir: &Path, name: &str) -> String {
    let text = std::fs::read_to_string(dir.join(name)).unwrap();
    text.lines()
        .map(|l| {
            let mut v: serde_json::Value = serde_json::from_str(l).unwrap();
            v.as_object_mut().unwrap().remove("seconds");
            v.to_string() + "\n"
        })
        .collect()
}

fn run(cfg: &SweepConfig, s: &Scorer, dir: &Path) -> Outcome {
    run_sweep(cfg, s, dir, &Hooks::default()).unwrap()
}

#[test]
fn racing_top_k_equals_exhaustive_ranking() {
    racing_matches_exhaustive(Some(0.5), 2);
}

/// The default rule (max_keep = keep: plain quartering, no z-test extension).
#[test]
fn default_racing_top_k_equals_exhaustive_ranking() {
    racing_matches_exhaustive(None, 1);
}

/// `max_keep`: None = the default of `SweepConfig::new`.
fn racing_matches_exhaustive(max_keep: Option<f64>, min_stages: usize) {
    let f = fixture();
    let s = Scorer::new(&f.data, &f.table, "reference", 16).unwrap();
    assert!(
        f.data.fragments().len() > 60,
        "{}",
        f.data.fragments().len()
    );
    let mut cfg = config(&s, 2);
    match max_keep {
        Some(v) => cfg.max_keep = v,
        None => {
            cfg.max_keep = SweepConfig::new(2, &s, "synthetic").max_keep;
            assert_eq!(cfg.max_keep, cfg.keep, "default: plain quartering");
        }
    }
    let max_keep = cfg.max_keep;
    let race = tmp(&format!("race{max_keep}"));
    let Outcome::Complete(sum) = run(&cfg, &s, &race) else {
        panic!()
    };
    assert!(sum.stages.len() >= min_stages, "{sum:?}");
    assert!(sum.sampled_share < 1.0, "{sum:?}");
    let mut ex_cfg = cfg.clone();
    ex_cfg.exhaustive = true;
    let ex = tmp(&format!("exhaustive{max_keep}"));
    run(&ex_cfg, &s, &ex);

    let ex_rows = rows(&ex);
    let race_rows = rows(&race);
    assert_eq!(ex_rows.len(), 28);
    assert_eq!(race_rows.len(), 28);
    let mut ranked: Vec<&Row> = ex_rows.iter().filter(|r| r.error.is_some()).collect();
    ranked.sort_by(|a, b| a.error.unwrap().total_cmp(&b.error.unwrap()));
    let mut top: Vec<&Row> = race_rows.iter().filter(|r| r.full).collect();
    top.sort_by(|a, b| a.error.unwrap().total_cmp(&b.error.unwrap()));
    assert_eq!(top.len(), 4);
    for (r, e) in top.iter().zip(&ranked) {
        assert_eq!(
            r.index, e.index,
            "racing top K differs from exhaustive ranking"
        );
        assert_eq!(r.error, e.error);
        assert_eq!(r.fragments, f.data.fragments().len() as u64);
    }
    // Eliminated candidates carry an estimate with standard error and sample size, and are
    // (in this easy case) no better than the K-th best.
    for r in race_rows.iter().filter(|r| !r.full && r.error.is_some()) {
        assert!(r.fragments > 0 && r.fragments < f.data.fragments().len() as u64);
        assert!(r.stderr.unwrap() > 0.0);
        let exact = ex_rows.iter().find(|e| e.index == r.index).unwrap();
        assert!(exact.error.unwrap() >= top[3].error.unwrap());
    }
    // The exhaustive error equals an independent computation from per-fragment errors.
    let e0 = &ranked[0];
    let cols: Vec<usize> = e0
        .functions
        .iter()
        .map(|n| f.table.names().iter().position(|x| x == n).unwrap())
        .collect();
    let ids: Vec<u32> = (0..f.data.fragments().len() as u32).collect();
    let errs = s.errors_seq(&cols, &ids).unwrap();
    let direct =
        (f.data.trivial_error() + errs.errors.iter().sum::<f64>()) / f.data.total_count() as f64;
    assert!((direct - e0.error.unwrap()).abs() < 1e-12);
    for d in [race, ex] {
        std::fs::remove_dir_all(d).unwrap();
    }
}

#[test]
fn degenerate_and_duplicate_candidates_are_flagged() {
    let f = fixture();
    let s = Scorer::new(&f.data, &f.table, "reference", 64).unwrap();
    let mut cfg = config(&s, 2);
    cfg.exhaustive = true;
    // {z,1-z} degenerate, {z^2, 2z^2+1} degenerate, {z, 2z^2+1} duplicate of {z, z^2},
    // {1-z, z^3} duplicate of {z, z^3}, {z, z^2}, {z, z^3} scored.
    let idx = |a: usize, b: usize| momentlab::basis::candidates::subset_to_index(&[a, b]).unwrap();
    cfg.candidates = Some(vec![
        idx(0, 6),
        idx(1, 7),
        idx(0, 7),
        idx(2, 6),
        idx(0, 1),
        idx(0, 2),
    ]);
    let dir = tmp("flags");
    run(&cfg, &s, &dir);
    let r = rows(&dir);
    let get = |a, b| r.iter().find(|x| x.index == idx(a, b)).unwrap();
    assert!(get(0, 6).degenerate && get(0, 6).error.is_none());
    assert!(get(1, 7).degenerate);
    assert_eq!(get(0, 7).duplicate_of, Some(idx(0, 1)));
    assert_eq!(get(2, 6).duplicate_of, Some(idx(0, 2)));
    assert!(get(0, 7).error.is_none() && get(0, 7).fragments == 0);
    assert!(get(0, 1).error.is_some() && get(0, 1).full);
    assert!(get(0, 2).error.is_some());
    // Duplicates really score the same (checked by solving them anyway).
    let ids: Vec<u32> = (0..f.data.fragments().len() as u32).collect();
    let a = s.errors_seq(&[0, 7], &ids).unwrap();
    let b = s.errors_seq(&[0, 1], &ids).unwrap();
    let (sa, sb): (f64, f64) = (a.errors.iter().sum(), b.errors.iter().sum());
    assert!((sa - sb).abs() < 1e-6 * ids.len() as f64, "{sa} {sb}");
    // A duplicate whose representative is not in the run is scored itself.
    cfg.candidates = Some(vec![idx(0, 7)]);
    let dir2 = tmp("flags2");
    run(&cfg, &s, &dir2);
    assert!(rows(&dir2)[0].error.is_some());
    for d in [dir, dir2] {
        std::fs::remove_dir_all(d).unwrap();
    }
}

#[test]
fn interrupted_runs_resume_to_the_same_file() {
    let f = fixture();
    let s = Scorer::new(&f.data, &f.table, "reference", 16).unwrap();
    let cfg = config(&s, 2);
    let full = tmp("uninterrupted");
    run(&cfg, &s, &full);
    let want = file_without_seconds(&full, "results.jsonl");
    let want_stage0 = file_without_seconds(&full, "stage0.jsonl");
    // Kill after k batches, once or repeatedly, then resume.
    for k in [1usize, 2, 4, 7, 11] {
        let dir = tmp(&format!("resume{k}"));
        let mut stops = 0;
        loop {
            let hooks = Hooks {
                stop_after_batches: Some(k),
                progress: None,
            };
            match run_sweep(&cfg, &s, &dir, &hooks).unwrap() {
                Outcome::Stopped => stops += 1,
                Outcome::Complete(_) => break,
            }
            assert!(stops < 100);
        }
        assert!(stops >= 1);
        assert_eq!(file_without_seconds(&dir, "results.jsonl"), want, "k = {k}");
        assert_eq!(
            file_without_seconds(&dir, "stage0.jsonl"),
            want_stage0,
            "k = {k}"
        );
        std::fs::remove_dir_all(dir).unwrap();
    }
    // Torn writes: stop, cut the results and stage files mid-line, resume.
    for (k, cut) in [(3usize, 5usize), (6, 17), (9, 1)] {
        let dir = tmp(&format!("torn{k}"));
        let hooks = Hooks {
            stop_after_batches: Some(k),
            progress: None,
        };
        assert_eq!(run_sweep(&cfg, &s, &dir, &hooks).unwrap(), Outcome::Stopped);
        for name in ["results.jsonl", "stage0.jsonl", "stage1.jsonl"] {
            let p = dir.join(name);
            if let Ok(mut bytes) = std::fs::read(&p) {
                if bytes.len() > cut {
                    bytes.truncate(bytes.len() - cut);
                    std::fs::write(&p, bytes).unwrap();
                }
            }
        }
        run(&cfg, &s, &dir);
        assert_eq!(
            file_without_seconds(&dir, "results.jsonl"),
            want,
            "torn {k}"
        );
        std::fs::remove_dir_all(dir).unwrap();
    }
    // Resuming with a different configuration is refused.
    let mut other = cfg.clone();
    other.seed = 99;
    let e = run_sweep(&other, &s, &full, &Hooks::default()).unwrap_err();
    assert!(e.to_string().contains("'seed'"), "{e}");
    std::fs::remove_dir_all(full).unwrap();
}

#[test]
fn shards_merge_to_the_single_run() {
    let f = fixture();
    let s = Scorer::new(&f.data, &f.table, "reference", 16).unwrap();
    for exhaustive in [true, false] {
        let mut cfg = config(&s, 2);
        cfg.exhaustive = exhaustive;
        let single = tmp(&format!("single{exhaustive}"));
        run(&cfg, &s, &single);
        let mut dirs = Vec::new();
        for i in 0..3 {
            let mut c = cfg.clone();
            c.shard = [i, 3];
            let d = tmp(&format!("shard{exhaustive}{i}"));
            run(&c, &s, &d);
            dirs.push(d);
        }
        let merged = tmp(&format!("merged{exhaustive}"));
        // Missing shard is an error.
        let e = merge_dirs(&dirs[..2], &merged, false).unwrap_err();
        assert!(e.to_string().contains("shard 2/3 is missing"), "{e}");
        assert_eq!(merge_dirs(&dirs, &merged, false).unwrap(), 28);
        let (a, b) = (rows(&single), rows(&merged));
        if exhaustive {
            assert_eq!(a, b);
        } else {
            // Racing: the global top K is scored identically in both.
            let top = |rs: &[Row]| {
                let mut t: Vec<Row> = rs.iter().filter(|r| r.full).cloned().collect();
                t.sort_by(|x, y| x.error.unwrap().total_cmp(&y.error.unwrap()));
                t.truncate(cfg.top);
                t.into_iter()
                    .map(|mut r| {
                        r.stage = 0;
                        r
                    })
                    .collect::<Vec<_>>()
            };
            assert_eq!(top(&a), top(&b));
            assert_eq!(
                a.iter().map(|r| r.index).collect::<Vec<_>>(),
                b.iter().map(|r| r.index).collect::<Vec<_>>()
            );
        }
        // Merging twice into the same place, or mismatched configs, is refused.
        assert!(merge_dirs(&dirs, &merged, false).is_err());
        for d in dirs.into_iter().chain([single, merged]) {
            std::fs::remove_dir_all(d).unwrap();
        }
    }
}
