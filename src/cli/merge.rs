//! `momentlab merge`: combine the results directories of a sharded `momentlab search`.

use anyhow::Result;
use std::path::PathBuf;

#[derive(clap::Args, Debug)]
pub struct Args {
    /// Results directories of the shards (each written by `search --shard i/N`).
    #[arg(required = true)]
    pub dirs: Vec<PathBuf>,
    /// Output directory (config.json + results.jsonl sorted by candidate index).
    #[arg(long)]
    pub out: PathBuf,
    /// Merge even if shards are missing or unfinished.
    #[arg(long)]
    pub allow_partial: bool,
}

pub fn run(args: Args) -> Result<()> {
    let n = crate::search::merge_dirs(&args.dirs, &args.out, args.allow_partial)?;
    eprintln!(
        "merge: {n} rows from {} shards into {}",
        args.dirs.len(),
        args.out.display()
    );
    Ok(())
}
