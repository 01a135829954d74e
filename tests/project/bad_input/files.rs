//! Files: inputs bounded and regular, stacks checked for meaning, outputs never replaced
//! without `--force`.

use super::*;

#[test]
fn inputs_are_bounded_regular_files_and_names_are_plain() {
    let s = Scratch::new("inputs");
    // lp: 100 functions is a one-line error, not a panic in the dense kernels.
    let basis: Vec<String> = (1..=100).map(|k| format!("\"z^{k}\"")).collect();
    let moments: Vec<String> = (1..=100)
        .map(|k| format!("{}", 1.0 / (k + 1) as f64))
        .collect();
    let batch = format!(
        r#"{{"basis": [{}], "problems": [{{"moments": [{}], "zf": 0.5}}]}}"#,
        basis.join(","),
        moments.join(",")
    );
    let f = s.write("lp100.json", &batch);
    expect(&["lp", &f], 1, &["100 functions", "limit of 31"]);
    // ESM with a moment below e^{80·0} = 1: no distribution has it (was G = 1).
    let f = s.write(
        "esm.json",
        r#"{"technique": "esm", "problems": [{"moments": [0.5], "zf": 0.5}]}"#,
    );
    expect(
        &["shadow", &f],
        1,
        &["moment 1 = 5e-1 is outside the range"],
    );
    // Non-regular files: a FIFO (must not block), a directory, a link to /dev/zero.
    let fifo = s.path("pipe.json");
    let c = std::ffi::CString::new(fifo.to_str().unwrap()).unwrap();
    assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0);
    expect(
        &["lp", fifo.to_str().unwrap()],
        1,
        &["pipe.json: is a FIFO"],
    );
    expect(
        &["shadow", &s.p("")],
        1,
        &["is a directory, not a regular file"],
    );
    let zero = s.path("zero.json");
    std::os::unix::fs::symlink("/dev/zero", &zero).unwrap();
    expect(
        &[
            "candidates",
            "count",
            "--m",
            "2",
            "--catalog",
            zero.to_str().unwrap(),
        ],
        1,
        &["zero.json: is a character device"],
    );
    expect(
        &["lp", "--catalog", zero.to_str().unwrap(), &s.p("esm.json")],
        1,
        &["is a character device"],
    );
    // A depth stack or mesh that is a link to a device is named as such, never "no such file".
    let zexr = s.path("zero.exr");
    std::os::unix::fs::symlink("/dev/zero", &zexr).unwrap();
    expect(
        &["import", zexr.to_str().unwrap()],
        1,
        &["zero.exr: is a character device, not a regular file"],
    );
    let zdir = s.path("zstacks");
    std::fs::create_dir_all(&zdir).unwrap();
    std::os::unix::fs::symlink("/dev/zero", zdir.join("v.exr")).unwrap();
    expect(
        &[
            "evaluate",
            "--technique",
            "vsm",
            "--stacks",
            zdir.to_str().unwrap(),
        ],
        1,
        &["v.exr: is a character device, not a regular file"],
    );
    let zobj = s.path("zero.obj");
    std::os::unix::fs::symlink("/dev/zero", &zobj).unwrap();
    expect(
        &[
            "render",
            "--scenes",
            zobj.to_str().unwrap(),
            "--out",
            &s.p("zr"),
        ],
        1,
        &["zero.obj: is a character device, not a regular file"],
    );
    // Catalog names with a comma or a newline.
    for (tag, name, want) in [
        ("comma", "a,b", "contains a comma"),
        ("newline", "a\\nb", "control character"),
        ("semicolon", "a;b", "contains a semicolon"),
    ] {
        let cat = s.write(
            &format!("cat-{tag}.json"),
            &format!(r#"{{"functions": [{{"name": "{name}", "formula": "z"}}, {{"name": "y", "formula": "z^2"}}]}}"#),
        );
        expect(
            &["candidates", "count", "--m", "1", "--catalog", &cat],
            1,
            &[want],
        );
    }
}

#[test]
fn stacks_are_checked_for_meaning_and_never_rewritten_in_place() {
    let f = Fixtures::new();
    let s = Scratch::new("stacks");
    // A sidecar with an unknown field: refused (a copy would silently drop it).
    momentlab::stack::write(&s.path("extra/v.exr"), &stack(false)).unwrap();
    let mut m = serde_json::to_value(meta(16, 1)).unwrap();
    m["exposure"] = serde_json::json!(2.0);
    std::fs::write(s.path("extra/v.json"), m.to_string()).unwrap();
    expect(
        &["import", &s.p("extra/v.exr"), "--out", &s.p("o1")],
        1,
        &["unknown field `exposure`"],
    );
    // Two channels for one layer's Z (layer0.Z and layer000.Z).
    {
        use exr::prelude::*;
        let n = 16 * 16;
        let ch = |name: &str| {
            AnyChannel::new(
                Text::new_or_none(name).unwrap(),
                FlatSamples::F32(vec![0.5; n]),
            )
        };
        let list: SmallVec<[AnyChannel<FlatSamples>; 4]> = SmallVec::from_vec(vec![
            ch("layer0.Z"),
            ch("layer000.Z"),
            ch("layer000.dzdu"),
            ch("layer000.dzdv"),
        ]);
        let enc = Encoding {
            compression: Compression::ZIP16,
            blocks: Blocks::ScanLines,
            line_order: LineOrder::Increasing,
        };
        let layer = Layer::new(
            (16, 16),
            LayerAttributes::default(),
            enc,
            AnyChannels::sort(list),
        );
        Image::from_layer(layer)
            .write()
            .to_file(s.path("twice.exr"))
            .unwrap();
        std::fs::write(
            s.path("twice.json"),
            serde_json::to_string(&meta(16, 1)).unwrap(),
        )
        .unwrap();
    }
    expect(
        &["import", &s.p("twice.exr")],
        1,
        &["'layer0.Z'", "'layer000.Z'", "one channel per layer"],
    );
    // `import X --out X` must not rewrite its own input, with or without --force.
    let before = snapshot(&f.root.join("a"));
    for force in [false, true] {
        let mut a = args(&["import", &f.p("a/v.exr"), "--out", &f.p("a")]);
        if force {
            a.push("--force".into());
        }
        let refs: Vec<&str> = a.iter().map(String::as_str).collect();
        expect(&refs, 1, &["rewritten in place"]);
    }
    assert_eq!(snapshot(&f.root.join("a")), before);
    assert!(!s.path("o1").exists());
}

/// Every writing subcommand, pointed at a folder that holds a file it would write: refused
/// (one line, exit 1) before its work, the file untouched, nothing else written there.
#[test]
fn writing_commands_refuse_existing_files_without_force() {
    let f = Fixtures::new();
    let s = Scratch::new("force");
    let theta_dir = format!("{}/reports/theta", env!("CARGO_MANIFEST_DIR"));
    let a = f.p("a");
    let cases: Vec<(&str, Vec<String>)> = vec![
        (
            "render/thin_light0.json",
            args(&[
                "render",
                "--only",
                "thin",
                "--resolution",
                "16",
                "--out",
                &s.p("render"),
            ]),
        ),
        (
            "import/v.exr",
            args(&["import", &f.p("a/v.exr"), "--out", &s.p("import")]),
        ),
        (
            "pictures/s_v_vsm.png",
            args(&[
                "evaluate",
                "--technique",
                "vsm",
                "--stacks",
                &a,
                "--pictures",
                &s.p("pictures"),
            ]),
        ),
        (
            "merge/results.jsonl",
            args(&["merge", &a, "--out", &s.p("merge")]),
        ),
        (
            "theta/theta2.hlsl",
            args(&[
                "theta",
                "--moments",
                "2",
                "--restarts",
                "1",
                "--out",
                &s.p("theta"),
            ]),
        ),
        (
            "summary/summary.json",
            args(&["theta", "--summary", &s.p("summary")]),
        ),
        (
            "quantize/quantize_alpha.svg",
            args(&[
                "quantize",
                "--stacks",
                &a,
                "--theta-dir",
                &theta_dir,
                "--techniques",
                "vsm",
                "--out",
                &s.p("quantize"),
            ]),
        ),
        (
            "stability/heatmap_u16.svg",
            args(&["stability", "--samples", "5", "--out", &s.p("stability")]),
        ),
        // The sweep's report: a chart, and the Markdown of `--report-only` on finished rows.
        (
            "sweep-report/fig4_m1.svg",
            [
                tiny_sweep(&s.p("sweep")),
                args(&["--out", &s.p("sweep-report")]),
            ]
            .concat(),
        ),
        (
            "report-only/search_m1.md",
            [
                tiny_sweep(&s.p("finished")),
                args(&["--report-only", "--out", &s.p("report-only")]),
            ]
            .concat(),
        ),
        (
            "reproduce/r/index.html",
            args(&[
                "reproduce",
                "--tiny",
                "--run",
                "r",
                "--out",
                &s.p("reproduce"),
                "--results",
                &s.p("reproduce-data"),
            ]),
        ),
    ];
    // Finished rows for `--report-only`.
    let (code, _, err) = run(
        &[tiny_sweep(&s.p("finished")), args(&["--no-report"])]
            .concat()
            .iter()
            .map(String::as_str)
            .collect::<Vec<_>>(),
        None,
    );
    assert_eq!(code, 0, "{err}");
    for (file, a) in &cases {
        s.write(file, "precious\n");
        let dir = s.path(file).parent().unwrap().to_path_buf();
        let before = snapshot(&dir);
        let refs: Vec<&str> = a.iter().map(String::as_str).collect();
        expect(&refs, 1, &["exists already", "--force"]);
        assert_eq!(snapshot(&dir), before, "{a:?} changed {}", dir.display());
    }
    // A dangling link where an output goes: refused, and with --force replaced, never followed.
    let victim = s.path("outside/victim.exr");
    std::fs::create_dir_all(s.path("outside")).unwrap();
    std::fs::create_dir_all(s.path("linked")).unwrap();
    std::os::unix::fs::symlink(&victim, s.path("linked/thin_light0.exr")).unwrap();
    let render = ["render", "--only", "thin", "--resolution", "16", "--out"];
    let mut r: Vec<&str> = render.to_vec();
    let linked = s.p("linked");
    r.push(&linked);
    expect(&r, 1, &["thin_light0.exr exists already"]);
    r.push("--force");
    let (code, _, err) = run(&r, None);
    assert_eq!(code, 0, "{err}");
    assert!(!victim.exists(), "the link was followed out of --out");
    assert_eq!(
        momentlab::stack::load_dir(&s.path("linked")).unwrap().len(),
        4
    );
    // The sweep never created its results folder; with --force its report replaces the chart.
    assert!(!s.path("sweep").exists());
    let mut forced = [
        tiny_sweep(&s.p("sweep")),
        args(&["--out", &s.p("sweep-report")]),
    ]
    .concat();
    forced.push("--force".into());
    let (code, _, err) = run(&forced.iter().map(String::as_str).collect::<Vec<_>>(), None);
    assert_eq!(code, 0, "{err}");
    let svg = std::fs::read_to_string(s.path("sweep-report/fig4_m1.svg")).unwrap();
    assert!(svg.starts_with("<svg") && svg.contains("Candidate errors, m = 1"));
    assert!(s.path("sweep-report/search_m1.md").exists());
    // --force replaces a stale file.
    let (code, _, err) = run(
        &[
            "render",
            "--only",
            "thin",
            "--resolution",
            "16",
            "--out",
            &s.p("render"),
            "--force",
        ],
        None,
    );
    assert_eq!(code, 0, "{err}");
    assert_eq!(
        momentlab::stack::load_dir(&s.path("render")).unwrap().len(),
        4
    );
}
