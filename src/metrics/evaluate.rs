//! The evaluation loop: every fragment of every view shaded by a subject (a technique, PCF or
//! the exact CDF) from the filtered moment maps, in chunks over threads.

use super::*;

/// What is evaluated against PCF.
#[derive(Clone, Copy)]
pub enum Subject<'a> {
    /// A moment technique (closed form or LP candidate).
    Technique(&'a dyn Technique),
    /// PCF itself, recomputed per fragment through the same loop (its error is 0).
    Pcf,
    /// The exact F_Z(z_f − ε′) of the unsnapped depth distribution: what an ideal technique
    /// that knew Z_t would return. Its error is the floor set by the technique bias ε′ (it
    /// differs from PCF only through the biases), not a technique.
    Cdf,
}

impl<'a> Subject<'a> {
    /// The technique's name, or "pcf" / "cdf" for the references.
    pub fn name(&self) -> String {
        match self {
            Subject::Technique(t) => t.name(),
            Subject::Pcf => "pcf".to_string(),
            Subject::Cdf => "cdf".to_string(),
        }
    }

    /// One thread's state for the chunk loops: the technique's evaluator (None for PCF and
    /// the CDF) and a buffer of m moments.
    fn chunk_state(self, m: usize) -> (Option<Box<dyn Evaluator + 'a>>, Vec<f64>) {
        let ev = match self {
            Subject::Technique(t) => Some(t.evaluator()),
            Subject::Pcf | Subject::Cdf => None,
        };
        (ev, vec![0.0; m])
    }
}

/// Start a chunk from a cold evaluator, so that its bits do not depend on which chunks its
/// thread ran before.
pub(super) fn cold(ev: &mut Option<Box<dyn Evaluator + '_>>) {
    if let Some(e) = ev.as_mut() {
        e.reset();
    }
}

/// Progress callback: (fragments done, fragments planned), over all views.
pub type Progress = Arc<dyn Fn(usize, usize) + Send + Sync>;

/// Options of [`evaluate`].
#[derive(Clone, Default)]
pub struct EvalOptions {
    /// Depth biases of PCF and of the technique.
    pub bias: Bias,
    /// Which fragments to evaluate.
    pub subsample: Subsample,
    /// Skip the evaluation of trivial fragments (G := 0). `None` = automatic: skip for grid
    /// techniques (LP candidates, sharp lower bounds by construction), evaluate closed forms
    /// everywhere (they are cheap and not all of them are lower bounds, e.g. CSM).
    pub skip_trivial: Option<bool>,
    /// Keep per-fragment values (G, PCF) in the report ([`ViewReport::values`]).
    pub keep_values: bool,
    /// Count |G − PCF| per bin of these edges ([`histogram_bin`]) into
    /// [`ViewReport::histogram`], without keeping the values.
    pub histogram: Option<Arc<[f64]>>,
    /// Called as fragments finish (done, planned).
    pub progress: Option<Progress>,
}

/// One evaluated fragment (kept with [`EvalOptions::keep_values`]).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct FragmentValue {
    /// Texel index y·width + x.
    pub texel: usize,
    /// Depth layer of the fragment (0 = front).
    pub layer: usize,
    /// The PCF reference.
    pub pcf: f64,
    /// The technique's G.
    pub g: f64,
    /// Whether F_Z(z_f − ε′) = 0 (G := 0 when trivial fragments are skipped).
    pub trivial: bool,
}

/// Error of a technique against PCF over all fragments of all layers of `stacks`.
pub fn evaluate(
    stacks: &[DepthStack],
    technique: &dyn Technique,
    opts: &EvalOptions,
) -> Result<EvalReport> {
    evaluate_subject(stacks, Subject::Technique(technique), opts)
}

/// Per-view state of the shading loop.
pub(super) struct ViewShader<'a> {
    subject: Subject<'a>,
    stack: &'a DepthStack,
    front: FrontMap,
    /// Moment maps (of the snapped front map for grid techniques).
    maps: Vec<Vec<f64>>,
    /// 9×9 min of the (snapped) front map.
    min_map: Vec<f64>,
    grid: Option<&'a Grid>,
    skip_trivial: bool,
    bias: Bias,
}

impl<'a> ViewShader<'a> {
    fn new(subject: Subject<'a>, stack: &'a DepthStack, opts: &EvalOptions) -> ViewShader<'a> {
        let (w, h) = (stack.meta.width, stack.meta.height);
        let kern = Gaussian::paper();
        let front = FrontMap::of(stack);
        let (grid, maps, min_map, skip) = match subject {
            Subject::Pcf | Subject::Cdf => (None, Vec::new(), Vec::new(), false),
            Subject::Technique(t) => {
                let grid = t.depth_grid();
                let snapped: Vec<f64> = match grid {
                    Some(g) => front.depth.iter().map(|&z| snap(g, z)).collect(),
                    None => front.depth.clone(),
                };
                let maps =
                    kernel::moment_maps_of(&snapped, w, h, t.moment_count(), &kern, |z, o| {
                        t.basis(z, o)
                    });
                let min_map = kernel::min_filter(&snapped, w, h, kern.radius());
                (
                    grid,
                    maps,
                    min_map,
                    opts.skip_trivial.unwrap_or(grid.is_some()),
                )
            }
        };
        ViewShader {
            subject,
            stack,
            front,
            maps,
            min_map,
            grid,
            skip_trivial: skip,
            bias: opts.bias,
        }
    }

    /// (G, trivial, solved) of one fragment.
    fn shade(
        &self,
        ev: &mut Option<Box<dyn Evaluator + 'a>>,
        buf: &mut [f64],
        f: &Fragment,
    ) -> (f64, bool, bool) {
        match self.subject {
            Subject::Pcf => {
                let g = pcf_of(self.stack, &self.front, f.texel, f.layer, &self.bias);
                (g, f.trivial, true)
            }
            Subject::Cdf => {
                let (w, h) = (self.stack.meta.width, self.stack.meta.height);
                let g = kernel::depth_distribution(
                    &self.front.depth,
                    w,
                    h,
                    f.texel % w,
                    f.texel / w,
                    &Gaussian::paper(),
                )
                .iter()
                .filter(|(z, _)| *z < f.zf)
                .map(|(_, wt)| wt)
                .sum();
                (g, f.trivial, true)
            }
            Subject::Technique(_) => {
                let zf = match self.grid {
                    Some(g) => snap(g, f.zf),
                    None => f.zf,
                };
                let trivial = self.min_map[f.texel] >= zf;
                if trivial && self.skip_trivial {
                    return (0.0, true, false);
                }
                for (j, map) in self.maps.iter().enumerate() {
                    buf[j] = map[f.texel];
                }
                let ev = ev.as_mut().expect("technique evaluator");
                (ev.shadow(buf, zf), trivial, true)
            }
        }
    }
}

#[derive(Default)]
pub(super) struct Partial {
    sum: f64,
    sum_scaled: [f64; 2],
    leak: f64,
    trivial: usize,
    solved: usize,
    non_finite: usize,
    unsettled: usize,
    out_of_range: usize,
    values: Vec<FragmentValue>,
    histogram: Vec<u64>,
}

impl Partial {
    /// Empty sums, with a zero count for every bin of the histogram `edges` (if any).
    fn with_bins(edges: Option<&[f64]>) -> Partial {
        Partial {
            histogram: vec![0; edges.map_or(0, |e| e.len().saturating_sub(1))],
            ..Partial::default()
        }
    }
}

/// Error unless the stacks hold at least one fragment: an empty input has no error to
/// report (never a 0 % result).
pub fn require_fragments(stacks: &[DepthStack]) -> Result<()> {
    if stacks.iter().all(|s| s.fragment_count() == 0) {
        bail!(
            "the depth stacks hold 0 fragments ({} views, every texel empty); nothing to evaluate",
            stacks.len()
        );
    }
    Ok(())
}

/// [`evaluate`] for a technique or PCF itself.
pub fn evaluate_subject(
    stacks: &[DepthStack],
    subject: Subject<'_>,
    opts: &EvalOptions,
) -> Result<EvalReport> {
    let mut reports = evaluate_subjects(stacks, &[subject], opts)?;
    Ok(reports.remove(0))
}

/// [`evaluate_subject`] for several subjects on the same fragments: each view's fragments and
/// their PCF reference (most of the work for a closed form) are built once and shaded by every
/// subject in turn. One report per subject, in order; each report's `seconds` counts the
/// shared fragment building once.
pub fn evaluate_subjects(
    stacks: &[DepthStack],
    subjects: &[Subject<'_>],
    opts: &EvalOptions,
) -> Result<Vec<EvalReport>> {
    evaluate_subjects_with(stacks, subjects, opts, None)
}

/// Where completed units of an evaluation — one subject on one view — are kept across runs (a
/// checkpoint). Keys are `<view index>.<scene>.<view>.<subject>`.
pub trait ViewStore: Sync {
    /// The report of unit `key` if an earlier run completed it.
    fn get(&self, key: &str) -> Result<Option<ViewReport>>;
    /// Unit `key` is complete.
    fn put(&self, key: &str, report: &ViewReport) -> Result<()>;
}

/// [`evaluate_subjects`] with the units (subject × view) kept in `store`: a unit found there is
/// not shaded again (a view whose units are all there is not even built), every other one is
/// recorded when complete. A unit depends only on its view, subject and options, so the
/// reports equal those of an uninterrupted run but for the times. Not with
/// [`EvalOptions::keep_values`] (a stored unit keeps no values).
pub fn evaluate_subjects_with(
    stacks: &[DepthStack],
    subjects: &[Subject<'_>],
    opts: &EvalOptions,
    store: Option<&dyn ViewStore>,
) -> Result<Vec<EvalReport>> {
    if store.is_some() && opts.keep_values {
        bail!("an evaluation that keeps its values cannot be resumed");
    }
    require_fragments(stacks)?;
    opts.bias.validate()?;
    opts.subsample.validate()?;
    for subject in subjects {
        if let Subject::Technique(t) = subject {
            if t.moment_count() == 0 {
                bail!("technique {}: no moments", t.name());
            }
        }
    }
    for s in stacks {
        check_stack(s)?;
    }
    let start = Instant::now();
    let picks: Vec<Vec<(usize, usize)>> = stacks
        .iter()
        .enumerate()
        .map(|(v, s)| select(s, v, &opts.subsample))
        .collect();
    let picked = start.elapsed().as_secs_f64();
    let planned: usize = picks.iter().map(|p| p.len()).sum::<usize>() * subjects.len();
    let done = AtomicUsize::new(0);
    let mut views: Vec<Vec<ViewReport>> = subjects.iter().map(|_| Vec::new()).collect();
    for (v, (stack, picked)) in stacks.iter().zip(&picks).enumerate() {
        let keys: Vec<String> = subjects
            .iter()
            .map(|s| format!("{v}.{}.{}.{}", stack.meta.scene, stack.meta.view, s.name()))
            .collect();
        let mut stored: Vec<Option<ViewReport>> = match store {
            Some(st) => keys.iter().map(|k| st.get(k)).collect::<Result<_>>()?,
            None => vec![None; subjects.len()],
        };
        let mut frags = None;
        let mut build = 0.0;
        for (k, &subject) in subjects.iter().enumerate() {
            if let Some(r) = stored[k].take() {
                let d = done.fetch_add(picked.len(), Ordering::Relaxed) + picked.len();
                if let Some(cb) = &opts.progress {
                    cb(d, planned);
                }
                views[k].push(r);
                continue;
            }
            let frags = frags.get_or_insert_with(|| {
                let t0 = Instant::now();
                let f = fragments_at(stack, v, &opts.bias, picked);
                build = t0.elapsed().as_secs_f64();
                f
            });
            let progress = (&done, planned);
            let r = shade_view(stack, frags, subject, opts, progress, build);
            if let Some(st) = store {
                st.put(&keys[k], &r)?;
            }
            views[k].push(r);
        }
    }
    Ok(subjects
        .iter()
        .zip(views)
        .map(|(subject, views)| report_of(subject.name(), views, opts, picked))
        .collect())
}

/// One view's report for `subject` on its fragments `frags` (built in `build` seconds, counted
/// in the view's `seconds`); `progress` = (fragments shaded so far, planned in all).
pub(super) fn shade_view(
    stack: &DepthStack,
    frags: &[Fragment],
    subject: Subject<'_>,
    opts: &EvalOptions,
    (done, planned): (&AtomicUsize, usize),
    build: f64,
) -> ViewReport {
    let t0 = Instant::now();
    let m = match subject {
        Subject::Technique(t) => t.moment_count(),
        Subject::Pcf | Subject::Cdf => 0,
    };
    let shader = ViewShader::new(subject, stack, opts);
    let t1 = Instant::now();
    let keep = opts.keep_values;
    let edges = opts.histogram.as_deref();
    let partials: Vec<Partial> = frags
        .par_chunks(512)
        .map_init(
            || subject.chunk_state(m),
            |(ev, buf), chunk| {
                cold(ev);
                let mut p = Partial::with_bins(edges);
                let unsettled0 = ev.as_ref().map_or(0, |e| e.unsettled());
                for f in chunk {
                    let (g, trivial, solved) = shader.shade(ev, buf, f);
                    p.trivial += trivial as usize;
                    p.solved += solved as usize;
                    if g.is_finite() {
                        p.sum += (g - f.pcf).abs();
                        p.sum_scaled[0] += (g - f.pcf_scaled[0]).abs();
                        p.sum_scaled[1] += (g - f.pcf_scaled[1]).abs();
                        p.leak += (f.pcf - g).max(0.0);
                        if !(-1e-9..=1.0 + 1e-9).contains(&g) {
                            p.out_of_range += 1;
                        }
                    } else {
                        p.non_finite += 1;
                    }
                    if let Some(k) = edges.and_then(|e| histogram_bin(e, (g - f.pcf).abs())) {
                        p.histogram[k] += 1;
                    }
                    if keep {
                        p.values.push(FragmentValue {
                            texel: f.texel,
                            layer: f.layer,
                            pcf: f.pcf,
                            g,
                            trivial,
                        });
                    }
                }
                p.unsettled = ev.as_ref().map_or(0, |e| e.unsettled()) - unsettled0;
                let d = done.fetch_add(chunk.len(), Ordering::Relaxed) + chunk.len();
                if let Some(cb) = &opts.progress {
                    cb(d, planned);
                }
                p
            },
        )
        .collect();
    let shade_seconds = t1.elapsed().as_secs_f64();
    let mut total = Partial::with_bins(edges);
    let mut values = Vec::new();
    for p in partials {
        total.sum += p.sum;
        total.sum_scaled[0] += p.sum_scaled[0];
        total.sum_scaled[1] += p.sum_scaled[1];
        total.leak += p.leak;
        total.trivial += p.trivial;
        total.solved += p.solved;
        total.non_finite += p.non_finite;
        total.unsettled += p.unsettled;
        total.out_of_range += p.out_of_range;
        for (t, c) in total.histogram.iter_mut().zip(&p.histogram) {
            *t += c;
        }
        values.extend(p.values);
    }
    let finite = frags.len() - total.non_finite;
    let mean = |x: f64| finite_mean(x, finite, frags.len());
    ViewReport {
        sum_abs_error_scaled: total.sum_scaled,
        error_scaled: total.sum_scaled.map(mean),
        sum_leak: total.leak,
        leak: mean(total.leak),
        scene: stack.meta.scene.clone(),
        view: stack.meta.view.clone(),
        width: stack.meta.width,
        height: stack.meta.height,
        layers: stack.depth.len(),
        fragments_total: stack.fragment_count(),
        fragments: frags.len(),
        trivial: total.trivial,
        solved: total.solved,
        non_finite: total.non_finite,
        unsettled: total.unsettled,
        out_of_range: total.out_of_range,
        sum_abs_error: total.sum,
        error: mean(total.sum),
        seconds: build + t0.elapsed().as_secs_f64(),
        shade_seconds,
        histogram: total.histogram,
        values: keep.then_some(values),
    }
}

/// Front-layer shadow maps of one view for pictures: per texel the PCF and the subject's G of
/// the front-layer fragment (NaN where the texel has no surface).
pub struct FrontShadows {
    /// PCF per texel, row-major.
    pub pcf: Vec<f64>,
    /// The subject's G per texel, row-major.
    pub g: Vec<f64>,
}

/// PCF and G of every front-layer fragment of `stack` (full resolution, no subsampling).
pub fn front_shadows(
    stack: &DepthStack,
    subject: Subject<'_>,
    bias: &Bias,
) -> Result<FrontShadows> {
    layer_shadows(stack, 0, subject, bias)
}

/// PCF and G of every fragment of layer `layer` (the layer+1-th surface along each texel's
/// ray; NaN where a texel has fewer surfaces): where the shadows cast onto that layer fall.
pub fn layer_shadows(
    stack: &DepthStack,
    layer: usize,
    subject: Subject<'_>,
    bias: &Bias,
) -> Result<FrontShadows> {
    check_stack(stack)?;
    bias.validate()?;
    let n = stack.texel_count();
    let picked: Vec<(usize, usize)> = match stack.depth.get(layer) {
        Some(l) => (0..n)
            .filter(|&t| l[t].is_finite())
            .map(|t| (layer, t))
            .collect(),
        None => Vec::new(),
    };
    let opts = EvalOptions {
        bias: *bias,
        ..Default::default()
    };
    let frags = fragments_at(stack, 0, bias, &picked);
    let shader = ViewShader::new(subject, stack, &opts);
    let m = shader.maps.len();
    let gs: Vec<f64> = frags
        .par_chunks(512)
        .map_init(
            || subject.chunk_state(m),
            |(ev, buf), chunk| {
                cold(ev);
                chunk
                    .iter()
                    .map(|f| shader.shade(ev, buf, f).0)
                    .collect::<Vec<f64>>()
            },
        )
        .flatten()
        .collect();
    let mut out = FrontShadows {
        pcf: vec![f64::NAN; n],
        g: vec![f64::NAN; n],
    };
    for (f, g) in frags.iter().zip(gs) {
        out.pcf[f.texel] = f.pcf;
        out.g[f.texel] = g;
    }
    Ok(out)
}
