//! The stress harness behind `momentlab stability`: every technique on random and adversarial
//! inputs, exact and quantized, against the sharp bound of Algorithm 1 (Peters & Klein 2015,
//! Section 3.1) with the technique's own basis on a fine grid of [0,1] that also contains the
//! Diracs of the known input distribution and z_f.
//!
//! Pure library code (no IO): [`generate`] draws the inputs, [`run`] evaluates and summarises;
//! the CLI writes tables and plots. Documented in docs/stability.md.

use crate::lp::{make_solver, GridTable, SolverKind, Status};
use crate::quantize::theta::{self, Theta};
use crate::technique::Technique;
use crate::Grid;
use anyhow::Result;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use serde::Serialize;

/// Families of inputs (docs/stability.md lists what each one stresses).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Scenario {
    /// 4–8 Diracs anywhere in [0,1].
    Random,
    /// One Dirac (singular Hankel/Toeplitz matrix for m ≥ 2).
    OneDirac,
    /// Two Diracs (singular for m = 4).
    TwoDiracs,
    /// Three Diracs (singular for m = 6).
    ThreeDiracs,
    /// Two Diracs plus a third of weight 1e-7…1e-3, or three Diracs within 1e-4…1e-2:
    /// nearly singular matrices.
    NearSingular,
    /// z_f exactly at a support point.
    ZfAtSupport,
    /// z_f within 1e-6…1e-2 of a support point.
    ZfNearSupport,
    /// Diracs at depth 0 and/or 1.
    Ends,
    /// z_f where c₃ of Hamburger 4MSM (Algorithm 2) vanishes, ± 1e-9.
    C3Zero,
    /// Occluder and receiver 1e-4…1e-2 apart, z_f just behind the receiver.
    ShortRange,
}

impl Scenario {
    /// Every scenario, in report order.
    pub const ALL: [Scenario; 10] = [
        Scenario::Random,
        Scenario::OneDirac,
        Scenario::TwoDiracs,
        Scenario::ThreeDiracs,
        Scenario::NearSingular,
        Scenario::ZfAtSupport,
        Scenario::ZfNearSupport,
        Scenario::Ends,
        Scenario::C3Zero,
        Scenario::ShortRange,
    ];
    /// The snake_case name used in reports and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Scenario::Random => "random",
            Scenario::OneDirac => "one_dirac",
            Scenario::TwoDiracs => "two_diracs",
            Scenario::ThreeDiracs => "three_diracs",
            Scenario::NearSingular => "near_singular",
            Scenario::ZfAtSupport => "zf_at_support",
            Scenario::ZfNearSupport => "zf_near_support",
            Scenario::Ends => "depths_0_1",
            Scenario::C3Zero => "c3_zero",
            Scenario::ShortRange => "short_range",
        }
    }
}

/// How the moments reach the technique.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Mode {
    /// Exact f64 moments.
    F64,
    /// Each moment rounded to f32.
    F32,
    /// θ(b) rounded to f32, then θ⁻¹ (only where a θ is known).
    F32Theta,
    /// Each moment mapped affinely by the bounding box of b([0,1]) to [0,1] and rounded to 16 bits.
    U16,
    /// θ(b) rounded to 16 bits, then θ⁻¹ (only where a θ is known).
    U16Theta,
}

impl Mode {
    /// Every mode, in report order.
    pub const ALL: [Mode; 5] = [
        Mode::F64,
        Mode::F32,
        Mode::F32Theta,
        Mode::U16,
        Mode::U16Theta,
    ];
    /// The name used in reports ("f64", "f32", "f32_theta", …).
    pub fn name(self) -> &'static str {
        match self {
            Mode::F64 => "f64",
            Mode::F32 => "f32",
            Mode::F32Theta => "f32+theta",
            Mode::U16 => "u16",
            Mode::U16Theta => "u16+theta",
        }
    }
}

/// One input: a depth distribution (Diracs) and a fragment depth.
#[derive(Clone, Debug, Serialize)]
pub struct Sample {
    /// The scenario that generated the sample.
    pub scenario: Scenario,
    /// (depth, weight), weights sum to 1.
    pub atoms: Vec<(f64, f64)>,
    /// Fragment depth z_f in [0,1].
    pub zf: f64,
}

impl Sample {
    /// Mean depth Σ w_i z_i of the Diracs.
    pub fn mean(&self) -> f64 {
        self.atoms.iter().map(|a| a.0 * a.1).sum()
    }
    /// Depth variance Σ w_i (z_i − mean)².
    pub fn variance(&self) -> f64 {
        let m = self.mean();
        self.atoms.iter().map(|a| a.1 * (a.0 - m).powi(2)).sum()
    }
}

/// Harness settings.
#[derive(Clone, Debug, Serialize)]
pub struct Config {
    /// Inputs drawn in all, cycling through [`Scenario::ALL`].
    pub samples: usize,
    /// Seed of the sample generator (same seed, same samples).
    pub seed: u64,
    /// Uniform points of the oracle's grid on [0,1] (plus the sample's Diracs and z_f).
    pub grid_points: usize,
    /// Deviation above the sharp bound counted as a violated lower bound. The bias alone may
    /// lift G by up to α·F_{Z*}(z_f) ≤ α (≤ 4·10⁻³ for every default), hence 10⁻².
    pub over_tolerance: f64,
}

impl Default for Config {
    fn default() -> Self {
        Config {
            samples: 3000,
            seed: 1,
            grid_points: 256,
            over_tolerance: 1e-2,
        }
    }
}

/// The published θ for a technique name (crate::quantize::theta): θ₄ of Peters & Klein 2015,
/// Section 4.3, for Hamburger/Hausdorff 4MSM; θ₆ of the supplementary document (Table 1) for
/// 6MSM; θ₂ of Section 4.3 for VSM. None for the other techniques.
pub fn theta_for(spec: &str) -> Option<Theta> {
    match spec {
        "hamburger4" | "hausdorff4" => Some(theta::published_theta4()),
        "hamburger6" => Some(theta::published_theta6()),
        "vsm" => Some(theta::published_theta2()),
        _ => None,
    }
}

/// Inverse of a small matrix (the crate's LU, [`crate::linalg::Lu`]); None when singular.
fn invert(m: &[Vec<f64>]) -> Option<Vec<Vec<f64>>> {
    crate::linalg::Lu::factor_rows(m).map(|lu| lu.inverse_rows())
}

/// Moments E_Z[b] of a Dirac mixture under a technique's basis.
pub fn moments(tech: &dyn Technique, atoms: &[(f64, f64)]) -> Vec<f64> {
    let m = tech.moment_count();
    let mut b = vec![0.0; m];
    let mut row = vec![0.0; m];
    for &(z, w) in atoms {
        tech.basis(z, &mut row);
        for j in 0..m {
            b[j] += w * row[j];
        }
    }
    b
}

/// z_f ∈ [0,1] where c₃ of Algorithm 2 (m = 4) vanishes for the moments of `atoms`:
/// c = B⁻¹(1, z_f, z_f²) and c₃(z_f) is a quadratic in z_f.
pub fn c3_zero_depths(atoms: &[(f64, f64)]) -> Vec<f64> {
    let mom = |j: i32| atoms.iter().map(|a| a.1 * a.0.powi(j)).sum::<f64>();
    let b: Vec<f64> = (0..5).map(mom).collect();
    let bm = vec![
        vec![b[0], b[1], b[2]],
        vec![b[1], b[2], b[3]],
        vec![b[2], b[3], b[4]],
    ];
    let Some(inv) = invert(&bm) else {
        return Vec::new();
    };
    // c₃(z) = inv[2][0] + inv[2][1] z + inv[2][2] z²
    let (c, bq, a) = (inv[2][0], inv[2][1], inv[2][2]);
    let mut out = Vec::new();
    if a.abs() < 1e-300 {
        if bq != 0.0 {
            out.push(-c / bq);
        }
    } else {
        let d = bq * bq - 4.0 * a * c;
        if d >= 0.0 {
            let s = d.sqrt();
            out.push((-bq + s) / (2.0 * a));
            out.push((-bq - s) / (2.0 * a));
        }
    }
    out.retain(|z| (0.0..=1.0).contains(z));
    out
}

fn normalize(atoms: &mut [(f64, f64)]) {
    let s: f64 = atoms.iter().map(|a| a.1).sum();
    for a in atoms.iter_mut() {
        a.1 /= s;
    }
}

/// Draw `cfg.samples` inputs, cycling through [`Scenario::ALL`].
pub fn generate(cfg: &Config) -> Vec<Sample> {
    let mut rng = ChaCha8Rng::seed_from_u64(cfg.seed);
    (0..cfg.samples)
        .map(|i| {
            let sc = Scenario::ALL[i % Scenario::ALL.len()];
            draw(sc, &mut rng)
        })
        .collect()
}

fn diracs(rng: &mut ChaCha8Rng, k: usize) -> Vec<(f64, f64)> {
    let mut a: Vec<(f64, f64)> = (0..k)
        .map(|_| (rng.gen::<f64>(), rng.gen_range(0.05..1.0)))
        .collect();
    normalize(&mut a);
    a
}

fn draw(sc: Scenario, rng: &mut ChaCha8Rng) -> Sample {
    let mut zf: f64 = rng.gen();
    let atoms = match sc {
        Scenario::Random => {
            let k = rng.gen_range(4..=8);
            diracs(rng, k)
        }
        Scenario::OneDirac => diracs(rng, 1),
        Scenario::TwoDiracs => diracs(rng, 2),
        Scenario::ThreeDiracs => diracs(rng, 3),
        Scenario::NearSingular => {
            if rng.gen_bool(0.5) {
                let mut a = diracs(rng, 2);
                let w = 10f64.powf(rng.gen_range(-7.0..-3.0));
                for x in a.iter_mut() {
                    x.1 *= 1.0 - w;
                }
                a.push((rng.gen(), w));
                a
            } else {
                let c: f64 = rng.gen_range(0.01..0.95);
                let s = 10f64.powf(rng.gen_range(-4.0..-2.0));
                let mut a: Vec<(f64, f64)> = (0..3)
                    .map(|_| (c + s * rng.gen::<f64>(), rng.gen_range(0.1..1.0)))
                    .collect();
                normalize(&mut a);
                zf = c + s * rng.gen_range(-1.0..2.0);
                a
            }
        }
        Scenario::ZfAtSupport => {
            let k = rng.gen_range(2..=3);
            let a = diracs(rng, k);
            zf = a[rng.gen_range(0..k)].0;
            a
        }
        Scenario::ZfNearSupport => {
            let k = rng.gen_range(2..=3);
            let a = diracs(rng, k);
            let d = 10f64.powf(rng.gen_range(-6.0..-2.0));
            zf = a[rng.gen_range(0..k)].0 + if rng.gen_bool(0.5) { d } else { -d };
            a
        }
        Scenario::Ends => {
            let mut a = match rng.gen_range(0..3) {
                0 => vec![(0.0, 1.0)],
                1 => vec![(1.0, 1.0)],
                _ => vec![
                    (0.0, rng.gen_range(0.1..1.0)),
                    (1.0, rng.gen_range(0.1..1.0)),
                ],
            };
            if rng.gen_bool(0.5) {
                a.push((rng.gen(), rng.gen_range(0.1..1.0)));
            }
            normalize(&mut a);
            a
        }
        Scenario::C3Zero => {
            let a = diracs(rng, 3);
            let roots = c3_zero_depths(&a);
            if let Some(&r) = roots.first() {
                zf = r + rng.gen_range(-1e-9..1e-9);
            }
            a
        }
        Scenario::ShortRange => {
            let d: f64 = rng.gen_range(0.05..0.9);
            let gap = 10f64.powf(rng.gen_range(-4.0..-2.0));
            let w = rng.gen_range(0.2..0.8);
            zf = d + gap * rng.gen_range(1.0..1.5);
            vec![(d, w), (d + gap, 1.0 - w)]
        }
    };
    Sample {
        scenario: sc,
        atoms,
        zf: zf.clamp(0.0, 1.0),
    }
}

/// Per-(technique, mode) or per-(technique, scenario) summary.
#[derive(Clone, Debug, Default, Serialize)]
pub struct Summary {
    /// Inputs evaluated (including NaN results).
    pub count: usize,
    /// Inputs where the oracle itself failed (excluded from the deviation statistics).
    pub oracle_failures: usize,
    /// Share of inputs where G is NaN or infinite.
    pub nan_share: f64,
    /// Share of inputs where G is finite but outside [0,1].
    pub outside_share: f64,
    /// Largest |G − sharp bound| over inputs with a finite G and oracle.
    pub max_abs_dev: f64,
    /// Mean |G − sharp bound| over inputs with a finite G and oracle (NaN when none).
    pub mean_abs_dev: f64,
    /// Share of G above the sharp bound by more than `over_tolerance` (too dark: the lower-bound
    /// property is violated).
    pub over_share: f64,
    #[serde(skip)]
    acc: (usize, usize, usize, f64, f64, usize),
}

impl Summary {
    fn add(&mut self, g: f64, sharp: f64, over_tol: f64) {
        self.count += 1;
        let (nan, outside, n, max, sum, over) = &mut self.acc;
        if !g.is_finite() {
            *nan += 1;
            return;
        }
        if !(0.0..=1.0).contains(&g) {
            *outside += 1;
        }
        if !sharp.is_finite() {
            self.oracle_failures += 1;
            return;
        }
        let d = g - sharp;
        *n += 1;
        *max = max.max(d.abs());
        *sum += d.abs();
        if d > over_tol {
            *over += 1;
        }
    }
    fn finish(&mut self) {
        let (nan, outside, n, max, sum, over) = self.acc;
        let c = self.count.max(1) as f64;
        self.nan_share = nan as f64 / c;
        self.outside_share = outside as f64 / c;
        self.max_abs_dev = max;
        self.mean_abs_dev = if n > 0 { sum / n as f64 } else { f64::NAN };
        self.over_share = if n > 0 { over as f64 / n as f64 } else { 0.0 };
    }
}

/// One evaluated point (for plots): technique index, mode, log₁₀ variance, z_f − mean, G − sharp.
#[derive(Clone, Debug, Serialize)]
pub struct Point {
    /// Index of the technique in [`Report::techniques`].
    pub technique: usize,
    /// Moment precision the point was evaluated in.
    pub mode: Mode,
    /// Scenario that generated the input.
    pub scenario: Scenario,
    /// log₁₀ of the depth variance of the input.
    pub log10_variance: f64,
    /// z_f minus the mean depth of the input.
    pub zf_minus_mean: f64,
    /// G − sharp bound; NaN when G is NaN/inf or the oracle failed.
    pub dev: f64,
    /// Whether G was finite.
    pub g_finite: bool,
}

/// Everything `momentlab stability` reports.
#[derive(Clone, Debug, Serialize)]
pub struct Report {
    /// The harness settings.
    pub config: Config,
    /// Name of the LP solver that computed the sharp bound.
    pub lp_solver: String,
    /// Technique spec names, indexed as in `by_mode`, `by_scenario` and [`Point::technique`].
    pub techniques: Vec<String>,
    /// by_mode[t] = (mode, summary) for the modes that apply to technique t.
    pub by_mode: Vec<Vec<(Mode, Summary)>>,
    /// by_scenario[t] = (scenario, summary) over all modes of technique t.
    pub by_scenario: Vec<Vec<(Scenario, Summary)>>,
    /// Every evaluated point, for the plots (not serialized).
    #[serde(skip)]
    pub points: Vec<Point>,
}

/// Quantizer of one technique: bounding box of b([0,1]) and optional θ.
struct Quant {
    lo: Vec<f64>,
    hi: Vec<f64>,
    theta: Option<Theta>,
}

impl Quant {
    fn new(spec: &str, tech: &dyn Technique) -> Quant {
        let m = tech.moment_count();
        let (mut lo, mut hi) = (vec![f64::INFINITY; m], vec![f64::NEG_INFINITY; m]);
        let mut row = vec![0.0; m];
        for i in 0..=4096 {
            tech.basis(i as f64 / 4096.0, &mut row);
            for j in 0..m {
                lo[j] = lo[j].min(row[j]);
                hi[j] = hi[j].max(row[j]);
            }
        }
        let theta = theta_for(spec).filter(|t| t.m() == m);
        Quant { lo, hi, theta }
    }
    fn applies(&self, mode: Mode) -> bool {
        !matches!(mode, Mode::F32Theta | Mode::U16Theta) || self.theta.is_some()
    }
    fn quantize(&self, b: &[f64], mode: Mode) -> Vec<f64> {
        let u16r = |u: f64| (u.clamp(0.0, 1.0) * 65535.0).round() / 65535.0;
        match mode {
            Mode::F64 => b.to_vec(),
            Mode::F32 => b.iter().map(|&v| v as f32 as f64).collect(),
            Mode::U16 => b
                .iter()
                .enumerate()
                .map(|(j, &v)| {
                    let w = (self.hi[j] - self.lo[j]).max(f64::MIN_POSITIVE);
                    self.lo[j] + w * u16r((v - self.lo[j]) / w)
                })
                .collect(),
            Mode::F32Theta | Mode::U16Theta => {
                let th = self.theta.as_ref().expect("checked by applies");
                let mut t = vec![0.0; b.len()];
                th.encode(b, &mut t);
                for v in t.iter_mut() {
                    *v = if mode == Mode::U16Theta {
                        u16r(*v)
                    } else {
                        *v as f32 as f64
                    };
                }
                let mut out = vec![0.0; b.len()];
                th.decode(&t, &mut out);
                out
            }
        }
    }
}

/// The sharp bound for a sample under a technique's basis: Algorithm 1 on the uniform grid of
/// [0,1] ∪ the sample's Diracs ∪ {z_f}; NaN if the LP fails.
pub fn sharp_bound(tech: &dyn Technique, sample: &Sample, grid_points: usize, solver: &str) -> f64 {
    let mut pts: Vec<f64> = (0..grid_points)
        .map(|i| i as f64 / (grid_points - 1) as f64)
        .collect();
    pts.extend(sample.atoms.iter().map(|a| a.0));
    pts.push(sample.zf);
    let Ok(grid) = Grid::from_values(pts) else {
        return f64::NAN;
    };
    let m = tech.moment_count();
    // Scale each basis function by its largest magnitude on the grid (an equivalent LP; keeps
    // e.g. ESM's exp(80z) ~ 1e34 within the solver's tolerances).
    let mut scale = vec![0.0f64; m];
    let mut row = vec![0.0; m];
    for &z in grid.points() {
        tech.basis(z, &mut row);
        for j in 0..m {
            scale[j] = scale[j].max(row[j].abs());
        }
    }
    let scale: Vec<f64> = scale
        .iter()
        .map(|&s| {
            if s > 0.0 && s.is_finite() {
                1.0 / s
            } else {
                1.0
            }
        })
        .collect();
    let Ok(table) = GridTable::from_fn(&grid, m, |z, out| {
        tech.basis(z, out);
        for (o, s) in out.iter_mut().zip(&scale) {
            *o *= s;
        }
    }) else {
        return f64::NAN;
    };
    // The sample's Diracs are grid points: the LP gets the distribution itself (its moments
    // formed from the table, and a feasible start), as the pipeline does.
    let dist: Vec<(u32, f64)> = sample
        .atoms
        .iter()
        .map(|&(z, w)| (grid.nearest(z) as u32, w))
        .collect();
    let Ok(kind) = solver.parse::<SolverKind>() else {
        return f64::NAN;
    };
    let mut s = make_solver(kind, table);
    match s.solve_distribution(&dist, sample.zf) {
        Ok(sol) if sol.status == Status::Optimal => sol.g,
        _ => f64::NAN,
    }
}

/// The LP solver used as oracle: the certified fast solver.
pub fn oracle_solver() -> String {
    SolverKind::Fast.name().into()
}

/// Per technique on one sample: the sharp bound and G per applicable mode.
type TechResult = (f64, Vec<(Mode, f64)>);

/// Heat-map cells `[row][col]` (None: no input fell in the cell).
pub type Cells = Vec<Vec<Option<f64>>>;

/// A technique under test: its name, the instance for f64/f32 moments and the instance for
/// 16-bit moments (e.g. a stronger default bias).
pub struct Entry {
    /// The technique's spec name.
    pub name: String,
    /// Instance used for f64 and f32 moments.
    pub t32: Box<dyn Technique>,
    /// Instance used for 16-bit moments.
    pub t16: Box<dyn Technique>,
}

/// One unit of the study as a checkpoint keeps it: per input of the family, in input order,
/// the sharp bound and G per applicable mode (in [`Mode::ALL`] order), as float bits (G may be
/// NaN or infinite).
pub type UnitBits = Vec<(u64, Vec<u64>)>;

/// Where completed units of the study — one technique on the inputs of one family — are kept
/// across runs (a checkpoint). Keys are `<technique>.<family>`.
pub trait UnitStore: Sync {
    /// The unit `key` if an earlier run completed it.
    fn get(&self, key: &str) -> Result<Option<UnitBits>>;
    /// Unit `key` is complete.
    fn put(&self, key: &str, unit: &UnitBits) -> Result<()>;
}

/// One technique on one sample: the sharp bound and G per applicable mode.
fn evaluate_one(cfg: &Config, e: &Entry, q: &Quant, s: &Sample, solver: &str) -> TechResult {
    let t = e.t32.as_ref();
    let sharp = sharp_bound(t, s, cfg.grid_points, solver);
    let b = moments(t, &s.atoms);
    let mut ev = t.evaluator();
    let mut ev16 = e.t16.evaluator();
    let gs = Mode::ALL
        .iter()
        .filter(|&&m| q.applies(m))
        .map(|&m| {
            let bq = q.quantize(&b, m);
            let g = if matches!(m, Mode::U16 | Mode::U16Theta) {
                ev16.shadow(&bq, s.zf)
            } else {
                ev.shadow(&bq, s.zf)
            };
            (m, g)
        })
        .collect();
    (sharp, gs)
}

/// One unit of the study: a technique on the samples `idx` of one family, kept as `key`.
struct Unit<'a> {
    entry: &'a Entry,
    quant: &'a Quant,
    idx: &'a [usize],
    key: &'a str,
}

/// The results of `u` on its samples: from `store` when an earlier run completed it, else
/// evaluated (in parallel over the samples) and recorded there.
fn run_unit(
    cfg: &Config,
    samples: &[Sample],
    u: &Unit,
    solver: &str,
    (progress, store): (&(dyn Fn(usize) + Sync), Option<&dyn UnitStore>),
) -> Result<Vec<TechResult>> {
    let (idx, key) = (u.idx, u.key);
    let modes: Vec<Mode> = Mode::ALL
        .into_iter()
        .filter(|&m| u.quant.applies(m))
        .collect();
    if let Some(kept) = store.map(|s| s.get(key)).transpose()?.flatten() {
        if kept.len() != idx.len() || kept.iter().any(|(_, g)| g.len() != modes.len()) {
            anyhow::bail!("checkpoint: unit {key} does not fit the study");
        }
        progress(idx.len());
        return Ok(kept
            .iter()
            .map(|(sharp, g)| {
                let gs = modes.iter().zip(g).map(|(&m, &b)| (m, f64::from_bits(b)));
                (f64::from_bits(*sharp), gs.collect())
            })
            .collect());
    }
    let r: Vec<TechResult> = idx
        .par_iter()
        .map(|&i| {
            let r = evaluate_one(cfg, u.entry, u.quant, &samples[i], solver);
            progress(1);
            r
        })
        .collect();
    if let Some(s) = store {
        let bits = r
            .iter()
            .map(|(sharp, gs)| (sharp.to_bits(), gs.iter().map(|g| g.1.to_bits()).collect()))
            .collect();
        s.put(key, &bits)?;
    }
    Ok(r)
}

/// Evaluate every technique (spec name, technique) on every sample and mode. The work runs in
/// units — one technique on the samples of one family — kept in `store` when given: a unit
/// found there is not evaluated again, every other one is recorded when complete. Each
/// (technique, sample) result depends on nothing else, so the report equals that of an
/// uninterrupted run. `progress` is called with the number of (sample, technique) pairs
/// finished (from worker threads).
pub fn run(
    cfg: &Config,
    techniques: &[Entry],
    samples: &[Sample],
    progress: &(dyn Fn(usize) + Sync),
    store: Option<&dyn UnitStore>,
) -> Result<Report> {
    let solver = oracle_solver();
    let quants: Vec<Quant> = techniques
        .iter()
        .map(|e| Quant::new(&e.name, e.t32.as_ref()))
        .collect();
    let units: Vec<(usize, Scenario)> = (0..techniques.len())
        .flat_map(|t| Scenario::ALL.iter().map(move |&f| (t, f)))
        .collect();
    let members: Vec<Vec<usize>> = Scenario::ALL
        .iter()
        .map(|&f| {
            (0..samples.len())
                .filter(|&i| samples[i].scenario == f)
                .collect()
        })
        .collect();
    let family = |f: Scenario| Scenario::ALL.iter().position(|&x| x == f).unwrap();
    let results: Vec<Vec<TechResult>> = units
        .par_iter()
        .map(|&(t, f)| {
            let key = format!("{}.{}", techniques[t].name, f.name());
            let unit = Unit {
                entry: &techniques[t],
                quant: &quants[t],
                idx: &members[family(f)],
                key: &key,
            };
            run_unit(cfg, samples, &unit, &solver, (progress, store))
        })
        .collect::<Result<_>>()?;
    // Per sample: for each technique, the sharp bound and G per applicable mode.
    let mut slots: Vec<Vec<Option<TechResult>>> = vec![vec![None; techniques.len()]; samples.len()];
    for (&(t, f), r) in units.iter().zip(results) {
        for (&i, v) in members[family(f)].iter().zip(r) {
            slots[i][t] = Some(v);
        }
    }
    let per_sample: Vec<Vec<TechResult>> = slots
        .into_iter()
        .map(|v| {
            v.into_iter()
                .map(|r| r.expect("every unit evaluated"))
                .collect()
        })
        .collect();
    let nt = techniques.len();
    let mut by_mode: Vec<Vec<(Mode, Summary)>> = quants
        .iter()
        .map(|q| {
            Mode::ALL
                .iter()
                .filter(|&&m| q.applies(m))
                .map(|&m| (m, Summary::default()))
                .collect()
        })
        .collect();
    let mut by_scenario: Vec<Vec<(Scenario, Summary)>> = (0..nt)
        .map(|_| {
            Scenario::ALL
                .iter()
                .map(|&s| (s, Summary::default()))
                .collect()
        })
        .collect();
    let mut points = Vec::new();
    for (s, res) in samples.iter().zip(&per_sample) {
        let (lv, dz) = (s.variance().max(1e-300).log10(), s.zf - s.mean());
        for (t, (sharp, gs)) in res.iter().enumerate() {
            for &(mode, g) in gs {
                if let Some(e) = by_mode[t].iter_mut().find(|e| e.0 == mode) {
                    e.1.add(g, *sharp, cfg.over_tolerance);
                }
                if let Some(e) = by_scenario[t].iter_mut().find(|e| e.0 == s.scenario) {
                    e.1.add(g, *sharp, cfg.over_tolerance);
                }
                points.push(Point {
                    technique: t,
                    mode,
                    scenario: s.scenario,
                    log10_variance: lv,
                    zf_minus_mean: dz,
                    dev: if g.is_finite() { g - sharp } else { f64::NAN },
                    g_finite: g.is_finite(),
                });
            }
        }
    }
    for v in by_mode.iter_mut() {
        for e in v.iter_mut() {
            e.1.finish();
        }
    }
    for v in by_scenario.iter_mut() {
        for e in v.iter_mut() {
            e.1.finish();
        }
    }
    Ok(Report {
        config: cfg.clone(),
        lp_solver: solver,
        techniques: techniques.iter().map(|e| e.name.clone()).collect(),
        by_mode,
        by_scenario,
        points,
    })
}

/// Heat-map cells over log₁₀ variance × (z_f − mean): mean |G − sharp| per cell (NaN/inf results
/// count as 1), None where no input fell. Returns (cells[row][col], variance range, dz range).
pub fn heat_map(
    points: &[Point],
    technique: usize,
    mode: Mode,
    rows: usize,
    cols: usize,
) -> (Cells, (f64, f64), (f64, f64)) {
    let (v0, v1) = (-10.0, 0.0);
    let (d0, d1) = (-0.6, 0.6);
    let mut sum = vec![vec![0.0; cols]; rows];
    let mut cnt = vec![vec![0usize; cols]; rows];
    for p in points
        .iter()
        .filter(|p| p.technique == technique && p.mode == mode)
    {
        let e = if p.g_finite {
            if p.dev.is_nan() {
                continue;
            }
            p.dev.abs()
        } else {
            1.0
        };
        let r = (((p.log10_variance.clamp(v0, v1) - v0) / (v1 - v0)) * rows as f64) as usize;
        let c = (((p.zf_minus_mean.clamp(d0, d1) - d0) / (d1 - d0)) * cols as f64) as usize;
        let (r, c) = (r.min(rows - 1), c.min(cols - 1));
        sum[r][c] += e;
        cnt[r][c] += 1;
    }
    let cells = (0..rows)
        .map(|r| {
            (0..cols)
                .map(|c| (cnt[r][c] > 0).then(|| sum[r][c] / cnt[r][c] as f64))
                .collect()
        })
        .collect();
    (cells, (v0, v1), (d0, d1))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn theta_for_names() {
        assert_eq!(theta_for("hamburger4").unwrap().m(), 4);
        assert_eq!(theta_for("hamburger6").unwrap().m(), 6);
        assert_eq!(theta_for("vsm").unwrap().m(), 2);
        assert!(theta_for("tmsm").is_none());
    }

    #[test]
    fn c3_zero_depths_make_c3_vanish() {
        let atoms = [(0.2, 0.3), (0.5, 0.3), (0.9, 0.4)];
        for z in c3_zero_depths(&atoms) {
            let mom = |j: i32| atoms.iter().map(|a| a.1 * f64::powi(a.0, j)).sum::<f64>();
            let b: Vec<f64> = (0..5).map(mom).collect();
            let bm = vec![
                vec![b[0], b[1], b[2]],
                vec![b[1], b[2], b[3]],
                vec![b[2], b[3], b[4]],
            ];
            let inv = invert(&bm).unwrap();
            let c3 = inv[2][0] + inv[2][1] * z + inv[2][2] * z * z;
            assert!(c3.abs() < 1e-9 * inv[2][2].abs().max(1.0), "{c3}");
        }
    }
}
