//! Step 1: the depth stacks of the run in `<results>/<run>/stacks`: the embedded default
//! dataset rendered at the planned resolution, written stack by stack and then marked complete
//! by [`MARKER`] (the [`Manifest`]: dataset fingerprint, resolution, stack names). The folder is
//! read back only when its marker equals the planned set and it holds exactly the stacks the
//! marker lists; otherwise the set is rendered again (a run killed while writing them leaves no
//! marker), replacing the run's own stack files. A stack that neither the planned set nor the
//! folder's marker lists is an error: the folder is not the run's own.

use crate::artefact::OutDir;
use crate::stack::DepthStack;
use anyhow::{bail, Context, Result};
use serde::{Deserialize, Serialize};
use std::collections::BTreeSet;
use std::path::Path;
use std::time::Instant;

/// The completion marker of a stacks folder, written after the last stack.
pub const MARKER: &str = "complete.json";

/// What [`MARKER`] records: which set of stacks the folder holds.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Manifest {
    /// The dataset the stacks are rendered from: `embedded <fingerprint>` for the embedded
    /// default dataset ([`crate::render::embedded_fingerprint`]).
    pub dataset: String,
    /// Width and height of every stack.
    pub resolution: usize,
    /// File stems of the stacks (`<scene>_<light>`: `<stem>.exr` and `<stem>.json`), in
    /// dataset order.
    pub stacks: Vec<String>,
}

impl Manifest {
    /// The set the embedded default dataset gives at `resolution`; nothing is rendered.
    pub fn default_dataset(resolution: usize) -> Result<Manifest> {
        Ok(Manifest {
            dataset: format!("embedded {}", crate::render::embedded_fingerprint()),
            resolution,
            stacks: crate::render::default_dataset_views()?
                .into_iter()
                .map(|(scene, light)| format!("{scene}_{light}"))
                .collect(),
        })
    }
}

/// The stacks in `dir` at `resolution`, rendering and writing them when missing, incomplete or
/// stale (see the module docs).
pub fn load_or_render(dir: &Path, resolution: usize) -> Result<Vec<DepthStack>> {
    let want = Manifest::default_dataset(resolution)?;
    load_or_render_with(dir, &want, || crate::render::default_dataset(resolution))
}

/// [`load_or_render`] of the set `want`, produced by `render` when it cannot be read back.
fn load_or_render_with(
    dir: &Path,
    want: &Manifest,
    render: impl FnOnce() -> Result<Vec<DepthStack>>,
) -> Result<Vec<DepthStack>> {
    let out = OutDir::new(dir, true)?;
    let marker = if out.exists(MARKER)? {
        crate::artefact::read_json::<Manifest>(&dir.join(MARKER)).ok()
    } else {
        None
    };
    // The run's own stacks: the planned set and the set of the folder's marker.
    let own: BTreeSet<&str> = want
        .stacks
        .iter()
        .chain(marker.iter().flat_map(|m| &m.stacks))
        .map(String::as_str)
        .collect();
    let present = stack_stems(dir)?;
    if let Some(s) = present.iter().find(|s| !own.contains(s.as_str())) {
        bail!(
            "{}: not a stack of the default dataset at {r}×{r} ({} lists the set); remove it \
             or pass --force to start the run over",
            dir.join(format!("{s}.exr")).display(),
            dir.join(MARKER).display(),
            r = want.resolution
        );
    }
    if marker.as_ref() == Some(want) && present == want.stacks.iter().cloned().collect() {
        match read_back(dir, want) {
            Ok(stacks) => return Ok(stacks),
            Err(e) => eprintln!("  {e:#}; rendering the stacks again"),
        }
    }
    // Not complete until the marker is written again, after the last stack.
    out.remove(MARKER)?;
    let t0 = Instant::now();
    let stacks = render()?;
    let stems: Vec<String> = stacks.iter().map(|s| s.file_stem()).collect();
    if stems != want.stacks {
        bail!(
            "rendered stacks {stems:?} are not the planned set {:?}",
            want.stacks
        );
    }
    for s in &own {
        if !want.stacks.iter().any(|w| w == s) {
            for name in crate::stack::file_names(s) {
                out.remove(&name)?;
            }
        }
    }
    for st in &stacks {
        crate::stack::write_to(&out, &st.file_stem(), st)?;
    }
    out.write_json(MARKER, want)?;
    eprintln!(
        "  rendered {} views in {:.1} s",
        stacks.len(),
        t0.elapsed().as_secs_f64()
    );
    Ok(stacks)
}

/// The stems of the `.exr` files in `dir` (none when `dir` is missing).
fn stack_stems(dir: &Path) -> Result<BTreeSet<String>> {
    if std::fs::symlink_metadata(dir).is_err() {
        return Ok(BTreeSet::new());
    }
    Ok(crate::stack::exr_files(dir)?
        .iter()
        .filter_map(|p| p.file_stem().map(|s| s.to_string_lossy().into_owned()))
        .collect())
}

/// The stacks `want` lists, read from `dir` in its order; an error names a stack that does not
/// read or has another resolution or name.
fn read_back(dir: &Path, want: &Manifest) -> Result<Vec<DepthStack>> {
    want.stacks
        .iter()
        .map(|stem| {
            let path = dir.join(format!("{stem}.exr"));
            let st = crate::stack::read(&path)?;
            let m = &st.meta;
            if m.width != want.resolution || m.height != want.resolution {
                bail!(
                    "{}: {}×{}, not {r}×{r}",
                    path.display(),
                    m.width,
                    m.height,
                    r = want.resolution
                );
            }
            if st.file_stem() != *stem {
                bail!(
                    "{}: holds view {} of scene {}",
                    path.display(),
                    m.view,
                    m.scene
                );
            }
            Ok(st)
        })
        .collect::<Result<Vec<_>>>()
        .context("reading back the stacks")
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::fs;
    use std::os::unix::fs::MetadataExt;

    const R: usize = 16;

    fn ino(p: &Path) -> u64 {
        fs::metadata(p).unwrap().ino()
    }

    /// A set of rendered stacks at R×R in a fresh folder: (folder, planned set, first stack).
    fn rendered(tag: &str) -> (std::path::PathBuf, Manifest, std::path::PathBuf) {
        let dir =
            std::env::temp_dir().join(format!("momentlab-stacks-{tag}-{}", std::process::id()));
        let _ = fs::remove_dir_all(&dir);
        let want = Manifest::default_dataset(R).unwrap();
        assert!(want.stacks.len() >= 2, "{:?}", want.stacks);
        let stacks = load_or_render(&dir, R).unwrap();
        assert_eq!(stacks.len(), want.stacks.len());
        let marker: Manifest = crate::artefact::read_json(&dir.join(MARKER)).unwrap();
        assert_eq!(marker, want);
        let first = dir.join(format!("{}.exr", want.stacks[0]));
        (dir, want, first)
    }

    #[test]
    fn a_complete_set_is_read_back_and_an_incomplete_one_rendered_again() {
        let (dir, want, first) = rendered("reuse");
        // Complete: read back, nothing rewritten.
        let before = ino(&first);
        let again = load_or_render_with(&dir, &want, || panic!("rendered a complete set")).unwrap();
        assert_eq!(
            again.iter().map(|s| s.file_stem()).collect::<Vec<_>>(),
            want.stacks
        );
        assert_eq!(ino(&first), before);
        // One stack missing (a run killed while writing them): rendered again.
        let last = want.stacks.last().unwrap();
        fs::remove_file(dir.join(format!("{last}.exr"))).unwrap();
        load_or_render(&dir, R).unwrap();
        assert!(dir.join(format!("{last}.exr")).exists());
        assert_ne!(ino(&first), before, "the incomplete set was reused");
        // No marker (killed before it): rendered again, even with every stack there.
        fs::remove_file(dir.join(MARKER)).unwrap();
        let before = ino(&first);
        load_or_render(&dir, R).unwrap();
        assert_ne!(ino(&first), before, "a set without its marker was reused");
        // Another resolution: rendered again.
        let stacks = load_or_render(&dir, R + 8).unwrap();
        assert!(stacks.iter().all(|s| s.meta.width == R + 8));
        fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn a_foreign_stack_is_an_error_not_part_of_the_dataset() {
        let (dir, want, first) = rendered("foreign");
        fs::copy(&first, dir.join("other_view.exr")).unwrap();
        fs::copy(first.with_extension("json"), dir.join("other_view.json")).unwrap();
        let before = ino(&first);
        let e = format!("{:#}", load_or_render(&dir, R).unwrap_err());
        assert!(
            e.contains("other_view.exr") && e.contains("--force") && !e.contains('\n'),
            "{e}"
        );
        assert_eq!(ino(&first), before);
        // A marker listing a stack that is not there is not complete either.
        let mut more = want.clone();
        more.stacks.push("other_view".into());
        fs::remove_file(dir.join("other_view.exr")).unwrap();
        crate::artefact::write_json(&dir.join(MARKER), &more).unwrap();
        load_or_render(&dir, R).unwrap();
        assert_ne!(ino(&first), before);
        let marker: Manifest = crate::artefact::read_json(&dir.join(MARKER)).unwrap();
        assert_eq!(marker, want);
        fs::remove_dir_all(&dir).unwrap();
    }
}
