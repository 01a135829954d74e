//! Standard streams and signals: a closed pipe, `-` for stdin, a full device, errors after
//! progress, thread clamping, checks before the work, and interrupts.

use super::*;

/// Closing stdout early (`| head -c 10`) ends the command quietly with exit 0.
#[test]
fn broken_pipe_ends_quietly() {
    let problems: Vec<String> = (0..3000)
        .map(|k| {
            format!(
                r#"{{"moments": [0.5, 0.3], "zf": {}}}"#,
                (k % 100) as f64 / 100.0
            )
        })
        .collect();
    let batch = format!(
        r#"{{"basis": ["z", "z^2"], "problems": [{}]}}"#,
        problems.join(",")
    );
    for (a, stdin) in [
        (vec!["lp", "-"], Some(batch)),
        (vec!["candidates", "list"], None),
    ] {
        let mut child = Command::new(bin())
            .args(&a)
            .env("MOMENTLAB_PROGRESS", "off")
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        let mut w = child.stdin.take().unwrap();
        std::thread::spawn(move || {
            if let Some(s) = stdin {
                let _ = w.write_all(s.as_bytes());
            }
        });
        let mut out = child.stdout.take().unwrap();
        let mut head = [0u8; 10];
        out.read_exact(&mut head).unwrap();
        drop(out);
        let mut err = String::new();
        child
            .stderr
            .take()
            .unwrap()
            .read_to_string(&mut err)
            .unwrap();
        let status = child.wait().unwrap();
        assert_eq!(status.code(), Some(0), "{a:?}: {err}");
        assert!(err.is_empty(), "{a:?}: {err}");
    }
}

/// `-` is stdin for FILE arguments.
#[test]
fn dash_is_stdin() {
    for a in [vec!["lp", "-"], vec!["lp"]] {
        let (code, out, err) = run(&a, Some(LP_OK));
        assert_eq!(code, 0, "{a:?}: {err}");
        let v: serde_json::Value = serde_json::from_str(&out).unwrap();
        assert_eq!(v["results"][0]["status"], "optimal", "{a:?}");
    }
}

/// stdout on a full device: one line, exit 1 (a closed pipe stays quiet: broken_pipe_ends_quietly).
#[test]
fn stdout_write_errors_are_one_line_errors() {
    let f = Fixtures::new();
    let s = Scratch::new("full");
    let full = || {
        std::fs::OpenOptions::new()
            .write(true)
            .open("/dev/full")
            .unwrap()
    };
    let lp = s.write("lp.json", LP_OK);
    let cmds: Vec<Vec<String>> = vec![
        args(&["import", &f.p("a/v.exr")]),
        args(&["evaluate", "--technique", "vsm", "--stacks", &f.p("a")]),
        args(&[
            "render",
            "--only",
            "thin",
            "--resolution",
            "16",
            "--out",
            &s.p("r"),
        ]),
        args(&["stability", "--samples", "5", "--out", &s.p("st"), "--json"]),
        args(&["lp", &lp]),
        args(&["candidates", "count", "--m", "2"]),
    ];
    for a in &cmds {
        let refs: Vec<&str> = a.iter().map(String::as_str).collect();
        let (code, err) = run_env(&refs, &[], Some(full()));
        assert_eq!(code, 1, "{a:?}: {err}");
        assert_eq!(err.lines().count(), 1, "{a:?}: {err:?}");
        assert!(
            err.contains("stdout") && err.contains("No space left"),
            "{a:?}: {err}"
        );
    }
}

/// An error after progress output is the last line of stderr, and the only error line: with
/// progress lines due all the time, `evaluate > /dev/full` shows progress, then the error.
#[test]
fn an_error_after_progress_is_the_last_line() {
    for mode in ["lines", "bar"] {
        let full = std::fs::OpenOptions::new()
            .write(true)
            .open("/dev/full")
            .unwrap();
        let (code, err) = run_env(
            &["evaluate", "--technique", "vsm", "--resolution", "24"],
            &[
                ("MOMENTLAB_PROGRESS", mode),
                ("MOMENTLAB_PROGRESS_INTERVAL", "0"),
            ],
            Some(full),
        );
        assert_eq!(code, 1, "{err}");
        let lines: Vec<&str> = err.lines().collect();
        if mode == "lines" {
            assert!(
                lines.iter().any(|l| l.starts_with("evaluate vsm: ")),
                "no progress shown: {err:?}"
            );
        }
        let last = lines.last().unwrap();
        assert!(
            last.starts_with("error: writing stdout") && last.contains("No space left"),
            "{mode}: the last line is not the error: {err:?}"
        );
        assert_eq!(
            lines.iter().filter(|l| l.contains("error")).count(),
            1,
            "{mode}: {err:?}"
        );
        assert!(!err.contains('\r'), "{mode}: {err:?}");
    }
}

/// Thread requests beyond the CPUs are clamped; the note never precedes an error line.
#[test]
fn thread_requests_are_clamped_and_quiet_on_errors() {
    for var in ["SLURM_CPUS_PER_TASK", "RAYON_NUM_THREADS"] {
        let (code, err) = run_env(&["candidates", "subset", "z,nope"], &[(var, "20000")], None);
        assert_eq!(code, 1, "{err}");
        assert_eq!(err.lines().count(), 1, "{var}: {err:?}");
        let (code, err) = run_env(
            &["candidates", "count", "--m", "2"],
            &[(var, "20000")],
            None,
        );
        assert_eq!(code, 0, "{err}");
        assert!(
            err.contains(var) && err.contains("20000") && err.contains("used"),
            "{var}: {err:?}"
        );
    }
}

/// Checks that used to run after the expensive work now come first (each case would render
/// the default dataset or run a θ search before failing; the 10 s limit of `run` catches it).
#[test]
fn checks_come_before_the_work() {
    let s = Scratch::new("early");
    let file = s.write("file", "x");
    expect(
        &["theta", "--moments", "4", "--out", &file],
        1,
        &["--out", "not a folder"],
    );
    expect(
        &["search", "--results", &file],
        1,
        &["--results", "not a folder"],
    );
    expect(
        &["search", "--names", "z,nope"],
        1,
        &["unknown function 'nope'"],
    );
    expect(
        &[
            "search",
            "--m",
            "2",
            "--names",
            "z,z^2",
            "--report-only",
            "--results",
            &s.p("none"),
        ],
        1,
        &["--report-only"],
    );
}

/// SIGINT or SIGTERM during a long command: exit status 130 and exactly one stderr line saying
/// so (progress output ends first), and the output folder holds no half-written file.
#[test]
fn interrupts_exit_130_with_one_line() {
    let s = Scratch::new("interrupt");
    for (sig, name, args) in [
        (
            libc::SIGINT,
            "SIGINT",
            vec![
                "theta",
                "--m",
                "4",
                "--restarts",
                "100000",
                "--out",
                "theta",
            ],
        ),
        (
            libc::SIGTERM,
            "SIGTERM",
            vec!["stability", "--samples", "200000", "--out", "stab"],
        ),
    ] {
        let mut args: Vec<String> = args.iter().map(|a| a.to_string()).collect();
        let last = args.len() - 1;
        args[last] = s.p(&args[last]);
        let child = Command::new(bin())
            .args(&args)
            .env("MOMENTLAB_PROGRESS", "lines")
            .env("MOMENTLAB_PROGRESS_INTERVAL", "0.1")
            .stdin(Stdio::null())
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        std::thread::sleep(std::time::Duration::from_millis(1500));
        assert_eq!(unsafe { libc::kill(child.id() as i32, sig) }, 0);
        let out = child.wait_with_output().unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(130), "{args:?}: {err}");
        let lines: Vec<&str> = err.lines().collect();
        let last = lines.last().unwrap();
        assert!(
            last.starts_with(&format!("error: {}: interrupted by {name}", args[0])),
            "{err}"
        );
        assert_eq!(
            lines.iter().filter(|l| l.contains("error")).count(),
            1,
            "{err}"
        );
        // Whatever was written is whole: no temporary file of the writer left behind.
        if let Ok(d) = std::fs::read_dir(&args[args.len() - 1]) {
            for e in d {
                let n = e.unwrap().file_name().to_string_lossy().into_owned();
                assert!(!n.ends_with(".tmp"), "{n} left in the output folder");
            }
        }
    }
}
