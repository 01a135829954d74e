//! Reference scoring for sweep reports: the paper's bases as LP candidates on every fragment
//! (PCF, VSM, ESM, b_MSM, b_TMSM), the closed forms via `metrics::evaluate`, the winner and the
//! ranks of the references among the candidates ([`summarize`]), and the data of the Fig. 3
//! analogue (F_Z and the sharp lower bounds of Algorithm 1 for m = 2, 3, 4). Drawing and
//! Markdown: `crate::report::sweep`, `crate::report::sweep_charts`.

use super::race::Moments;
use super::results::{ranking, Row};
use super::score::bound_curve;
use super::tieset::tie_set;
use super::{Dataset, FunctionTable, Scorer};
use crate::metrics::{self, Bias, EvalOptions, Subject};
use crate::stack::DepthStack;
use anyhow::{Context, Result};
use serde::Serialize;
use std::cell::RefCell;
use std::f64::consts::PI;
use std::rc::Rc;

/// A labelled error value marked in the histogram (e.g. "b_MSM (LP)").
#[derive(Clone, Debug, PartialEq)]
pub struct Reference {
    /// Label in the histogram and tables.
    pub label: String,
    /// Number of functions (ranks are only stated among candidates of the same m).
    pub m: usize,
    /// Mean |G − PCF|.
    pub error: f64,
    /// Standard error of `error`.
    pub stderr: f64,
    /// A closed-form technique evaluated by [`metrics::evaluate`] on every fragment of the
    /// stacks (not an LP candidate on the sweep's fragments).
    pub closed_form: bool,
    /// error − error(winner) and its standard error, paired on the same fragments
    /// ([`pair_with_winner`]); None: filled in unpaired by [`summarize`].
    pub diff: Option<(f64, f64)>,
}

/// The paper's reference bases (Eq. 1 and VSM/ESM) tabulated on a grid, for reference values
/// and Fig. 3: columns z, z², z³, z⁴, sin 2πz, cos 2πz, sin 4πz, cos 4πz, exp(80(z−1)).
pub fn paper_bases(grid: &crate::Grid) -> Result<FunctionTable> {
    let names = [
        "z",
        "z^2",
        "z^3",
        "z^4",
        "sin(2pi z)",
        "cos(2pi z)",
        "sin(4pi z)",
        "cos(4pi z)",
        "exp(80(z-1))",
    ];
    FunctionTable::new(
        grid,
        names.iter().map(|s| s.to_string()).collect(),
        |j, z| match j {
            0..=3 => z.powi(j as i32 + 1),
            4 => (2.0 * PI * z).sin(),
            5 => (2.0 * PI * z).cos(),
            6 => (4.0 * PI * z).sin(),
            7 => (4.0 * PI * z).cos(),
            _ => (80.0 * (z - 1.0)).exp(),
        },
    )
}

/// Display names of the columns of [`paper_bases`] (Fig. 3 legends).
const FIG3_NAMES: [&str; 8] = [
    "z", "z²", "z³", "z⁴", "sin 2πz", "cos 2πz", "sin 4πz", "cos 4πz",
];

/// Columns of [`paper_bases`] of the polynomial basis (z, …, z^m).
pub fn poly_cols(m: usize) -> Vec<usize> {
    (0..m).collect()
}
/// Columns of [`paper_bases`] of the trigonometric basis (sin 2πz, cos 2πz, …), m of them.
pub fn trig_cols(m: usize) -> Vec<usize> {
    (4..4 + m).collect()
}

/// Number of LP references scored on every fragment after a race ([`lp_references`]).
pub const LP_REFERENCES: usize = 4;

/// The paper's LP reference bases: (label, columns of [`paper_bases`]).
fn lp_reference_sets() -> [(&'static str, Vec<usize>); LP_REFERENCES] {
    [
        ("VSM (LP)", vec![0, 1]),
        ("ESM c=80 (LP)", vec![8]),
        ("b_MSM (LP)", poly_cols(4)),
        ("b_TMSM (LP)", trig_cols(4)),
    ]
}

/// Reference values as LP candidates on every fragment: PCF (0), VSM = (z, z²),
/// ESM = exp(80(z−1)) (c = 80), b_MSM, b_TMSM.
pub fn lp_references(data: &Dataset, solver: &str, chunk: usize) -> Result<Vec<Reference>> {
    Ok(lp_reference_errors(data, solver, chunk, &|_| {})?
        .iter()
        .map(|(r, _)| r.clone())
        .collect())
}

/// [`lp_references`] with each reference's per-fragment errors (fragment order 0..n);
/// `tick(fragments)` as solves finish.
fn lp_reference_errors(
    data: &Dataset,
    solver: &str,
    chunk: usize,
    tick: &(dyn Fn(u64) + Sync),
) -> Result<Vec<(Reference, Vec<f64>)>> {
    let table = paper_bases(data.grid())?;
    let s = Scorer::new(data, &table, solver, chunk)?;
    let ids: Vec<u32> = (0..data.fragments().len() as u32).collect();
    let sets = lp_reference_sets();
    let subsets: Vec<Vec<usize>> = sets.iter().map(|s| s.1.clone()).collect();
    let errs = s.errors_many(&subsets, &ids, tick)?;
    let mut out = vec![(
        Reference {
            label: "PCF".into(),
            m: 0,
            error: 0.0,
            stderr: 0.0,
            closed_form: false,
            diff: None,
        },
        Vec::new(),
    )];
    for ((label, cols), e) in sets.iter().zip(errs) {
        let m = Moments::of(&e.errors);
        let (error, stderr) = data.error_estimate(m.n, m.sum, m.sumsq);
        out.push((
            Reference {
                label: label.to_string(),
                m: cols.len(),
                error,
                stderr: if stderr.is_finite() { stderr } else { 0.0 },
                closed_form: false,
                diff: None,
            },
            e.errors,
        ));
    }
    Ok(out)
}

/// The references of the sweeps on one set of depth stacks, each computed once and kept for
/// the next sweep (`reproduce` sweeps m = 2, 3 and 4 on the same stacks and dataset): the
/// closed forms on the stacks ([`closed_form_references`], per bias) and the LP references'
/// per-fragment errors (per dataset, told apart by [`Dataset::fingerprint`], solver and
/// chunk). Neither depends on m.
#[derive(Default)]
pub struct ReferenceCache<'a> {
    stacks: Option<&'a [DepthStack]>,
    closed: RefCell<Option<(Bias, Vec<Reference>)>>,
    lp: RefCell<Option<(LpKey, LpErrors)>>,
}

/// What the LP references' errors depend on: the dataset's fingerprint, solver and chunk.
type LpKey = (u64, String, usize);
/// The LP references with their per-fragment errors.
type LpErrors = Rc<Vec<(Reference, Vec<f64>)>>;

impl<'a> ReferenceCache<'a> {
    /// A cache for sweeps on `stacks` (None: no closed-form references, e.g. synthetic data).
    pub fn new(stacks: Option<&'a [DepthStack]>) -> ReferenceCache<'a> {
        ReferenceCache {
            stacks,
            ..ReferenceCache::default()
        }
    }

    /// The stacks the closed forms are evaluated on.
    pub fn stacks(&self) -> Option<&'a [DepthStack]> {
        self.stacks
    }

    /// [`closed_form_references`] on the stacks with `bias` (empty without stacks).
    pub fn closed_forms(&self, bias: &Bias) -> Result<Vec<Reference>> {
        let Some(stacks) = self.stacks else {
            return Ok(Vec::new());
        };
        if let Some((b, refs)) = &*self.closed.borrow() {
            if b == bias {
                return Ok(refs.clone());
            }
        }
        let refs = closed_form_references(stacks, bias)?;
        *self.closed.borrow_mut() = Some((*bias, refs.clone()));
        Ok(refs)
    }

    /// The LP references' errors on every fragment of `data` ([`lp_reference_errors`]);
    /// `tick(fragments)` as solves finish (not called when they are known already).
    fn lp_errors(
        &self,
        data: &Dataset,
        solver: &str,
        chunk: usize,
        tick: &(dyn Fn(u64) + Sync),
    ) -> Result<LpErrors> {
        let key = (data.fingerprint(), solver.to_string(), chunk);
        if let Some((k, e)) = &*self.lp.borrow() {
            if *k == key {
                return Ok(e.clone());
            }
        }
        let e = Rc::new(lp_reference_errors(data, solver, chunk, tick)?);
        *self.lp.borrow_mut() = Some((key, e.clone()));
        Ok(e)
    }
}

/// [`lp_references`] with the paired difference of each reference to the winner `cols` of
/// `table` (both scored on every fragment of `data`, same solver): mean of
/// e_ref − e_winner over the fragments, scaled like the errors, with its standard error.
/// The references' errors come from `cache` when it holds them for this dataset; `tick`
/// counts the fragments solved (winner and references).
pub fn lp_references_paired(
    data: &Dataset,
    table: &FunctionTable,
    winner: &[usize],
    (solver, chunk): (&str, usize),
    cache: &ReferenceCache,
    tick: &(dyn Fn(u64) + Sync),
) -> Result<Vec<Reference>> {
    let ids: Vec<u32> = (0..data.fragments().len() as u32).collect();
    let s = Scorer::new(data, table, solver, chunk)?;
    let ew = s.errors_many(&[winner.to_vec()], &ids, tick)?;
    let ew = &ew[0].errors;
    let scale = data.nontrivial_population() as f64 / data.total_count().max(1) as f64;
    Ok(cache
        .lp_errors(data, solver, chunk, tick)?
        .iter()
        .map(|(r, e)| {
            let mut r = r.clone();
            if !e.is_empty() {
                let d: Vec<f64> = e.iter().zip(ew).map(|(a, b)| a - b).collect();
                let m = Moments::of(&d);
                r.diff = Some((m.mean() * scale, m.se() * scale));
            }
            r
        })
        .collect())
}

/// Closed-form techniques marked in the Fig. 4 analogue: (registry name, label, m).
pub const CLOSED_FORMS: [(&str, &str, usize); 4] = [
    ("hamburger4", "4MSM Hamburger (closed form)", 4),
    ("tmsm", "TMSM (closed form)", 4),
    ("vsm", "VSM (closed form)", 2),
    ("esm", "ESM (closed form)", 1),
];

/// The closed forms of [`CLOSED_FORMS`] (`technique::by_name`, default parameters) evaluated
/// with [`metrics::evaluate`] on every fragment of `stacks` with `bias`: the population value
/// the sweep's sampled candidate errors estimate (standard error 0: nothing is sampled).
pub fn closed_form_references(stacks: &[DepthStack], bias: &Bias) -> Result<Vec<Reference>> {
    let opts = EvalOptions {
        bias: *bias,
        ..EvalOptions::default()
    };
    let techniques = CLOSED_FORMS
        .iter()
        .map(|(name, _, _)| crate::technique::by_name(name))
        .collect::<Result<Vec<_>>>()?;
    let subjects: Vec<Subject> = techniques
        .iter()
        .map(|t| Subject::Technique(t.as_ref()))
        .collect();
    // One pass over the fragments and their PCF reference for all closed forms.
    let reports = metrics::evaluate_subjects(stacks, &subjects, &opts)
        .context("evaluating the closed-form references")?;
    Ok(CLOSED_FORMS
        .iter()
        .zip(reports)
        .map(|((_, label, m), r)| Reference {
            label: label.to_string(),
            m: *m,
            error: r.error,
            stderr: 0.0,
            closed_form: true,
            diff: None,
        })
        .collect())
}

/// A reference value with its rank among the scored candidates of the same m.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct RankedReference {
    /// Label of the reference.
    pub label: String,
    /// Number of functions.
    pub m: usize,
    /// Mean |G − PCF|.
    pub error: f64,
    /// Standard error of `error`.
    pub stderr: f64,
    /// Whether it is a closed-form technique (see [`Reference::closed_form`]).
    pub closed_form: bool,
    /// 1 + number of candidates with a smaller error (None: different m or PCF).
    pub rank: Option<usize>,
    /// error − error(winner) and its standard error (None: PCF).
    pub diff: Option<(f64, f64)>,
    /// `diff` is paired on the same fragments (LP references) rather than unpaired (closed
    /// forms: exact value minus the winner's estimate).
    pub paired: bool,
}

/// The best candidate of a results set.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Best {
    /// Candidate index.
    pub index: u64,
    /// Names of its basis functions.
    pub functions: Vec<String>,
    /// Mean |G − PCF|.
    pub error: f64,
    /// Standard error of `error`.
    pub stderr: f64,
    /// Scored on every fragment of the dataset (not only a racing sample).
    pub full: bool,
}

/// What a report says, as numbers (for `momentlab reproduce`).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Summary {
    /// Candidates with an error (scored, or duplicates of a scored one).
    pub scored: usize,
    /// The winner (the best survivor of the race, or the best candidate scored on every
    /// fragment).
    pub best: Option<Best>,
    /// The references with their ranks.
    pub references: Vec<RankedReference>,
    /// Racing: candidates statistically tied for first (the winner included), eliminated by
    /// evidence, left unresolved by an LP budget (0 for exhaustive runs).
    pub tied: usize,
    /// Candidates eliminated by the racing tests.
    pub confidence_eliminated: usize,
    /// Candidates left unresolved by the LP budget.
    pub unresolved: usize,
}

impl Summary {
    /// The reference with this label, if present.
    pub fn reference(&self, label: &str) -> Option<&RankedReference> {
        self.references.iter().find(|r| r.label == label)
    }
}

/// The winner and the ranks of `refs` among `rows` (same m only), with each reference's
/// difference to the winner (paired where [`lp_references_paired`] computed it, else unpaired:
/// √(se_ref² + se_winner²)).
pub fn summarize(rows: &[Row], refs: &[Reference]) -> Summary {
    let errs = errors_of(rows);
    let t = tie_set(rows);
    let best = t.winner.as_ref().map(|r| Best {
        index: r.index,
        functions: r.functions.clone(),
        error: r.error.unwrap_or(f64::NAN),
        stderr: r.stderr.unwrap_or(0.0),
        full: r.full,
    });
    let m = best.as_ref().map(|b| b.functions.len());
    Summary {
        scored: errs.len(),
        references: refs
            .iter()
            .map(|r| {
                let unpaired = best.as_ref().map(|b| {
                    (
                        r.error - b.error,
                        (r.stderr * r.stderr + b.stderr * b.stderr).sqrt(),
                    )
                });
                RankedReference {
                    label: r.label.clone(),
                    m: r.m,
                    error: r.error,
                    stderr: r.stderr,
                    closed_form: r.closed_form,
                    rank: (Some(r.m) == m && r.label != "PCF").then(|| rank_of(&errs, r.error)),
                    diff: if r.label == "PCF" {
                        None
                    } else {
                        r.diff.or(unpaired)
                    },
                    paired: r.diff.is_some(),
                }
            })
            .collect(),
        best,
        tied: t.tied.len(),
        confidence_eliminated: t.confidence,
        unresolved: t.unresolved.len(),
    }
}

/// Scored errors of a results set (duplicates resolved), ascending.
pub fn errors_of(rows: &[Row]) -> Vec<f64> {
    ranking(rows).iter().filter_map(|r| r.error).collect()
}

/// One Fig. 3 panel: F_Z and the bounds G for m = 2, 3, 4 of one basis family.
pub struct Fig3Panel {
    /// Panel title (the basis family).
    pub title: String,
    /// z_f values.
    pub z: Vec<f64>,
    /// F_Z(z_f) of the panel's distribution.
    pub cdf: Vec<f64>,
    /// (label, G values) for m = 2, 3, 4.
    pub bounds: Vec<(String, Vec<f64>)>,
}

/// Fig. 3 analogue data for `kernels` (distribution ids): polynomial and trigonometric bases,
/// m = 2, 3, 4, G at up to `points` grid depths.
pub fn fig3_panels(
    data: &Dataset,
    kernels: &[u32],
    points: usize,
    solver: &str,
) -> Result<Vec<Fig3Panel>> {
    let table = paper_bases(data.grid())?;
    let n = data.grid().len();
    let step = n.div_ceil(points.max(2)).max(1);
    let mut idx: Vec<usize> = (0..n).step_by(step).collect();
    if *idx.last().unwrap() != n - 1 {
        idx.push(n - 1);
    }
    let z: Vec<f64> = idx.iter().map(|&i| data.grid().points()[i]).collect();
    let mut out = Vec::new();
    for &k in kernels {
        let dist = data.distribution(k);
        let cdf: Vec<f64> = idx.iter().map(|&i| data.cdf(k, i as u32)).collect();
        for (family, cols) in [
            ("polynomial", poly_cols as fn(usize) -> Vec<usize>),
            ("trigonometric", trig_cols),
        ] {
            let mut bounds = Vec::new();
            for m in 2..=4 {
                let c = cols(m);
                let g = bound_curve(&table, &c, dist, &idx, solver)?;
                let names: Vec<&str> = c.iter().map(|&j| FIG3_NAMES[j]).collect();
                bounds.push((format!("({})", names.join(", ")), g));
            }
            out.push(Fig3Panel {
                title: format!(
                    "{family} bases; a filter window with {} distinct depths",
                    dist.len()
                ),
                z: z.clone(),
                cdf: cdf.clone(),
                bounds,
            });
        }
    }
    Ok(out)
}

/// Kernels for Fig. 3: the `count` distributions with the most distinct depths (ties: id).
pub fn pick_kernels(data: &Dataset, count: usize) -> Vec<u32> {
    let mut d: Vec<(usize, u32)> = (0..data.distribution_count() as u32)
        .map(|k| (data.distribution(k).len(), k))
        .collect();
    d.sort_by(|a, b| b.0.cmp(&a.0).then(a.1.cmp(&b.1)));
    d.into_iter().take(count).map(|x| x.1).collect()
}

/// Rank of an error value among the scored candidates: 1 + #candidates strictly better.
pub fn rank_of(errors_sorted: &[f64], e: f64) -> usize {
    1 + errors_sorted.partition_point(|&x| x < e)
}
