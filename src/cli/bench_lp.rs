//! `momentlab bench lp` (scaffold: owned by the helper building it).

use anyhow::{bail, Result};

#[derive(clap::Args, Debug)]
pub struct Args {}

pub fn run(_args: Args) -> Result<()> {
    bail!("'bench lp' is not implemented yet")
}
