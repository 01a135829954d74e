//! Sweep shards: merges and reports verify them; one writer per results folder.

use super::*;

#[test]
fn merges_and_reports_verify_their_shards() {
    let s = Scratch::new("merge");
    for i in 0..2 {
        let (code, err) = shard(&s.p(&format!("s{i}")), i, "1");
        assert_eq!(code, 0, "{err}");
    }
    let (code, err) = shard(&s.p("foreign1"), 1, "2");
    assert_eq!(code, 0, "{err}");
    let (s0, s1) = (s.p("s0"), s.p("s1"));
    // The good merge, for reference.
    let (code, _, err) = run(&["merge", &s0, &s1, "--out", &s.p("good")], None);
    assert_eq!(code, 0, "{err}");
    let n = rows_of(&s.path("good")).len();
    assert_eq!(
        n,
        rows_of(&s.path("s0")).len() + rows_of(&s.path("s1")).len()
    );
    // Broken copies of shard 0.
    let variant = |tag: &str, edit: &dyn Fn(&Path)| -> String {
        let d = s.path(tag);
        copy_dir(&s.path("s0"), &d);
        edit(&d);
        d.display().to_string()
    };
    let torn = variant("torn", &|d| {
        let mut f = std::fs::OpenOptions::new()
            .append(true)
            .open(d.join("results.jsonl"))
            .unwrap();
        f.write_all(br#"{"index": 99, "functions": ["#).unwrap();
    });
    let empty = variant("empty", &|d| {
        std::fs::remove_file(d.join("results.jsonl")).unwrap()
    });
    let dup = variant("dup", &|d| {
        let rows = rows_of(d);
        let mut f = std::fs::OpenOptions::new()
            .append(true)
            .open(d.join("results.jsonl"))
            .unwrap();
        writeln!(f, "{}", rows[0]).unwrap();
    });
    let lost = variant("lost", &|d| {
        let rows = rows_of(d);
        std::fs::write(d.join("results.jsonl"), rows[1..].join("\n") + "\n").unwrap();
    });
    let unfinished = variant("unfinished", &|d| {
        std::fs::remove_file(d.join("complete.json")).unwrap()
    });
    let foreign = s.p("foreign1");
    let cases: Vec<(Vec<&str>, &[&str])> = vec![
        (vec![&torn, &s1], &["torn row"]),
        (
            vec![&empty, &s1],
            &["marked complete but has no results.jsonl"],
        ),
        (vec![&dup, &s1], &["appears twice"]),
        (vec![&lost, &s1], &["rows, but complete.json says"]),
        (vec![&unfinished, &s1], &["is not complete"]),
        (vec![&s0, &foreign], &["different configuration"]),
        (vec![&s0], &["shard 1/2 is missing"]),
        (vec![&s0, &s0], &["given twice"]),
    ];
    for (i, (dirs, want)) in cases.iter().enumerate() {
        let out = s.p(&format!("m{i}"));
        let mut a = vec!["merge"];
        a.extend(dirs.iter().copied());
        a.extend(["--out", &out]);
        expect(&a, 1, want);
        assert!(!Path::new(&out).exists(), "{a:?} wrote {out}");
    }
    // --report-only refuses the same things, and a single shard presented as the whole run.
    let report = |dir: &str| {
        vec![
            "search",
            "--synthetic",
            "40",
            "--m",
            "1",
            "--exhaustive",
            "--grid",
            "64",
            "--seed",
            "1",
            "--report-only",
            "--results",
            dir.to_string().leak(),
            "--report",
            s.p("rep").leak(),
        ]
    };
    expect(&report(&s0), 1, &["shard 0/2 of a sharded run", "merge"]);
    let merged_dup = variant("merged-dup", &|d| {
        std::fs::remove_dir_all(d).unwrap();
        copy_dir(&s.path("good"), d);
        let rows = rows_of(d);
        let mut f = std::fs::OpenOptions::new()
            .append(true)
            .open(d.join("results.jsonl"))
            .unwrap();
        writeln!(f, "{}", rows[0]).unwrap();
    });
    expect(&report(&merged_dup), 1, &["appears twice"]);
    expect(&report(&torn), 1, &["torn row"]);
    assert!(!s.path("rep").exists());
}

#[test]
fn a_second_writer_on_one_results_folder_fails_cleanly() {
    let s = Scratch::new("lock");
    // Deterministic: the folder is held (the lock the sweep takes), the second writer fails.
    let d = s.path("held");
    std::fs::create_dir_all(&d).unwrap();
    let lock = std::fs::OpenOptions::new()
        .create(true)
        .truncate(false)
        .write(true)
        .open(d.join(".momentlab.lock"))
        .unwrap();
    lock.try_lock().unwrap();
    let held = d.display().to_string();
    let (code, err) = shard(&held, 0, "1");
    assert_eq!(code, 1, "{err}");
    assert_eq!(err.lines().count(), 1, "{err:?}");
    assert!(err.contains("in use by another momentlab run"), "{err}");
    expect(
        &["merge", &s.p("nothing"), "--out", &held],
        1,
        &["in use", "another momentlab run"],
    );
    assert!(!d.join("results.jsonl").exists() && !d.join("config.json").exists());
    drop(lock);
    // Two concurrent runs into one folder: each either completes or is refused cleanly, and
    // the rows are there once each.
    let dir = s.p("both");
    let spawn = || {
        let dir = dir.clone();
        std::thread::spawn(move || shard(&dir, 0, "1"))
    };
    let (a, b) = (spawn(), spawn());
    let outcomes = [a.join().unwrap(), b.join().unwrap()];
    for (code, err) in &outcomes {
        assert!(
            *code == 0 || (*code == 1 && err.contains("in use by another momentlab run")),
            "{code}: {err}"
        );
        if *code == 1 {
            assert_eq!(err.lines().count(), 1, "{err:?}");
        }
    }
    assert!(outcomes.iter().any(|(c, _)| *c == 0));
    let rows = rows_of(&s.path("both"));
    let mut idx: Vec<u64> = rows
        .iter()
        .map(|r| {
            serde_json::from_str::<serde_json::Value>(r).unwrap()["index"]
                .as_u64()
                .unwrap()
        })
        .collect();
    let n = idx.len();
    idx.sort();
    idx.dedup();
    assert_eq!(idx.len(), n, "rows written twice");
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(s.path("both/complete.json")).unwrap())
            .unwrap();
    assert_eq!(summary["candidates"].as_u64().unwrap() as usize, n);
}
