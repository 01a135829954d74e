//! `momentlab shadow [FILE]`: closed-form shadow intensities for a JSON batch (stdin if no
//! file); the format and the evaluation are [`momentlab::batch::shadow`].

use anyhow::{Context, Result};
use momentlab::batch::shadow::evaluate_batch;

/// The input and output format, shown by `momentlab shadow --help`.
pub const SCHEMA_HELP: &str = r#"Input (JSON object; stdin when FILE is omitted or `-`):
  technique   string, required: vsm, esm, evsm, csm, hamburger, hamburger4, hausdorff4,
              hamburger6, tmsm, or "lp:f1,f2,…" (catalog names or formulas)
  problems    array, required: {"moments": [b1, …, bm], "zf": z_f}
              moments: the filtered moments b = E[b(Z)] of the technique's basis (m values,
              each within the range of its basis function over [0,1])
              zf: any finite receiver depth. Hamburger MSM (hamburger, hamburger4,
              hamburger6), vsm, esm and evsm evaluate their formula at z_f; techniques on
              [0,1] (hausdorff4, tmsm, csm, lp:…) answer G = 0 for z_f < 0 and
              G = F_Z(1) = 1 for z_f > 1 (the sharp bound over distributions on [0,1]).
  optional technique parameters (docs/techniques.md): alpha, b_star, bias ("standard" |
  "clamped"), quant_bits (32 | 16), precision ("f64" | "f32"), moment_count (hamburger;
  default: the first problem's), esm_c, evsm_c_pos, evsm_c_neg, csm_terms, min_variance

Output (one line of JSON on stdout): {"results": [{"g": G}, …]}, one per problem in order;
G in [0,1] is the shadow intensity (0 = lit), null when not finite.

Example:
  echo '{"technique":"hamburger4","alpha":3e-5,"precision":"f32",
         "problems":[{"moments":[0.5,0.25,0.125,0.0625],"zf":0.6},
                     {"moments":[0.5,0.25,0.125,0.0625],"zf":-0.002}]}' | momentlab shadow
  {"results":[{"g":0.9992789030075073},{"g":0.0}]}"#;

#[derive(clap::Args, Debug)]
#[command(after_long_help = SCHEMA_HELP)]
pub struct Args {
    /// Input JSON file (stdin when omitted or `-`); the format is under --help.
    pub file: Option<std::path::PathBuf>,
}

pub fn run(args: Args) -> Result<()> {
    let (text, src) = super::common::read_input(args.file.as_deref())?;
    let out = evaluate_batch(&text, &src)?;
    use std::io::Write;
    writeln!(std::io::stdout().lock(), "{}", serde_json::to_string(&out)?)
        .context("writing stdout")?;
    Ok(())
}
