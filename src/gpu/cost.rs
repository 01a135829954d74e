//! The GPU cost of a setting: nanoseconds per shadow lookup, measured by `gpu bench` where an
//! adapter exists ([`measured_costs`]), otherwise predicted from the lookup program itself
//! ([`gpu_cost`]), and the size of the setting's export.
//!
//! **The program.** The lookup of technique × storage is `tunedShadow` of the module that
//! `tune export` and `gpu check` emit ([`export::module`] of the setting [`study::settings`]
//! runs): the decode of the stored channels (θ⁻¹ where the storage has θ), the moment bias and
//! the reconstruction. α, the depth bias and the own parameters (ESM c, EVSM c±) change its
//! constants only, so one program stands for every setting of technique × storage.
//!
//! **What is counted** ([`OpCount`]): every statement of the shader IR once per execution —
//! a statement inside a loop body once per trip — in four classes: arithmetic (+ − × negation,
//! abs, min, max, clamp), division, transcendental (sqrt, exp, log, sin, cos, acos, atan2) and
//! selects `(a cmp b) ? x : y`. The IR has no data-dependent branches: every branch of a
//! reconstruction is computed and chosen by a select, which is what its `?:` compiles to. Loops
//! have constant trip counts; each trip adds one loop-control step.
//!
//! **The model.** Weighted operations
//! W = arithmetic + selects + 4·(division + transcendental) + 2·(loop trips),
//! the weights fixed beforehand: a division or a transcendental is a
//! reciprocal, root, exponential or sine of a GPU's special-function unit, a quarter of the
//! arithmetic rate (AMD GCN/RDNA; an NVIDIA SM has 16 such lanes beside 64 to 128 f32 lanes),
//! and a loop trip is a counter increment and a compare-and-branch. Then ns per lookup
//! = a + b·W, with a (the lookup pass itself: dispatch, texture fetch, write) and b fitted by
//! least squares on the relative residuals, Σ ((a + b·Wᵢ)/yᵢ − 1)², over the lookup times yᵢ
//! of a committed `gpu bench` artefact (`reports/gpu/<adapter>.json`, one fit per artefact,
//! [`fits`]). A hardware artefact is preferred to a software one (lavapipe runs the shader on
//! the CPU); the cost names the adapter it is calibrated on. With b > 0 the order of settings
//! by cost is the order by W on any calibration: the fit sets the scale in nanoseconds.
//!
//! **The export.** `export_lines` is the line count of the GLSL file `tune export` writes for
//! the setting; above [`EXPORT_LINES_BOUND`] the cost is flagged.

use crate::gpu::bench::{self, Plan, Report};
use crate::gpu::{study, Gpu};
use crate::shader::ir::{Func, Node, Op};
use crate::stack::DepthStack;
use crate::tune::export;
use crate::tune::space::{Setting, StorageKind, TechniqueKind};
use anyhow::{anyhow, bail, Result};
use serde::{Deserialize, Serialize};
use std::path::Path;
use std::sync::OnceLock;

/// Weight of an arithmetic operation or a select in [`OpCount::weighted`].
pub const W_ARITHMETIC: f64 = 1.0;
/// Weight of a division or a transcendental: quarter-rate special-function units.
pub const W_SPECIAL: f64 = 4.0;
/// Weight of one loop trip: counter increment, compare and branch.
pub const W_LOOP_TRIP: f64 = 2.0;

/// The export size bound (lines of GLSL), defined beside the export.
pub use crate::tune::export::EXPORT_LINES_BOUND;

/// Where a [`GpuCost`]'s nanoseconds come from.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "lowercase")]
pub enum CostSource {
    /// `gpu bench`'s lookup pass on this adapter.
    Measured {
        /// Name of the adapter.
        adapter: String,
    },
    /// The op-count model, calibrated on the bench artefacts of these adapters.
    Model {
        /// Names of the adapters.
        calibrated_on: Vec<String>,
    },
}

/// Operations of one execution of a shader function (a loop body counted once per trip).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct OpCount {
    /// + − × negation, abs, min, max, clamp.
    pub arithmetic: u64,
    /// Divisions.
    pub division: u64,
    /// sqrt, exp, log, sin, cos, acos, atan2.
    pub transcendental: u64,
    /// `(a cmp b) ? x : y`: the branches of the reconstruction.
    pub selects: u64,
    /// Loops in the program (each with a constant trip count).
    pub loops: u64,
    /// Iterations of all loops together.
    pub loop_trips: u64,
}

impl OpCount {
    /// The counts of `f`; an error for malformed loops.
    pub fn of(f: &Func) -> Result<OpCount> {
        let scope = f.scopes()?;
        let mut c = OpCount::default();
        for (n, s) in f.nodes.iter().zip(&scope) {
            let k = match s.map(|b| &f.nodes[b]) {
                Some(Node::Loop(trips)) => *trips as u64,
                _ => 1,
            };
            match n {
                Node::Loop(trips) => {
                    c.loops += 1;
                    c.loop_trips += *trips as u64;
                }
                Node::Op(op) => {
                    use Op::*;
                    let class = match op {
                        Add(..) | Sub(..) | Mul(..) | Neg(_) | Abs(_) | Min(..) | Max(..)
                        | Clamp(..) => &mut c.arithmetic,
                        Div(..) => &mut c.division,
                        Sqrt(_) | Cos(_) | Sin(_) | Acos(_) | Atan2(..) | Exp(_) | Log(_) => {
                            &mut c.transcendental
                        }
                        Select(..) => &mut c.selects,
                    };
                    *class += k;
                }
                Node::Input(..) | Node::Const(_) | Node::Var(_) | Node::EndLoop(_) => {}
            }
        }
        Ok(c)
    }

    /// W = arithmetic + selects + 4·(division + transcendental) + 2·loop trips.
    pub fn weighted(&self) -> f64 {
        W_ARITHMETIC * (self.arithmetic + self.selects) as f64
            + W_SPECIAL * (self.division + self.transcendental) as f64
            + W_LOOP_TRIP * self.loop_trips as f64
    }
}

/// The GPU cost of technique × storage.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct GpuCost {
    /// Nanoseconds per shadow lookup (one fragment).
    pub ns_per_lookup: f64,
    /// Where `ns_per_lookup` comes from.
    pub source: CostSource,
    /// Operations of the lookup program (`tunedShadow`).
    pub ops: OpCount,
    /// Lines of the setting's GLSL export (`shadow.glsl`).
    pub export_lines: usize,
    /// `export_lines` > [`EXPORT_LINES_BOUND`].
    pub over_size_bound: bool,
}

/// The setting `gpu check` and `gpu bench` run for technique × storage; an error when the
/// technique does not use the storage in `tune`'s space.
pub fn setting(t: TechniqueKind, s: StorageKind) -> Result<Setting> {
    study::settings()
        .into_iter()
        .find(|x| x.family.technique == t && x.family.storage == s)
        .ok_or_else(|| {
            anyhow!(
                "gpu cost: {} does not use {} storage (it uses {})",
                t.name(),
                s.name(),
                t.storages()
                    .iter()
                    .map(|s| s.name())
                    .collect::<Vec<_>>()
                    .join(", ")
            )
        })
}

/// What the program of technique × storage gives without a GPU: its op counts and export size.
#[derive(Clone, Copy, Debug)]
struct Program {
    technique: TechniqueKind,
    storage: StorageKind,
    ops: OpCount,
    export_lines: usize,
}

fn program(t: TechniqueKind, s: StorageKind) -> Result<Program> {
    let st = setting(t, s)?;
    let Some(m) = export::module(&st, export::header(&st))? else {
        bail!("gpu cost: {} has no shader reconstruction", st.label());
    };
    let f = m
        .func("tunedShadow")
        .ok_or_else(|| anyhow!("gpu cost: {}: no tunedShadow", st.label()))?;
    Ok(Program {
        technique: t,
        storage: s,
        ops: OpCount::of(f)?,
        export_lines: export::module_glsl_lines(&m)?,
    })
}

/// Every technique × storage of `tune`'s space, built once.
fn programs() -> Result<&'static [Program]> {
    static P: OnceLock<Result<Vec<Program>, String>> = OnceLock::new();
    P.get_or_init(|| {
        TechniqueKind::ALL
            .iter()
            .flat_map(|&t| t.storages().iter().map(move |&s| (t, s)))
            .map(|(t, s)| program(t, s))
            .collect::<Result<Vec<_>>>()
            .map_err(|e| e.to_string())
    })
    .as_deref()
    .map_err(|e| anyhow!("{e}"))
}

fn program_of(t: TechniqueKind, s: StorageKind) -> Result<Program> {
    setting(t, s)?;
    programs()?
        .iter()
        .find(|p| p.technique == t && p.storage == s)
        .copied()
        .ok_or_else(|| anyhow!("gpu cost: no program for {} {}", t.name(), s.name()))
}

/// One technique × storage of a calibration.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct FitRow {
    /// The technique.
    pub technique: TechniqueKind,
    /// The storage format.
    pub storage: StorageKind,
    /// W of its lookup program.
    pub weighted_ops: f64,
    /// The bench's ns per lookup (see [`lookup_ns`]).
    pub measured_ns: f64,
    /// a + b·W.
    pub model_ns: f64,
}

impl FitRow {
    /// model / measured − 1.
    pub fn residual(&self) -> f64 {
        self.model_ns / self.measured_ns - 1.0
    }
}

/// The model ns = a + b·W calibrated on one bench artefact.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Fit {
    /// Name of the adapter of the bench artefact.
    pub adapter: String,
    /// Whether that adapter is a software rasterizer.
    pub software: bool,
    /// a: ns per lookup of a program without operations.
    pub intercept_ns: f64,
    /// b: ns per weighted operation.
    pub ns_per_op: f64,
    /// The technique × storage rows fitted.
    pub rows: Vec<FitRow>,
}

impl Fit {
    /// Predicted ns per lookup, a + b·W, for a program with operations `ops`.
    pub fn predict(&self, ops: &OpCount) -> f64 {
        self.intercept_ns + self.ns_per_op * ops.weighted()
    }

    /// Largest |residual| and root mean square residual.
    pub fn residual_summary(&self) -> (f64, f64) {
        let r: Vec<f64> = self.rows.iter().map(FitRow::residual).collect();
        let max = r.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        let rms = (r.iter().map(|x| x * x).sum::<f64>() / r.len().max(1) as f64).sqrt();
        (max, rms)
    }
}

/// A bench's ns per lookup of technique × storage: the median, over the points at the base
/// shadow-map size and output resolution (the filter taps do not change the lookup pass), of
/// each point's median lookup time divided by the lookups (output²). None when the bench has
/// no such point.
pub fn lookup_ns(r: &Report, t: TechniqueKind, s: StorageKind) -> Option<f64> {
    let (size, _, output) = r.plan.base;
    let mut v: Vec<f64> = r
        .points
        .iter()
        .filter(|p| p.technique == t.name() && p.storage == s.name())
        .filter(|p| p.size == size && p.output == output && output > 0)
        .map(|p| p.lookup_ms.median * 1e6 / (output * output) as f64)
        .collect();
    v.sort_by(f64::total_cmp);
    v.get(v.len() / 2).copied()
}

/// Fit a + b·W to the lookup times of `r` (relative least squares). A fit with a < 0 is
/// refitted through the origin (a = 0); one with b ≤ 0 (no time grows with the program) is an
/// error, as is a bench without per-pass times or with fewer than two distinct programs.
pub fn fit(r: &Report) -> Result<Fit> {
    let name = &r.adapter.name;
    if r.timer != "timestamp" {
        bail!(
            "gpu cost: the bench of {name} has no per-pass times (timer '{}')",
            r.timer
        );
    }
    let mut rows = Vec::new();
    for p in programs()? {
        if let Some(y) = lookup_ns(r, p.technique, p.storage) {
            if !(y.is_finite() && y > 0.0) {
                bail!(
                    "gpu cost: the bench of {name} has lookup time {y} ns for {} {}",
                    p.technique.name(),
                    p.storage.name()
                );
            }
            rows.push(FitRow {
                technique: p.technique,
                storage: p.storage,
                weighted_ops: p.ops.weighted(),
                measured_ns: y,
                model_ns: 0.0,
            });
        }
    }
    let distinct = rows.iter().any(|r| r.weighted_ops != rows[0].weighted_ops);
    if rows.len() < 2 || !distinct {
        bail!("gpu cost: the bench of {name} has fewer than two distinct lookup programs");
    }
    // minimise Σ (a·uᵢ + b·vᵢ − 1)², uᵢ = 1/yᵢ, vᵢ = Wᵢ/yᵢ
    let (mut suu, mut suv, mut svv, mut su, mut sv) = (0.0, 0.0, 0.0, 0.0, 0.0);
    for row in &rows {
        let (u, v) = (1.0 / row.measured_ns, row.weighted_ops / row.measured_ns);
        suu += u * u;
        suv += u * v;
        svv += v * v;
        su += u;
        sv += v;
    }
    let det = suu * svv - suv * suv;
    let (mut a, mut b) = ((su * svv - sv * suv) / det, (suu * sv - suv * su) / det);
    if a < 0.0 {
        a = 0.0;
        b = sv / svv;
    }
    if !(b.is_finite() && b > 0.0 && a.is_finite()) {
        bail!("gpu cost: the lookup times of {name} do not grow with the program (b = {b})");
    }
    for row in &mut rows {
        row.model_ns = a + b * row.weighted_ops;
    }
    Ok(Fit {
        adapter: name.clone(),
        software: r.adapter.software,
        intercept_ns: a,
        ns_per_op: b,
        rows,
    })
}

/// The committed bench artefacts the model is calibrated on (`reports/gpu/*.json`, embedded;
/// a unit test keeps this list equal to the directory).
pub const BENCHES: [(&str, &str); 1] = [(
    "llvmpipe-llvm-15-0-6-256-bits.json",
    include_str!("../../reports/gpu/llvmpipe-llvm-15-0-6-256-bits.json"),
)];

/// The fits of every [`BENCHES`] artefact, computed once.
pub fn fits() -> Result<&'static [Fit]> {
    static F: OnceLock<Result<Vec<Fit>, String>> = OnceLock::new();
    F.get_or_init(|| {
        BENCHES
            .iter()
            .map(|(file, text)| {
                let r: Report =
                    serde_json::from_str(text).map_err(|e| anyhow!("reports/gpu/{file}: {e}"))?;
                fit(&r)
            })
            .collect::<Result<Vec<_>>>()
            .map_err(|e| e.to_string())
    })
    .as_deref()
    .map_err(|e| anyhow!("{e}"))
}

/// The fit [`gpu_cost`] uses: the first hardware one, else the first software one.
pub fn calibration() -> Result<&'static Fit> {
    let f = fits()?;
    f.iter()
        .find(|f| !f.software)
        .or_else(|| f.first())
        .ok_or_else(|| anyhow!("gpu cost: no bench artefact to calibrate on"))
}

/// The modelled GPU cost of technique × storage (no GPU needed): a + b·W of its lookup program
/// on [`calibration`], its op counts and its export size. An error when the technique does not
/// use the storage.
pub fn gpu_cost(t: TechniqueKind, s: StorageKind) -> Result<GpuCost> {
    let p = program_of(t, s)?;
    let fit = calibration()?;
    Ok(GpuCost {
        ns_per_lookup: fit.predict(&p.ops),
        source: CostSource::Model {
            calibrated_on: vec![fit.adapter.clone()],
        },
        ops: p.ops,
        export_lines: p.export_lines,
        over_size_bound: p.export_lines > EXPORT_LINES_BOUND,
    })
}

/// The point [`measured_costs`] times: the committed bench's base point — a 512² shadow map,
/// the 9×9 filter, 256² lookups — three runs after a warm-up.
pub const MEASURE: (usize, usize, usize) = (512, 9, 256);
/// Timed runs per technique × storage at [`MEASURE`].
pub const MEASURE_REPEATS: usize = 3;

/// The measured GPU cost of each technique × storage of `pairs` on `gpu`: `gpu bench`'s lookup
/// pass (timestamp queries) at [`MEASURE`] on the depth stack `src` (scaled to the map size),
/// the median of [`MEASURE_REPEATS`] runs over the lookups; op counts and export size as in
/// [`gpu_cost`]. Errors (before any GPU work) for a pair outside `tune`'s space, and for an
/// adapter without timestamp queries, whose pass times cannot be split.
pub fn measured_costs(
    gpu: &Gpu,
    pairs: &[(TechniqueKind, StorageKind)],
    src: &DepthStack,
) -> Result<Vec<GpuCost>> {
    let programs = pairs
        .iter()
        .map(|&(t, s)| program_of(t, s))
        .collect::<Result<Vec<_>>>()?;
    let settings = pairs
        .iter()
        .map(|&(t, s)| setting(t, s))
        .collect::<Result<Vec<_>>>()?;
    if !gpu.timestamps {
        bail!(
            "gpu cost: {} has no timestamp queries, so the lookup pass cannot be timed on its own",
            gpu.adapter.label()
        );
    }
    let plan = Plan {
        sizes: vec![MEASURE.0],
        filters: vec![],
        outputs: vec![],
        base: MEASURE,
        repeats: MEASURE_REPEATS,
        repeats_large: MEASURE_REPEATS,
        large_from: usize::MAX,
    };
    let report = bench::run(gpu, &plan, &settings, src, |_| {})?;
    programs
        .iter()
        .map(|p| {
            let ns = lookup_ns(&report, p.technique, p.storage)
                .filter(|x| x.is_finite() && *x > 0.0)
                .ok_or_else(|| {
                    anyhow!(
                        "gpu cost: no lookup time for {} {} on {}",
                        p.technique.name(),
                        p.storage.name(),
                        gpu.adapter.name
                    )
                })?;
            Ok(GpuCost {
                ns_per_lookup: ns,
                source: CostSource::Measured {
                    adapter: gpu.adapter.name.clone(),
                },
                ops: p.ops,
                export_lines: p.export_lines,
                over_size_bound: p.export_lines > EXPORT_LINES_BOUND,
            })
        })
        .collect()
}

/// docs/tune.md's `gpu-cost` block: per bench artefact under `reports/gpu/`, the fitted a and
/// b and, per technique × storage, W, the measured and modelled ns per lookup and the residual;
/// then the export sizes against [`EXPORT_LINES_BOUND`].
pub fn docs_block(reports: &Path) -> Result<String> {
    let dir = reports.join("gpu");
    let mut files: Vec<std::path::PathBuf> = std::fs::read_dir(&dir)
        .map_err(|e| anyhow!("{}: {e}", dir.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "json"))
        .collect();
    files.sort();
    if files.is_empty() {
        bail!("{}: no bench artefact", dir.display());
    }
    let mut s = String::new();
    for f in files {
        let r: Report = crate::artefact::read_json(&f)?;
        let fit = fit(&r)?;
        let (max, rms) = fit.residual_summary();
        let name = f.file_name().and_then(|x| x.to_str()).unwrap_or("");
        s += &format!(
            "Calibrated on **{}** ({}; `reports/gpu/{name}`): a = {:.1} ns, b = {:.4} ns per \
             weighted operation; residuals at most {:.0} %, root mean square {:.0} %.\n\n",
            fit.adapter,
            if fit.software {
                "software: CPU times"
            } else {
                "hardware"
            },
            fit.intercept_ns,
            fit.ns_per_op,
            100.0 * max,
            100.0 * rms
        );
        s += "| technique | storage | W | measured ns | model ns | residual |\n\
              | --- | --- | ---: | ---: | ---: | ---: |\n";
        for row in &fit.rows {
            s += &format!(
                "| {} | {} | {:.0} | {:.1} | {:.1} | {:+.0} % |\n",
                row.technique.name(),
                row.storage.name(),
                row.weighted_ops,
                row.measured_ns,
                row.model_ns,
                100.0 * row.residual()
            );
        }
        // the bench's own spread: programs with the same W measured apart
        let mut spread: Option<(f64, &FitRow, &FitRow)> = None;
        for (i, x) in fit.rows.iter().enumerate() {
            for y in &fit.rows[i + 1..] {
                let ratio = x.measured_ns.max(y.measured_ns) / x.measured_ns.min(y.measured_ns);
                if x.weighted_ops == y.weighted_ops && spread.is_none_or(|s| ratio > s.0) {
                    spread = Some((ratio, x, y));
                }
            }
        }
        if let Some((ratio, x, y)) = spread {
            s += &format!(
                "\nThe bench's own spread: programs with the same operations measure up to \
                 {ratio:.1}× apart ({} {} and {} {}).\n",
                x.technique.name(),
                x.storage.name(),
                y.technique.name(),
                y.storage.name()
            );
        }
        s += "\n";
    }
    let ps = programs()?;
    let lines = |t: TechniqueKind| {
        let v: Vec<usize> = ps
            .iter()
            .filter(|p| p.technique == t)
            .map(|p| p.export_lines)
            .collect();
        (v.iter().copied().min(), v.iter().copied().max())
    };
    let cells: Vec<String> = TechniqueKind::ALL
        .iter()
        .map(|&t| match lines(t) {
            (Some(lo), Some(hi)) if lo == hi => format!("{} {lo}", t.name()),
            (Some(lo), Some(hi)) => format!("{} {lo}–{hi}", t.name()),
            _ => t.name().to_string(),
        })
        .collect();
    s += &format!(
        "Lines of `shadow.glsl` per technique (over its storages): {}; flagged above {}.\n",
        cells.join(", "),
        EXPORT_LINES_BOUND
    );
    Ok(s)
}

/// `tune`'s cost of a technique × storage: the model's ns per lookup ([`gpu_cost`]).
pub fn tune_cost(t: TechniqueKind, s: StorageKind) -> anyhow::Result<f64> {
    Ok(gpu_cost(t, s)?.ns_per_lookup)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shader::{Cmp, Shape};

    /// A function with every operation class and one loop: counts by hand.
    #[test]
    fn op_counts_of_a_hand_built_function_are_exact() {
        let mut f = Func::new("k");
        let x = f.input_scalar("x");
        let y = f.input_scalar("y");
        let one = f.c(1.0);
        let a = f.add(x, y); // arithmetic 1
        let d = f.div(a, y); // division 1
        let e = f.exp(d); // transcendental 1
        let s = f.select(Cmp::Lt, x, y, e, a); // select 1
                                               // 3 trips of: 2 arithmetic, 1 sqrt, 1 select, 1 division
        let out = f.repeat(3, &[s, a], |f, v| {
            let p = f.mul(v[0], v[1]);
            let q = f.sub(p, one);
            let r = f.sqrt(q);
            let c = f.select(Cmp::Gt, r, one, r, q);
            let w = f.div(c, v[1]);
            vec![w, c]
        });
        let m = f.max(out[0], out[1]); // arithmetic 1
        let cl = f.clamp(m, x, y); // arithmetic 1
        f.ret(Shape::Scalar, &[cl]);
        f.validate().unwrap();
        let c = OpCount::of(&f).unwrap();
        assert_eq!(
            c,
            OpCount {
                arithmetic: 3 + 2 * 3,
                division: 1 + 3,
                transcendental: 1 + 3,
                selects: 1 + 3,
                loops: 1,
                loop_trips: 3,
            }
        );
        assert_eq!(c.weighted(), 9.0 + 4.0 + 4.0 * 8.0 + 2.0 * 3.0);
        // the IR's own dynamic statement count agrees
        let classes = c.arithmetic + c.division + c.transcendental + c.selects;
        assert_eq!(classes as usize, f.n_ops());
    }

    #[test]
    fn every_program_is_counted_as_the_ir_executes_it() {
        for p in programs().unwrap() {
            let st = setting(p.technique, p.storage).unwrap();
            let m = export::module(&st, vec![]).unwrap().unwrap();
            let f = m.func("tunedShadow").unwrap();
            let o = p.ops;
            assert_eq!(
                (o.arithmetic + o.division + o.transcendental + o.selects) as usize,
                f.n_ops(),
                "{} {}",
                p.technique.name(),
                p.storage.name()
            );
        }
    }

    /// Largest |model/measured − 1| and root mean square allowed on the committed lavapipe
    /// bench. Programs with the same operations measure up to 1.6× apart there (6MSM f32 and
    /// UNORM16 at the base point), so the bound is the bench's own spread, not tighter.
    const MAX_RESIDUAL: f64 = 0.35;
    const RMS_RESIDUAL: f64 = 0.20;

    #[test]
    fn the_model_reproduces_the_lavapipe_bench() {
        let fits = fits().unwrap();
        let lp = fits
            .iter()
            .find(|f| f.adapter.starts_with("llvmpipe"))
            .expect("the lavapipe bench is committed");
        // every technique × storage of tune's space is in the calibration
        assert_eq!(lp.rows.len(), programs().unwrap().len());
        for row in &lp.rows {
            eprintln!(
                "{} {}: W {:.0}, measured {:.1} ns, model {:.1} ns, {:+.1} %",
                row.technique.name(),
                row.storage.name(),
                row.weighted_ops,
                row.measured_ns,
                row.model_ns,
                100.0 * row.residual()
            );
            assert!(
                row.residual().abs() <= MAX_RESIDUAL,
                "{} {}: residual {:+.1} %",
                row.technique.name(),
                row.storage.name(),
                100.0 * row.residual()
            );
        }
        let (max, rms) = lp.residual_summary();
        eprintln!(
            "a = {:.2} ns, b = {:.5} ns/op; max {:.1} %, rms {:.1} %",
            lp.intercept_ns,
            lp.ns_per_op,
            100.0 * max,
            100.0 * rms
        );
        assert!(rms <= RMS_RESIDUAL, "rms residual {rms}");
        assert!(lp.intercept_ns > 0.0 && lp.ns_per_op > 0.0);
    }

    #[test]
    fn tmsm_costs_ten_hamburger4_and_its_export_is_over_the_bound() {
        for s in [StorageKind::F32, StorageKind::Unorm16Theta] {
            let tmsm = gpu_cost(TechniqueKind::Tmsm, s).unwrap();
            let h4 = gpu_cost(TechniqueKind::Hamburger4, s).unwrap();
            assert!(
                tmsm.ns_per_lookup > 10.0 * h4.ns_per_lookup,
                "{}: TMSM {} ns, Hamburger 4MSM {} ns",
                s.name(),
                tmsm.ns_per_lookup,
                h4.ns_per_lookup
            );
            assert!(tmsm.over_size_bound && tmsm.export_lines > EXPORT_LINES_BOUND);
            assert!(!h4.over_size_bound);
            assert!(tmsm.ops.loops > 0 && tmsm.ops.loop_trips >= tmsm.ops.loops);
        }
    }

    #[test]
    fn every_setting_has_a_finite_positive_cost_and_only_tmsm_is_over_the_bound() {
        let mut largest_other = 0;
        for t in TechniqueKind::ALL {
            for s in StorageKind::ALL {
                let c = gpu_cost(t, s);
                if !t.storages().contains(&s) {
                    let e = c.unwrap_err().to_string();
                    assert!(e.contains(t.name()) && e.contains(s.name()), "{e}");
                    continue;
                }
                let c = c.unwrap();
                assert!(
                    c.ns_per_lookup.is_finite() && c.ns_per_lookup > 0.0,
                    "{c:?}"
                );
                assert!(matches!(
                    &c.source,
                    CostSource::Model { calibrated_on } if !calibrated_on.is_empty()
                ));
                assert!(c.ops.weighted() > 0.0);
                assert_eq!(c.over_size_bound, t == TechniqueKind::Tmsm, "{t:?} {s:?}");
                if t != TechniqueKind::Tmsm {
                    largest_other = largest_other.max(c.export_lines);
                }
            }
        }
        // the margin the bound's documentation states: about a third above the largest
        assert!(
            largest_other * 5 <= EXPORT_LINES_BOUND * 4 && largest_other * 3 >= EXPORT_LINES_BOUND,
            "largest non-TMSM export {largest_other} lines"
        );
    }

    #[test]
    fn export_lines_are_the_lines_tune_export_writes() {
        let st = setting(TechniqueKind::Hamburger6, StorageKind::Unorm16Theta).unwrap();
        let m = export::module(&st, export::header(&st)).unwrap().unwrap();
        let [glsl, _, _] = export::shader_texts(&m).unwrap();
        let c = gpu_cost(TechniqueKind::Hamburger6, StorageKind::Unorm16Theta).unwrap();
        assert_eq!(c.export_lines, glsl.lines().count());
    }

    #[test]
    fn the_embedded_benches_are_the_committed_artefacts() {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("reports/gpu");
        let mut on_disk: Vec<String> = std::fs::read_dir(&dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .filter(|n| n.ends_with(".json"))
            .collect();
        on_disk.sort();
        let mut embedded: Vec<String> = BENCHES.iter().map(|b| b.0.to_string()).collect();
        embedded.sort();
        assert_eq!(
            embedded, on_disk,
            "list every reports/gpu/*.json in cost::BENCHES"
        );
        for (name, text) in BENCHES {
            let disk =
                crate::artefact::read_text(&dir.join(name), crate::artefact::Limit::ARTEFACT)
                    .unwrap();
            assert_eq!(text, disk, "{name}");
        }
    }

    #[test]
    fn a_bench_without_pass_times_or_programs_does_not_calibrate() {
        let (_, text) = BENCHES[0];
        let mut r: Report = serde_json::from_str(text).unwrap();
        let ok = fit(&r).unwrap();
        assert!(ok.ns_per_op > 0.0);
        r.timer = "wall".into();
        assert!(fit(&r).unwrap_err().to_string().contains("per-pass"));
        r.timer = "timestamp".into();
        r.points
            .retain(|p| p.technique == "vsm" && p.storage == "f32");
        assert!(fit(&r).unwrap_err().to_string().contains("two distinct"));
    }
}
