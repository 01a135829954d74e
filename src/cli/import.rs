//! `momentlab import`: validate depth stacks written by another renderer (layout in
//! docs/stacks.md), or convert deep OpenEXR images (detected by their version bits) to stacks,
//! and, with `--out`, write them there in canonical form.

use anyhow::{bail, Context, Result};
use momentlab::artefact::OutDir;
use momentlab::stack;
use std::path::{Path, PathBuf};

#[derive(clap::Args, Debug)]
pub struct Args {
    /// `.exr` stack files (sidecar `.json` next to each) or directories of them.
    #[arg(required = true)]
    pub inputs: Vec<PathBuf>,
    /// Copy the validated stacks here (same file names; two inputs with the same name are
    /// refused). Without it: validate only.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Replace files that already exist in --out (otherwise refused). An input is never its
    /// own destination.
    #[arg(long, alias = "overwrite", requires = "out")]
    pub force: bool,
    /// Print the validated stacks as JSON instead of lines.
    #[arg(long)]
    pub json: bool,
    /// Deep OpenEXR inputs: sort each pixel's samples by Z (without it, unsorted samples are
    /// an error).
    #[arg(long)]
    pub sort: bool,
}

/// Refuse, before reading anything, two inputs that would land on the same file in `out`, an
/// input that is its own destination, and (without --force) files that exist there already.
fn check_destinations(files: &[PathBuf], out: &OutDir) -> Result<()> {
    let same = |a: &Path, b: &Path| matches!((a.canonicalize(), b.canonicalize()), (Ok(x), Ok(y)) if x == y);
    let mut names = Vec::new();
    for f in files {
        let stem = f
            .file_stem()
            .with_context(|| format!("{}: no file name", f.display()))?
            .to_string_lossy()
            .into_owned();
        for (dest, src) in stack::file_names(&stem)
            .iter()
            .zip([f.clone(), stack::sidecar_path(f)])
        {
            let d = out.path(dest)?;
            if same(&d, &src) {
                bail!(
                    "{} would be rewritten in place; import into another --out folder",
                    src.display()
                );
            }
        }
        names.extend(stack::file_names(&stem));
    }
    out.reserve(&names).map_err(|e| {
        if e.to_string().contains("two outputs named") {
            anyhow::anyhow!(
                "{e}: two inputs would both be written to {}",
                out.root().display()
            )
        } else {
            e
        }
    })
}

pub fn run(args: Args) -> Result<()> {
    let mut files = Vec::new();
    for p in &args.inputs {
        if p.as_os_str() == "-" {
            bail!("'-': a depth stack is an .exr file with a .json sidecar and cannot come from stdin; give its path");
        }
        if p.is_dir() {
            let found = stack::exr_files(p)?;
            if found.is_empty() {
                bail!("{}: no .exr depth stacks in this directory", p.display());
            }
            files.extend(found);
        } else if p.extension().is_some_and(|e| e.eq_ignore_ascii_case("exr")) {
            momentlab::artefact::check_regular(p)?;
            files.push(p.clone());
        } else {
            bail!(
                "{}: expected a .exr depth stack or a directory",
                p.display()
            );
        }
    }
    let out = match &args.out {
        Some(o) => {
            let out = OutDir::new(o, args.force)?;
            check_destinations(&files, &out)?;
            Some(out)
        }
        None => None,
    };
    // read (= validate) everything before writing anything
    let mut deep_stats = Vec::new();
    let mut stacks = Vec::new();
    for f in &files {
        if stack::is_deep_file(f)? {
            let (st, stats) = stack::deep::read_deep_stack(f, args.sort)
                .with_context(|| format!("{}", f.display()))?;
            stacks.push(st);
            deep_stats.push(Some(stats));
        } else {
            stacks.push(stack::read(f)?);
            deep_stats.push(None);
        }
    }
    let mut rows = Vec::new();
    for ((f, st), deep) in files.iter().zip(&stacks).zip(&deep_stats) {
        let m = &st.meta;
        rows.push(serde_json::json!({
            "file": f, "scene": m.scene, "view": m.view, "width": m.width, "height": m.height,
            "layers": m.layers, "fragments": st.fragment_count(), "deep": deep,
        }));
        if let Some(out) = &out {
            let stem = f.file_stem().context("input has no file name")?;
            stack::write_to(out, &stem.to_string_lossy(), st)?;
        }
        if args.json {
            continue;
        }
        let note = deep.as_ref().map_or(String::new(), |d| {
            format!(
                " (deep: {} samples, {} merged, {} transparent dropped, {} partly transparent \
                 and {} volumetric kept as opaque)",
                d.samples, d.merged, d.transparent, d.partial_alpha, d.volumetric
            )
        });
        println!(
            "ok {}: {}/{} {}x{} {} layers {} fragments{note}",
            f.display(),
            m.scene,
            m.view,
            m.width,
            m.height,
            m.layers,
            st.fragment_count()
        );
    }
    if args.json {
        println!(
            "{}",
            serde_json::to_string_pretty(&serde_json::json!({ "stacks": rows, "out": args.out }))?
        );
        return Ok(());
    }
    match &args.out {
        Some(out) => println!("imported {} stacks into {}", stacks.len(), out.display()),
        None => println!("validated {} stacks", stacks.len()),
    }
    Ok(())
}
