//! `tune` on constructed depth stacks whose answer is known, and its one-line errors.
//!
//! The scene: a receiver plane at depth z_r, half of it under an occluder plane tilted by
//! g = 10⁻⁴ per texel in x and y at least Δ in front of it (two layers where the occluder
//! covers the receiver), with its exact slopes, so the PCF reference and a slope-scaled technique
//! bias keep both planes lit where they are lit. Fully shadowed receiver fragments see a
//! filter window of depths spread by the tilt (variance ≈ 2g²·σ_k² ≈ 10⁻⁷) at z_f ≤ z_r, so the
//! shadow map must resolve a gap Δ next to that spread.
//! * Δ = 0.25: every storage resolves it; 16-bit storage costs half the bits, so with the
//!   default tolerance the choice is a 16-bit setting.
//! * Δ = 5·10⁻⁴: 16-bit storage resolves it worse. Its rounding (UNORM 1.5·10⁻⁵ per channel
//!   and texel, binary16 2⁻¹¹ relative) perturbs the filtered moments, so a valid reconstruction
//!   needs α ≳ 10⁻⁵, whose bias variance α/4 is not small against Δ²; the exponential warps
//!   under the binary16 limit c ≤ 5.5 (EVSM) leak e^{−cΔ} ≈ 1 of the shadow. 32-bit floats
//!   (rounding 6·10⁻⁸ relative) allow α ≈ 10⁻⁷. The test asserts the gap (the best 16-bit
//!   setting is more than twice the tolerance worse than the best 32-bit one), so the choice
//!   is 32-bit at the default tolerance, and 16-bit again at a tolerance above the gap.

use momentlab::progress::Bar;
use momentlab::stack::{DepthStack, StackMeta};
use momentlab::tune::space::{StorageKind, TechniqueKind};
use momentlab::tune::{tune, Options};

fn scene(name: &str, delta: f32, n: usize) -> DepthStack {
    let zr = 0.6f32;
    let t = n * n;
    let mut front = vec![zr; t];
    let mut back = vec![f32::INFINITY; t];
    let g = 1e-4f32;
    let mut slope = vec![0.0f32; t];
    for y in 0..n {
        for x in 0..n / 2 {
            front[y * n + x] = zr - delta - g * (x + y) as f32;
            back[y * n + x] = zr;
            slope[y * n + x] = -g;
        }
    }
    DepthStack {
        meta: StackMeta {
            scene: name.into(),
            view: "light0".into(),
            light_dir: [0.0, 0.0, -1.0],
            near: 1.0,
            far: 2.0,
            width: n,
            height: n,
            layers: 2,
            ..Default::default()
        },
        depth: vec![front, back],
        dzdu: vec![slope.clone(), vec![0.0; t]],
        dzdv: vec![slope, vec![0.0; t]],
    }
}

/// The four-moment techniques: 16-bit storage is 64 bits per texel, 32-bit 128.
fn options(tolerance: f64) -> Options {
    Options {
        techniques: vec![
            TechniqueKind::Evsm,
            TechniqueKind::Hamburger4,
            TechniqueKind::Hausdorff4,
            TechniqueKind::Tmsm,
        ],
        tolerance,
        fragments_per_scene: 3000,
        screen_per_scene: 600,
        speed_inputs: 500,
        ..Options::default()
    }
}

#[test]
fn picks_16_bit_when_the_tolerance_allows_and_32_bit_when_not() {
    let stacks = vec![scene("far", 0.25, 40), scene("near", 5e-4, 40)];
    let t = tune(&stacks, &options(0.002), &Bar::hidden()).unwrap();
    let far = t.scenes.iter().find(|s| s.scene == "far").unwrap();
    let near = t.scenes.iter().find(|s| s.scene == "near").unwrap();
    eprintln!("{}", momentlab::tune::table::table(&t));
    // Far: some setting is (nearly) exact, and a 16-bit one is within the tolerance.
    assert!(far.best.error < 0.002, "{:?}", far.best);
    assert_eq!(
        far.chosen.setting.family.storage.bits(),
        16,
        "{:?}",
        far.chosen
    );
    assert_eq!(far.chosen.bits_per_texel, 64);
    assert!(far.chosen.error <= far.best.error + 0.002);
    // Near: every 16-bit setting misses the shadow; the choice is 32-bit.
    assert!(near.best.error < 0.1, "{:?}", near.best);
    assert_eq!(
        near.chosen.setting.family.storage.bits(),
        32,
        "{:?}",
        near.chosen
    );
    assert_eq!(near.chosen.bits_per_texel, 128);
    let only16 = tune(
        &stacks,
        &Options {
            storages: vec![
                StorageKind::Unorm16Theta,
                StorageKind::Unorm16,
                StorageKind::F16,
            ],
            ..options(0.0)
        },
        &Bar::hidden(),
    )
    .unwrap();
    let best16 = only16.scenes.iter().find(|s| s.scene == "near").unwrap();
    assert!(
        best16.best.error > near.best.error + 2.0 * 0.002,
        "16-bit {:?}",
        best16.best
    );
    // A tolerance above the gap lets 16 bits back in.
    let gap = best16.best.error - near.best.error;
    let loose = tune(&stacks[1..], &options(gap + 0.005), &Bar::hidden()).unwrap();
    assert_eq!(
        loose.scenes[0].chosen.bits_per_texel, 64,
        "{:?}",
        loose.scenes[0].chosen
    );
    // The noise bound: what competes keeps it, and near's tight cluster rejects settings.
    for s in t
        .scenes
        .iter()
        .chain([&t.overall])
        .flat_map(|s| [&s.chosen, &s.best].into_iter().chain(&s.pareto))
    {
        assert!(s.feasible && s.noise_share <= 0.001, "{s:?}");
        assert!(s.noise_p999.is_finite(), "{s:?}");
    }
    assert!(near.infeasible > 0, "near rejected nothing");
    let paper16 = &near.references[0];
    assert!(paper16.name.contains("16-bit") && !paper16.scored.feasible);
    // Without the bound the noisy small-α settings compete again, and look better.
    let unbounded = tune(
        &stacks[1..],
        &Options {
            max_noise: 1.0,
            ..options(0.002)
        },
        &Bar::hidden(),
    )
    .unwrap();
    let u = &unbounded.scenes[0];
    assert_eq!(u.infeasible, 0);
    assert!(u.best.noise_share > 0.001, "{:?}", u.best);
    assert!(u.best.error < near.best.error, "{:?}", u.best);
    // The runner-up of Far is another family, with a paired interval.
    let p = far.chosen_minus_runner_up.unwrap();
    assert!(p.half_width.is_finite() && p.fragments == far.fragments);
    // Leak + darkening + noise + non-finite = error, everywhere.
    for s in t.scenes.iter().flat_map(|s| s.pareto.iter()) {
        let sum = s.leak + s.darkening + s.noise + s.non_finite as f64 / s.fragments as f64;
        assert!((sum - s.error).abs() < 1e-12, "{s:?}");
    }
    // With a huge tolerance the cheapest setting wins everywhere (16 bits, one moment: ESM).
    let t = tune(
        &stacks,
        &Options {
            techniques: vec![TechniqueKind::Hamburger4, TechniqueKind::Esm],
            ..options(1.0)
        },
        &Bar::hidden(),
    )
    .unwrap();
    assert_eq!(t.overall.chosen.bits_per_texel, 16);
    assert_eq!(
        t.overall.chosen.setting.family.technique,
        TechniqueKind::Esm
    );
    // Restricted to 32-bit storage, the choice is 32-bit whatever the tolerance.
    let t = tune(
        &stacks,
        &Options {
            storages: vec![StorageKind::F32],
            ..options(1.0)
        },
        &Bar::hidden(),
    )
    .unwrap();
    assert!(t
        .scenes
        .iter()
        .all(|s| s.chosen.setting.family.storage == StorageKind::F32));
}

#[test]
fn bad_input_is_one_line_before_any_work() {
    let dir = crate::common::tmp("tune");
    let missing = dir.join("missing");
    let cases: Vec<(Vec<String>, &str)> = vec![
        (
            vec!["--stacks".into(), missing.display().to_string()],
            "missing",
        ),
        (
            vec!["--stacks".into(), dir.display().to_string()],
            "--stacks",
        ),
        (
            vec![
                "--technique".into(),
                "esm".into(),
                "--storages".into(),
                "unorm16".into(),
            ],
            "empty search space",
        ),
        (
            vec!["--technique".into(), "hamburger5".into()],
            "hamburger5",
        ),
        (vec!["--storages".into(), "f8".into()], "f8"),
        (vec!["--technique".into(), ",".into()], "empty search space"),
        (vec!["--tolerance".into(), "-1".into()], "tolerance"),
    ];
    for (args, what) in cases {
        let mut a = vec!["tune"];
        a.extend(args.iter().map(String::as_str));
        let (code, out, err) = crate::common::run(&a, None);
        assert_ne!(code, 0, "{a:?}");
        assert!(out.is_empty(), "{a:?}: {out}");
        assert_eq!(err.trim().lines().count(), 1, "{a:?}: {err}");
        assert!(err.contains(what), "{a:?}: {err}");
        assert!(!err.contains("rendering"), "{a:?} did work first: {err}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// `tune --out T` with cheap settings (rendering at 16², a few fragments, one family).
fn tune_into(out: &std::path::Path, extra: &[&str]) -> (i32, String, String) {
    let out = out.display().to_string();
    let mut a = vec![
        "tune",
        "--resolution",
        "16",
        "--fragments",
        "64",
        "--screen",
        "64",
        "--technique",
        "vsm",
        "--storages",
        "f32",
        "--out",
        &out,
    ];
    a.extend(extra);
    crate::common::run(&a, None)
}

#[test]
fn a_linked_export_folder_is_refused_and_nothing_is_written_outside() {
    let dir = crate::common::tmp("tune-export-link");
    let (out, outside) = (dir.join("T"), dir.join("outside"));
    std::fs::create_dir_all(&out).unwrap();
    std::fs::create_dir_all(&outside).unwrap();
    std::os::unix::fs::symlink(&outside, out.join("export")).unwrap();
    for extra in [&[][..], &["--force"][..]] {
        let (code, _, err) = tune_into(&out, extra);
        assert_ne!(code, 0, "{extra:?}: {err}");
        assert_eq!(err.trim().lines().count(), 1, "{extra:?}: {err}");
        assert!(
            err.contains("symbolic link") && err.contains("export"),
            "{err}"
        );
        let written: Vec<_> = std::fs::read_dir(&outside).unwrap().collect();
        assert!(
            written.is_empty(),
            "{extra:?}: written outside: {written:?}"
        );
        assert!(
            !out.join("tune.json").exists(),
            "{extra:?}: tune.json written"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn an_existing_export_file_stops_tune_before_any_output_or_work() {
    let dir = crate::common::tmp("tune-export-exists");
    let out = dir.join("T");
    std::fs::create_dir_all(out.join("export/all")).unwrap();
    std::fs::write(out.join("export/all/setting.json"), "mine").unwrap();
    let (code, _, err) = tune_into(&out, &[]);
    assert_ne!(code, 0, "{err}");
    assert_eq!(err.trim().lines().count(), 1, "{err}");
    assert!(
        err.contains("export/all/setting.json") && err.contains("--force"),
        "{err}"
    );
    assert!(!err.contains("rendering"), "did work first: {err}");
    assert!(!out.join("tune.json").exists(), "tune.json written first");
    let mut files = Vec::new();
    let mut todo = vec![out.clone()];
    while let Some(d) = todo.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                todo.push(p);
            } else {
                files.push(p);
            }
        }
    }
    assert_eq!(files, vec![out.join("export/all/setting.json")]);
    assert_eq!(
        std::fs::read_to_string(out.join("export/all/setting.json")).unwrap(),
        "mine"
    );
    // With --force the tuning runs and replaces it.
    let (code, _, err) = tune_into(&out, &["--force"]);
    assert_eq!(code, 0, "{err}");
    assert!(out.join("tune.json").exists());
    assert_ne!(
        std::fs::read_to_string(out.join("export/all/setting.json")).unwrap(),
        "mine"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// Noise never lowers a score: zero-mean noise added to the stored moments leaves the
/// technique's own error (leak + darkening, from exact moments) bit for bit as it was, and the
/// score averaged over seeded realisations does not fall (Jensen: E|ν + δ| ≥ |ν|); at amplitudes
/// of a storage step and more it rises.
#[test]
fn adding_zero_mean_noise_to_the_moments_never_lowers_a_score() {
    use momentlab::tune::sample;
    use momentlab::tune::score::{accumulate, outcomes, Moments};
    use momentlab::tune::space::{DepthBias, Family, Own, Setting};
    let stacks = vec![scene("far", 0.25, 40), scene("near", 5e-4, 40)];
    let s = sample::draw(&stacks, 1500, 11, &|_| {}).unwrap();
    let idx: Vec<usize> = (0..s.len()).collect();
    let score = |setting: &Setting, stored: &[f64], exact: &[f64]| {
        let o = outcomes(setting, (stored, exact), &s, &idx).unwrap();
        let mut a = accumulate(&o, &s, &idx, false);
        let first = a.remove(0);
        a.iter().fold(first, |mut x, y| {
            x.merge(y);
            x
        })
    };
    let mut x = 0x9e3779b97f4a7c15u64;
    let mut uniform = move || {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        (x >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    };
    for (technique, storage, alpha) in [
        (TechniqueKind::Hamburger4, StorageKind::F32, 6e-6),
        (TechniqueKind::Hamburger4, StorageKind::Unorm16Theta, 3e-5),
        (TechniqueKind::Hausdorff4, StorageKind::F32, 2e-6),
        (TechniqueKind::Vsm, StorageKind::F32, 1e-5),
    ] {
        let family = Family {
            technique,
            storage,
            own: Own::None,
        };
        let m = Moments::compute(&family, &s).unwrap();
        let setting = Setting {
            family,
            alpha,
            depth_bias: DepthBias {
                constant: 1e-4,
                slope_scale: 2.0,
            },
        };
        let base = score(&setting, &m.stored, &m.exact);
        for amp in [1e-7, 1e-6, 1e-5, 1e-4] {
            let runs = 12;
            let mut scores = Vec::new();
            for _ in 0..runs {
                let noisy: Vec<f64> = m.stored.iter().map(|v| v + amp * uniform()).collect();
                let a = score(&setting, &noisy, &m.exact);
                // the technique's own error does not move
                assert_eq!((a.leak, a.dark), (base.leak, base.dark), "{technique:?}");
                scores.push(a.score());
            }
            let mean = scores.iter().sum::<f64>() / runs as f64;
            let sd =
                (scores.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (runs - 1) as f64).sqrt();
            assert!(
                mean >= base.score() - 2.0 * sd / (runs as f64).sqrt() - 1e-12,
                "{technique:?} {storage:?} amp {amp}: {mean} < {}",
                base.score()
            );
            if amp >= 1e-5 {
                assert!(mean > base.score(), "{technique:?} {storage:?} amp {amp}");
            }
        }
    }
}

/// 6MSM's registry default α meets the noise bound on the default scenes: for every target of
/// the committed tuning, the `hamburger6` α floors at f32 and 16-bit θ₆ exist and lie at or
/// below the defaults (`hamburger6::ALPHA_NOISE_BOUND_F32`, `_16BIT`), and the tuning was run
/// with the default bound.
#[test]
fn six_moment_default_alpha_meets_the_noise_bound_of_the_committed_tuning() {
    use momentlab::technique::hamburger6::{ALPHA_NOISE_BOUND_16BIT, ALPHA_NOISE_BOUND_F32};
    let file =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("reports/default/tune/tune.json");
    let t: momentlab::tune::Tuning =
        serde_json::from_str(&std::fs::read_to_string(&file).unwrap()).unwrap();
    assert_eq!(t.max_noise, Options::default().max_noise);
    for target in t.scenes.iter().chain(std::iter::once(&t.overall)) {
        for (family, default) in [
            ("hamburger6 f32", ALPHA_NOISE_BOUND_F32),
            ("hamburger6 unorm16-theta", ALPHA_NOISE_BOUND_16BIT),
        ] {
            let floor = target
                .alpha_floor
                .iter()
                .find(|f| f.family == family)
                .and_then(|f| f.alpha)
                .unwrap_or_else(|| panic!("{}: no feasible α for {family}", target.scene));
            assert!(
                floor <= default,
                "{}: {family} needs α ≥ {floor}, the default is {default}",
                target.scene
            );
        }
    }
    // the registry's default hamburger6 is the clamped 6MSM at those α (f64: the same G on a
    // two-Dirac input whose biased moments depend on α)
    use momentlab::technique::hamburger6::{Hamburger6, B_STAR_CLAMPED};
    use momentlab::technique::linalg::Precision;
    use momentlab::technique::ClosedForm;
    let b: Vec<f64> = (1..=6)
        .map(|k| 0.5 * 0.2f64.powi(k) + 0.5 * 0.7f64.powi(k))
        .collect();
    for (q, alpha) in [(32, ALPHA_NOISE_BOUND_F32), (16, ALPHA_NOISE_BOUND_16BIT)] {
        let mut p = momentlab::technique::registry::Params::with(Precision::F64, None);
        p.quant_bits = q;
        let t = momentlab::technique::registry::build("hamburger6", &p).unwrap();
        let mut ev = t.evaluator();
        let want = Hamburger6::new(alpha, B_STAR_CLAMPED, Precision::F64).shadow(&b, 0.5);
        assert_eq!(ev.shadow(&b, 0.5), want, "quant_bits {q}");
        let other = Hamburger6::new(4e-3, B_STAR_CLAMPED, Precision::F64).shadow(&b, 0.5);
        assert_ne!(want, other, "the input does not tell α apart");
    }
}
