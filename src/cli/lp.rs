//! `momentlab lp [FILE]`: Algorithm 1 for a JSON batch (stdin when no file); the format and
//! the solving are [`momentlab::batch::lp`].

use anyhow::{Context, Result};
use momentlab::basis::Catalog;
use momentlab::batch::lp::solve_batch;
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
