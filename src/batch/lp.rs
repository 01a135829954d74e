//! The JSON batch of `momentlab lp`: Algorithm 1 for many (moments, z_f) problems of one basis
//! and grid.
//!
//! Input:  {"basis": ["z", "z^2", …], "grid": {"points": 1024} | {"values": [..]},
//!          "solver": "fast" | "reference", "problems": [{"moments": [..], "zf": 0.4}, …]}
//! ("grid" defaults to 1024 uniform points, "solver" to "fast").
//! Output: {"results": [{"status": "optimal", "g": 0.25, "support": [[z, w], …]},
//!          {"status": "infeasible"}, {"status": "failed", "reason": "…"}, …]}
//! Everything is validated before any LP is solved; a problem that is infeasible or that the
//! solver cannot settle gets its own status, the rest of the batch is answered.

use crate::basis::Catalog;
use crate::lp::{make_solver, GridTable, SolverKind, Status};
use crate::Grid;
use anyhow::{bail, Context, Result};
use rayon::prelude::*;
use serde::Deserialize;

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
    let solver: SolverKind = input.solver.as_deref().unwrap_or("fast").parse()?;
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
            let mut s = make_solver(solver, table.clone());
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
