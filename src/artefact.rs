//! Artefact files, the one place where commands, the pipeline and the sweep read and write:
//!
//! * [`OutDir`] (module [`out`]): the one output writer — confined to its folder, refusing to
//!   overwrite unless forced, atomic (temporary file, fsync, rename), one file per name and run,
//!   and an advisory lock for folders that grow across runs (results);
//! * [`input`]: the one bounded reader — every JSON or text input, with a named size [`Limit`],
//!   regular files only;
//! * [`Checkpoint`] (module [`checkpoint`]): the completed units of a long command, so that the
//!   same command after a kill resumes;
//! * JSON lines appended and flushed per batch (resumable sweeps) and read back with a torn
//!   last line dropped.

pub mod checkpoint;
pub mod input;
pub mod interrupt;
pub mod out;

pub use checkpoint::Checkpoint;
pub use input::{check_regular, read_bytes, read_input, read_text, Limit};
pub use out::{check_name, safe_name, DirLock, OutDir, LOCK_FILE};

use anyhow::{anyhow, Context, Result};
use serde::de::DeserializeOwned;
use serde::Serialize;
use std::fs;
use std::os::unix::fs::OpenOptionsExt;
use std::path::Path;

/// Write `value` as pretty JSON (with a final newline) to `path`, atomically, replacing an
/// existing file: for the pipeline's own caches. Command outputs go through [`OutDir`].
pub fn write_json<T: Serialize + ?Sized>(path: &Path, value: &T) -> Result<()> {
    write_text(path, &(serde_json::to_string_pretty(value)? + "\n"))
}

/// Write `text` to `path` atomically, creating the parent folders and replacing an existing
/// file (see [`write_json`]).
pub fn write_text(path: &Path, text: &str) -> Result<()> {
    let (dir, name) = OutDir::for_file(path, true)?;
    dir.write_text(&name, text).map(|_| ())
}

/// Read a JSON file (bounded by [`Limit::ARTEFACT`]; regular files only).
pub fn read_json<T: DeserializeOwned>(path: &Path) -> Result<T> {
    input::read_json(path, Limit::ARTEFACT)
}

/// Read a JSON-lines file (bounded by [`Limit::ROWS`]). A last line without '\n' is a torn
/// write: it is ignored and, with `repair`, cut off the file. A missing file reads as empty.
pub fn read_jsonl<T: DeserializeOwned>(path: &Path, repair: bool) -> Result<Vec<T>> {
    if fs::symlink_metadata(path).is_err() {
        return Ok(Vec::new());
    }
    let text = read_bytes(path, Limit::ROWS)?;
    let keep = text.iter().rposition(|&c| c == b'\n').map_or(0, |p| p + 1);
    if keep < text.len() && repair {
        // Cut the file itself, never what a symbolic link in its place points at.
        let f = fs::OpenOptions::new()
            .write(true)
            .custom_flags(libc::O_NOFOLLOW)
            .open(path)
            .map_err(|e| match e.raw_os_error() {
                Some(libc::ELOOP) => anyhow!(
                    "{}: is a symbolic link; refusing to repair through it",
                    path.display()
                ),
                _ => anyhow!("repairing {}: {e}", path.display()),
            })?;
        f.set_len(keep as u64)
            .with_context(|| format!("repairing {}", path.display()))?;
    }
    let body = std::str::from_utf8(&text[..keep])
        .with_context(|| format!("{}: not UTF-8", path.display()))?;
    body.lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty())
        .map(|(i, l)| {
            serde_json::from_str(l)
                .with_context(|| format!("{}:{}: bad row", path.display(), i + 1))
        })
        .collect()
}

/// Append rows (one JSON line each) to `path` and flush; never follows a symbolic link.
pub fn append_jsonl<T: Serialize>(path: &Path, rows: &[T]) -> Result<()> {
    if rows.is_empty() {
        return Ok(());
    }
    out::append_jsonl_nofollow(path, rows)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Write;

    #[test]
    fn torn_last_line_is_dropped_and_repaired() {
        let dir = std::env::temp_dir().join(format!("momentlab-jsonl-{}", std::process::id()));
        fs::create_dir_all(&dir).unwrap();
        let p = dir.join("x.jsonl");
        let _ = fs::remove_file(&p);
        assert!(read_jsonl::<u32>(&p, true).unwrap().is_empty());
        append_jsonl(&p, &[1u32, 2, 3]).unwrap();
        fs::OpenOptions::new()
            .append(true)
            .open(&p)
            .unwrap()
            .write_all(b"4")
            .unwrap();
        assert_eq!(read_jsonl::<u32>(&p, false).unwrap(), vec![1, 2, 3]);
        assert_eq!(fs::read(&p).unwrap().len(), 7);
        assert_eq!(read_jsonl::<u32>(&p, true).unwrap(), vec![1, 2, 3]);
        assert_eq!(fs::read(&p).unwrap().len(), 6);
        fs::write(&p, "1\nx\n3\n").unwrap();
        let e = read_jsonl::<u32>(&p, true).unwrap_err();
        assert!(format!("{e:#}").contains("x.jsonl:2"), "{e:#}");
        fs::remove_dir_all(&dir).unwrap();
    }

    /// A results file that is a link to a file elsewhere is never cut through the link.
    #[test]
    fn repair_does_not_follow_a_symbolic_link() {
        let dir = std::env::temp_dir().join(format!("momentlab-jsonl-link-{}", std::process::id()));
        let _ = fs::remove_dir_all(&dir);
        fs::create_dir_all(dir.join("out")).unwrap();
        let outside = dir.join("outside.jsonl");
        fs::write(&outside, "1\n2\n3").unwrap();
        let link = dir.join("out/results.jsonl");
        std::os::unix::fs::symlink(&outside, &link).unwrap();
        let e = format!("{:#}", read_jsonl::<u32>(&link, true).unwrap_err());
        assert!(e.contains("symbolic link"), "{e}");
        assert_eq!(
            fs::read(&outside).unwrap().len(),
            5,
            "the outside file was cut"
        );
        // Read-only use still reads the whole lines.
        assert_eq!(read_jsonl::<u32>(&link, false).unwrap(), vec![1, 2]);
        fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn json_round_trips_into_new_folders_without_leftovers() {
        let dir = std::env::temp_dir().join(format!("momentlab-json-{}", std::process::id()));
        let _ = fs::remove_dir_all(&dir);
        let p = dir.join("a/b/v.json");
        write_json(&p, &vec![1.5f64, 2.0]).unwrap();
        assert_eq!(read_json::<Vec<f64>>(&p).unwrap(), vec![1.5, 2.0]);
        assert!(fs::read_to_string(&p).unwrap().ends_with('\n'));
        let names: Vec<_> = fs::read_dir(dir.join("a/b")).unwrap().collect();
        assert_eq!(names.len(), 1, "temporary file left behind");
        fs::write(&p, "{").unwrap();
        assert!(format!("{:#}", read_json::<Vec<f64>>(&p).unwrap_err()).contains("v.json"));
        fs::remove_dir_all(&dir).unwrap();
    }
}
