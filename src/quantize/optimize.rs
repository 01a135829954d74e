//! Search for θ maximising log₂|det A| under exact containment (Section 4.3 of the 2015 paper).
//!
//! Method: block-coordinate (row-wise) LP ascent. det A is linear in each row a_i with the
//! cofactor vector c_i as gradient, and each row's feasible set K = {a : max_z a·b(z) −
//! min_z a·b(z) ≤ 1} is convex and symmetric, so the best row given the others is the LP
//! max c_i·a s.t. 0 ≤ a·b(z) + t ≤ 1. The semi-infinite constraint is handled by cutting
//! planes: solve on a finite set of z, ask the curve's extrema oracle (exact derivative roots
//! for polynomials) for the true extrema, add the violated ones, repeat. Work happens in
//! well-conditioned coordinates q = W(b − μ): for the power basis (z, …, z^m) the shifted
//! Chebyshev polynomials q_k = T_k(2z − 1) (W exact integers), for other bases b whitened by
//! its covariance over Chebyshev nodes; the result is mapped back to b (matrix and offset) and
//! verified there. Independent random starts run in parallel (rayon), each with its own RNG
//! stream derived from (seed, start index), so any start can be re-run alone; the best is
//! kept and the share of starts that reach it is reported ([`basin`]). A final
//! tie-break sweep picks, among rows of equal gain, the one with the smallest degree-weighted
//! L1 norm Σ_j e_j |a_j| (prefers low-degree rows, e.g. z instead of z² in θ₂).

use super::curve::{row_min_max, Curve};
use super::linalg::Lu;
use super::theta::{normalize_rows, Theta};
use crate::linalg::dot;
use anyhow::{bail, Result};
use good_lp::{microlp, variable, variables, Expression, Solution as _, SolverModel, Variable};
use rand::{Rng, SeedableRng};
use rayon::prelude::*;

/// Options of [`optimize`].
#[derive(Clone, Debug)]
pub struct Options {
    /// Seed of the random starts.
    pub seed: u64,
    /// Independent random starts.
    pub restarts: usize,
    /// Maximum sweeps over all rows per start.
    pub max_sweeps: usize,
    /// Stop a start when a sweep gains less than this many bits.
    pub tol_bits: f64,
    /// Relative shrink that makes the final θ strictly feasible.
    pub margin: f64,
    /// Basin-hopping steps per start: perturb all rows by relative noise `hop_sigma`,
    /// re-ascend, keep if better.
    pub hops: usize,
    /// Relative noise of a basin-hopping perturbation.
    pub hop_sigma: f64,
    /// Run only these start indices (of 0..restarts) instead of all: re-runs a start of a
    /// seeded search exactly (e.g. the one that reached the best basin) in a fraction of the time.
    pub only_starts: Option<Vec<usize>>,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            seed: 1,
            restarts: 16,
            max_sweeps: 400,
            tol_bits: 1e-9,
            margin: 1e-9,
            hops: 0,
            hop_sigma: 0.2,
            only_starts: None,
        }
    }
}

/// Result of [`optimize`].
#[derive(Clone, Debug)]
pub struct Outcome {
    /// The best θ found (strictly feasible after the `margin` shrink).
    pub theta: Theta,
    /// Gain of each start after convergence (bits), in start order.
    pub start_gains: Vec<f64>,
    /// The start index of each entry of `start_gains` (0..restarts, or `only_starts`).
    pub start_indices: Vec<usize>,
    /// Start index (not position) of the best start.
    pub best_start: usize,
    /// Total LPs solved.
    pub lps: usize,
}

/// Whitened coordinates q = W (b − μ).
struct Frame {
    m: usize,
    w: Vec<Vec<f64>>,
    mu: Vec<f64>,
}

impl Frame {
    fn new(curve: &dyn Curve) -> Result<Frame> {
        let m = curve.dim();
        if curve
            .monomial_exponents()
            .is_some_and(|e| e.iter().copied().eq(1..=m as u32))
        {
            return Ok(Frame::chebyshev(m));
        }
        let n = 2000;
        let mut xs = Vec::with_capacity(n);
        let mut mu = vec![0.0; m];
        for k in 0..n {
            let z = 0.5 * (1.0 - (std::f64::consts::PI * (k as f64 + 0.5) / n as f64).cos());
            let mut b = vec![0.0; m];
            curve.eval(z, &mut b);
            for (u, v) in mu.iter_mut().zip(&b) {
                *u += v / n as f64;
            }
            xs.push(b);
        }
        let mut cov = vec![vec![0.0; m]; m];
        for x in &xs {
            for i in 0..m {
                for j in 0..m {
                    cov[i][j] += (x[i] - mu[i]) * (x[j] - mu[j]) / n as f64;
                }
            }
        }
        // Cholesky cov = L Lᵀ, W = L⁻¹.
        let mut l = vec![vec![0.0; m]; m];
        for i in 0..m {
            for j in 0..=i {
                let s: f64 = cov[i][j] - (0..j).map(|k| l[i][k] * l[j][k]).sum::<f64>();
                if i == j {
                    if !(s > 1e-300) {
                        bail!(
                            "basis functions are linearly dependent (with the constant) on [0,1]"
                        );
                    }
                    l[i][i] = s.sqrt();
                } else {
                    l[i][j] = s / l[j][j];
                }
            }
        }
        let Some(lu) = Lu::new(&l) else {
            bail!("basis functions are linearly dependent on [0,1]");
        };
        Ok(Frame {
            m,
            w: lu.inverse(),
            mu,
        })
    }

    /// Power basis: q_k = T_k(2z − 1), k = 1..m, i.e. W[k][j] = coefficient of z^{j+1} in
    /// T_{k+1}(2z − 1) and W μ = −(T_k(−1))_k = −((−1)^k)_k.
    fn chebyshev(m: usize) -> Frame {
        let (w, c0) = shifted_chebyshev(m);
        let lu = Lu::new(&w).expect("shifted Chebyshev matrix is triangular with nonzero diagonal");
        let mu = lu.solve(&c0.iter().map(|v| -v).collect::<Vec<_>>());
        Frame { m, w, mu }
    }

    fn q(&self, curve: &dyn Curve, z: f64) -> Vec<f64> {
        let mut b = vec![0.0; self.m];
        curve.eval(z, &mut b);
        let d: Vec<f64> = b.iter().zip(&self.mu).map(|(p, q)| p - q).collect();
        self.w
            .iter()
            .map(|r| r.iter().zip(&d).map(|(p, q)| p * q).sum())
            .collect()
    }

    /// b-space coefficients Wᵀ ã.
    fn to_b(&self, aq: &[f64]) -> Vec<f64> {
        (0..self.m)
            .map(|j| (0..self.m).map(|i| aq[i] * self.w[i][j]).sum())
            .collect()
    }

    /// Extrema of ã·q(z) over [0,1]: all candidates (z, value) in q-space values.
    fn extrema(&self, curve: &dyn Curve, aq: &[f64]) -> Vec<(f64, f64)> {
        let ab = self.to_b(aq);
        let shift: f64 = ab.iter().zip(&self.mu).map(|(p, q)| p * q).sum();
        curve
            .extrema(&ab)
            .into_iter()
            .map(|(z, v)| (z, v - shift))
            .collect()
    }
}

/// Monomial coefficients of T_k(2z − 1), k = 1..m: (rows of z¹…z^m, constant terms).
pub fn shifted_chebyshev(m: usize) -> (Vec<Vec<f64>>, Vec<f64>) {
    // T_0 = 1, T_1 = 2z − 1, T_{k+1} = 2(2z − 1)T_k − T_{k−1}, coefficients ascending.
    let mut polys: Vec<Vec<f64>> = vec![vec![1.0], vec![-1.0, 2.0]];
    while polys.len() <= m {
        let k = polys.len();
        let mut next = vec![0.0; k + 1];
        for (j, &c) in polys[k - 1].iter().enumerate() {
            next[j + 1] += 4.0 * c;
            next[j] -= 2.0 * c;
        }
        for (j, &c) in polys[k - 2].iter().enumerate() {
            next[j] -= c;
        }
        polys.push(next);
    }
    let w = (1..=m)
        .map(|k| {
            (1..=m)
                .map(|j| polys[k].get(j).copied().unwrap_or(0.0))
                .collect()
        })
        .collect();
    let c0 = (1..=m).map(|k| polys[k][0]).collect();
    (w, c0)
}

/// One row: q-space coefficients, offset, and its working set of constraint points.
#[derive(Clone)]
struct Row {
    a: Vec<f64>,
    pts: Vec<(f64, Vec<f64>)>,
}

/// What the row LP optimises.
enum Goal<'a> {
    /// max c·ã.
    Ascend(&'a [f64]),
    /// min Σ w_j |(Wᵀã)_j| subject to c·ã ≥ floor.
    TieBreak(&'a [f64], f64, &'a [f64]),
}

/// Solve the row LP with cutting planes; returns ã scaled to range exactly 1 (true range).
fn row_lp(
    frame: &Frame,
    curve: &dyn Curve,
    goal: &Goal,
    pts: &mut Vec<(f64, Vec<f64>)>,
    lps: &mut usize,
) -> Option<Vec<f64>> {
    let m = frame.m;
    for _ in 0..40 {
        *lps += 1;
        let (av, tv) = match goal {
            Goal::Ascend(c) => {
                let mut obj = c.to_vec();
                obj.push(0.0);
                let mut g = Vec::with_capacity(2 * pts.len());
                let mut h = Vec::with_capacity(2 * pts.len());
                for (_, q) in pts.iter() {
                    let mut up = q.clone();
                    up.push(1.0);
                    g.push(up.iter().map(|v| -v).collect());
                    h.push(0.0);
                    g.push(up);
                    h.push(1.0);
                }
                match super::lpsmall::max_free(&obj, &g, &h) {
                    Some(x) => (x[..m].to_vec(), x[m]),
                    None => microlp_row(frame, goal, pts)?,
                }
            }
            Goal::TieBreak(..) => microlp_row(frame, goal, pts)?,
        };
        let ext = frame.extrema(curve, &av);
        let (lo, hi) = ext.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |r, e| {
            (r.0.min(e.1), r.1.max(e.1))
        });
        let range = hi - lo;
        if !(range > 0.0) || !range.is_finite() {
            return None;
        }
        let mut added = false;
        for &(z, v) in &ext {
            let violated = v + tv > 1.0 + 1e-12 || v + tv < -1e-12;
            if violated && pts.iter().all(|p| (p.0 - z).abs() > 1e-13) {
                pts.push((z, frame.q(curve, z)));
                added = true;
            }
        }
        if range <= 1.0 + 1e-12 || !added {
            // prune the working set: drop points far from both bounds
            if pts.len() > 10 * m {
                pts.retain(|(_, q)| {
                    let v = dot(&av, q) + tv;
                    !(v > 1e-3 && v < 1.0 - 1e-3)
                });
            }
            return Some(av.iter().map(|v| v / range).collect());
        }
    }
    None
}

/// The row LP through good_lp + microlp (tie-break goal, and fallback).
fn microlp_row(frame: &Frame, goal: &Goal, pts: &[(f64, Vec<f64>)]) -> Option<(Vec<f64>, f64)> {
    let m = frame.m;
    let bound = 1e6;
    let mut vars = variables!();
    let a: Vec<Variable> = (0..m)
        .map(|_| vars.add(variable().min(-bound).max(bound)))
        .collect();
    let t = vars.add(variable().min(-bound).max(bound));
    let mut cons = Vec::new();
    let mut model = match goal {
        Goal::Ascend(c) => {
            let obj: Expression = a.iter().zip(c.iter()).map(|(v, &ci)| ci * *v).sum();
            vars.maximise(obj).using(microlp)
        }
        Goal::TieBreak(c, floor, w) => {
            let u: Vec<Variable> = (0..m).map(|_| vars.add(variable().min(0.0))).collect();
            let obj: Expression = u.iter().zip(w.iter()).map(|(v, &wj)| wj * *v).sum();
            let ab: Vec<Expression> = (0..m)
                .map(|j| (0..m).map(|i| frame.w[i][j] * a[i]).sum())
                .collect();
            for (e, uj) in ab.into_iter().zip(&u) {
                cons.push(e.clone().leq(*uj));
                cons.push((-e).leq(*uj));
            }
            let ca: Expression = a.iter().zip(c.iter()).map(|(v, &ci)| ci * *v).sum();
            cons.push(ca.geq(*floor));
            vars.minimise(obj).using(microlp)
        }
    };
    for (_, q) in pts.iter() {
        let e: Expression = a.iter().zip(q).map(|(v, &qj)| qj * *v).sum::<Expression>() + t;
        cons.push(e.clone().geq(0.0));
        cons.push(e.leq(1.0));
    }
    for c in cons {
        model = model.with(c);
    }
    let sol = model.solve().ok()?;
    let av: Vec<f64> = a.iter().map(|v| sol.value(*v)).collect();
    let tv = sol.value(t);
    Some((av, tv))
}

fn initial_points(frame: &Frame, curve: &dyn Curve) -> Vec<(f64, Vec<f64>)> {
    let n = 2 * frame.m + 2;
    (0..=n)
        .map(|k| {
            let z = 0.5 * (1.0 - (std::f64::consts::PI * k as f64 / n as f64).cos());
            (z, frame.q(curve, z))
        })
        .collect()
}

fn log2det(rows: &[Row]) -> f64 {
    let a: Vec<Vec<f64>> = rows.iter().map(|r| r.a.clone()).collect();
    Lu::new(&a)
        .map(|lu| lu.log2_abs_det().0)
        .unwrap_or(f64::NEG_INFINITY)
}

/// Cofactor direction of row i (∝ gradient of det with respect to row i), unit length.
fn cofactor_dir(rows: &[Row], i: usize) -> Option<Vec<f64>> {
    let m = rows.len();
    let a: Vec<Vec<f64>> = rows.iter().map(|r| r.a.clone()).collect();
    let lu = Lu::new(&a)?;
    let mut e = vec![0.0; m];
    e[i] = 1.0;
    let c = lu.solve(&e); // column i of A⁻¹ = cofactors of row i / det
    let n = dot(&c, &c).sqrt();
    Some(c.iter().map(|v| v / n).collect())
}

fn ascend(
    frame: &Frame,
    curve: &dyn Curve,
    rows: &mut [Row],
    opts: &Options,
    rng: &mut impl Rng,
    lps: &mut usize,
) -> f64 {
    let m = rows.len();
    let mut cur = log2det(rows);
    for _ in 0..opts.max_sweeps {
        let before = cur;
        let mut order: Vec<usize> = (0..m).collect();
        for k in (1..m).rev() {
            order.swap(k, rng.gen_range(0..=k));
        }
        for &i in &order {
            let Some(c) = cofactor_dir(rows, i) else {
                continue;
            };
            let old = dot(&c, &rows[i].a).abs();
            let mut pts = std::mem::take(&mut rows[i].pts);
            if let Some(a) = row_lp(frame, curve, &Goal::Ascend(&c), &mut pts, lps) {
                if dot(&c, &a) > old {
                    rows[i].a = a;
                }
            }
            rows[i].pts = pts;
        }
        cur = log2det(rows);
        if cur - before < opts.tol_bits {
            break;
        }
    }
    cur
}

fn tie_break(frame: &Frame, curve: &dyn Curve, rows: &mut [Row], weights: &[f64], lps: &mut usize) {
    let m = rows.len();
    for i in 0..m {
        let before = log2det(rows);
        let Some(c) = cofactor_dir(rows, i) else {
            continue;
        };
        let sgn = dot(&c, &rows[i].a).signum();
        let c: Vec<f64> = c.iter().map(|v| v * sgn).collect();
        let floor = dot(&c, &rows[i].a) * (1.0 - 1e-11);
        let mut pts = rows[i].pts.clone();
        let res = row_lp(
            frame,
            curve,
            &Goal::TieBreak(&c, floor, weights),
            &mut pts,
            lps,
        );
        if let Some(a) = res {
            let old = std::mem::replace(&mut rows[i].a, a);
            if log2det(rows) < before - 1e-9 {
                rows[i].a = old;
            } else {
                rows[i].pts = pts;
            }
        }
    }
}

/// Maximise log₂|det A| over θ(b) = A b + t with θ(b([0,1])) ⊆ [0,1]^m. `progress` is called
/// after each start with (start index, its gain in bits).
pub fn optimize(
    curve: &dyn Curve,
    opts: &Options,
    progress: &(dyn Fn(usize, f64) + Sync),
) -> Result<Outcome> {
    optimize_with(curve, opts, progress, None)
}

/// A converged start as a checkpoint stores it: its gain and rows (the row vectors and their
/// cutting-plane points), as float bits so that a resumed search continues exactly.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct StartState {
    gain: u64,
    rows: Vec<RowBits>,
    lps: usize,
}

/// A row as float bits: its vector and its cutting-plane points (z, q(z)).
type RowBits = (Vec<u64>, Vec<(u64, Vec<u64>)>);

impl StartState {
    fn of(g: f64, rows: &[Row], lps: usize) -> StartState {
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<u64>>();
        StartState {
            gain: g.to_bits(),
            rows: rows
                .iter()
                .map(|r| {
                    let pts = r.pts.iter().map(|(z, q)| (z.to_bits(), bits(q))).collect();
                    (bits(&r.a), pts)
                })
                .collect(),
            lps,
        }
    }

    /// (gain, rows, LPs), or None when the state does not fit a basis of `m` functions.
    fn restore(&self, m: usize) -> Option<(f64, Vec<Row>, usize)> {
        let floats = |v: &[u64]| v.iter().map(|&b| f64::from_bits(b)).collect::<Vec<f64>>();
        let rows: Vec<Row> = self
            .rows
            .iter()
            .map(|(a, pts)| Row {
                a: floats(a),
                pts: pts
                    .iter()
                    .map(|(z, q)| (f64::from_bits(*z), floats(q)))
                    .collect(),
            })
            .collect();
        let fits = rows.len() == m
            && rows
                .iter()
                .all(|r| r.a.len() == m && r.pts.iter().all(|p| p.1.len() == m));
        fits.then_some((f64::from_bits(self.gain), rows, self.lps))
    }
}

/// Where completed starts are kept across runs (a checkpoint): [`optimize_with`] takes a
/// start from it instead of running it, and records every start it runs.
pub trait StartStore: Sync {
    /// Start `k` if an earlier run completed it.
    fn get(&self, k: usize) -> Result<Option<StartState>>;
    /// Start `k` has converged.
    fn put(&self, k: usize, state: &StartState) -> Result<()>;
}

/// [`optimize`] with the starts kept in `store`: a start found there is not run again, every
/// other start is recorded as soon as it converges. Each start depends only on (seed, start
/// index, options), so the outcome equals that of an uninterrupted run.
pub fn optimize_with(
    curve: &dyn Curve,
    opts: &Options,
    progress: &(dyn Fn(usize, f64) + Sync),
    store: Option<&dyn StartStore>,
) -> Result<Outcome> {
    let m = curve.dim();
    if m == 0 {
        bail!("empty basis");
    }
    if opts.restarts == 0 {
        bail!("--restarts must be at least 1");
    }
    let starts: Vec<usize> = match &opts.only_starts {
        Some(v) => {
            if v.is_empty() || v.iter().any(|&k| k >= opts.restarts) {
                bail!(
                    "start indices must be non-empty and below --restarts {}, got {v:?}",
                    opts.restarts
                );
            }
            v.clone()
        }
        None => (0..opts.restarts).collect(),
    };
    let frame = Frame::new(curve)?;
    let init_pts = initial_points(&frame, curve);
    let runs: Vec<(f64, Vec<Row>, usize)> = starts
        .par_iter()
        .map(|&k| -> Result<(f64, Vec<Row>, usize)> {
            if let Some(st) = store.map(|s| s.get(k)).transpose()?.flatten() {
                if let Some((g, rows, lps)) = st.restore(m) {
                    progress(k, g + frame_gain(&frame));
                    return Ok((g, rows, lps));
                }
                bail!("checkpoint: start {k} does not fit a basis of {m} functions");
            }
            let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(
                opts.seed
                    .wrapping_mul(0x9E37_79B9_7F4A_7C15)
                    .wrapping_add(k as u64),
            );
            let mut lps = 0;
            let mut rows: Vec<Row> = (0..m)
                .map(|_| {
                    let mut a: Vec<f64> = (0..m).map(|_| normal(&mut rng)).collect();
                    normalize_row(&frame, curve, &mut a);
                    Row {
                        a,
                        pts: init_pts.clone(),
                    }
                })
                .collect();
            let mut g = ascend(&frame, curve, &mut rows, opts, &mut rng, &mut lps);
            for _ in 0..opts.hops {
                let mut trial = rows.clone();
                for r in trial.iter_mut() {
                    let n = dot(&r.a, &r.a).sqrt();
                    for v in r.a.iter_mut() {
                        *v += opts.hop_sigma * n * normal(&mut rng) / (m as f64).sqrt();
                    }
                    normalize_row(&frame, curve, &mut r.a);
                }
                let gt = ascend(&frame, curve, &mut trial, opts, &mut rng, &mut lps);
                if gt > g {
                    g = gt;
                    rows = trial;
                }
            }
            if let Some(s) = store {
                s.put(k, &StartState::of(g, &rows, lps))?;
            }
            progress(k, g + frame_gain(&frame));
            Ok((g, rows, lps))
        })
        .collect::<Result<_>>()?;
    let mut lps: usize = runs.iter().map(|r| r.2).sum();
    let start_gains: Vec<f64> = runs.iter().map(|r| r.0 + frame_gain(&frame)).collect();
    let best = (0..runs.len())
        .max_by(|&i, &j| runs[i].0.total_cmp(&runs[j].0))
        .unwrap();
    let mut rows = runs[best].1.clone();
    let weights: Vec<f64> = match curve.monomial_exponents() {
        Some(e) => e.iter().map(|&v| v as f64).collect(),
        None => (1..=m).map(|v| v as f64).collect(),
    };
    for _ in 0..3 {
        tie_break(&frame, curve, &mut rows, &weights, &mut lps);
    }
    // Map back: A = Ã W, t = −min over z of the row (set by normalisation).
    let a_b: Vec<Vec<f64>> = rows.iter().map(|r| frame.to_b(&r.a)).collect();
    let mut offset = Vec::with_capacity(m);
    for row in &a_b {
        let (_, lo, _, _) = row_min_max(curve, row);
        offset.push(-lo);
    }
    let raw = Theta::new(curve.names(), a_b, offset)?;
    let theta = normalize_rows(&raw, curve, opts.margin)?;
    Ok(Outcome {
        theta,
        start_gains,
        best_start: starts[best],
        start_indices: starts,
        lps,
    })
}

/// Standard normal sample (Box–Muller).
fn normal(rng: &mut impl Rng) -> f64 {
    let u: f64 = rng.gen_range(1e-12..1.0);
    let v: f64 = rng.gen_range(0.0..1.0);
    (-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * v).cos()
}

/// Scale a q-space row to range exactly 1 over [0,1].
fn normalize_row(frame: &Frame, curve: &dyn Curve, a: &mut [f64]) {
    let ext = frame.extrema(curve, a);
    let (lo, hi) = ext.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |r, e| {
        (r.0.min(e.1), r.1.max(e.1))
    });
    if hi > lo {
        a.iter_mut().for_each(|v| *v /= hi - lo);
    }
}

/// log₂|det W|: gain of the whitening itself (q-space det + this = b-space det).
fn frame_gain(frame: &Frame) -> f64 {
    Lu::new(&frame.w)
        .map(|lu| lu.log2_abs_det().0)
        .unwrap_or(f64::NAN)
}

/// How many starts reached the best basin: starts within `tol_bits` of the best gain.
#[derive(Clone, Debug, serde::Serialize)]
pub struct Basin {
    /// The best gain log₂|det A| over the starts, bits.
    pub best_bits: f64,
    /// Tolerance that defines the best basin, bits.
    pub tol_bits: f64,
    /// Start indices within `tol_bits` of the best, ascending.
    pub starts: Vec<usize>,
    /// starts.len() / number of starts run.
    pub share: f64,
    /// Best gain of the starts outside the basin (second-best basin), if any.
    pub runner_up_bits: Option<f64>,
}

/// Basin statistics of a search ([`Outcome::start_gains`] with their start indices).
pub fn basin(gains: &[f64], indices: &[usize], tol_bits: f64) -> Basin {
    let best = gains.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let mut starts: Vec<usize> = gains
        .iter()
        .zip(indices)
        .filter(|(g, _)| **g >= best - tol_bits)
        .map(|(_, &k)| k)
        .collect();
    starts.sort_unstable();
    let runner_up = gains
        .iter()
        .copied()
        .filter(|g| *g < best - tol_bits)
        .fold(None, |a: Option<f64>, g| Some(a.map_or(g, |v| v.max(g))));
    Basin {
        best_bits: best,
        tol_bits,
        share: starts.len() as f64 / gains.len().max(1) as f64,
        starts,
        runner_up_bits: runner_up,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};

    #[test]
    fn shifted_chebyshev_rows_are_t_k_of_2z_minus_1() {
        let m = 10;
        let (w, c0) = shifted_chebyshev(m);
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(2);
        for _ in 0..2000 {
            let z: f64 = rng.gen_range(0.0..=1.0);
            for k in 1..=m {
                let mono: f64 = c0[k - 1]
                    + (1..=m)
                        .map(|j| w[k - 1][j - 1] * z.powi(j as i32))
                        .sum::<f64>();
                let trig = (k as f64 * (2.0 * z - 1.0).clamp(-1.0, 1.0).acos()).cos();
                // rounding of the monomial sum grows with Σ|coefficients| = T_k(3)
                let scale: f64 = w[k - 1].iter().map(|v| v.abs()).sum::<f64>() + 1.0;
                let tol = 1e-14 * scale + 1e-12;
                assert!((mono - trig).abs() < tol, "k={k} z={z}: {mono} vs {trig}");
            }
        }
        // the frame maps b(z) to q(z) = T_k(2z − 1) through W(b − μ)
        let curve = super::super::curve::MonomialCurve::power(6).unwrap();
        let f = Frame::new(&curve).unwrap();
        for z in [0.0, 0.3, 1.0] {
            let q = f.q(&curve, z);
            for (k, v) in q.iter().enumerate() {
                let t = ((k + 1) as f64 * (2.0 * z - 1.0).acos()).cos();
                assert!((v - t).abs() < 1e-9);
            }
        }
    }

    #[test]
    fn basin_counts_starts_near_the_best() {
        let b = basin(&[1.0, 3.0, 2.9995, 2.0], &[4, 5, 6, 7], 1e-3);
        assert_eq!(b.starts, vec![5, 6]);
        assert_eq!(b.share, 0.5);
        assert_eq!(b.runner_up_bits, Some(2.0));
        assert_eq!(basin(&[1.0], &[0], 1e-3).runner_up_bits, None);
    }
}
