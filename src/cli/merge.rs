//! `momentlab merge`: combine the results directories of a sharded `momentlab search`. Every
//! shard is verified first (completion marker, row count, no torn or duplicated rows, one
//! configuration); see [`momentlab::search::merge::verify_results`].

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
    /// Print {"rows", "candidates", "shards", "out", "complete"} as JSON instead of a line; a
    /// partial merge adds "partial": true and what is missing (see `partial.json`).
    #[arg(long)]
    pub json: bool,
}

pub fn run(args: Args) -> Result<()> {
    let m = momentlab::search::merge_dirs(&args.dirs, &args.out, args.allow_partial, args.force)?;
    if args.json {
        let mut v = serde_json::json!({
            "rows": m.rows,
            "candidates": m.candidates,
            "shards": args.dirs.len(),
            "out": args.out,
            "complete": m.partial.is_none(),
        });
        if let Some(p) = &m.partial {
            v.as_object_mut()
                .unwrap()
                .extend(serde_json::to_value(p)?.as_object().unwrap().clone());
        }
        println!("{v}");
        return Ok(());
    }
    eprintln!(
        "merge: {} rows from {} shards into {}{}",
        m.rows,
        args.dirs.len(),
        args.out.display(),
        match &m.partial {
            None => " (complete)".to_string(),
            Some(p) => format!("; {} (no complete.json)", p.line()),
        }
    );
    Ok(())
}
