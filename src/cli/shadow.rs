//! `momentlab shadow [FILE]`: closed-form shadow intensities for a JSON batch (stdin if no
//! file). Input: {"technique": "hamburger4", "alpha": 3e-5, "precision": "f32",
//! "problems": [{"moments": [b1, …], "zf": 0.4}, …]} plus optional technique parameters (the
//! fields of `technique::registry::Params`). Output: {"results": [{"g": 0.31}, …]}.

use crate::technique::registry::{build, Params};
use anyhow::{anyhow, bail, Context, Result};
use serde_json::{Map, Value};
use std::io::Read;

#[derive(clap::Args, Debug)]
pub struct Args {
    /// Input JSON file (stdin when omitted).
    pub file: Option<std::path::PathBuf>,
}

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
            bail!("{src}: problem {i}: zf is not finite");
        }
        let g = ev.shadow(&p.moments, p.zf);
        results.push(
            serde_json::json!({ "g": if g.is_finite() { Value::from(g) } else { Value::Null } }),
        );
    }
    Ok(serde_json::json!({ "results": results }))
}

pub fn run(args: Args) -> Result<()> {
    let (text, src) = match &args.file {
        Some(p) => (
            std::fs::read_to_string(p).with_context(|| format!("reading {}", p.display()))?,
            p.display().to_string(),
        ),
        None => {
            let mut s = String::new();
            std::io::stdin()
                .read_to_string(&mut s)
                .context("reading stdin")?;
            (s, "stdin".to_string())
        }
    };
    let out = evaluate_batch(&text, &src)?;
    use std::io::Write;
    writeln!(std::io::stdout().lock(), "{}", serde_json::to_string(&out)?)
        .context("writing stdout")?;
    Ok(())
}
