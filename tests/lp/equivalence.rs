//! The fast solver against the reference (good_lp + microlp) on random and degenerate
//! instances of Algorithm 1.

use crate::common::lp::check_support;
use momentlab::basis::Catalog;
use momentlab::bench::instances::{
    kernel_patches, mixture_moments, power_table, random_mixture, smooth_functions, table_of,
    SmoothFn,
};
use momentlab::lp::FastSolver;
use momentlab::lp::ReferenceSolver;
use momentlab::lp::{support_reproduces, GridTable, MomentSolver, Solution, Status};
use momentlab::Grid;
use rand::seq::SliceRandom;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

const TOL_G: f64 = 1e-9;

/// A random distinct m-subset of the built-in smooth functions.
fn random_basis(rng: &mut ChaCha8Rng, m: usize) -> Vec<SmoothFn> {
    let mut all = smooth_functions();
    all.shuffle(rng);
    all.truncate(m);
    all
}

fn pick_zf(rng: &mut ChaCha8Rng, z: &[f64], mixture: &[(usize, f64)]) -> f64 {
    match rng.gen_range(0..6) {
        0 => rng.gen_range(0.0..=1.0),
        1 => z[rng.gen_range(0..z.len())],
        2 | 3 => z[mixture[rng.gen_range(0..mixture.len())].0],
        4 => 0.0,
        _ => 1.0,
    }
}

/// Mixture kinds: general (1–6 Diracs), a single Dirac, or a boundary point of the moment
/// space (fewer Diracs, or Diracs at the grid's end points).
fn pick_mixture(rng: &mut ChaCha8Rng, n: usize, m: usize) -> Vec<(usize, f64)> {
    match rng.gen_range(0..5) {
        0 => random_mixture(rng, n, 1),
        1 => {
            // Boundary: fewer than (m+1)/2 interior atoms, or an end point.
            let k = rng.gen_range(1..=(m / 2).max(1));
            let mut mix = random_mixture(rng, n, k);
            if rng.gen_bool(0.5) {
                let end = if rng.gen_bool(0.5) { 0 } else { n - 1 };
                if !mix.iter().any(|&(i, _)| i == end) {
                    mix[0].0 = end;
                }
            }
            mix
        }
        _ => {
            let k = rng.gen_range(1..=6);
            random_mixture(rng, n, k)
        }
    }
}

/// Tables whose [1, b] is worse conditioned than this on the grid are numerically
/// rank-deficient candidates (reported as degenerate by the sweep, not solved).
const COND_MAX: f64 = 1e8;
/// Where the rounding bound of the final basis exceeds 1e-9 (clustered support on a fine
/// grid), G is not determined to 1e-9 by double-precision moments: compare within this
/// multiple of the bound instead, and count such instances separately.
const BOUND_FACTOR: f64 = 10.0;
/// ... and never more than this absolute difference.
const LOOSE_MAX: f64 = 1e-4;

#[derive(Default)]
struct Tally {
    /// Feasible instances compared at 1e-9.
    strict: usize,
    /// Feasible instances whose |ΔG| > 1e-9 is within the rounding bound.
    loose: usize,
    infeasible: usize,
    skipped_tables: usize,
    /// Feasible instances (certified by the mixture) that the reference calls infeasible, and
    /// reference errors.
    reference_misreports: usize,
    /// Fast answers `failed` (no certificate either way; allowed by the contract, bounded).
    unsettled: usize,
    max_diff: f64,
    max_loose: f64,
    failures: Vec<String>,
}

impl Tally {
    fn compare(&mut self, what: &str, fast: &Solution, bound: f64, r: &Solution) {
        if fast.status != r.status {
            self.failures.push(format!(
                "{what}: status {:?} vs ref {:?}",
                fast.status, r.status
            ));
            return;
        }
        let d = (fast.g - r.g).abs();
        if d <= TOL_G {
            self.strict += 1;
            self.max_diff = self.max_diff.max(d);
        } else if d <= LOOSE_MAX && d <= BOUND_FACTOR * bound {
            self.loose += 1;
            self.max_loose = self.max_loose.max(d);
            if self.loose <= 5 {
                eprintln!("loose: {what}: diff {d:e} bound {bound:e}");
            }
        } else {
            self.failures.push(format!(
                "{what}: G fast {} ref {} (diff {d:e}, bound {bound:e})",
                fast.g, r.g
            ));
        }
    }

    /// The mixture certifies feasibility, but the reference says infeasible (microlp's phase-1
    /// tolerances): count it; the fast solutions must still be valid distributions with these
    /// moments and no worse than the mixture itself.
    fn misreport(
        &mut self,
        table: &GridTable,
        b: &[f64],
        zf: f64,
        mix: &[(usize, f64)],
        sols: &[&Solution],
        what: &str,
    ) {
        self.reference_misreports += 1;
        let z = table.grid().points();
        let g_mix: f64 = mix
            .iter()
            .filter(|&&(i, _)| z[i] < zf)
            .map(|&(_, w)| w)
            .sum();
        for sol in sols {
            let w = format!("(reference misreport): {what}");
            if let Err(e) = check_support(table, b, zf, sol, 1e-8) {
                self.failures.push(format!("{w}: {e}"));
            } else if sol.g > g_mix + 1e-8 {
                // 1e-8: b is the mixture's moments rounded to f64 (see below).
                self.failures
                    .push(format!("{w}: G {} > mixture {g_mix}", sol.g));
            }
        }
    }

    fn finish(&self, min_strict: usize) {
        self.finish_with(min_strict, 50, 1000, 50);
    }

    /// `loose_ratio`: at most one instance within the rounding bound per this many strict ones.
    /// `misreport_ratio`: at most one reference misreport per this many strict instances.
    /// `unsettled_ratio`: at most one `failed` answer per this many strict ones.
    fn finish_with(
        &self,
        min_strict: usize,
        loose_ratio: usize,
        misreport_ratio: usize,
        unsettled_ratio: usize,
    ) {
        eprintln!(
            "{} instances equal to 1e-9 (max |dG| {:e}), {} within the rounding bound (max |dG| {:e}), {} infeasible, {} tables skipped (cond > {COND_MAX:e}), {} reference misreports",
            self.strict, self.max_diff, self.loose, self.max_loose, self.infeasible, self.skipped_tables, self.reference_misreports
        );
        for f in self.failures.iter().take(10) {
            eprintln!("FAIL {f}");
        }
        eprintln!("{} unsettled (failed) fast answers", self.unsettled);
        assert!(self.failures.is_empty(), "{} failures", self.failures.len());
        assert!(
            self.unsettled * unsettled_ratio <= self.strict,
            "too many unsettled: {}",
            self.unsettled
        );
        assert!(
            self.strict >= min_strict,
            "only {} strict instances",
            self.strict
        );
        assert!(
            self.reference_misreports * misreport_ratio <= self.strict,
            "too many reference misreports: {}",
            self.reference_misreports
        );
        assert!(
            self.loose * loose_ratio <= self.strict,
            "too many ill-posed instances: {}",
            self.loose
        );
    }
}

/// A random basis: names, table on `grid`, m.
type MakeTable<'a> = &'a dyn Fn(&mut ChaCha8Rng, &Grid) -> (Vec<String>, GridTable, usize);

/// Random subsets of the built-in smooth functions, m = 1…8 (m = 4 favoured).
fn builtin_basis(rng: &mut ChaCha8Rng, grid: &Grid) -> (Vec<String>, GridTable, usize) {
    let m = if rng.gen_bool(0.4) {
        4
    } else {
        rng.gen_range(1..=8)
    };
    let fns = random_basis(rng, m);
    let names = fns.iter().map(|f| f.0.to_string()).collect();
    (names, table_of(grid, &fns).unwrap(), m)
}

/// Random 4-subsets of the embedded basis-function catalog.
fn catalog_basis(rng: &mut ChaCha8Rng, grid: &Grid) -> (Vec<String>, GridTable, usize) {
    let cat = Catalog::embedded();
    let mut idx: Vec<usize> = (0..cat.len()).collect();
    idx.shuffle(rng);
    idx.truncate(4);
    let names: Vec<String> = idx
        .iter()
        .map(|&i| cat.functions()[i].name().to_string())
        .collect();
    let basis = cat.basis(&names).unwrap();
    let table = GridTable::from_fn(grid, 4, |z, out| basis.eval(z, out)).unwrap();
    (names, table, 4)
}

fn run_family(
    seed: u64,
    tables: usize,
    per_table: usize,
    ns: &[usize],
    make: MakeTable,
    tally: &mut Tally,
) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    for t in 0..tables {
        let n = ns[rng.gen_range(0..ns.len())];
        let grid = Grid::uniform(n).unwrap();
        let (names, table, m) = make(&mut rng, &grid);
        let mut fast = FastSolver::new(table.clone());
        if fast.condition() > COND_MAX {
            tally.skipped_tables += 1;
            continue;
        }
        let mut cold = FastSolver::new(table.clone());
        cold.set_warm_start(false);
        let mut reference = ReferenceSolver::new(table.clone());
        for p in 0..per_table {
            let mix = pick_mixture(&mut rng, n, m);
            let b = mixture_moments(&table, &mix);
            // Several z_f per moment vector, as in evaluation (exercises warm start).
            for _ in 0..3 {
                let zf = pick_zf(&mut rng, grid.points(), &mix);
                let what = format!(
                    "seed {seed} table {t} problem {p}: n {n} basis {names:?} mix {mix:?} zf {zf} warm basis {:?}",
                    fast.warm_basis()
                );
                // A reference error (microlp: "singular matrix") counts like a misreport.
                let r = reference
                    .solve(&b, zf)
                    .unwrap_or_else(|_| Solution::infeasible());
                let (f, c) = match (fast.solve(&b, zf), cold.solve(&b, zf)) {
                    (Ok(f), Ok(c)) => (f, c),
                    (f, c) => {
                        tally.failures.push(format!(
                            "fast error: {what}: warm {:?} cold {:?} (cond {:e})",
                            f.err(),
                            c.err(),
                            fast.condition()
                        ));
                        continue;
                    }
                };
                if f.status == Status::Failed || c.status == Status::Failed {
                    for sol in [&f, &c] {
                        if sol.status == Status::Failed && !(sol.g.is_nan() && sol.reason.is_some())
                        {
                            tally.failures.push(format!("{what}: failed with a value"));
                        }
                    }
                    tally.unsettled += 1;
                    continue;
                }
                let fb = fast.last_error_bound();
                let cb = cold.last_error_bound();
                if r.status != Status::Optimal || !support_reproduces(&table, &b, &r, 1e-6) {
                    // The mixture certifies feasibility: a reference misreport (microlp's
                    // phase-1 tolerances, or a support that misses a tiny moment). The fast solution must still be a valid
                    // distribution no worse than the mixture itself.
                    tally.reference_misreports += 1;
                    let g_mix: f64 = mix
                        .iter()
                        .filter(|&&(i, _)| grid.points()[i] < zf)
                        .map(|&(_, w)| w)
                        .sum();
                    for (sol, name) in [(&f, "warm"), (&c, "cold")] {
                        let w = format!("{name} (reference misreport): {what}");
                        if let Err(e) = check_support(&table, &b, zf, sol, 1e-8) {
                            tally.failures.push(format!("{w}: {e}"));
                        } else if sol.g > g_mix + 1e-8 {
                            // 1e-8: b is the mixture's moments rounded to f64, which moves
                            // the optimum of clustered problems by |y|·ε (duals ~1e8).
                            tally
                                .failures
                                .push(format!("{w}: G {} > mixture {g_mix}", sol.g));
                        }
                    }
                    continue;
                }
                tally.compare(&what, &f, fb, &r);
                tally.compare(&format!("cold: {what}"), &c, cb, &r);
                for (sol, name) in [(&f, "warm"), (&c, "cold")] {
                    if let Err(e) = check_support(&table, &b, zf, sol, 1e-8) {
                        tally.failures.push(format!("{name}: {what}: {e}"));
                    }
                }
            }
            // An infeasible neighbour: push b outside the convex hull of the grid columns
            // along a random direction ℓ, by a clear margin.
            if p % 4 == 0 {
                let l: Vec<f64> = (0..m).map(|_| rng.gen_range(-1.0..1.0)).collect();
                let proj = |v: &[f64]| v.iter().zip(&l).map(|(a, b)| a * b).sum::<f64>();
                let hmax = (0..n).map(|i| proj(table.row(i))).fold(f64::MIN, f64::max);
                let ll = proj(&l);
                let scale = (0..n)
                    .flat_map(|i| table.row(i).iter().map(|v| v.abs()))
                    .fold(0.0, f64::max);
                let margin = 1e-3 * scale * ll.sqrt();
                let step = (hmax - proj(&b) + margin) / ll;
                let bad: Vec<f64> = b.iter().zip(&l).map(|(a, d)| a + step * d).collect();
                let zf = rng.gen_range(0.0..=1.0);
                let what = format!("infeasible: seed {seed} table {t} basis {names:?} b {bad:?}");
                let r = reference.solve(&bad, zf);
                let f = fast.solve(&bad, zf).unwrap();
                let r_infeasible = r.as_ref().map(|r| r.status == Status::Infeasible);
                if f.status == Status::Failed {
                    tally.unsettled += 1;
                    continue;
                }
                if r_infeasible.is_err() {
                    tally.reference_misreports += 1;
                }
                if matches!(r_infeasible, Ok(false)) || f.status != Status::Infeasible {
                    let r = r.map(|r| r.status);
                    tally
                        .failures
                        .push(format!("{what}: ref {r:?} fast {:?}", f.status));
                } else if !(f.g.is_nan() && f.support.is_empty()) {
                    tally
                        .failures
                        .push(format!("{what}: infeasible with a solution"));
                } else {
                    tally.infeasible += 1;
                }
            }
        }
    }
}

#[test]
fn fast_equals_reference_on_random_instances() {
    let mut tally = Tally::default();
    run_family(
        1,
        200,
        12,
        &[16, 24, 32, 48, 64],
        &builtin_basis,
        &mut tally,
    );
    run_family(2, 40, 10, &[128], &builtin_basis, &mut tally);
    tally.finish(7000);
}

#[test]
fn fast_equals_reference_on_catalog_candidates() {
    let mut tally = Tally::default();
    run_family(3, 120, 8, &[24, 32, 64, 128], &catalog_basis, &mut tally);
    // microlp misreports about 0.3 % of these: supports that miss the tiny moments of
    // exp(−40z)-type catalog entries by orders of magnitude (the fast answers are then checked
    // against the mixture instead).
    tally.finish_with(2000, 50, 200, 50);
}

#[test]
fn power_basis_matches_reference() {
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let mut tally = Tally::default();
    for &n in &[17usize, 33, 64] {
        for m in 1..=6 {
            let grid = Grid::uniform(n).unwrap();
            let table = power_table(&grid, m).unwrap();
            let mut fast = FastSolver::new(table.clone());
            let mut reference = ReferenceSolver::new(table.clone());
            for _ in 0..40 {
                let mix = pick_mixture(&mut rng, n, m);
                let b = mixture_moments(&table, &mix);
                let zf = pick_zf(&mut rng, grid.points(), &mix);
                let r = reference.solve(&b, zf).unwrap();
                let f = fast.solve(&b, zf).unwrap();
                let what = format!("power m {m} n {n} mix {mix:?} zf {zf}");
                tally.compare(&what, &f, fast.last_error_bound(), &r);
                if let Err(e) = check_support(&table, &b, zf, &f, 1e-8) {
                    tally.failures.push(format!("{what}: {e}"));
                }
            }
        }
    }
    tally.finish(3 * 6 * 40 * 9 / 10);
}

/// Realistic problems (9×9 Gaussian kernels over depth maps with 1–3 clusters, the MSM power
/// basis) at n = 256 and n = 1024, the benchmark's distribution.
#[test]
fn kernel_problems_match_reference_at_1024() {
    let mut tally = Tally::default();
    for &(n, patches) in &[(256usize, 100usize), (1024, 50)] {
        let grid = Grid::uniform(n).unwrap();
        let table = power_table(&grid, 4).unwrap();
        let mut rng = ChaCha8Rng::seed_from_u64(11 + n as u64);
        let mut fast = FastSolver::new(table.clone());
        let mut reference = ReferenceSolver::new(table.clone());
        for (k, patch) in kernel_patches(&mut rng, &grid, patches).iter().enumerate() {
            let b = mixture_moments(&table, &patch.mixture);
            for &zf in &patch.zf {
                let what = format!("kernel n {n} patch {k}: b {b:?} zf {zf}");
                let r = match reference.solve(&b, zf) {
                    Ok(r) => r,
                    Err(e) => {
                        tally.failures.push(format!("{what}: reference: {e}"));
                        continue;
                    }
                };
                let f = fast.solve(&b, zf).unwrap();
                if f.status == Status::Failed {
                    tally.unsettled += 1;
                    continue;
                }
                if r.status == Status::Infeasible {
                    tally.misreport(&table, &b, zf, &patch.mixture, &[&f], &what);
                    continue;
                }
                tally.compare(&what, &f, fast.last_error_bound(), &r);
                if let Err(e) = check_support(&table, &b, zf, &f, 1e-8) {
                    tally.failures.push(format!("{what}: {e}"));
                }
            }
        }
    }
    // Kernel problems at z_f on the receiver's own cluster are ill-posed at 1e-9 much more
    // often than random mixtures: allow up to a fifth of them within the rounding bound.
    // From the moments alone (no distribution to start from) about 6 % of these come back
    // `failed`: the f64 moments of a window on 2–3 neighbouring grid points leave G open
    // beyond 1e-9 (docs/lp.md). None would be the goal; this bounds the share.
    tally.finish_with(300, 5, 100, 10);
}
