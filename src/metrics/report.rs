//! The reports of an evaluation: per view and over all views (error, leak, throughput).

use super::*;

/// Result for one view. It reads back from its JSON (a checkpoint of `evaluate`): a mean JSON
/// wrote as null (NaN: every output non-finite; JSON has no NaN) reads as NaN, the kept values
/// as none.
#[derive(Clone, Debug, Serialize, serde::Deserialize)]
pub struct ViewReport {
    /// Scene name.
    pub scene: String,
    /// View name within the scene.
    pub view: String,
    /// Stack width in texels.
    pub width: usize,
    /// Stack height in texels.
    pub height: usize,
    /// Depth layers of the stack.
    pub layers: usize,
    /// All fragments of the view.
    pub fragments_total: usize,
    /// Evaluated fragments (after subsampling).
    pub fragments: usize,
    /// Evaluated fragments with F_Z(z_f − ε′) = 0 (after grid snapping for LP candidates).
    pub trivial: usize,
    /// Fragments for which the technique was called (not skipped as trivial).
    pub solved: usize,
    /// Fragments with non-finite G (excluded from the mean, reported here).
    pub non_finite: usize,
    /// Fragments whose LP was unsettled: scored as the trivial bound G = 0 (included in the
    /// mean; `lp::UNSETTLED_G`).
    pub unsettled: usize,
    /// Fragments with finite G outside [0,1] (more than 1e-9; included in the mean as is).
    pub out_of_range: usize,
    /// Σ |G − PCF| over the finite fragments.
    pub sum_abs_error: f64,
    /// Mean |G − PCF| over the finite fragments (0 without fragments, NaN when every output
    /// was non-finite).
    #[serde(deserialize_with = "nan_if_null")]
    pub error: f64,
    /// Σ |G − PCF| with PCF's ε scaled by [`EPSILON_FACTORS`].
    pub sum_abs_error_scaled: [f64; 2],
    /// Mean |G − PCF| with PCF's ε scaled by [`EPSILON_FACTORS`] (reference sensitivity).
    #[serde(deserialize_with = "nans_if_null")]
    pub error_scaled: [f64; 2],
    /// Σ max(0, PCF − G): light leaked (G below the reference).
    pub sum_leak: f64,
    /// Mean max(0, PCF − G) over the finite fragments: the light-leaking part of `error`.
    #[serde(deserialize_with = "nan_if_null")]
    pub leak: f64,
    /// Wall time of the view (fragments, moment maps, shading), seconds.
    pub seconds: f64,
    /// Wall time of the shading loop alone, seconds.
    pub shade_seconds: f64,
    /// Fragments per bin of |G − PCF| over [`EvalOptions::histogram`]'s edges (empty
    /// without them).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub histogram: Vec<u64>,
    /// Per-fragment values, kept when asked for (not serialized).
    #[serde(skip)]
    pub values: Option<Vec<FragmentValue>>,
}

/// A float written as null (NaN) reads back as NaN.
fn nan_if_null<'de, D: serde::Deserializer<'de>>(d: D) -> std::result::Result<f64, D::Error> {
    use serde::Deserialize;
    Ok(Option::<f64>::deserialize(d)?.unwrap_or(f64::NAN))
}

/// [`nan_if_null`] for a pair.
fn nans_if_null<'de, D: serde::Deserializer<'de>>(d: D) -> std::result::Result<[f64; 2], D::Error> {
    use serde::Deserialize;
    Ok(<[Option<f64>; 2]>::deserialize(d)?.map(|x| x.unwrap_or(f64::NAN)))
}

/// Result over all views.
#[derive(Clone, Debug, Serialize)]
pub struct EvalReport {
    /// Technique spec name.
    pub technique: String,
    /// Depth bias applied to the fragments.
    pub bias: Bias,
    /// Which fragments were evaluated.
    pub subsample: Subsample,
    /// All fragments of all views.
    pub fragments_total: usize,
    /// Evaluated fragments (after subsampling).
    pub fragments: usize,
    /// Evaluated fragments with F_Z(z_f − ε′) = 0.
    pub trivial: usize,
    /// Fragments for which the technique was called (not skipped as trivial).
    pub solved: usize,
    /// Fragments with non-finite G (excluded from the mean).
    pub non_finite: usize,
    /// LP answers scored as the trivial bound because the solver settled neither verdict.
    pub unsettled: usize,
    /// Fragments with finite G outside [0,1] by more than 1e-9.
    pub out_of_range: usize,
    /// Mean |G − PCF| over all finite evaluated fragments of all views.
    pub error: f64,
    /// `error` with PCF's constant ε scaled by [`EPSILON_FACTORS`] (ε/3, 3ε): how much of the
    /// error depends on the reference's constant.
    pub error_scaled: [f64; 2],
    /// Mean max(0, PCF − G): the light-leaking part of `error` (the rest, mean
    /// max(0, G − PCF), is over-darkening).
    pub leak: f64,
    /// Wall time of all views, seconds.
    pub seconds: f64,
    /// Technique calls per second of shading time (throughput over real, non-trivial fragments
    /// when trivial ones are skipped).
    pub solves_per_second: f64,
    /// Evaluated fragments per second of total wall time.
    pub fragments_per_second: f64,
    /// Per-view results.
    pub views: Vec<ViewReport>,
}

/// The bin of e among the bins [edges[k], edges[k+1]) of a histogram (the last one also holds
/// everything above it); None for a negative or NaN e. `edges` holds at least two edges.
pub fn histogram_bin(edges: &[f64], e: f64) -> Option<usize> {
    if e.is_nan() || e < 0.0 || edges.len() < 2 {
        return None;
    }
    let k = edges[1..].partition_point(|&edge| edge <= e);
    Some(k.min(edges.len() - 2))
}

/// Mean of a sum over the `finite` of `fragments` fragments: 0 for no fragments, NaN when
/// every output was non-finite (no error is known, and none is reported as perfect).
pub(super) fn finite_mean(sum: f64, finite: usize, fragments: usize) -> f64 {
    match (finite, fragments) {
        (_, 0) => 0.0,
        (0, _) => f64::NAN,
        _ => sum / finite as f64,
    }
}

/// The report over all `views` of one subject (`picked`: seconds spent choosing fragments).
pub(super) fn report_of(
    technique: String,
    views: Vec<ViewReport>,
    opts: &EvalOptions,
    picked: f64,
) -> EvalReport {
    let seconds = picked + views.iter().map(|v| v.seconds).sum::<f64>();
    let sum = |f: fn(&ViewReport) -> usize| views.iter().map(f).sum::<usize>();
    let fragments = sum(|v| v.fragments);
    let non_finite = sum(|v| v.non_finite);
    let solved = sum(|v| v.solved);
    let sum_abs: f64 = views.iter().map(|v| v.sum_abs_error).sum();
    let sum_scaled: [f64; 2] =
        std::array::from_fn(|k| views.iter().map(|v| v.sum_abs_error_scaled[k]).sum());
    let sum_leak: f64 = views.iter().map(|v| v.sum_leak).sum();
    let finite = fragments - non_finite;
    let mean = |x: f64| finite_mean(x, finite, fragments);
    let shade: f64 = views.iter().map(|v| v.shade_seconds).sum();
    EvalReport {
        technique,
        bias: opts.bias,
        subsample: opts.subsample,
        fragments_total: sum(|v| v.fragments_total),
        fragments,
        trivial: sum(|v| v.trivial),
        solved,
        non_finite,
        unsettled: sum(|v| v.unsettled),
        out_of_range: sum(|v| v.out_of_range),
        error: mean(sum_abs),
        error_scaled: sum_scaled.map(mean),
        leak: mean(sum_leak),
        seconds,
        solves_per_second: if shade > 0.0 {
            solved as f64 / shade
        } else {
            0.0
        },
        fragments_per_second: if seconds > 0.0 {
            fragments as f64 / seconds
        } else {
            0.0
        },
        views,
    }
}

#[cfg(test)]
mod tests {
    use super::histogram_bin;

    #[test]
    fn histogram_bins_are_half_open_and_the_last_is_open_above() {
        let edges = [0.0, 1.0, 2.0, 4.0];
        let bins: Vec<Option<usize>> = [0.0, 0.5, 1.0, 1.999, 2.0, 4.0, 1e300, f64::INFINITY]
            .iter()
            .map(|&e| histogram_bin(&edges, e))
            .collect();
        let want = [0, 0, 1, 1, 2, 2, 2, 2].map(Some);
        assert_eq!(bins, want);
        assert_eq!(histogram_bin(&edges, -1e-300), None);
        assert_eq!(histogram_bin(&edges, f64::NAN), None);
        assert_eq!(histogram_bin(&[0.0], 0.5), None);
    }
}
