//! `momentlab lp [FILE]`: Algorithm 1 for a JSON batch (stdin when no file).
//!
//! Input:  {"basis": ["z", "z^2", …], "grid": {"points": 1024} | {"values": [..]},
//!          "solver": "fast" | "reference", "problems": [{"moments": [..], "zf": 0.4}, …]}
//! ("grid" defaults to 1024 uniform points, "solver" to "fast").
//! Output: {"results": [{"status": "optimal", "g": 0.25, "support": [[z, w], …]},
//!          {"status": "infeasible"}, {"status": "failed", "reason": "…"}, …]}
//! Everything is validated before any LP is solved; a problem that is infeasible or that the
//! solver cannot settle gets its own status, the rest of the batch is answered.

use crate::basis::Catalog;
use crate::lp::{make_solver, GridTable, Status};
use crate::Grid;
use anyhow::{bail, Context, Result};
use rayon::prelude::*;
use serde::Deserialize;
use std::path::PathBuf;

/// The input and output format, shown by `momentlab lp --help`.
pub const SCHEMA_HELP: &str = r#"Input (JSON object; stdin when FILE is omitted or `-`):
  basis     array of strings, required: catalog names or formulas, e.g. ["z", "z^2"],
            ["sin(2πz)", "cos(2πz)"], ["exp(40z)"] (m = its length)
  problems  array, required: {"moments": [b1, …, bm], "zf": z_f}, z_f in [0,1]
  grid      optional: {"points": n} (uniform on [0,1], 2..=1048576) or
            {"values": [z1, …]} (in [0,1]); default {"points": 1024}
  solver    optional: "fast" (default) or "reference"

Output (one line of JSON on stdout, --pretty to indent): {"results": [...]}, one per
problem in order:
  {"status": "optimal", "g": G, "support": [[z, w], …]}  G: the sharp lower bound of
      P(Z < z_f) over distributions on the grid (Algorithm 1); support: a minimising one
  {"status": "infeasible"}                 no distribution on the grid has these moments
  {"status": "failed", "reason": "…"}      the solver could not certify either verdict
Everything is validated before any LP is solved; a bad batch is one error line (exit 1).

Example:
  echo '{"basis":["z","z^2"],"grid":{"points":5},
         "problems":[{"moments":[0.5,0.3125],"zf":0.6}]}' | momentlab lp
  {"results":[{"status":"optimal","g":0.5,"support":[[0.25,0.5],[0.75,0.5]]}]}"#;

#[derive(clap::Args, Debug)]
#[command(after_long_help = SCHEMA_HELP)]
pub struct Args {
    /// JSON batch file (stdin when omitted or `-`; a regular file of at most 1 GiB); the format is
    /// under --help. Limits checked before any allocation: at most 31 basis functions, at most
    /// 1048576 grid points.
    pub file: Option<PathBuf>,
    /// Catalog used to resolve basis names (default: the embedded catalog).
    #[arg(long)]
    pub catalog: Option<PathBuf>,
    /// Pretty-print the output JSON.
    #[arg(long)]
    pub pretty: bool,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Input {
    basis: Vec<String>,
    #[serde(default)]
    grid: Option<GridSpec>,
    #[serde(default)]
    solver: Option<String>,
    problems: Vec<Problem>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct GridSpec {
    #[serde(default)]
    points: Option<usize>,
    #[serde(default)]
    values: Option<Vec<f64>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Problem {
    moments: Vec<f64>,
    zf: f64,
}

/// Problems solved by one solver instance (consecutive problems share warm-start state).
const CHUNK: usize = 64;

fn grid_of(spec: Option<GridSpec>) -> Result<Grid> {
    match spec {
        None => Grid::uniform(crate::grid::DEFAULT_POINTS),
        Some(GridSpec {
            points: Some(n),
            values: None,
        }) => {
            if n > crate::grid::MAX_POINTS {
                bail!(
                    "grid: {n} points is more than the supported {}",
                    crate::grid::MAX_POINTS
                );
            }
            Grid::uniform(n)
        }
        Some(GridSpec {
            points: None,
            values: Some(v),
        }) => {
            if let Some(i) = v.iter().position(|x| !(0.0..=1.0).contains(x)) {
                bail!("grid: value {i} ({}) is outside [0,1]", v[i]);
            }
            Grid::from_values(v)
        }
        Some(_) => bail!("grid: give exactly one of \"points\" or \"values\""),
    }
}

/// One result, serialised as {"status", "g", "support"} in that order.
#[derive(serde::Serialize)]
struct Output {
    status: Status,
    #[serde(skip_serializing_if = "Option::is_none")]
    g: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    support: Option<Vec<[f64; 2]>>,
    #[serde(skip_serializing_if = "Option::is_none")]
    reason: Option<String>,
}

fn output(sol: crate::lp::Solution) -> Output {
    let optimal = sol.status == Status::Optimal;
    Output {
        status: sol.status,
        g: optimal.then_some(sol.g),
        support: optimal.then(|| sol.support.iter().map(|&(z, w)| [z, w]).collect()),
        reason: sol.reason,
    }
}

#[derive(serde::Serialize)]
struct Results {
    results: Vec<Output>,
}

/// Validates and solves a batch; returns the output JSON text.
pub fn solve_batch(text: &str, catalog: &Catalog, pretty: bool) -> Result<String> {
    let input: Input = serde_json::from_str(text).context("malformed input JSON")?;
    if input.basis.is_empty() {
        bail!("basis: need at least one function");
    }
    let basis = catalog.basis(&input.basis)?;
    let grid = grid_of(input.grid)?;
    let solver = input.solver.unwrap_or_else(|| "fast".to_string());
    let m = basis.len();
    for (k, p) in input.problems.iter().enumerate() {
        if p.moments.len() != m {
            bail!(
                "problem {k}: expected {m} moments (one per basis function), got {}",
                p.moments.len()
            );
        }
        if let Some(j) = p.moments.iter().position(|x| !x.is_finite()) {
            bail!("problem {k}: moment {j} is not finite ({})", p.moments[j]);
        }
        if !(0.0..=1.0).contains(&p.zf) {
            bail!("problem {k}: zf = {} is outside [0,1]", p.zf);
        }
    }
    let table = GridTable::from_fn(&grid, m, |z, out| basis.eval(z, out))?;
    // Fail early (unknown or unavailable solver) before spawning work.
    make_solver(&solver, table.clone())?;

    let bar = if input.problems.len() < 1000 {
        crate::progress::Bar::hidden()
    } else {
        crate::progress::Bar::new("lp problems", input.problems.len() as u64)
    };
    let chunks: Vec<Vec<Output>> = input
        .problems
        .par_chunks(CHUNK)
        .enumerate()
        .map(|(c, chunk)| -> Result<Vec<Output>> {
            let mut s = make_solver(&solver, table.clone())?;
            let mut out = Vec::with_capacity(chunk.len());
            for (k, p) in chunk.iter().enumerate() {
                let sol = s.solve(&p.moments, p.zf).unwrap_or_else(|e| {
                    let k = c * CHUNK + k;
                    crate::lp::Solution::failed(format!("problem {k}: {e:#}"))
                });
                out.push(output(sol));
                bar.inc(1);
            }
            Ok(out)
        })
        .collect::<Result<_>>()?;
    bar.finish();
    let out = Results {
        results: chunks.into_iter().flatten().collect(),
    };
    Ok(if pretty {
        serde_json::to_string_pretty(&out)?
    } else {
        serde_json::to_string(&out)?
    })
}

pub fn run(args: Args) -> Result<()> {
    let catalog = match &args.catalog {
        Some(p) => Catalog::load(p)?,
        None => Catalog::embedded(),
    };
    let (text, source) = super::common::read_input(args.file.as_deref())?;
    let out = solve_batch(&text, &catalog, args.pretty).with_context(|| format!("lp {source}"))?;
    use std::io::Write;
    writeln!(std::io::stdout().lock(), "{out}").context("writing stdout")?;
    Ok(())
}
