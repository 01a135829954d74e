//! `momentlab tune`: no more model than a scene needs, chosen from data. Per scene and over all
//! scenes, search technique × storage × moment bias α × technique depth bias × the technique's
//! own parameters ([`space`]) for the cheapest setting whose error is within a tolerance of the
//! best one, and compare it with the paper's and the engines' published defaults.
//!
//! Score of a setting ([`score`]): over a seeded fragment sample ([`sample`]), the moments a
//! GPU pipeline gives the lookup (texels stored in the setting's format, the separable filter
//! accumulated in f32 with each pass stored in the format, θ⁻¹ in f32) and G in f32 at z_f − ε′,
//! against G_exact, the same technique in f64 on exact moments. The score is leak + darkening
//! (of G_exact against PCF) + noise (|G − G_exact|); a setting whose share of fragments with
//! noise above 1/255 exceeds `max_noise` is infeasible, and the α grid of each family is
//! refined to the smallest α that keeps that bound.
//!
//! Coarse to fine: every setting of the grid is scored on a screening subsample; per target
//! (scene or all) and family the `keep` best at or above the α floor are re-scored on the whole
//! sample. On that sample the chosen setting is the feasible one that is cheapest within
//! `tolerance` of the best (bits per texel first, as in the paper's cost model, then the GPU
//! cost per lookup of [`Options::cost`], then error); the runner-up is the setting chosen when the
//! chosen one's technique and storage are left out. Differences to the runner-up and to the published defaults are paired (same fragments) with a 95 % normal
//! confidence interval: mean ± 1.96·sd/√n.

pub mod export;
pub mod sample;
pub mod score;
pub mod space;
pub mod table;
pub mod units;

use crate::progress::Bar;
use crate::stack::DepthStack;
use anyhow::{bail, Result};
use rayon::prelude::*;
use sample::Sample;
use score::{Acc, Moments, Outcome};
use serde::{Deserialize, Serialize};
use space::{DepthBias, Family, Own, Setting, StorageKind, TechniqueKind};
use std::time::Instant;

/// What to search and how much data to score on.
#[derive(Clone, Debug)]
pub struct Options {
    /// Techniques searched.
    pub techniques: Vec<TechniqueKind>,
    /// Storage formats searched.
    pub storages: Vec<StorageKind>,
    /// Error above the best setting that is acceptable (absolute; 0.002 = 0.2 points).
    pub tolerance: f64,
    /// Largest share of fragments whose G is more than 1/255 from G_exact (noise) for a
    /// feasible setting (0.001 = 0.1 %).
    pub max_noise: f64,
    /// Fragments sampled per scene (the confirming sample).
    pub fragments_per_scene: usize,
    /// Fragments per scene of the screening subsample (at most `fragments_per_scene`).
    pub screen_per_scene: usize,
    /// Settings per target and family re-scored on the whole sample.
    pub keep: usize,
    /// Seed of the fragment sample.
    pub seed: u64,
    /// Fragments of the speed measurement per family.
    pub speed_inputs: usize,
    /// GPU ns per lookup of a technique × storage, the second cost after bits per texel
    /// (`crate::gpu::cost::gpu_cost` in the command line and the pipeline; None: bits only,
    /// then error).
    pub cost: Option<CostFn>,
}

/// GPU ns per lookup of a technique × storage.
pub type CostFn = fn(TechniqueKind, StorageKind) -> Result<f64>;

impl Default for Options {
    fn default() -> Options {
        Options {
            techniques: TechniqueKind::ALL.to_vec(),
            storages: StorageKind::ALL.to_vec(),
            tolerance: 0.002,
            max_noise: crate::quantize::pipeline::MAX_NOISE,
            fragments_per_scene: 8192,
            screen_per_scene: 1024,
            keep: 2,
            seed: 2015,
            speed_inputs: 4096,
            cost: None,
        }
    }
}

impl Options {
    /// The families to search; a one-line error for an unusable option or an empty space.
    pub fn check(&self) -> Result<Vec<Family>> {
        if !(self.tolerance.is_finite() && self.tolerance >= 0.0) {
            bail!(
                "tolerance must be a finite number ≥ 0, got {}",
                self.tolerance
            );
        }
        if !(self.max_noise.is_finite() && (0.0..=1.0).contains(&self.max_noise)) {
            bail!(
                "max noise must be a share in [0, 1] (0.001 = 0.1 %), got {}",
                self.max_noise
            );
        }
        if self.fragments_per_scene == 0 || self.screen_per_scene == 0 || self.keep == 0 {
            bail!("fragments per scene, screening fragments and kept settings must be ≥ 1");
        }
        if self.speed_inputs == 0 {
            bail!("speed inputs must be ≥ 1");
        }
        space::families(&self.techniques, &self.storages)
    }
}

/// A setting scored on a set of fragments.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Scored {
    /// The setting.
    pub setting: Setting,
    /// Its label ([`Setting::label`]).
    pub label: String,
    /// Bits stored per texel (m × bits per channel).
    pub bits_per_texel: u32,
    /// GPU time per lookup in ns (`crate::gpu::cost::gpu_cost`: the shader-IR model calibrated on the
    /// committed GPU benches), not CPU time.
    pub ns_per_fragment: f64,
    /// The score ([`score`]): leak + darkening + noise + non_finite/fragments, an upper bound
    /// of mean |G − PCF| that noise cannot lower.
    pub error: f64,
    /// Mean max(PCF − G_exact, 0): light leaking of the technique on exact moments.
    pub leak: f64,
    /// Mean max(G_exact − PCF, 0): over-darkening of the technique on exact moments.
    pub darkening: f64,
    /// Mean |G − G_exact|: noise from storage and f32 arithmetic.
    pub noise: f64,
    /// 99.9th percentile of |G − G_exact| (NaN where not measured).
    pub noise_p999: f64,
    /// Share of fragments with |G − G_exact| > 1/255 (non-finite ones included).
    pub noise_share: f64,
    /// noise_share ≤ the run's max_noise.
    pub feasible: bool,
    /// Fragments whose G or G_exact is not finite (scored as 1).
    pub non_finite: usize,
    /// Fragments scored.
    pub fragments: usize,
}

/// A paired difference of mean errors on the same fragments with its 95 % interval.
#[derive(Clone, Copy, Debug, Serialize, Deserialize)]
pub struct Paired {
    /// mean(a − b) over the paired fragments.
    pub mean: f64,
    /// 1.96·sd/√n of the per-fragment differences.
    pub half_width: f64,
    /// Fragments paired (n).
    pub fragments: usize,
}

impl Paired {
    /// mean(a − b) of per-fragment values.
    pub fn of(a: &[f64], b: &[f64]) -> Paired {
        let n = a.len().min(b.len());
        if n == 0 {
            return Paired {
                mean: f64::NAN,
                half_width: f64::NAN,
                fragments: 0,
            };
        }
        let d: Vec<f64> = a.iter().zip(b).map(|(x, y)| x - y).collect();
        let mean = d.iter().sum::<f64>() / n as f64;
        let var = if n > 1 {
            d.iter().map(|x| (x - mean) * (x - mean)).sum::<f64>() / (n - 1) as f64
        } else {
            f64::INFINITY
        };
        Paired {
            mean,
            half_width: 1.96 * (var / n as f64).sqrt(),
            fragments: n,
        }
    }
    /// Lower end of the 95 % interval, mean − half_width.
    pub fn lo(&self) -> f64 {
        self.mean - self.half_width
    }
    /// Upper end of the 95 % interval, mean + half_width.
    pub fn hi(&self) -> f64 {
        self.mean + self.half_width
    }
}

/// A published default evaluated on the same fragments, and what the tuned setting gains.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Reference {
    /// Name of the published default.
    pub name: String,
    /// The default scored on the target's fragments.
    pub scored: Scored,
    /// Its error minus the tuned (chosen) setting's error: > 0 means tuning helps.
    pub gain: Paired,
}

/// The result for one target: a scene, or all scenes ("all").
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Target {
    /// Scene name, or "all".
    pub scene: String,
    /// Fragments of the target in the confirming sample.
    pub fragments: usize,
    /// The feasible setting with the smallest error.
    pub best: Scored,
    /// The cheapest feasible setting within `tolerance` of the best.
    pub chosen: Scored,
    /// Chosen minus best error (≤ tolerance by construction), paired.
    pub chosen_minus_best: Paired,
    /// The setting chosen when the chosen one's technique and storage are left out.
    pub runner_up: Option<Scored>,
    /// Chosen minus runner-up error, paired.
    pub chosen_minus_runner_up: Option<Paired>,
    /// Settings no other setting beats in bits per texel, ns per fragment and error at once
    /// (ascending bits, then ns).
    pub pareto: Vec<Scored>,
    /// The published defaults ([`references`]) on the same fragments.
    pub references: Vec<Reference>,
    /// Per family searched: the smallest α that keeps the noise bound on this target's
    /// fragments (None: no α of the grid does).
    pub alpha_floor: Vec<AlphaFloor>,
    /// Settings confirmed on this target that break the noise bound (left out of the choice).
    pub infeasible: usize,
}

/// The smallest moment bias α of a family that keeps the noise bound.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct AlphaFloor {
    /// The family's label.
    pub family: String,
    /// The smallest α of the refined grid that keeps the noise bound (None: none does).
    pub alpha: Option<f64>,
}

/// Everything `tune` found.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Tuning {
    /// Error above the best setting that is acceptable (absolute).
    pub tolerance: f64,
    /// Largest share of fragments with noise above 1/255 for a feasible setting.
    pub max_noise: f64,
    /// Fragments sampled per scene (the confirming sample).
    pub fragments_per_scene: usize,
    /// Fragments per scene of the screening subsample.
    pub screen_per_scene: usize,
    /// Seed of the fragment sample.
    pub seed: u64,
    /// Families searched (technique × storage × own parameters).
    pub families: usize,
    /// Settings scored on the screening subsample.
    pub settings_screened: usize,
    /// Settings re-scored on the whole sample.
    pub settings_confirmed: usize,
    /// The result per scene.
    pub scenes: Vec<Target>,
    /// The result over all scenes.
    pub overall: Target,
    /// Wall time, seconds.
    pub seconds: f64,
}

/// The published defaults compared against (depth bias: momentlab's evaluation default,
/// ε = 10⁻⁴, s = 2, so only α and the exponents differ).
pub fn references() -> Vec<(String, Setting)> {
    let db = DepthBias {
        constant: 1e-4,
        slope_scale: 2.0,
    };
    let s = |t, st, own, alpha| Setting {
        family: Family {
            technique: t,
            storage: st,
            own,
        },
        alpha,
        depth_bias: db,
    };
    use StorageKind::*;
    use TechniqueKind::*;
    vec![
        (
            "paper 4MSM 16-bit θ₄ (α = 3e-5)".into(),
            s(Hamburger4, Unorm16Theta, Own::None, 3e-5),
        ),
        (
            "paper 4MSM 32-bit (α = 2e-6)".into(),
            s(Hamburger4, F32, Own::None, 2e-6),
        ),
        (
            "MJP 4MSM 32-bit (α = 3e-6)".into(),
            s(Hamburger4, F32, Own::None, 3e-6),
        ),
        (
            "MJP EVSM 32-bit (c = 40/5)".into(),
            s(
                Evsm,
                F32,
                Own::Evsm {
                    c_pos: 40.0,
                    c_neg: 5.0,
                },
                0.0,
            ),
        ),
        (
            "Filament EVSM fp16 (c = 5.54)".into(),
            s(
                Evsm,
                F16,
                Own::Evsm {
                    c_pos: 5.54,
                    c_neg: 5.54,
                },
                0.0,
            ),
        ),
        (
            "Filament EVSM fp32 (c = 42)".into(),
            s(
                Evsm,
                F32,
                Own::Evsm {
                    c_pos: 42.0,
                    c_neg: 42.0,
                },
                0.0,
            ),
        ),
        (
            "HDRP EVSM 32-bit (c = 15)".into(),
            s(
                Evsm,
                F32,
                Own::Evsm {
                    c_pos: 15.0,
                    c_neg: 15.0,
                },
                0.0,
            ),
        ),
        (
            "HDRP HDIMS 4MSM 32-bit (α = 6e-7)".into(),
            s(Hamburger4, F32, Own::None, 6e-7),
        ),
    ]
}

/// Per-scene accumulators of each setting on fragments `idx` (parallel over settings); `keep`
/// keeps every fragment's noise for quantiles. Setting `g` is unit `<phase>.<g>` of `store`.
fn score_all(
    settings: &[(usize, Setting)],
    moments: &[Moments],
    (sample, idx): (&Sample, &[usize]),
    (bar, keep): (&Bar, bool),
    (phase, store): (&str, Option<&dyn units::UnitStore>),
) -> Result<Vec<Vec<Acc>>> {
    settings
        .par_iter()
        .enumerate()
        .map(|(g, (fi, s))| {
            let accs = units::accs(store, &format!("{phase}.{g}"), || {
                let m = &moments[*fi];
                let o = score::outcomes(s, (&m.stored, &m.exact), sample, idx)?;
                Ok(score::accumulate(&o, sample, idx, keep))
            })?;
            bar.inc(1);
            Ok(accs)
        })
        .collect()
}

/// The noise floor of α per target (each scene, then all scenes) and family, on the target's
/// whole sample ([`smallest_feasible_alpha`]); target `t`, family `k` is unit `floor.<t>.<k>`
/// of `store`.
fn alpha_floors(
    families: &[Family],
    moments: &[Moments],
    fam_index: &dyn Fn(&Family) -> usize,
    (sample, max_noise): (&Sample, f64),
    (bar, store): (&Bar, Option<&dyn units::UnitStore>),
) -> Result<Vec<Vec<Option<f64>>>> {
    let nscenes = sample.scenes.len();
    bar.phase(
        "tune: smallest α within the noise bound",
        ((nscenes + 1) * families.len()) as u64,
    );
    let mut floor = Vec::with_capacity(nscenes + 1);
    for t in 0..=nscenes {
        let idx: Vec<usize> = if t == nscenes {
            (0..sample.len()).collect()
        } else {
            sample.of_scene(t)
        };
        let mut row = Vec::with_capacity(families.len());
        for (k, f) in families.iter().enumerate() {
            row.push(units::floor(store, &format!("floor.{t}.{k}"), || {
                smallest_feasible_alpha(&moments[fam_index(f)], sample, &idx, max_noise)
            })?);
            bar.inc(1);
        }
        floor.push(row);
    }
    Ok(floor)
}

/// Per-fragment scores (leak + darkening + noise, 1 where not finite) of `s` on `idx`.
fn fragment_scores(s: &Setting, m: &Moments, sample: &Sample, idx: &[usize]) -> Result<Vec<f64>> {
    Ok(score::outcomes(s, (&m.stored, &m.exact), sample, idx)?
        .iter()
        .map(Outcome::score)
        .collect())
}

/// The smallest α at which family `m.family` keeps the noise bound on fragments `idx`, at the
/// default depth bias (ε = 10⁻⁴, s = 2; the depth bias moves z_f, not the moments): the first
/// feasible α of the grid, refined by four bisection steps in log α towards the grid value
/// below it (when that is > 0). None when no α of the grid is feasible.
fn smallest_feasible_alpha(
    m: &Moments,
    sample: &Sample,
    idx: &[usize],
    max_noise: f64,
) -> Result<Option<f64>> {
    let share = |alpha: f64| -> Result<f64> {
        let s = Setting {
            family: m.family,
            alpha,
            depth_bias: DepthBias {
                constant: 1e-4,
                slope_scale: 2.0,
            },
        };
        let o = score::outcomes(&s, (&m.stored, &m.exact), sample, idx)?;
        let mut a = Acc::new(false);
        o.iter().for_each(|x| a.add(x));
        Ok(a.noise_share())
    };
    let grid = m.family.technique.alphas();
    let mut below = None;
    for &alpha in grid {
        if share(alpha)? <= max_noise {
            let Some(lo) = below.filter(|&lo: &f64| lo > 0.0) else {
                return Ok(Some(alpha));
            };
            let (mut lo, mut hi) = (lo, alpha);
            for _ in 0..4 {
                let mid: f64 = (lo * hi).sqrt();
                if share(mid)? <= max_noise {
                    hi = mid;
                } else {
                    lo = mid;
                }
            }
            // three significant digits, rounded up so the bound still holds on the grid value
            let e = hi.log10().floor() as i32 - 2;
            let k = (hi / 10f64.powi(e)).ceil();
            let rounded: f64 = format!("{k}e{e}").parse().unwrap_or(hi);
            return Ok(Some(if share(rounded)? <= max_noise {
                rounded
            } else {
                hi
            }));
        }
        below = Some(alpha);
    }
    Ok(None)
}

fn scored(s: &Setting, acc: &Acc, ns: f64, max_noise: f64) -> Scored {
    let n = acc.n.max(1) as f64;
    Scored {
        setting: *s,
        label: s.label(),
        bits_per_texel: s.family.bits_per_texel(),
        ns_per_fragment: ns,
        error: acc.score(),
        leak: acc.leak / n,
        darkening: acc.dark / n,
        noise: acc.noise / n,
        noise_p999: acc.noise_quantile(0.999),
        noise_share: acc.noise_share(),
        feasible: acc.noise_share() <= max_noise,
        non_finite: acc.non_finite,
        fragments: acc.n,
    }
}

/// Cheapest first: bits per texel, then GPU ns per lookup, then error.
fn cheaper(a: &Scored, b: &Scored) -> std::cmp::Ordering {
    a.bits_per_texel
        .cmp(&b.bits_per_texel)
        .then(a.ns_per_fragment.total_cmp(&b.ns_per_fragment))
        .then(a.error.total_cmp(&b.error))
}

/// Index of the cheapest entry within `tolerance` of the best error among `rows`.
pub fn cheapest_within(rows: &[Scored], tolerance: f64) -> Option<usize> {
    let best = rows.iter().map(|r| r.error).fold(f64::INFINITY, f64::min);
    if !best.is_finite() {
        return None;
    }
    (0..rows.len())
        .filter(|&i| rows[i].error <= best + tolerance)
        .min_by(|&i, &j| cheaper(&rows[i], &rows[j]))
}

/// Indices of the rows no other row beats in (bits, ns, error) at once, cheapest first.
pub fn pareto(rows: &[Scored]) -> Vec<usize> {
    let le = |a: &Scored, b: &Scored| {
        a.bits_per_texel <= b.bits_per_texel
            && a.ns_per_fragment <= b.ns_per_fragment
            && a.error <= b.error
    };
    let lt = |a: &Scored, b: &Scored| {
        a.bits_per_texel < b.bits_per_texel
            || a.ns_per_fragment < b.ns_per_fragment
            || a.error < b.error
    };
    let mut out: Vec<usize> = (0..rows.len())
        .filter(|&i| rows[i].error.is_finite())
        .filter(|&i| {
            !(0..rows.len()).any(|j| j != i && le(&rows[j], &rows[i]) && lt(&rows[j], &rows[i]))
        })
        .collect();
    out.sort_by(|&i, &j| cheaper(&rows[i], &rows[j]));
    out
}

/// Run the search on `stacks`; progress on `bar`.
pub fn tune(stacks: &[DepthStack], opts: &Options, bar: &Bar) -> Result<Tuning> {
    tune_with(stacks, opts, bar, None)
}

/// [`tune`] with its units (α floors, screened and confirmed settings; [`units`]) kept in
/// `store`: a unit found there is not computed again, every other one is recorded when
/// complete, so the tuning equals that of an uninterrupted run but for `seconds`. The store
/// must hold units of the same options and stacks only.
pub fn tune_with(
    stacks: &[DepthStack],
    opts: &Options,
    bar: &Bar,
    store: Option<&dyn units::UnitStore>,
) -> Result<Tuning> {
    let start = Instant::now();
    let families = opts.check()?;
    crate::metrics::require_fragments(stacks)?;
    for s in stacks {
        crate::metrics::check_stack(s)?;
    }
    bar.phase("tune: sampling fragments", stacks.len() as u64);
    let sample = sample::draw(stacks, opts.fragments_per_scene, opts.seed, &|v| {
        bar.set_done(v as u64)
    })?;
    let nscenes = sample.scenes.len();

    // Families of the space, then those of the references that are not in it.
    let refs = references();
    let mut fams = families.clone();
    for (_, r) in &refs {
        if !fams.contains(&r.family) {
            fams.push(r.family);
        }
    }
    let fam_index = |f: &Family| fams.iter().position(|g| g == f).expect("family listed");
    bar.phase("tune: storing and filtering moments", fams.len() as u64);
    let mut moments = Vec::with_capacity(fams.len());
    for f in &fams {
        moments.push(Moments::compute(f, &sample)?);
        bar.inc(1);
    }
    // GPU cost per lookup (0 without a cost model).
    let mut ns = Vec::with_capacity(fams.len());
    for f in &fams {
        ns.push(match opts.cost {
            Some(c) => c(f.technique, f.storage)?,
            None => 0.0,
        });
    }

    // The noise floor of α per target and family, on the target's whole sample.
    let floor = alpha_floors(
        &families,
        &moments,
        &fam_index,
        (&sample, opts.max_noise),
        (bar, store),
    )?;

    let screen = screen_fragments(&sample, opts.screen_per_scene);
    let grid = screen_grid(&families, &floor, &fam_index);
    bar.phase("tune: screening the grid", grid.len() as u64);
    let screened = score_all(
        &grid,
        &moments,
        (&sample, &screen),
        (bar, false),
        ("screen", store),
    )?;

    let mut confirm = shortlist(&floor, &families, (&grid, &screened), &fam_index, opts.keep);
    let n_searched = confirm.len();
    for (_, r) in &refs {
        push_new(&mut confirm, (fam_index(&r.family), *r));
    }
    bar.phase("tune: confirming on the whole sample", confirm.len() as u64);
    let all: Vec<usize> = (0..sample.len()).collect();
    let confirmed = score_all(
        &confirm,
        &moments,
        (&sample, &all),
        (bar, true),
        ("confirm", store),
    )?;
    bar.finish();

    let run = Confirmed {
        opts,
        sample: &sample,
        moments: &moments,
        families: &families,
        refs: &refs,
        floor: &floor,
        ns: &ns,
        confirm: &confirm,
        confirmed: &confirmed,
        n_searched,
    };
    let scenes = (0..nscenes)
        .map(|t| run.target(t))
        .collect::<Result<Vec<_>>>()?;
    let overall = run.target(nscenes)?;
    Ok(Tuning {
        tolerance: opts.tolerance,
        max_noise: opts.max_noise,
        fragments_per_scene: opts.fragments_per_scene,
        screen_per_scene: opts.screen_per_scene,
        seed: opts.seed,
        families: families.len(),
        settings_screened: grid.len(),
        settings_confirmed: n_searched,
        scenes,
        overall,
        seconds: start.elapsed().as_secs_f64(),
    })
}

/// The screening fragments: about `per_scene` of each scene, every k-th of its fragments.
fn screen_fragments(sample: &Sample, per_scene: usize) -> Vec<usize> {
    let mut screen = Vec::new();
    for s in 0..sample.scenes.len() {
        let of = sample.of_scene(s);
        let k = of.len().div_ceil(per_scene.min(of.len()).max(1));
        screen.extend(of.into_iter().step_by(k.max(1)));
    }
    screen
}

/// The screening grid: per family its technique's α grid plus every target's α floor, each α
/// with the family's bias grid ([`space::grid_at`]), tagged with the family's index.
fn screen_grid(
    families: &[Family],
    floor: &[Vec<Option<f64>>],
    fam_index: &dyn Fn(&Family) -> usize,
) -> Vec<(usize, Setting)> {
    let mut grid = Vec::new();
    for (k, f) in families.iter().enumerate() {
        let mut alphas: Vec<f64> = f.technique.alphas().to_vec();
        alphas.extend(floor.iter().filter_map(|row| row[k]));
        alphas.sort_by(f64::total_cmp);
        alphas.dedup();
        for s in space::grid_at(f, &alphas) {
            grid.push((fam_index(f), s));
        }
    }
    grid
}

/// Add `x` unless its setting is already listed.
fn push_new(c: &mut Vec<(usize, Setting)>, x: (usize, Setting)) {
    if !c.iter().any(|y| y.1 == x.1) {
        c.push(x);
    }
}

/// The settings to confirm: per target (each scene, then all) and family, the `keep` best of
/// the screen at or above the target's α floor, each setting once.
fn shortlist(
    floor: &[Vec<Option<f64>>],
    families: &[Family],
    (grid, screened): (&[(usize, Setting)], &[Vec<Acc>]),
    fam_index: &dyn Fn(&Family) -> usize,
    keep: usize,
) -> Vec<(usize, Setting)> {
    let nscenes = floor.len() - 1;
    let mut confirm = Vec::new();
    for (target, floors) in floor.iter().enumerate() {
        let err = |accs: &Vec<Acc>| {
            if target == nscenes {
                let mut a = Acc::new(false);
                accs.iter().for_each(|x| a.merge(x));
                a.score()
            } else {
                accs[target].score()
            }
        };
        for (k, f) in families.iter().enumerate() {
            let Some(least) = floors[k] else { continue };
            let fi = fam_index(f);
            let mut rows: Vec<usize> = (0..grid.len())
                .filter(|&g| grid[g].0 == fi && grid[g].1.alpha >= least)
                .collect();
            rows.sort_by(|&a, &b| err(&screened[a]).total_cmp(&err(&screened[b])));
            for &g in rows.iter().take(keep) {
                push_new(&mut confirm, grid[g]);
            }
        }
    }
    confirm
}

/// The confirmed settings of a search and what choosing among them needs: the sample, the
/// moments of each family, the α floors and the GPU cost per family.
struct Confirmed<'a> {
    opts: &'a Options,
    sample: &'a Sample,
    moments: &'a [Moments],
    families: &'a [Family],
    refs: &'a [(String, Setting)],
    floor: &'a [Vec<Option<f64>>],
    ns: &'a [f64],
    confirm: &'a [(usize, Setting)],
    confirmed: &'a [Vec<Acc>],
    n_searched: usize,
}

impl Confirmed<'_> {
    /// The fragments of target `t`: scene `t`, or the whole sample for `t` = number of scenes.
    fn indices(&self, t: usize) -> Vec<usize> {
        if t == self.sample.scenes.len() {
            (0..self.sample.len()).collect()
        } else {
            self.sample.of_scene(t)
        }
    }

    /// Target `t`'s choice: among the confirmed settings within the noise bound, the cheapest
    /// within the tolerance of the best, its runner-up of another technique or storage, the
    /// paired differences to both and to each reference, the Pareto front and the α floors.
    fn target(&self, t: usize) -> Result<Target> {
        let idx = self.indices(t);
        let acc_of = |accs: &Vec<Acc>| {
            if t == self.sample.scenes.len() {
                let mut a = Acc::new(true);
                accs.iter().for_each(|x| a.merge(x));
                a
            } else {
                accs[t].clone()
            }
        };
        let row = |k: usize| {
            scored(
                &self.confirm[k].1,
                &acc_of(&self.confirmed[k]),
                self.ns[self.confirm[k].0],
                self.opts.max_noise,
            )
        };
        let all_rows: Vec<Scored> = (0..self.n_searched).map(row).collect();
        // Only settings within the noise bound compete.
        let ok: Vec<usize> = (0..self.n_searched)
            .filter(|&k| all_rows[k].feasible)
            .collect();
        let rows: Vec<Scored> = ok.iter().map(|&k| all_rows[k].clone()).collect();
        let name = if t == self.sample.scenes.len() {
            "all".to_string()
        } else {
            self.sample.scenes[t].clone()
        };
        let Some(c) = cheapest_within(&rows, self.opts.tolerance) else {
            let least = all_rows
                .iter()
                .min_by(|a, b| a.noise_share.total_cmp(&b.noise_share))
                .map(|r| {
                    format!(
                        "; the least noisy is {} at {:.3} %",
                        r.label,
                        100.0 * r.noise_share
                    )
                })
                .unwrap_or_default();
            bail!(
            "{name}: no setting keeps the noise bound (at most {:.3} % of fragments more than 1/255 from exact moments){least}; raise --max-noise or allow 32-bit storage",
            100.0 * self.opts.max_noise
        );
        };
        let b = (0..rows.len())
            .min_by(|&i, &j| rows[i].error.total_cmp(&rows[j].error))
            .expect("rows");
        let errs = |k: usize| -> Result<Vec<f64>> {
            let (fi, s) = &self.confirm[k];
            fragment_scores(s, &self.moments[*fi], self.sample, &idx)
        };
        let chosen_errs = errs(ok[c])?;
        let same = |k: usize| {
            rows[k].setting.family.technique == rows[c].setting.family.technique
                && rows[k].setting.family.storage == rows[c].setting.family.storage
        };
        let others: Vec<usize> = (0..rows.len()).filter(|&k| !same(k)).collect();
        let sub: Vec<Scored> = others.iter().map(|&k| rows[k].clone()).collect();
        let runner = cheapest_within(&sub, self.opts.tolerance).map(|k| others[k]);
        let runner_pair = match runner {
            Some(r) => Some(Paired::of(&chosen_errs, &errs(ok[r])?)),
            None => None,
        };
        let mut references = Vec::new();
        for (name, r) in self.refs.iter() {
            let k = self
                .confirm
                .iter()
                .position(|x| x.1 == *r)
                .expect("reference confirmed");
            references.push(Reference {
                name: name.clone(),
                scored: row(k),
                gain: Paired::of(&errs(k)?, &chosen_errs),
            });
        }
        Ok(Target {
            scene: name,
            fragments: idx.len(),
            best: rows[b].clone(),
            chosen: rows[c].clone(),
            chosen_minus_best: Paired::of(&chosen_errs, &errs(ok[b])?),
            runner_up: runner.map(|r| rows[r].clone()),
            chosen_minus_runner_up: runner_pair,
            pareto: pareto(&rows).into_iter().map(|k| rows[k].clone()).collect(),
            references,
            alpha_floor: self
                .families
                .iter()
                .zip(&self.floor[t])
                .map(|(f, a)| AlphaFloor {
                    family: f.label(),
                    alpha: *a,
                })
                .collect(),
            infeasible: self.n_searched - ok.len(),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(bits: u32, ns: f64, error: f64) -> Scored {
        let f = Family {
            technique: TechniqueKind::Vsm,
            storage: StorageKind::F32,
            own: Own::None,
        };
        Scored {
            setting: Setting {
                family: f,
                alpha: 0.0,
                depth_bias: DepthBias {
                    constant: 0.0,
                    slope_scale: 0.0,
                },
            },
            label: String::new(),
            bits_per_texel: bits,
            ns_per_fragment: ns,
            error,
            leak: error,
            darkening: 0.0,
            noise: 0.0,
            noise_p999: 0.0,
            noise_share: 0.0,
            feasible: true,
            non_finite: 0,
            fragments: 1,
        }
    }

    #[test]
    fn cheapest_within_orders_bits_then_ns_then_error() {
        let rows = vec![
            row(128, 10.0, 0.010),
            row(64, 50.0, 0.011),
            row(64, 20.0, 0.0115),
        ];
        assert_eq!(cheapest_within(&rows, 0.002), Some(2));
        assert_eq!(cheapest_within(&rows, 0.0012), Some(1));
        assert_eq!(cheapest_within(&rows, 0.0), Some(0));
        assert_eq!(pareto(&rows), vec![2, 1, 0]);
        let dominated = vec![
            row(64, 10.0, 0.01),
            row(64, 20.0, 0.02),
            row(32, 30.0, 0.005),
        ];
        assert_eq!(pareto(&dominated), vec![2, 0]);
    }

    #[test]
    fn paired_interval_is_normal_theory() {
        let a = [1.0, 2.0, 3.0, 4.0];
        let b = [0.0, 0.0, 0.0, 0.0];
        let p = Paired::of(&a, &b);
        assert!((p.mean - 2.5).abs() < 1e-15);
        // sd = sqrt(5/3), n = 4
        assert!((p.half_width - 1.96 * (5.0f64 / 3.0 / 4.0).sqrt()).abs() < 1e-12);
        assert!(p.lo() < p.mean && p.mean < p.hi());
    }
}
