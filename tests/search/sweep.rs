//! The candidate sweep on a tiny synthetic dataset (reference LP, small grid): racing equals the
//! exhaustive ranking, interrupted runs resume to the same file, shards merge to the single run,
//! degenerate and duplicate-span candidates are flagged.

use crate::common::search::{table, WITH_DEGENERATE};
use crate::common::tmp_path;
use momentlab::search::race::Elimination;
use momentlab::search::{
    merge_dirs, read_rows, run_sweep, Dataset, FunctionTable, Hooks, Outcome, Row, Scorer,
    SweepConfig, SweepSummary,
};
use momentlab::Grid;
use std::path::Path;

struct Fixture {
    data: Dataset,
    table: FunctionTable,
}

fn fixture() -> Fixture {
    let grid = Grid::uniform(24).unwrap();
    Fixture {
        data: Dataset::synthetic(11, &grid, 3, 60, 3).unwrap(),
        table: table(&grid, &WITH_DEGENERATE),
    }
}

fn config(s: &Scorer, m: usize) -> SweepConfig {
    let mut c = SweepConfig::new(m, s, "synthetic");
    c.first_sample = 40;
    c.growth = 2;
    // Every block after stage 0 is tested first on its prefixes of 1/8, 1/4 and 1/2 that hold
    // ≥ 20 fragments (the early looks), then whole; stage 0's block is the common sample, one
    // look.
    c.early_look = 20;
    c.pilot = 4;
    c.batch = 3;
    c
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

/// The default rule (99 % confidence, elimination by evidence only) against the exhaustive run.
#[test]
fn racing_finds_the_exhaustive_winner() {
    racing_matches_exhaustive(2);
}

fn racing_matches_exhaustive(min_stages: usize) {
    let f = fixture();
    let s = Scorer::new(&f.data, &f.table, "reference", 16).unwrap();
    assert!(
        f.data.fragments().len() > 60,
        "{}",
        f.data.fragments().len()
    );
    let cfg = config(&s, 2);
    let race = tmp_path("race");
    let Outcome::Complete(sum) = run(&cfg, &s, &race) else {
        panic!()
    };
    assert!(sum.stages.len() >= min_stages, "{sum:?}");
    // Stage 0's block (40 fragments, the common sample) was looked at once, stage 1's block
    // (80) twice: the second half's statistics exist.
    assert!(!race.join("stage0.look1.jsonl").exists());
    assert!(race.join("stage1.look1.jsonl").exists());
    let (_, plan) = momentlab::search::race::blocks(f.data.fragments().len(), 40, 2);
    let planned: usize = plan
        .iter()
        .enumerate()
        .map(|(k, r)| momentlab::search::race::looks(k, r.len(), 20).len())
        .sum();
    assert!(planned > plan.len());
    assert_eq!(sum.race.as_ref().unwrap().looks, planned as u64);
    assert!(sum.sampled_share < 1.0, "{sum:?}");
    let race_sum = sum.race.clone().unwrap();
    check_stage_logs(&sum);
    let mut ex_cfg = cfg.clone();
    ex_cfg.exhaustive = true;
    let ex = tmp_path("exhaustive");
    run(&ex_cfg, &s, &ex);

    let ex_rows = rows(&ex);
    let race_rows = rows(&race);
    assert_eq!(ex_rows.len(), 28);
    assert_eq!(race_rows.len(), 28);
    let exact = |i: u64| {
        ex_rows
            .iter()
            .find(|e| e.index == i)
            .unwrap()
            .error
            .unwrap()
    };
    let mut ranked: Vec<&Row> = ex_rows.iter().filter(|r| r.error.is_some()).collect();
    ranked.sort_by(|a, b| a.error.unwrap().total_cmp(&b.error.unwrap()));
    // The survivors (tied for first) are scored on every fragment: their errors are the
    // exhaustive ones (pooled over the blocks in another order: equal to rounding).
    let tied: Vec<&Row> = race_rows.iter().filter(|r| r.tied).collect();
    assert_eq!(tied.len() as u64, race_sum.tied);
    assert!(!tied.is_empty());
    for r in &tied {
        assert!(r.full && r.fragments == f.data.fragments().len() as u64);
        assert!((r.error.unwrap() - exact(r.index)).abs() < 1e-12);
        assert_eq!(r.versus, race_sum.winner);
        // The paired difference to the winner is the difference of the exhaustive errors.
        let w = exact(race_sum.winner.unwrap());
        assert!((r.diff.unwrap() - (exact(r.index) - w)).abs() < 1e-12);
    }
    // The exhaustive winner is tied for first, and it is the race's winner here.
    assert!(tied.iter().any(|r| r.index == ranked[0].index));
    assert_eq!(race_sum.winner, Some(ranked[0].index));
    // Every eliminated candidate left by evidence: it is worse than its stage reference on the
    // whole sample (no false elimination in this easy case), and carries its evidence: the
    // stage and look, the paired difference, its s.e. and the lower bound (> 0, below Δ).
    let mut conf = 0;
    for r in race_rows.iter().filter(|r| r.eliminated.is_some()) {
        assert!(r.fragments > 0 && r.fragments < f.data.fragments().len() as u64);
        assert_eq!(r.eliminated, Some(Elimination::Confidence));
        conf += 1;
        let (d, se, lo) = (r.diff.unwrap(), r.diff_se.unwrap(), r.diff_lower.unwrap());
        assert!(r.stderr.unwrap() > 0.0 && se > 0.0, "{r:?}");
        assert!(lo > 0.0 && lo < d, "{r:?}");
        let look = r.look.unwrap();
        assert!(
            look <= momentlab::search::race::EARLY_LOOKS && (r.stage > 0 || look == 0),
            "{r:?}"
        );
        assert!(r.stage < race_sum.stages.len(), "{r:?}");
        assert!(exact(r.index) > exact(r.versus.unwrap()), "{r:?}");
    }
    assert_eq!(conf, race_sum.confidence_eliminated);
    assert!(conf > 0);
    // Every candidate of the race carries its estimate on the common sample (stage 0's 40
    // fragments); a candidate eliminated in stage 0 saw only them.
    for r in race_rows
        .iter()
        .filter(|r| !r.degenerate && r.duplicate_of.is_none())
    {
        assert_eq!(r.common_fragments, 40, "{r:?}");
        assert!(r.common_error.is_some() && r.common_stderr.unwrap() > 0.0);
        if r.stage == 0 && r.eliminated.is_some() {
            assert!((r.common_error.unwrap() - r.error.unwrap()).abs() < 1e-12);
        }
    }
    assert_eq!(race_sum.common_fragments, 40);
    assert!(!race_sum.lp_budget_bound && race_sum.unresolved == 0);
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

/// An LP budget ends the race before the look that would exceed it and eliminates no one: the
/// eliminations before it are the unbudgeted race's, the survivors are unresolved (neither
/// eliminated nor completed) and the best is among them.
#[test]
fn an_lp_budget_leaves_survivors_unresolved() {
    let f = fixture();
    let s = Scorer::new(&f.data, &f.table, "reference", 16).unwrap();
    let cfg = config(&s, 2);
    let free = tmp_path("budget-free");
    let Outcome::Complete(all) = run(&cfg, &s, &free) else {
        panic!()
    };
    let stage0 = all.race.as_ref().unwrap().stages[0].clone();
    assert!(stage0.candidates - stage0.confidence_eliminated > 1);
    // Pilot and stage 0 fit, stage 1's first look does not.
    let mut capped = cfg.clone();
    capped.lp_budget = cfg.pilot as u64 * 40 + (stage0.candidates + 1) * 40 + 10;
    let dir = tmp_path("budget");
    let Outcome::Complete(sum) = run(&capped, &s, &dir) else {
        panic!()
    };
    let race = sum.race.as_ref().unwrap();
    assert!(race.lp_budget_bound && !race.resolved && !race.budget_bound);
    assert!(sum.lp_solves <= capped.lp_budget, "{sum:?}");
    assert_eq!(race.stages.len(), 1);
    assert_eq!(race.tied, 0);
    let left = stage0.candidates - stage0.confidence_eliminated;
    assert_eq!(race.unresolved, left);
    let (free_rows, rows) = (rows(&free), rows(&dir));
    assert_eq!(rows.len(), free_rows.len());
    for (a, b) in rows.iter().zip(&free_rows) {
        if b.eliminated.is_some() && b.stage == 0 {
            // The same eliminations with the same evidence.
            assert_eq!((a.eliminated, a.diff_lower), (b.eliminated, b.diff_lower));
        } else if !a.degenerate && a.duplicate_of.is_none() {
            assert!(a.unresolved && !a.tied && a.eliminated.is_none(), "{a:?}");
            assert_eq!(a.fragments, 40, "not completed: {a:?}");
        }
    }
    let unresolved = rows.iter().filter(|r| r.unresolved).count() as u64;
    assert_eq!(unresolved, left);
    // The unbudgeted winner is among the unresolved.
    let w = all.race.as_ref().unwrap().winner.unwrap();
    assert!(rows.iter().any(|r| r.index == w && r.unresolved));
    for d in [free, dir] {
        std::fs::remove_dir_all(d).unwrap();
    }
}

/// Each stage's log adds up: its survivors (the next stage's candidates, or the fully scored
/// ones after the last stage) are its candidates less its eliminations by evidence, the only
/// kind there is.
fn check_stage_logs(sum: &SweepSummary) {
    let race = sum.race.as_ref().unwrap();
    for (k, st) in race.stages.iter().enumerate() {
        let survivors = race
            .stages
            .get(k + 1)
            .map_or(sum.full, |next| next.candidates);
        assert_eq!(
            survivors,
            st.candidates - st.confidence_eliminated,
            "{st:?}"
        );
        assert!(st.early_eliminated <= st.confidence_eliminated, "{st:?}");
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
    let dir = tmp_path("flags");
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
    let dir2 = tmp_path("flags2");
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
    let full = tmp_path("uninterrupted");
    run(&cfg, &s, &full);
    let want = file_without_seconds(&full, "results.jsonl");
    let want_stage0 = file_without_seconds(&full, "stage0.jsonl");
    let want_look = file_without_seconds(&full, "stage1.look1.jsonl");
    // Kill after k batches, once or repeatedly, then resume.
    for k in [1usize, 2, 4, 7, 11] {
        let dir = tmp_path(&format!("resume{k}"));
        let mut stops = 0;
        loop {
            let hooks = Hooks {
                stop_after_batches: Some(k),
                progress: None,
                half_width: None,
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
        assert_eq!(
            file_without_seconds(&dir, "stage1.look1.jsonl"),
            want_look,
            "k = {k}"
        );
        std::fs::remove_dir_all(dir).unwrap();
    }
    // Torn writes: stop, cut the results and stage files mid-line, resume.
    for (k, cut) in [(3usize, 5usize), (6, 17), (9, 1)] {
        let dir = tmp_path(&format!("torn{k}"));
        let hooks = Hooks {
            stop_after_batches: Some(k),
            progress: None,
            half_width: None,
        };
        assert_eq!(run_sweep(&cfg, &s, &dir, &hooks).unwrap(), Outcome::Stopped);
        for name in [
            "results.jsonl",
            "stage0.jsonl",
            "stage1.look1.jsonl",
            "stage1.jsonl",
        ] {
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
        let single = tmp_path(&format!("single{exhaustive}"));
        run(&cfg, &s, &single);
        let mut dirs = Vec::new();
        for i in 0..3 {
            let mut c = cfg.clone();
            c.shard = [i, 3];
            let d = tmp_path(&format!("shard{exhaustive}{i}"));
            run(&c, &s, &d);
            dirs.push(d);
        }
        let merged = tmp_path(&format!("merged{exhaustive}"));
        // Missing shard is an error.
        let e = merge_dirs(&dirs[..2], &merged, false, false).unwrap_err();
        assert!(format!("{e:#}").contains("shard 2/3 is missing"), "{e:#}");
        let m = merge_dirs(&dirs, &merged, false, false).unwrap();
        assert_eq!((m.rows, m.partial), (28, None));
        assert!(merged.join("complete.json").exists() && !merged.join("partial.json").exists());
        let (a, b) = (rows(&single), rows(&merged));
        if exhaustive {
            assert_eq!(a, b);
        } else {
            // Racing: every shard completes its survivors on every fragment, so the global
            // winner (the best tied row) is the same with the same error in both.
            let winner = |rs: &[Row]| {
                let mut t: Vec<Row> = rs.iter().filter(|r| r.tied).cloned().collect();
                t.sort_by(|x, y| x.error.unwrap().total_cmp(&y.error.unwrap()));
                (t[0].index, t[0].error.unwrap())
            };
            let (wa, wb) = (winner(&a), winner(&b));
            assert_eq!(wa.0, wb.0);
            assert!((wa.1 - wb.1).abs() < 1e-12);
            assert_eq!(
                a.iter().map(|r| r.index).collect::<Vec<_>>(),
                b.iter().map(|r| r.index).collect::<Vec<_>>()
            );
        }
        // Merging twice into the same place, or mismatched configs, is refused.
        assert!(merge_dirs(&dirs, &merged, false, false).is_err());
        for d in dirs.into_iter().chain([single, merged]) {
            std::fs::remove_dir_all(d).unwrap();
        }
    }
}

/// `merge --allow-partial` with a shard missing, or a shard unfinished, writes no completion
/// marker: `partial.json` names the missing shards and candidates, and so do the merge's JSON
/// output, its line and the sweep report.
#[test]
fn partial_merge_is_never_labelled_complete() {
    use crate::common::run as cli;
    use momentlab::search::merge::Partial;
    let f = fixture();
    let s = Scorer::new(&f.data, &f.table, "reference", 16).unwrap();
    let mut cfg = config(&s, 2);
    cfg.exhaustive = true;
    let mut dirs = Vec::new();
    for i in 0..3 {
        let mut c = cfg.clone();
        c.shard = [i, 3];
        let d = tmp_path(&format!("partial-shard{i}"));
        run(&c, &s, &d);
        dirs.push(d);
    }
    let all: Vec<u64> = dirs.iter().flat_map(|d| rows(d)).map(|r| r.index).collect();
    assert_eq!(all.len(), 28);
    let of_shard = |i: u64| -> Vec<u64> {
        let mut v: Vec<u64> = all.iter().copied().filter(|c| c % 3 == i).collect();
        v.sort();
        v
    };
    let s = |d: &Path| d.to_str().unwrap().to_string();
    // Shard 2 missing: the rows of shards 0 and 1, no completion marker.
    let out = tmp_path("partial-merged");
    let (code, stdout, stderr) = cli(
        &[
            "merge",
            &s(&dirs[0]),
            &s(&dirs[1]),
            "--allow-partial",
            "--json",
            "--out",
            &s(&out),
        ],
        None,
    );
    assert_eq!(code, 0, "{stderr}");
    assert!(
        !out.join("complete.json").exists(),
        "a partial merge marked complete"
    );
    let p: Partial =
        serde_json::from_slice(&std::fs::read(out.join("partial.json")).unwrap()).unwrap();
    assert!(p.partial);
    assert_eq!(p.missing_shards, vec![2]);
    assert!(p.incomplete_shards.is_empty());
    assert_eq!(p.candidates, 28);
    assert_eq!(p.missing_candidate_list, of_shard(2));
    assert_eq!(p.missing_candidates, of_shard(2).len() as u64);
    let v: serde_json::Value = serde_json::from_str(&stdout).unwrap();
    assert_eq!(v["partial"], true);
    assert_eq!(v["complete"], false);
    assert_eq!(v["missing_shards"], serde_json::json!([2]));
    assert_eq!(v["missing_candidate_list"], serde_json::json!(of_shard(2)));
    assert_eq!(v["rows"], 28 - of_shard(2).len());
    // The line form says partial and names shard 2/3.
    let out2 = tmp_path("partial-merged-line");
    let (code, _, stderr) = cli(
        &[
            "merge",
            &s(&dirs[0]),
            &s(&dirs[1]),
            "--allow-partial",
            "--out",
            &s(&out2),
        ],
        None,
    );
    assert_eq!(code, 0, "{stderr}");
    assert!(
        stderr.contains("partial: shards 2/3 missing") && stderr.contains("no complete.json"),
        "{stderr}"
    );
    // All shards given, one unfinished (killed: no marker, rows cut): still partial.
    std::fs::remove_file(dirs[1].join("complete.json")).unwrap();
    let text = std::fs::read_to_string(dirs[1].join("results.jsonl")).unwrap();
    let kept: Vec<&str> = text.lines().take(3).collect();
    std::fs::write(dirs[1].join("results.jsonl"), kept.join("\n") + "\n").unwrap();
    let lost: Vec<u64> = of_shard(1)
        .into_iter()
        .filter(|i| !kept.iter().any(|l| l.contains(&format!("\"index\":{i},"))))
        .collect();
    assert_eq!(lost.len(), of_shard(1).len() - 3);
    let out3 = tmp_path("partial-merged-unfinished");
    let e = merge_dirs(&dirs, &out3, false, false).unwrap_err();
    assert!(format!("{e:#}").contains("not complete"), "{e:#}");
    let m = merge_dirs(&dirs, &out3, true, false).unwrap();
    let p = m.partial.expect("an unfinished shard merged as complete");
    assert!(!out3.join("complete.json").exists());
    assert!(p.missing_shards.is_empty());
    assert_eq!(p.incomplete_shards, vec![1]);
    assert_eq!(p.missing_candidate_list, lost);
    // The sweep report of the partial merge says so and names what is missing.
    let od = momentlab::artefact::OutDir::new(tmp_path("partial-report"), false).unwrap();
    let opts = momentlab::report::sweep::ReportOptions {
        partial: Some(p.clone()),
        fig3_points: 8,
        solver: "reference".into(),
        ..Default::default()
    };
    momentlab::report::sweep::write(&od, &read_rows(&out3).unwrap(), &f.data, &[], &opts).unwrap();
    let md = std::fs::read_to_string(od.root().join("search_m2.md")).unwrap();
    assert!(
        md.contains("**Partial results**") && md.contains("shards 1/3 unfinished"),
        "{md}"
    );
    assert!(md.contains(&format!("{} of 28 candidates missing", lost.len())));
    for d in dirs
        .into_iter()
        .chain([out, out2, out3, od.root().to_path_buf()])
    {
        std::fs::remove_dir_all(d).unwrap();
    }
}
