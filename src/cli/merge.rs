//! `momentlab merge`: combine the results directories of a sharded `momentlab search`. Every
//! shard is verified first (completion marker, row count, no torn or duplicated rows, one
//! configuration); see [`crate::search::merge::verify_results`].

use anyhow::Result;
use std::path::PathBuf;

#[derive(clap::Args, Debug)]
pub struct Args {
    /// Results directories of the shards (each written by `search --shard i/N`).
    #[arg(required = true)]
    pub dirs: Vec<PathBuf>,
    /// Output folder (config.json + results.jsonl sorted by candidate index).
    #[arg(long)]
    pub out: PathBuf,
    /// Replace files that already exist in --out (otherwise refused).
    #[arg(long)]
    pub force: bool,
    /// Merge even if shards are missing or unfinished.
    #[arg(long)]
    pub allow_partial: bool,
    /// Print {"rows", "shards", "out"} as JSON instead of a line.
    #[arg(long)]
    pub json: bool,
}

pub fn run(args: Args) -> Result<()> {
    let n = crate::search::merge_dirs(&args.dirs, &args.out, args.allow_partial, args.force)?;
    if args.json {
        println!(
            "{}",
            serde_json::json!({"rows": n, "shards": args.dirs.len(), "out": args.out})
        );
        return Ok(());
    }
    eprintln!(
        "merge: {n} rows from {} shards into {}",
        args.dirs.len(),
        args.out.display()
    );
    Ok(())
}
