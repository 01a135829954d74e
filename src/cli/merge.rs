//! `momentlab merge` (scaffold: owned by the helper building it).

use anyhow::{bail, Result};

#[derive(clap::Args, Debug)]
pub struct Args {}

pub fn run(_args: Args) -> Result<()> {
    bail!("'merge' is not implemented yet")
}
