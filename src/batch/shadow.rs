//! The JSON batch of `momentlab shadow`: closed-form shadow intensities for many
//! (moments, z_f) problems of one technique.
//!
//! Input: {"technique": "hamburger4", "alpha": 3e-5, "precision": "f32",
//! "problems": [{"moments": [b1, …], "zf": 0.4}, …]} plus optional technique parameters (the
//! fields of [`crate::technique::registry::Params`]). Output: {"results": [{"g": 0.31}, …]}.
//! Any finite z_f is answered ([`crate::technique::DepthDomain`]).

use crate::technique::registry::{build, Params};
use anyhow::{anyhow, bail, Context, Result};
use serde_json::{Map, Value};

#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct Problem {
    moments: Vec<f64>,
    zf: f64,
}

/// Parse the batch, evaluate, and return the output JSON. `src` names the input in errors.
pub fn evaluate_batch(text: &str, src: &str) -> Result<Value> {
    let v: Value = serde_json::from_str(text).map_err(|e| {
        anyhow!(
            "{src}: malformed JSON at line {}, column {}: {e}",
            e.line(),
            e.column()
        )
    })?;
    let Value::Object(mut obj) = v else {
        bail!("{src}: expected a JSON object");
    };
    let technique = match obj.remove("technique") {
        Some(Value::String(s)) => s,
        Some(_) => bail!("{src}: \"technique\" must be a string"),
        None => bail!("{src}: missing \"technique\""),
    };
    let problems = obj
        .remove("problems")
        .ok_or_else(|| anyhow!("{src}: missing \"problems\""))?;
    let problems: Vec<Problem> =
        serde_json::from_value(problems).map_err(|e| anyhow!("{src}: \"problems\": {e}"))?;
    if let Some(known) = crate::technique::registry::parameters_of(&technique) {
        if let Some(k) = obj.keys().find(|k| !known.contains(&k.as_str())) {
            bail!(
                "{src}: \"{k}\" does not apply to {technique} (its parameters: {})",
                if known.is_empty() {
                    "none".to_string()
                } else {
                    known.join(", ")
                }
            );
        }
    }
    let mut params: Params = serde_json::from_value(Value::Object(Map::from_iter(obj)))
        .map_err(|e| anyhow!("{src}: technique parameters: {e}"))?;
    if technique == "hamburger" && params.moment_count.is_none() {
        params.moment_count = problems.first().map(|p| p.moments.len());
    }
    let t = if technique.starts_with("lp:") {
        crate::technique::by_name(&technique)
    } else {
        build(&technique, &params)
    }
    .with_context(|| src.to_string())?;
    let m = t.moment_count();
    let range = moment_box(t.as_ref());
    let domain = t.depth_domain();
    let mut ev = t.evaluator();
    let mut results = Vec::with_capacity(problems.len());
    for (i, p) in problems.iter().enumerate() {
        if p.moments.len() != m {
            bail!(
                "{src}: problem {i}: {technique} needs {m} moments, got {}",
                p.moments.len()
            );
        }
        if let Some(j) = p.moments.iter().position(|x| !x.is_finite()) {
            bail!("{src}: problem {i}: moment {} is not finite", j + 1);
        }
        if !p.zf.is_finite() {
            bail!("{src}: problem {i}: zf = {} is not finite", p.zf);
        }
        if let Some(j) = (0..m).find(|&j| !(range[j].0..=range[j].1).contains(&p.moments[j])) {
            bail!(
                "{src}: problem {i}: moment {} = {:e} is outside the range [{:.6}, {:.6}] of its \
                 basis function on [0,1]; no depth distribution has these moments",
                j + 1,
                p.moments[j],
                range[j].0,
                range[j].1
            );
        }
        let g = domain.shadow(ev.as_mut(), &p.moments, p.zf);
        results.push(
            serde_json::json!({ "g": if g.is_finite() { Value::from(g) } else { Value::Null } }),
        );
    }
    Ok(serde_json::json!({ "results": results }))
}

/// Per basis function, the interval its moments can take: the range [lo, hi] of b_j over [0,1]
/// (sampled on 4097 points), each end widened by 1 % of min(width, max(|end|, 1)) plus 1e-6
/// for rounding, biases and storage. Moments of any depth distribution on [0,1] lie inside;
/// the slack is relative to the end itself, so a steep basis (ESM's e^{80z}, range
/// [1, 5.5·10³⁴]) still refuses a moment below 0.99 instead of answering G ≈ 1 for it.
fn moment_box(t: &dyn crate::technique::Technique) -> Vec<(f64, f64)> {
    let m = t.moment_count();
    let mut lo = vec![f64::INFINITY; m];
    let mut hi = vec![f64::NEG_INFINITY; m];
    let mut row = vec![0.0; m];
    for k in 0..=4096 {
        t.basis(k as f64 / 4096.0, &mut row);
        for j in 0..m {
            lo[j] = lo[j].min(row[j]);
            hi[j] = hi[j].max(row[j]);
        }
    }
    (0..m)
        .map(|j| {
            let w = hi[j] - lo[j];
            let slack = |end: f64| 0.01 * w.min(end.abs().max(1.0)) + 1e-6;
            (lo[j] - slack(lo[j]), hi[j] + slack(hi[j]))
        })
        .collect()
}
