//! `momentlab import` (scaffold: owned by the helper building it).

use anyhow::{bail, Result};

#[derive(clap::Args, Debug)]
pub struct Args {}

pub fn run(_args: Args) -> Result<()> {
    bail!("'import' is not implemented yet")
}
