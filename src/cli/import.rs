//! `momentlab import`: validate depth stacks written by another renderer (layout in
//! docs/stacks.md) and, with `--out`, copy them there in canonical form.

use crate::stack;
use anyhow::{bail, Context, Result};
use std::path::PathBuf;

#[derive(clap::Args, Debug)]
pub struct Args {
    /// `.exr` stack files (sidecar `.json` next to each) or directories of them.
    #[arg(required = true)]
    pub inputs: Vec<PathBuf>,
    /// Copy the validated stacks here (same file names). Without it: validate only.
    #[arg(long)]
    pub out: Option<PathBuf>,
}

pub fn run(args: Args) -> Result<()> {
    let mut files = Vec::new();
    for p in &args.inputs {
        if p.is_dir() {
            let found = stack::exr_files(p)?;
            if found.is_empty() {
                bail!("{}: no .exr depth stacks in this directory", p.display());
            }
            files.extend(found);
        } else if p.extension().is_some_and(|e| e.eq_ignore_ascii_case("exr")) {
            if !p.is_file() {
                bail!("{}: no such file", p.display());
            }
            files.push(p.clone());
        } else {
            bail!(
                "{}: expected a .exr depth stack or a directory",
                p.display()
            );
        }
    }
    if let Some(out) = &args.out {
        std::fs::create_dir_all(out).with_context(|| format!("creating {}", out.display()))?;
    }
    // read (= validate) everything before writing anything
    let stacks = files
        .iter()
        .map(|f| stack::read(f))
        .collect::<Result<Vec<_>>>()?;
    for (f, st) in files.iter().zip(&stacks) {
        let m = &st.meta;
        println!(
            "ok {}: {}/{} {}x{} {} layers {} fragments",
            f.display(),
            m.scene,
            m.view,
            m.width,
            m.height,
            m.layers,
            st.fragment_count()
        );
        if let Some(out) = &args.out {
            let name = f.file_name().context("input has no file name")?;
            stack::write(&out.join(name), st)?;
        }
    }
    match &args.out {
        Some(out) => println!("imported {} stacks into {}", stacks.len(), out.display()),
        None => println!("validated {} stacks", stacks.len()),
    }
    Ok(())
}
