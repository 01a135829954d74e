//! Exact optimality certificates for the fast solver on realistic kernel problems.
//!
//! On moment vectors of real filter kernels (a 9×9 Gaussian over 1–3 planar depth clusters,
//! the `bench lp` problems) the LP of Algorithm 1 is badly conditioned: the optimal support
//! consists of neighbouring grid points, bases have condition numbers of 1e6–1e9, and a
//! general LP solver with tolerances around 1e-9 is no longer an oracle (microlp's answers
//! violate the moment equations by up to 5e-8 and are then off by up to 0.1 in G). So here
//! the oracle is exact rational arithmetic on the LP exactly as both solvers see it (the f64
//! grid table and f64 moments): for the basis B the fast solver ends on we compute
//! x = B⁻¹b̄ and the duals y = c_Bᵀ B⁻¹ exactly and check x ≥ 0 and every reduced cost
//! c_j − yᵀa_j ≥ 0. Both hold ⇔ B is an optimal basis, and Σ_{z_i < z_f} x_i is the exact
//! G(b, z_f). A reduced cost of −δ < 0 still bounds the gap: G_B − G* ≤ δ (shift y along the
//! constant row).

#![allow(clippy::needless_range_loop)] // exact Gaussian elimination on small matrices

use momentlab::bench::corpus;
use momentlab::bench::instances::power_table;
use momentlab::bench::kernels::problems;
use momentlab::lp::FastSolver;
use momentlab::lp::ReferenceSolver;
use momentlab::lp::{GridTable, MomentSolver, Status};
use momentlab::Grid;
use num_bigint::BigInt;
use num_rational::BigRational;
use num_traits::{One, Signed, ToPrimitive, Zero};

/// Exact value of an f64.
fn q(x: f64) -> BigRational {
    BigRational::from_float(x).expect("finite")
}

/// Solve the square system M v = rhs exactly (Gaussian elimination); None if singular.
fn solve_exact(
    mut m: Vec<Vec<BigRational>>,
    mut rhs: Vec<BigRational>,
) -> Option<Vec<BigRational>> {
    let r = rhs.len();
    for c in 0..r {
        let p = (c..r).find(|&i| !m[i][c].is_zero())?;
        m.swap(c, p);
        rhs.swap(c, p);
        for i in 0..r {
            if i != c && !m[i][c].is_zero() {
                let f = &m[i][c] / &m[c][c];
                for k in c..r {
                    let v = &f * &m[c][k];
                    m[i][k] -= v;
                }
                let v = &f * &rhs[c];
                rhs[i] -= v;
            }
        }
    }
    Some((0..r).map(|i| &rhs[i] / &m[i][i]).collect())
}

/// What the exact check of a basis found.
#[derive(Debug)]
struct Certificate {
    /// Smallest basic weight (exact, rounded to f64): ≥ 0 ⇔ primal feasible.
    min_weight: f64,
    /// Smallest reduced cost over all columns (exact, rounded): ≥ 0 ⇔ dual feasible.
    min_reduced_cost: f64,
    /// Σ_{z_i < z_f} x_i of the basic solution (exact, rounded).
    g: f64,
    /// The columns with a negative reduced cost (exact, rounded).
    negative: Vec<(usize, f64)>,
}

impl Certificate {
    fn optimal(&self) -> bool {
        self.min_weight >= 0.0 && self.min_reduced_cost >= 0.0
    }
}

/// Exact certificate of `basis` (grid indices, m + 1 of them) for the LP on `table`.
fn certify(table: &GridTable, moments: &[f64], zf: f64, basis: &[usize]) -> Certificate {
    let mut bbar = vec![BigRational::one()];
    bbar.extend(moments.iter().map(|&v| q(v)));
    certify_rhs(table, bbar, zf, basis)
}

/// [`certify`] for the exact right-hand side b̄ = [1; b] (rationals).
fn certify_rhs(table: &GridTable, bbar: Vec<BigRational>, zf: f64, basis: &[usize]) -> Certificate {
    let (n, m) = (table.n(), table.m());
    assert_eq!(basis.len(), m + 1, "full-rank basis expected");
    let z = table.grid().points();
    let col = |i: usize| -> Vec<f64> {
        let mut c = vec![1.0];
        c.extend_from_slice(table.row(i));
        c
    };
    let bm: Vec<Vec<BigRational>> = (0..=m)
        .map(|k| basis.iter().map(|&i| q(col(i)[k])).collect())
        .collect();
    let x = solve_exact(bm.clone(), bbar).expect("basis singular in exact arithmetic");
    let cost = |i: usize| (z[i] < zf) as i64;
    let bt: Vec<Vec<BigRational>> = (0..=m)
        .map(|t| (0..=m).map(|k| bm[k][t].clone()).collect())
        .collect();
    let cb: Vec<BigRational> = basis
        .iter()
        .map(|&i| BigRational::from_integer(cost(i).into()))
        .collect();
    let y = solve_exact(bt, cb).expect("basis singular in exact arithmetic");
    // Reduced costs over a common denominator: y = Y / D, a_j = A_j / 2^S (every table entry
    // is an f64 in [−2^60, 2^60] with exponent ≥ −S), so d_j has the sign of
    // c_j D 2^S − Y·A_j.
    const S: u32 = 256;
    let d = y.iter().fold(BigInt::one(), |acc, v| {
        num_integer::lcm(acc, v.denom().clone())
    });
    let yi: Vec<BigInt> = y.iter().map(|v| v.numer() * (&d / v.denom())).collect();
    let scale = BigInt::one() << S;
    let as_int = |v: f64| -> BigInt {
        let r = q(v) * BigRational::from_integer(scale.clone());
        assert!(r.is_integer(), "table entry {v:e} below 2^-{S}");
        r.to_integer()
    };
    let den = BigRational::from_integer(&d * &scale);
    let mut min_d: Option<BigRational> = None;
    let mut negative = Vec::new();
    for j in 0..n {
        let a = col(j);
        let mut num = BigInt::from(cost(j)) * &d * &scale;
        for k in 0..=m {
            num -= &yi[k] * as_int(a[k]);
        }
        if num.is_negative() {
            let v = BigRational::new(num.clone(), &d * &scale);
            negative.push((j, v.to_f64().expect("finite")));
        }
        if min_d.as_ref().is_none_or(|v| num < *v.numer()) {
            min_d = Some(BigRational::new_raw(num, BigInt::one()));
        }
    }
    let min_d = min_d.expect("columns") / den;
    let g: BigRational = basis
        .iter()
        .zip(&x)
        .filter(|(&i, _)| cost(i) == 1)
        .map(|(_, v)| v.clone())
        .sum();
    let min_w = x.iter().min().expect("weights").clone();
    let f = |v: &BigRational| {
        if v.is_zero() {
            0.0
        } else {
            let s = v.to_f64().expect("finite");
            // Keep the sign of tiny values exact.
            if s == 0.0 {
                if v.is_negative() {
                    -f64::MIN_POSITIVE
                } else {
                    f64::MIN_POSITIVE
                }
            } else {
                s
            }
        }
    };
    Certificate {
        min_weight: f(&min_w),
        min_reduced_cost: f(&min_d),
        g: f(&g),
        negative,
    }
}

#[derive(Default, Debug)]
struct Tally {
    solved: usize,
    exactly_optimal: usize,
    /// Bases with x ≥ −1e-12 and reduced costs ≥ −1e-9 but not exactly optimal.
    near_optimal: usize,
    max_gap_bound: f64,
    max_g_error: f64,
    /// Answers `failed` (no certificate either way).
    unsettled: u64,
}

/// Run `count` realistic problems at grid size n through a fast solver (from the moments or
/// from the kernel's distribution) and certify every answer.
fn run(n: usize, count: usize, seed: u64, from_distribution: bool) -> (Tally, Vec<(f64, f64)>) {
    let grid = Grid::uniform(n).unwrap();
    let table = power_table(&grid, 4).unwrap();
    let probs = problems(&grid, 4, count, seed).unwrap();
    let mut fast = FastSolver::new(table.clone());
    let mut t = Tally::default();
    let mut exact = Vec::new();
    for (k, p) in probs.iter().enumerate() {
        let sol = if from_distribution {
            fast.solve_distribution(&p.dist, p.zf)
        } else {
            fast.solve(&p.moments, p.zf)
        }
        .unwrap();
        assert_ne!(
            sol.status,
            Status::Infeasible,
            "problem {k}: kernel moments are feasible"
        );
        if sol.status == Status::Failed {
            // Unsettled (`failed`, no certificate either way): no basis to check.
            t.unsettled += 1;
            exact.push((f64::NAN, sol.g));
            continue;
        }
        let basis = fast.warm_basis().expect("optimal basis").to_vec();
        let c = certify(&table, &p.moments, p.zf, &basis);
        t.solved += 1;
        assert!(
            c.min_weight >= -1e-12 && c.min_reduced_cost >= -1e-9,
            "problem {k} (n = {n}): basis {basis:?} not optimal: {c:?}"
        );
        if c.optimal() {
            t.exactly_optimal += 1;
        } else {
            t.near_optimal += 1;
        }
        t.max_gap_bound = t.max_gap_bound.max(-c.min_reduced_cost);
        let err = (sol.g - c.g).abs();
        // The weights of a basis with condition κ carry errors of about κ·ε.
        let allowed = 1e-9_f64.max(10.0 * fast.last_error_bound());
        assert!(
            err <= allowed,
            "problem {k} (n = {n}): G {} vs exact {} (error {err:e} > {allowed:e})",
            sol.g,
            c.g
        );
        t.max_g_error = t.max_g_error.max(err);
        exact.push((c.g, sol.g));
    }
    (t, exact)
}

/// Every basis was optimal to 1e-9 (asserted in `run`); at least `percent` % of them exactly.
fn check(t: &Tally, what: &str, percent: usize) {
    eprintln!("{what}: {t:?}");
    // About 3 % of the benchmark's kernel problems come back `failed` (z_f on a cluster of
    // 2–3 neighbouring grid points; docs/lp.md). None would be the goal; this
    // bounds the share.
    assert!(
        t.unsettled * 20 <= (t.solved as u64 + t.unsettled),
        "{what}: too many unsettled"
    );
    assert!(
        t.exactly_optimal * 100 >= percent * t.solved,
        "{what}: only {} of {} bases exactly optimal",
        t.exactly_optimal,
        t.solved
    );
}

#[test]
fn fast_bases_are_exactly_optimal_on_kernel_problems_from_moments() {
    let (t, exact) = run(1024, 160, 21, false);
    check(&t, "n = 1024, from the moments", 95);
    // The reference on the same problems, against the exact G: report how often it is off.
    let grid = Grid::uniform(1024).unwrap();
    let table = power_table(&grid, 4).unwrap();
    let probs = problems(&grid, 4, 160, 21).unwrap();
    let mut reference = ReferenceSolver::new(table);
    let (mut off, mut worst, mut total) = (0, 0.0f64, 0);
    for (p, &(g_exact, g_fast)) in probs.iter().zip(&exact).step_by(4) {
        if g_exact.is_nan() {
            continue;
        }
        let r = reference.solve(&p.moments, p.zf).unwrap();
        total += 1;
        let e = (r.g - g_exact).abs();
        worst = worst.max(e);
        if e > 1e-6 {
            off += 1;
        }
        // The fast solver is never the less accurate of the two by more than rounding.
        assert!(
            (g_fast - g_exact).abs() <= e + 1e-9,
            "fast {g_fast}, reference {}, exact {g_exact}",
            r.g
        );
    }
    eprintln!("reference: {off} of {total} off the exact G by > 1e-6 (worst {worst:e})");
}

/// The answers of the exact simplex (src/lp/fast/escalate/exact/, the last resort after the scaled
/// simplex) on the adversarial corpus, checked here by independent rational arithmetic: its
/// basis is exactly optimal for the distribution's exact moments Σ w_i ā_i / Σ w_i, and the G
/// it returns is that basis's exact G rounded.
#[test]
fn exact_simplex_answers_are_exactly_optimal_on_the_adversarial_corpus() {
    let groups = corpus::adversarial(6, false, 7).unwrap();
    let mut checked = 0;
    for g in groups.iter().filter(|g| g.table.m() >= 8) {
        let mut s = FastSolver::new(g.table.clone());
        let m = g.table.m();
        for p in &g.problems {
            for &zf in &p.zf {
                let sol = s.solve_distribution(&p.dist, zf).unwrap();
                let Some(basis) = s.last_exact_basis() else {
                    continue;
                };
                assert_eq!(sol.status, Status::Optimal, "{}", g.name);
                let total: BigRational = p.dist.iter().map(|e| q(e.1)).sum();
                let bbar: Vec<BigRational> = (0..=m)
                    .map(|j| {
                        let a = |i: u32| {
                            if j == 0 {
                                1.0
                            } else {
                                g.table.row(i as usize)[j - 1]
                            }
                        };
                        let s: BigRational = p.dist.iter().map(|&(i, w)| q(w) * q(a(i))).sum();
                        s / &total
                    })
                    .collect();
                let c = certify_rhs(&g.table, bbar, zf, basis);
                assert!(c.optimal(), "{}: {c:?}", g.name);
                assert!(
                    (c.g - sol.g).abs() <= 2.0 * f64::EPSILON,
                    "{}: G {} vs exact {}",
                    g.name,
                    sol.g,
                    c.g
                );
                checked += 1;
            }
        }
    }
    eprintln!("exact simplex answers checked: {checked}");
    assert!(checked >= 5, "{checked}");
}

#[test]
fn fast_bases_are_exactly_optimal_on_kernel_problems_from_distributions() {
    let (t, _) = run(1024, 160, 22, true);
    check(&t, "n = 1024, from the distribution", 95);
}

#[test]
fn fast_bases_are_exactly_optimal_at_other_grid_sizes() {
    // At n = 4096 neighbouring grid points are 2.4e-4 apart: reduced costs of the optimal
    // basis' neighbours are at the 1e-10 tolerance, so some bases are optimal to 1e-10 only.
    for (n, seed, percent) in [(256, 23, 95), (4096, 24, 80)] {
        let (t, _) = run(n, 60, seed, false);
        check(&t, &format!("n = {n}"), percent);
    }
}

/// Regression: 5 clustered Diracs, m = 6 power moments on a 52-point grid over [−1, 2]. The
/// first optimum's f64 weights (off by ~1e-3 from the basis' exact weights, which are
/// negative) gave G = 0.53821; the double-double refinement exposes them and the accurate
/// rerun gives the sharp bound (Hamburger 6MSM closed form: 0.5397510; microlp 0.5397516).
#[test]
fn clustered_m6_instance_is_rerun_accurately() {
    let d = [
        (0.7982058233879628, 0.16005965822225984),
        (0.8147327810331635, 0.3126368370787691),
        (0.670009305422431, 0.07824145909928222),
        (0.799688706535187, 0.2971493498516808),
        (0.7911884909604461, 0.1519126957480081),
    ];
    let zf = 0.8086966697765896;
    let closed_form_support = [
        0.8086966697765896,
        0.6700108426253251,
        0.7948231718232152,
        0.81715821009066,
    ];
    let power = |z: f64, out: &mut [f64]| {
        let mut p = 1.0;
        for o in out.iter_mut() {
            p *= z;
            *o = p;
        }
    };
    let mut b = vec![0.0; 6];
    let mut tmp = vec![0.0; 6];
    for &(z, w) in &d {
        power(z, &mut tmp);
        for j in 0..6 {
            b[j] += w * tmp[j];
        }
    }
    let mut pts = Grid::uniform_on(41, -1.0, 2.0).unwrap().points().to_vec();
    pts.extend(d.iter().map(|x| x.0));
    pts.push(zf);
    pts.extend(closed_form_support);
    let grid = Grid::from_values(pts).unwrap();
    let table = GridTable::from_fn(&grid, 6, power).unwrap();
    let mut fast = FastSolver::new(table);
    let sol = fast.solve(&b, zf).unwrap();
    assert!(fast.stats().accurate_retries >= 1, "{:?}", fast.stats());
    // Before the certificates this came back `optimal` 1.5e-3 off the closed form; now it is
    // either certified close to it or `failed` (its dual bound and G differ by 2e-8 > 1e-9).
    assert!(
        sol.status == Status::Failed || (sol.g - 0.5397510).abs() < 1e-4,
        "G {} {:?}",
        sol.g,
        sol.reason
    );
}

/// Regression: a numerically singular optimal basis (condition ~1e11 on a well-conditioned
/// table; the refined weights move along its near-null direction). The solver must answer
/// without falling back, with a distribution that reproduces the moments.
#[test]
fn numerically_singular_optimal_basis_still_answers() {
    let cat = momentlab::basis::Catalog::embedded();
    let names: Vec<String> = ["z^(1/3)", "z^5", "exp(-40z)", "tanh(4z)"]
        .iter()
        .map(|s| s.to_string())
        .collect();
    let basis = cat.basis(&names).unwrap();
    let grid = Grid::uniform(64).unwrap();
    let table = GridTable::from_fn(&grid, 4, |z, out| basis.eval(z, out)).unwrap();
    let mix = [
        (57usize, 0.36573955210386344),
        (47, 0.1788157627802305),
        (48, 0.29247352333857),
        (56, 0.16297116177733595),
    ];
    let b = momentlab::bench::instances::mixture_moments(&table, &mix);
    let zf = 0.7619047619047619;
    for warm in [true, false] {
        let mut fast = FastSolver::new(table.clone());
        if warm {
            fast.set_warm_basis(&[62, 52, 51, 40, 39]).unwrap();
        }
        let sol = fast.solve(&b, zf).unwrap();
        assert_eq!(sol.status, Status::Optimal);
        // The support reproduces the moments.
        let mut got = [0.0; 4];
        let mut tmp = vec![0.0; 4];
        let mut mass = 0.0;
        for &(z, w) in &sol.support {
            basis.eval(z, &mut tmp);
            mass += w;
            for j in 0..4 {
                got[j] += w * tmp[j];
            }
        }
        // The contract (lp::certify): every row to 1e-9 of its own magnitude.
        assert!((mass - 1.0).abs() <= 1e-9, "mass {mass}");
        for j in 0..4 {
            assert!(
                (got[j] - b[j]).abs() <= 1e-9 * b[j].abs(),
                "moment {j}: {} vs {}",
                got[j],
                b[j]
            );
        }
        // No worse than the mixture itself (which is feasible).
        let g_mix: f64 = mix
            .iter()
            .filter(|m| grid.points()[m.0] < zf)
            .map(|m| m.1)
            .sum();
        assert!(sol.g <= g_mix + 1e-9);
    }
}

/// Regression: a window of a rendered stack at n = 4096, 46 atoms in a cluster 0.597…0.611,
/// z_f = 0.795. The optimum holds two pairs of neighbouring grid points and z⁺ with weight
/// 4.5e-8; on the way there the f64 duals of the clustered basis made columns 2483 and 2484
/// swap places for hundreds of pivots (each "improving" by 1e-9) until the iteration cap, and
/// the problem was escalated (1 709 pivots, 6 ms). The answer must be exactly optimal within
/// the contract, found by the fast solver (no escalation) in a handful of pivots.
#[test]
fn clustered_window_at_n4096_does_not_ping_pong() {
    let atoms: [(u32, f64); 46] = [
        (2448, 0.0035618554214704493),
        (2451, 0.0065398909027219575),
        (2453, 0.00549758757164541),
        (2454, 0.010094071401662422),
        (2456, 0.02319083214636087),
        (2458, 0.022712771196571713),
        (2459, 0.014284435012370983),
        (2460, 0.013096760744698446),
        (2461, 0.020214349146474755),
        (2462, 0.020876568244282207),
        (2463, 0.020214349146474755),
        (2464, 0.0220474789399418),
        (2465, 0.024378506414033402),
        (2466, 0.0464418725952962),
        (2467, 0.035720328015221334),
        (2468, 0.028605955437628502),
        (2469, 0.028676573768712584),
        (2470, 0.03216781085909895),
        (2471, 0.03172511102046686),
        (2472, 0.030308420548137177),
        (2473, 0.07524450873476109),
        (2474, 0.030308420548137177),
        (2475, 0.03172511102046686),
        (2476, 0.0452645716037974),
        (2477, 0.04418576846164265),
        (2478, 0.028587369842663756),
        (2479, 0.02734730731903233),
        (2480, 0.02816743563270483),
        (2481, 0.024378506414033402),
        (2482, 0.0220474789399418),
        (2483, 0.023776204567945203),
        (2484, 0.020876568244282207),
        (2485, 0.020214349146474755),
        (2486, 0.018594348316343857),
        (2487, 0.02986424803638512),
        (2488, 0.014265916345115148),
        (2489, 0.013096760744698446),
        (2490, 0.010094071401662422),
        (2491, 0.0077798074995837595),
        (2492, 0.010094071401662422),
        (2493, 0.00549758757164541),
        (2494, 0.007132958172557574),
        (2495, 0.0065398909027219575),
        (2497, 0.00905944299311586),
        (2499, 0.0035618554214704493),
        (2502, 0.0019399121838833847),
    ];
    let zf = 0.7951159951159951;
    let grid = Grid::uniform(4096).unwrap();
    let table = power_table(&grid, 4).unwrap();
    let moments = momentlab::lp::distribution_moments(&table, &atoms).unwrap();
    let mut fast = FastSolver::new(table.clone());
    let sol = fast.solve_distribution(&atoms, zf).unwrap();
    assert_eq!(sol.status, Status::Optimal, "{:?}", sol.reason);
    let stats = fast.stats();
    assert_eq!(stats.escalations, 0, "{stats:?}");
    assert!(stats.pivots <= 50, "{stats:?}");
    let basis = fast.warm_basis().expect("optimal basis").to_vec();
    let c = certify(&table, &moments, zf, &basis);
    assert!(
        c.min_weight >= -1e-12 && c.min_reduced_cost >= -1e-9,
        "basis {basis:?}: {c:?}"
    );
    assert!((sol.g - c.g).abs() <= 1e-9, "G {} exact {}", sol.g, c.g);
}

/// Steep exponentials (exp(±40z) span 10^17 on [0, 1]) under realistic windows: Gaussian kernels
/// over 1–3 planar clusters (flat receivers, tight clusters; `bench::kernels`) and the
/// adversarial corpus's exponential tables. With band solves every answer is certified and
/// the basis it ends on passes the exact rational check (reduced costs ≥ −1e-9 over the whole
/// grid bound G_B − G* by 1e-9, G equals the exact G of the basis within 1e-9, the support
/// reproduces the moments to 1e-9); G equals the escalation's
/// (bands off) within 1e-9; and the escalations drop at least fourfold.
#[test]
fn steep_exponential_windows_are_certified_without_escalation() {
    use momentlab::lp::support_reproduces;
    let grid = Grid::uniform(1024).unwrap();
    let tables: Vec<(&str, GridTable)> = vec![
        (
            "exp(40z), tanh(10(z-0.5))",
            GridTable::from_fn(&grid, 2, |z, o| {
                (o[0], o[1]) = ((40.0 * z).exp(), (10.0 * (z - 0.5)).tanh())
            })
            .unwrap(),
        ),
        (
            "z, z^2, exp(40z), exp(-40z)",
            GridTable::from_fn(&grid, 4, |z, o| {
                o.copy_from_slice(&[z, z * z, (40.0 * z).exp(), (-40.0 * z).exp()])
            })
            .unwrap(),
        ),
        // Optimal bases with an atom at z = 0 (exp(40z)) or with a weight near 1e-9 there
        // (exp(−40z)): the bands' end points.
        (
            "exp(40z), z, z^2",
            GridTable::from_fn(&grid, 3, |z, o| {
                o.copy_from_slice(&[(40.0 * z).exp(), z, z * z])
            })
            .unwrap(),
        ),
        (
            "exp(-40z), exp(40z), z",
            GridTable::from_fn(&grid, 3, |z, o| {
                o.copy_from_slice(&[(-40.0 * z).exp(), (40.0 * z).exp(), z])
            })
            .unwrap(),
        ),
    ];
    /// (distribution, z_f) pairs of one table.
    type Windows = Vec<(Vec<(u32, f64)>, f64)>;
    let mut groups: Vec<(String, GridTable, Windows)> = Vec::new();
    for (name, table) in tables {
        let probs = problems(&grid, 4, 150, 5).unwrap();
        let list = probs.into_iter().map(|p| (p.dist, p.zf)).collect();
        groups.push((name.to_string(), table, list));
    }
    for g in corpus::adversarial(6, false, 7).unwrap() {
        if g.name.contains("exp") && g.table.n() >= 256 {
            let list = g
                .problems
                .iter()
                .flat_map(|p| p.zf.iter().map(|&zf| (p.dist.clone(), zf)))
                .collect();
            groups.push((g.name.clone(), g.table.clone(), list));
        }
    }
    let (mut esc_on, mut esc_off, mut checked, mut solved) = (0u64, 0u64, 0usize, 0usize);
    let mut ill_posed = 0usize;
    for (name, table, list) in &groups {
        let mut on = FastSolver::new(table.clone());
        let mut off = FastSolver::new(table.clone());
        off.set_band_solves(false);
        for (dist, zf) in list {
            let b = momentlab::lp::distribution_moments(table, dist).unwrap();
            let before = on.stats().band_certified;
            let a = on.solve_distribution(dist, *zf).unwrap();
            let o = off.solve_distribution(dist, *zf).unwrap();
            assert_eq!(a.status, Status::Optimal, "{name} zf {zf}: {a:?}");
            assert_eq!(o.status, Status::Optimal, "{name} zf {zf}: {o:?}");
            assert!(
                (a.g - o.g).abs() <= 1e-9,
                "{name} zf {zf}: G {} vs {}",
                a.g,
                o.g
            );
            solved += 1;
            // Certified from a band solve: the basis (the next warm start) checked exactly.
            if on.stats().band_certified > before {
                if let Some(basis) = on.warm_basis().map(<[usize]>::to_vec) {
                    if basis.len() == table.m() + 1 {
                        let c = certify(table, &b, *zf, &basis);
                        // Weak duality (Σ w_i = 1, and the caps w_i ≤ u_i = min(1, b_j / f_j(z_i))
                        // of the positive rows): G_B − G* ≤ min(|min_i d_i|, Σ_{d_i<0} u_i |d_i|).
                        let cap = |i: usize| {
                            (0..table.m())
                                .filter(|&j| (0..table.n()).all(|k| table.row(k)[j] > 0.0))
                                .map(|j| b[j] / table.row(i)[j])
                                .fold(1.0f64, f64::min)
                        };
                        let capped: f64 = c.negative.iter().map(|&(i, d)| -d * cap(i)).sum();
                        let gap = capped.min(-c.min_reduced_cost.min(0.0));
                        assert!(gap <= 1e-9, "{name} zf {zf}: gap {gap:e}, {c:?}");
                        // G of the basis. Where its exact weights on the f64 moments are
                        // negative beyond rounding (flat receivers and clusters under power
                        // rows: neighbouring points, G not determined to 1e-9 by f64 moments,
                        // see docs/lp.md) the certificate judges the positive support instead:
                        // counted as ill-posed, G checked against the escalation's only.
                        let dropped = -c.min_weight.min(0.0);
                        if dropped <= 1e-12 {
                            assert!(
                                (c.g - a.g).abs() <= 1e-9 + dropped,
                                "{name} zf {zf}: {} vs {c:?}",
                                a.g
                            );
                        } else {
                            ill_posed += 1;
                        }
                        // (The exact weights of a degenerate vertex can be ±1e-26 on columns
                        // where a row reaches 1e34: the certificate judges the positive support,
                        // and so does `support_reproduces`.)
                        assert!(support_reproduces(table, &b, &a, 1e-9), "{name}: {a:?}");
                        checked += 1;
                    }
                }
            }
        }
        eprintln!(
            "{name}: escalations {} with band solves, {} without ({} band-certified)",
            on.stats().escalations,
            off.stats().escalations,
            on.stats().band_certified
        );
        esc_on += on.stats().escalations;
        esc_off += off.stats().escalations;
    }
    eprintln!(
        "steep windows: {solved} solved, {checked} band bases checked exactly ({ill_posed} \
         ill-posed), escalations {esc_on} vs {esc_off}"
    );
    assert!(
        10 * ill_posed <= checked,
        "{ill_posed} of {checked} ill-posed"
    );
    assert!(
        esc_off >= 60,
        "the set must exercise the escalation: {esc_off}"
    );
    assert!(
        4 * esc_on <= esc_off,
        "escalations {esc_on} with band solves vs {esc_off}"
    );
    assert!(checked >= 50, "{checked}");
}
