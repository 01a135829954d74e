//! The sharded sweep on a real Slurm cluster (scripts/slurm/, README "Running on a cluster"):
//! an exhaustive m = 2 sweep on small rendered stacks as a 4-task job array plus the dependent
//! merge job equals the unsharded run exactly; an array task cancelled mid-run (`scancel`) and
//! resubmitted (`resubmit.sh`) resumes with no lost or duplicated rows; a task that fails on a
//! bad argument makes the merge job refuse with a one-line reason.
//!
//! Needs `sbatch` and a running cluster (`scripts/slurm/local-cluster.sh up`). Without them the
//! test says so loudly and passes, except with MOMENTLAB_REQUIRE_SLURM=1 (set by .ci/run after
//! it brought the cluster up), where a missing cluster is a failure.

use crate::common::{bin, momentlab, tmp};
use momentlab::search::{read_rows, Row};
use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::time::{Duration, Instant};

const SHARDS: usize = 4;
/// C(37, 2) candidates of the embedded catalog.
const CANDIDATES: usize = 666;
const TIMEOUT: Duration = Duration::from_secs(600);

fn scripts() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scripts/slurm")
}

fn run(cmd: &mut Command) -> Output {
    let out = cmd
        .output()
        .unwrap_or_else(|e| panic!("cannot run {cmd:?}: {e}"));
    assert!(
        out.status.success(),
        "{cmd:?} failed ({}):\n{}{}",
        out.status,
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    out
}

fn stdout(cmd: &mut Command) -> String {
    String::from_utf8_lossy(&run(cmd).stdout).into_owned()
}

/// Why the cluster cannot be used, if it cannot.
fn cluster_missing() -> Option<String> {
    match Command::new("sbatch").arg("--version").output() {
        Ok(o) if o.status.success() => {}
        _ => return Some("sbatch is not installed".into()),
    }
    match Command::new("sinfo").args(["-h", "-o", "%T"]).output() {
        Ok(o) if o.status.success() => {
            let s = String::from_utf8_lossy(&o.stdout);
            if s.lines()
                .any(|l| ["idle", "mixed", "allocated"].contains(&l.trim()))
            {
                None
            } else {
                Some(format!("no node takes jobs (sinfo: {})", s.trim()))
            }
        }
        _ => Some("the cluster does not answer (sinfo failed)".into()),
    }
}

/// The job ids of everything submitted, cancelled when the test ends (pass or fail).
struct Jobs(Vec<String>);

impl Drop for Jobs {
    fn drop(&mut self) {
        if !self.0.is_empty() {
            let _ = Command::new("scancel").args(&self.0).output();
        }
    }
}

/// `JobState` of a job (or of one array task, "123_4"); None when Slurm forgot it.
fn state(job: &str) -> Option<String> {
    let o = Command::new("scontrol")
        .args(["show", "job", "-o", job])
        .output()
        .ok()?;
    let text = String::from_utf8_lossy(&o.stdout);
    let line = text.lines().next()?;
    line.split_whitespace()
        .find_map(|f| f.strip_prefix("JobState="))
        .map(str::to_string)
}

/// Wait until no task of `job` is pending or running any more.
fn wait_done(job: &str) {
    let t0 = Instant::now();
    loop {
        let q = stdout(Command::new("squeue").args(["-h", "-j", job, "-o", "%i %T"]));
        if q.trim().is_empty() {
            return;
        }
        assert!(t0.elapsed() < TIMEOUT, "job {job} still queued: {q}");
        std::thread::sleep(Duration::from_millis(200));
    }
}

/// The last line of submit.sh / resubmit.sh: "<array job> <merge job>".
fn job_ids(out: &str) -> (String, String) {
    let last = out.lines().last().unwrap_or_default();
    let v: Vec<&str> = last.split_whitespace().collect();
    assert_eq!(v.len(), 2, "unexpected output: {out}");
    (v[0].to_string(), v[1].to_string())
}

/// Rows without the timing field, sorted by index.
fn rows(dir: &Path) -> Vec<Row> {
    let mut r = read_rows(dir).unwrap();
    r.iter_mut().for_each(|r| r.seconds = 0.0);
    r.sort_by_key(|r| r.index);
    r
}

fn read(p: &Path) -> String {
    std::fs::read_to_string(p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

fn logs(run: &Path) -> String {
    let mut out = String::new();
    if let Ok(d) = std::fs::read_dir(run.join("logs")) {
        let mut files: Vec<PathBuf> = d.map(|e| e.unwrap().path()).collect();
        files.sort();
        for f in files {
            out += &format!("--- {}\n{}", f.display(), read(&f));
        }
    }
    out
}

#[test]
fn sharded_sweep_on_slurm_merges_resumes_and_refuses_failures() {
    if let Some(why) = cluster_missing() {
        let msg = format!(
            "SLURM END-TO-END TEST NOT RUN: {why}. Start a local cluster with \
             `scripts/slurm/local-cluster.sh up` (root, Debian)."
        );
        if std::env::var("MOMENTLAB_REQUIRE_SLURM").as_deref() == Ok("1") {
            panic!("{msg} MOMENTLAB_REQUIRE_SLURM=1: a missing cluster is a failure.");
        }
        eprintln!("\n{0}\n{msg}\n{0}\n", "!".repeat(78));
        return;
    }
    let root = tmp("slurm-e2e");
    let mut jobs = Jobs(Vec::new());

    // Small rendered stacks (64², 49 465 fragments) and a 1 032-fragment stratified sample.
    let stacks = root.join("stacks");
    run(momentlab()
        .args(["render", "--resolution", "64", "--out"])
        .arg(&stacks));
    let stacks = stacks.to_str().unwrap().to_string();
    let args = [
        "--m",
        "2",
        "--stacks",
        &stacks,
        "--exhaustive",
        "--max-fragments",
        "1024",
        "--batch",
        "4",
        "--no-report",
    ];

    // The unsharded run, outside Slurm.
    let single = root.join("single");
    run(momentlab()
        .arg("search")
        .args(args)
        .arg("--results")
        .arg(&single));
    let single_rows = rows(&single);
    assert_eq!(single_rows.len(), CANDIDATES);

    // The job array and its merge job.
    let runs = root.join("run");
    let out = stdout(
        Command::new(scripts().join("submit.sh"))
            .arg(&runs)
            .arg(SHARDS.to_string())
            .arg("--cpus-per-task=1")
            .arg("--")
            .args(args)
            .env("MOMENTLAB", bin()),
    );
    let (array, merge) = job_ids(&out);
    jobs.0.extend([array.clone(), merge.clone()]);

    // Cancel task 1 once it has written some rows, before it finishes.
    let shard1 = runs.join("shard-1");
    let t0 = Instant::now();
    let before = loop {
        let n = read_rows(&shard1).map(|r| r.len()).unwrap_or(0);
        if n > 0 {
            stdout(Command::new("scancel").arg(format!("{array}_1")));
            break rows(&shard1);
        }
        assert!(
            t0.elapsed() < TIMEOUT,
            "task 1 wrote no rows:\n{}",
            logs(&runs)
        );
        std::thread::sleep(Duration::from_millis(10));
    };
    wait_done(&array);
    assert!(
        !shard1.join("complete.json").exists(),
        "task 1 finished before it could be cancelled (rows at cancel: {}); the test needs a \
         slower shard",
        before.len()
    );
    let partial = rows(&shard1);
    assert!(
        partial.len() >= before.len() && partial.len() < CANDIDATES / SHARDS,
        "{}",
        partial.len()
    );
    let failed = read(&shard1.join("FAILED"));
    assert!(failed.contains("terminated by SIGTERM"), "{failed}");
    for i in [0, 2, 3] {
        assert!(runs.join(format!("shard-{i}/complete.json")).exists());
    }
    // afterok + kill-on-invalid-dep: the merge job never ran.
    wait_done(&merge);
    assert!(!runs.join("merged").exists());
    assert!(
        matches!(state(&merge).as_deref(), None | Some("CANCELLED")),
        "{:?}",
        state(&merge)
    );
    // `momentlab merge` by hand refuses too, naming the cancelled task.
    let dirs: Vec<PathBuf> = (0..SHARDS)
        .map(|i| runs.join(format!("shard-{i}")))
        .collect();
    let o = momentlab()
        .arg("merge")
        .args(&dirs)
        .arg("--out")
        .arg(root.join("merged-by-hand"))
        .output()
        .unwrap();
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && e.contains("shard-1 failed"), "{e}");

    // Resubmit: only task 1 runs again, resumes, and the new merge job completes.
    let out = stdout(
        Command::new(scripts().join("resubmit.sh"))
            .arg(&runs)
            .env("MOMENTLAB", bin()),
    );
    assert!(out.contains("resubmitted: tasks 1 as"), "{out}");
    let (array2, merge2) = job_ids(&out);
    jobs.0.extend([array2.clone(), merge2.clone()]);
    wait_done(&array2);
    wait_done(&merge2);
    assert_eq!(
        state(&merge2).as_deref(),
        Some("COMPLETED"),
        "{}",
        logs(&runs)
    );
    assert!(!shard1.join("FAILED").exists());
    let resumed = rows(&shard1);
    assert_eq!(
        &resumed[..before.len()],
        &before[..],
        "rows written before the cancel changed"
    );
    let merged = rows(&runs.join("merged"));
    assert_eq!(merged.len(), CANDIDATES, "lost or duplicated rows");
    assert!(
        merged == single_rows,
        "merged shards differ from the unsharded run"
    );
    // The tasks ran rayon on their --cpus-per-task.
    let log = logs(&runs);
    assert!(
        log.contains("momentlab: 1 thread (SLURM_CPUS_PER_TASK)"),
        "{log}"
    );
    // Progress in batch logs: plain lines with done/total, rate and time; no carriage returns.
    assert!(!log.contains('\r'), "{log}");
    // The stage label ("search exhaustive:", "search final:") depends on the sweep mode.
    let done = " 167 candidates × 1024 fragments: 171 008/171 008 (100.0 %), ";
    assert!(
        log.lines()
            .any(|l| l.starts_with("search ") && l.contains(done) && l.contains("/s, elapsed ")),
        "{log}"
    );

    // A task that fails on a bad argument: the merge job (afterany, so it runs) refuses.
    let fail = root.join("fail");
    std::fs::create_dir_all(fail.join("logs")).unwrap();
    let sbatch = |task: &str, extra: &[&str]| -> String {
        let out = stdout(
            Command::new("sbatch")
                .args([
                    "--parsable",
                    "--array",
                    task,
                    "--cpus-per-task=2",
                    "--output",
                ])
                .arg(fail.join("logs/search-%A_%a.log"))
                .arg(scripts().join("search-array.sh"))
                .arg(&fail)
                .arg("2")
                .args(args)
                .args(["--candidates", "1,2,3,4"])
                .args(extra)
                .env("MOMENTLAB", bin()),
        );
        out.trim().split(';').next().unwrap().to_string()
    };
    let good = sbatch("0", &[]);
    let bad = sbatch("1", &["--solver", "nonsense"]);
    jobs.0.extend([good.clone(), bad.clone()]);
    let out = stdout(
        Command::new("sbatch")
            .args(["--parsable", &format!("--dependency=afterany:{good}:{bad}")])
            .arg("--output")
            .arg(fail.join("logs/merge-%j.log"))
            .arg(scripts().join("merge.sh"))
            .arg(&fail)
            .arg("2")
            .args(args)
            .env("MOMENTLAB", bin()),
    );
    let fmerge = out.trim().split(';').next().unwrap().to_string();
    jobs.0.push(fmerge.clone());
    wait_done(&fmerge);
    assert_eq!(state(&fmerge).as_deref(), Some("FAILED"), "{}", logs(&fail));
    let log = read(&fail.join(format!("logs/merge-{fmerge}.log")));
    let refusal: Vec<&str> = log.lines().filter(|l| l.starts_with("error:")).collect();
    assert_eq!(refusal.len(), 1, "{log}");
    let refusal = refusal[0];
    for part in [
        "shard-1 failed: shard 1/2: momentlab search exited with status 1",
        "unknown LP solver 'nonsense'",
        "resubmit",
    ] {
        assert!(refusal.contains(part), "missing '{part}' in: {refusal}");
    }
    assert!(!fail.join("merged").exists());
    assert!(
        read(&fail.join("logs").join(format!("search-{good}_0.log")))
            .contains("momentlab: 2 threads (SLURM_CPUS_PER_TASK)")
    );

    drop(jobs);
    std::fs::remove_dir_all(&root).unwrap();
}
