//! The sweep and `momentlab evaluate` agree: the sweep's exhaustive error of an LP candidate on
//! a small constructed depth stack (every fragment, no sampling) equals `metrics::evaluate`
//! with the same candidate as a technique ("lp:…" via `technique::by_name`, or an
//! `LpCandidate` on a small grid) to 1e-9. Also: the capped stratified sample of
//! `Dataset::from_stacks` keeps about the cap, every (view, layer) stratum in proportion, and
//! its estimate is within a few standard errors of the exact value.

use crate::common::tmp_path;
use momentlab::basis::Catalog;
use momentlab::metrics::{self, Bias, EvalOptions};
use momentlab::search::reference::ReferenceCache;
use momentlab::search::run::load_table;
use momentlab::search::{sweep_dataset, Dataset, SamplePlan, SweepOptions};
use momentlab::stack::{DepthStack, StackMeta};
use momentlab::technique::lp_candidate::LpCandidate;
use momentlab::technique::{by_name, Technique};
use momentlab::Grid;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// A w×h stack with `layers` surfaces per texel: a tilted ground plane in the deepest layer,
/// random box occluders above it (so shadow edges, partial PCF values and several layers).
fn stack(seed: u64, w: usize, h: usize, layers: usize) -> DepthStack {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let n = w * h;
    let mut depth = vec![vec![f32::INFINITY; n]; layers];
    let mut dzdu = vec![vec![0.0f32; n]; layers];
    let dzdv = vec![vec![0.0f32; n]; layers];
    // Occluder boxes: (x0, x1, y0, y1, depth), per layer above the ground.
    type Box4 = (usize, usize, usize, usize, f32);
    let boxes: Vec<Vec<Box4>> = (0..layers - 1)
        .map(|l| {
            (0..3)
                .map(|_| {
                    let x0 = rng.gen_range(0..w - 2);
                    let y0 = rng.gen_range(0..h - 2);
                    let x1 = rng.gen_range(x0 + 2..=w);
                    let y1 = rng.gen_range(y0 + 2..=h);
                    let base = 0.1 + 0.25 * l as f32;
                    (x0, x1, y0, y1, base + rng.gen_range(0.0..0.2))
                })
                .collect()
        })
        .collect();
    for y in 0..h {
        for x in 0..w {
            let t = y * w + x;
            let mut zs: Vec<(f32, f32)> = Vec::new();
            for bl in &boxes {
                for &(x0, x1, y0, y1, d) in bl {
                    if (x0..x1).contains(&x) && (y0..y1).contains(&y) {
                        zs.push((d, 0.0));
                        break;
                    }
                }
            }
            let slope = 0.004f32;
            zs.push((0.8 + slope * x as f32, slope));
            zs.sort_by(|a, b| a.0.total_cmp(&b.0));
            zs.dedup_by(|a, b| a.0 <= b.0);
            for (l, &(d, s)) in zs.iter().enumerate() {
                depth[l][t] = d;
                dzdu[l][t] = s;
            }
        }
    }
    DepthStack {
        meta: StackMeta {
            scene: "boxes".into(),
            view: format!("v{seed}"),
            light_dir: [0.0, 0.0, 1.0],
            near: 0.0,
            far: 1.0,
            width: w,
            height: h,
            layers,
            ..StackMeta::default()
        },
        depth,
        dzdu,
        dzdv,
    }
}

/// Exhaustive sweep errors (in the order of `names`) and the metrics::evaluate errors of the
/// same candidates as techniques on `grid`.
fn compare(stacks: &[DepthStack], grid: &Grid, solver: &str, names: &[&[&str]], tag: &str) {
    let bias = Bias::default();
    let plan = SamplePlan {
        max_fragments: None,
        seed: 1,
    };
    let data = Dataset::from_stacks(stacks, grid, &bias, &plan).unwrap();
    let all: usize = stacks.iter().map(|s| s.fragment_count()).sum();
    assert_eq!(data.total_count() as usize, all);
    assert_eq!(data.sampled_fraction(), 1.0);
    assert!(data.fragments().len() > 20, "{}", data.fragments().len());
    assert!(data.trivial_count() > 0);
    let table = load_table(None, grid).unwrap();
    let m = names[0].len();
    let dir = tmp_path(tag);
    let opts = SweepOptions {
        m,
        grid: grid.len(),
        solver: solver.to_string(),
        chunk: 64,
        bias,
        max_fragments: None,
        exhaustive: true,
        names: Some(
            names
                .iter()
                .map(|n| n.join(","))
                .collect::<Vec<_>>()
                .join(";"),
        ),
        closed_forms: false,
        ..SweepOptions::default()
    };
    let refs = ReferenceCache::new(Some(stacks));
    let r = sweep_dataset(&data, &table, &refs, &opts, &dir, None).unwrap();
    assert!(r.summary.is_some());
    for n in names {
        let row = r
            .rows
            .iter()
            .find(|row| row.functions == n.iter().map(|s| s.to_string()).collect::<Vec<_>>())
            .unwrap_or_else(|| panic!("no row for {n:?}"));
        assert_eq!(row.lp_failures, 0, "{n:?}");
        assert!(row.full && row.fragments == data.fragments().len() as u64);
        let tech: Box<dyn Technique> =
            if grid.len() == momentlab::technique::lp_candidate::DEFAULT_GRID_POINTS {
                by_name(&format!("lp:{}", n.join(","))).unwrap()
            } else {
                let basis = Catalog::embedded().basis(n).unwrap();
                Box::new(LpCandidate::new(basis, grid.clone(), solver.parse().unwrap()).unwrap())
            };
        let ev = metrics::evaluate(stacks, tech.as_ref(), &EvalOptions::default()).unwrap();
        assert_eq!(ev.non_finite, 0, "{n:?}");
        assert_eq!(ev.fragments, all);
        assert_eq!(ev.trivial as u64, data.trivial_count(), "{n:?}");
        let e = row.error.unwrap();
        assert!(
            (e - ev.error).abs() <= 1e-9,
            "{n:?}: sweep {e} vs evaluate {} (diff {:e})",
            ev.error,
            e - ev.error
        );
        // A wrong candidate would not agree: the check has teeth.
        assert!(e > 1e-6, "{n:?}: error {e} is suspiciously small");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `technique::by_name("lp:…")` (1024-point grid, the fast solver) against the sweep on the same grid with the same solver, on a tiny stack.
#[test]
fn sweep_equals_evaluate_for_registry_lp_candidates() {
    let stacks = vec![stack(3, 8, 8, 2)];
    let probe = LpCandidate::from_spec("z,z^2").unwrap();
    let solver = probe.solver_kind().name();
    compare(
        &stacks,
        &Grid::uniform(1024).unwrap(),
        solver,
        &[&["z", "z^2"]],
        "reg2",
    );
    compare(
        &stacks,
        &Grid::uniform(1024).unwrap(),
        solver,
        &[&["z", "z^2", "z^3", "z^4"]],
        "reg4",
    );
}

/// More candidates (polynomial, trigonometric, exponential) and two views on a small grid.
#[test]
fn sweep_equals_evaluate_on_a_small_grid() {
    let stacks = vec![stack(1, 12, 10, 3), stack(2, 9, 11, 2)];
    let grid = Grid::uniform(64).unwrap();
    compare(
        &stacks,
        &grid,
        "reference",
        &[&["z", "z^2"], &["z", "exp(5z)"], &["sin(2πz)", "cos(2πz)"]],
        "g2",
    );
    compare(
        &stacks,
        &grid,
        "reference",
        &[
            &["z", "z^2", "z^3", "z^4"],
            &["sin(2πz)", "cos(2πz)", "sin(4πz)", "cos(4πz)"],
        ],
        "g4",
    );
}

/// The capped sample: exactly `cap` fragments (at most the cap), strata in proportion,
/// deterministic per seed, and trivial fragments counted exactly.
#[test]
fn capped_sample_is_stratified_and_seeded() {
    let stacks = vec![stack(5, 40, 30, 3), stack(6, 30, 40, 4)];
    let grid = Grid::uniform(256).unwrap();
    let bias = Bias::default();
    let full = Dataset::from_stacks(
        &stacks,
        &grid,
        &bias,
        &SamplePlan {
            max_fragments: None,
            seed: 1,
        },
    )
    .unwrap();
    let pop = full.fragments().len();
    let cap = pop / 5;
    let plan = SamplePlan {
        max_fragments: Some(cap),
        seed: 9,
    };
    let s = Dataset::from_stacks(&stacks, &grid, &bias, &plan).unwrap();
    assert_eq!(s.nontrivial_population() as usize, pop);
    assert_eq!(s.trivial_count(), full.trivial_count());
    assert_eq!(s.trivial_error(), full.trivial_error());
    assert_eq!(s.total_count(), full.total_count());
    // PCF is computed only for the trivial and the kept fragments: bit for bit what
    // `metrics::fragments` gives for them, and the trivial error is the sum, in fragment
    // order, over the fragments the unsampled dataset does not hold.
    let mut reference = std::collections::HashMap::new();
    let mut trivial_error = 0.0;
    let nontrivial: std::collections::HashSet<(u32, u32, u32)> = full
        .fragments()
        .iter()
        .map(|f| (f.view, f.texel, f.layer))
        .collect();
    for (v, st) in stacks.iter().enumerate() {
        for f in metrics::fragments(st, v, &bias) {
            let key = (v as u32, f.texel as u32, f.layer as u32);
            if !nontrivial.contains(&key) {
                trivial_error += f.pcf;
            }
            reference.insert(key, f.pcf);
        }
    }
    assert_eq!(full.trivial_error().to_bits(), trivial_error.to_bits());
    for d in [&full, &s] {
        for f in d.fragments() {
            assert_eq!(
                f.pcf.to_bits(),
                reference[&(f.view, f.texel, f.layer)].to_bits()
            );
        }
    }
    let kept = s.fragments().len();
    // Systematic allocation: exactly the cap, ⌊p N_h⌋ or ⌈p N_h⌉ per stratum.
    let strata = |d: &Dataset| {
        let mut m = std::collections::BTreeMap::new();
        for f in d.fragments() {
            *m.entry((f.view, f.layer)).or_insert(0usize) += 1;
        }
        m
    };
    let (sf, ss) = (strata(&full), strata(&s));
    assert_eq!(kept, cap);
    // Every cap keeps exactly that many (the smallest, odd ones, one below the population).
    for c in [1, 7, cap + 1, pop - 1, pop] {
        let plan = SamplePlan {
            max_fragments: Some(c),
            seed: 3,
        };
        let d = Dataset::from_stacks(&stacks, &grid, &bias, &plan).unwrap();
        assert_eq!(d.fragments().len(), c, "cap {c}");
    }
    let p = cap as f64 / pop as f64;
    for (k, &n) in &sf {
        let got = *ss.get(k).unwrap_or(&0) as f64;
        assert!(
            (got - p * n as f64).abs() < 1.0 + 1e-9,
            "{k:?}: {got} of {n}"
        );
    }
    // Seeded: same seed, same sample; another seed, another sample.
    let again = Dataset::from_stacks(&stacks, &grid, &bias, &plan).unwrap();
    assert_eq!(again.fingerprint(), s.fingerprint());
    let other = Dataset::from_stacks(
        &stacks,
        &grid,
        &bias,
        &SamplePlan {
            max_fragments: Some(cap),
            seed: 10,
        },
    )
    .unwrap();
    assert_ne!(other.fingerprint(), s.fingerprint());
    // Estimate of the PCF mean (a fragment statistic with no LP) within 4 standard errors.
    let stat = |d: &Dataset| {
        let v: Vec<f64> = d.fragments().iter().map(|f| f.pcf).collect();
        let sum: f64 = v.iter().sum();
        let sumsq: f64 = v.iter().map(|x| x * x).sum();
        d.error_estimate(v.len() as u64, sum, sumsq)
    };
    let (exact, se0) = stat(&full);
    let (est, se) = stat(&s);
    assert!(se0 > 0.0 && se > se0);
    assert!((est - exact).abs() < 4.0 * se, "{est} vs {exact} ± {se}");
    assert!(Dataset::from_stacks(
        &stacks,
        &grid,
        &bias,
        &SamplePlan {
            max_fragments: Some(0),
            seed: 1
        }
    )
    .is_err());
}

/// The references a [`ReferenceCache`] keeps for the next sweep (as `reproduce` sweeps m = 2, 3
/// and 4) equal the references a fresh cache computes, for each m, and a dataset that changed
/// (another sample) gets its own LP references, not the kept ones.
#[test]
fn kept_references_equal_fresh_ones() {
    let stacks = [stack(11, 24, 20, 3), stack(12, 20, 24, 2)];
    let grid = Grid::uniform(64).unwrap();
    let table = load_table(None, &grid).unwrap();
    let shared = ReferenceCache::new(Some(&stacks[..]));
    for (tag, max_fragments) in [("all", None), ("capped", Some(120))] {
        let plan = SamplePlan {
            max_fragments,
            seed: 1,
        };
        let data = Dataset::from_stacks(&stacks, &grid, &Bias::default(), &plan).unwrap();
        for (m, names) in [(1, "z;z^2;exp(40z)"), (2, "z,z^2;z,exp(-10z);z^2,sin(πz)")] {
            let opts = SweepOptions {
                m,
                grid: grid.len(),
                chunk: 64,
                max_fragments,
                exhaustive: true,
                names: Some(names.to_string()),
                ..SweepOptions::default()
            };
            let run = |refs: &ReferenceCache, t: &str| {
                let dir = tmp_path(&format!("kept-refs-{tag}-m{m}-{t}"));
                let r = sweep_dataset(&data, &table, refs, &opts, &dir, None).unwrap();
                std::fs::remove_dir_all(&dir).ok();
                r.references
            };
            let kept = run(&shared, "kept");
            let fresh = run(&ReferenceCache::new(Some(&stacks[..])), "fresh");
            assert_eq!(kept, fresh, "{tag}, m = {m}");
            assert!(kept.iter().any(|r| r.closed_form) && kept.iter().any(|r| r.diff.is_some()));
        }
    }
}
