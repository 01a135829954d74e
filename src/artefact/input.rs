//! The one bounded reader: every JSON or text input (batches, catalogs, sidecars, scene files,
//! configs, result rows) is read through [`read_bytes`] / [`read_text`] / [`read_json`] with a
//! named [`Limit`]. Only regular files are read: a FIFO, device, socket or directory (also
//! behind a symbolic link, e.g. a link to /dev/zero) is refused with a clear message instead of
//! blocking or eating memory. The size is checked on the open file before anything is read, and
//! the read itself stops one byte past the limit.

use anyhow::{anyhow, bail, Context, Result};
use serde::de::DeserializeOwned;
use std::fs::File;
use std::io::Read;
use std::os::unix::fs::{FileTypeExt, OpenOptionsExt};
use std::path::Path;

/// A size limit with the name of the input kind it applies to (both appear in the error).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Limit {
    /// Largest accepted size in bytes.
    pub bytes: u64,
    /// What is being read ("sidecar", "scene file", …), for the error message.
    pub what: &'static str,
}

impl Limit {
    /// JSON batches of `lp` and `shadow` (and their stdin).
    pub const BATCH: Limit = Limit::new(1 << 30, "input batch");
    /// Stack sidecars (`<name>.json` next to the `.exr`).
    pub const SIDECAR: Limit = Limit::new(1 << 20, "sidecar");
    /// Scene description files.
    pub const SCENE: Limit = Limit::new(16 << 20, "scene file");
    /// Mesh files referenced by scenes (OBJ and the like).
    pub const MESH: Limit = Limit::new(1 << 30, "mesh file");
    /// A deep OpenEXR image (read whole before decoding).
    pub const DEEP: Limit = Limit::new(4 << 30, "deep OpenEXR image");
    /// Basis catalogs.
    pub const CATALOG: Limit = Limit::new(16 << 20, "catalog");
    /// Configuration, summary and marker files written by momentlab itself.
    pub const CONFIG: Limit = Limit::new(64 << 20, "configuration file");
    /// Result-row files (JSON lines of the sweep).
    pub const ROWS: Limit = Limit::new(8 << 30, "results file");
    /// Any other JSON or text artefact read back (reports, quantization tables, θ files).
    pub const ARTEFACT: Limit = Limit::new(256 << 20, "artefact");

    /// A limit of `bytes` for inputs called `what`.
    pub const fn new(bytes: u64, what: &'static str) -> Limit {
        Limit { bytes, what }
    }
}

impl std::fmt::Display for Limit {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "the {} limit for a {}",
            human_bytes(self.bytes),
            self.what
        )
    }
}

/// `n` bytes as "64 MiB", "1 GiB", "512 bytes".
pub fn human_bytes(n: u64) -> String {
    for (shift, unit) in [(40, "TiB"), (30, "GiB"), (20, "MiB"), (10, "KiB")] {
        if n >= 1 << shift && n.is_multiple_of(1 << shift) {
            return format!("{} {unit}", n >> shift);
        }
    }
    format!("{n} bytes")
}

/// What a non-regular file is, for "… is a FIFO, not a regular file".
fn kind(ft: std::fs::FileType) -> &'static str {
    if ft.is_dir() {
        "a directory"
    } else if ft.is_fifo() {
        "a FIFO (named pipe)"
    } else if ft.is_char_device() {
        "a character device"
    } else if ft.is_block_device() {
        "a block device"
    } else if ft.is_socket() {
        "a socket"
    } else {
        "not a regular file"
    }
}

/// Open `path` for reading if it is a regular file (symbolic links are followed: an input may
/// be a link, but what it points at must be a regular file). Opening never blocks on a FIFO.
/// Returns the file and its size.
pub fn open_regular(path: &Path) -> Result<(File, u64)> {
    let f = std::fs::OpenOptions::new()
        .read(true)
        .custom_flags(libc::O_NONBLOCK)
        .open(path)
        .map_err(|e| match e.kind() {
            std::io::ErrorKind::NotFound => anyhow!("{}: no such file", path.display()),
            std::io::ErrorKind::PermissionDenied => {
                anyhow!("{}: permission denied", path.display())
            }
            _ => anyhow!("{}: cannot open: {e}", path.display()),
        })?;
    let md = f
        .metadata()
        .with_context(|| format!("{}: cannot read", path.display()))?;
    if !md.file_type().is_file() {
        bail!(
            "{}: is {}, not a regular file",
            path.display(),
            kind(md.file_type())
        );
    }
    Ok((f, md.len()))
}

/// Check, without opening it, that `path` names a regular file (a symbolic link is followed):
/// "no such file" when nothing is there, "is a dangling symbolic link" for a link to nothing,
/// and "is a character device, not a regular file" (FIFO, socket, directory, …) for anything
/// else, also behind a link.
pub fn check_regular(path: &Path) -> Result<()> {
    match std::fs::metadata(path) {
        Ok(md) if md.file_type().is_file() => Ok(()),
        Ok(md) => bail!(
            "{}: is {}, not a regular file",
            path.display(),
            kind(md.file_type())
        ),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            if std::fs::symlink_metadata(path).is_ok() {
                bail!("{}: is a dangling symbolic link", path.display())
            }
            bail!("{}: no such file", path.display())
        }
        Err(e) => bail!("{}: cannot read: {e}", path.display()),
    }
}

/// The bytes of `path`, at most `limit.bytes` of them (else an error naming the limit).
pub fn read_bytes(path: &Path, limit: Limit) -> Result<Vec<u8>> {
    let (f, len) = open_regular(path)?;
    let name = path.display().to_string();
    if len > limit.bytes {
        bail!("{name}: {} is more than {limit}", human_bytes(len));
    }
    read_limited(f, &name, limit, len as usize)
}

/// Read at most `limit.bytes` from `r` (one byte more is an error naming the limit).
pub fn read_limited(r: impl Read, name: &str, limit: Limit, hint: usize) -> Result<Vec<u8>> {
    let mut buf = Vec::with_capacity(hint.min(limit.bytes as usize));
    r.take(limit.bytes + 1)
        .read_to_end(&mut buf)
        .with_context(|| format!("{name}: cannot read"))?;
    if buf.len() as u64 > limit.bytes {
        bail!("{name}: larger than {limit}");
    }
    Ok(buf)
}

/// The UTF-8 text of `path`, bounded by `limit`.
pub fn read_text(path: &Path, limit: Limit) -> Result<String> {
    let bytes = read_bytes(path, limit)?;
    String::from_utf8(bytes).map_err(|e| {
        anyhow!(
            "{}: not UTF-8 text (byte {})",
            path.display(),
            e.utf8_error().valid_up_to()
        )
    })
}

/// A JSON file, bounded by `limit`; a parse error names the file, line and column.
pub fn read_json<T: DeserializeOwned>(path: &Path, limit: Limit) -> Result<T> {
    let text = read_text(path, limit)?;
    serde_json::from_str(&text).map_err(|e| anyhow!("{}: invalid JSON: {e}", path.display()))
}

/// A FILE argument: `None` or `-` reads stdin, anything else the file; bounded by `limit`.
/// Returns (text, name for errors: the path or "stdin").
pub fn read_input(file: Option<&Path>, limit: Limit) -> Result<(String, String)> {
    match file {
        Some(p) if p.as_os_str() != "-" => Ok((read_text(p, limit)?, p.display().to_string())),
        _ => {
            let bytes = read_limited(std::io::stdin().lock(), "stdin", limit, 0)?;
            let text = String::from_utf8(bytes).map_err(|_| anyhow!("stdin: not UTF-8 text"))?;
            Ok((text, "stdin".to_string()))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tmp(tag: &str) -> std::path::PathBuf {
        let d = std::env::temp_dir().join(format!("momentlab-input-{tag}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    #[test]
    fn limits_are_named_and_exact() {
        let d = tmp("limit");
        let p = d.join("a.json");
        std::fs::write(&p, "[1,2,3]").unwrap();
        let l = Limit::new(7, "test input");
        assert_eq!(read_json::<Vec<u8>>(&p, l).unwrap(), vec![1, 2, 3]);
        let e = read_text(&p, Limit::new(6, "test input")).unwrap_err();
        let e = format!("{e:#}");
        assert!(
            e.contains("a.json") && e.contains("6 bytes limit for a test input"),
            "{e}"
        );
        std::fs::write(&p, "[1,").unwrap();
        let e = format!("{:#}", read_json::<Vec<u8>>(&p, l).unwrap_err());
        assert!(
            e.contains("a.json: invalid JSON") && e.contains("line 1"),
            "{e}"
        );
        let e = format!("{:#}", read_text(&d.join("nope"), l).unwrap_err());
        assert!(e.ends_with("nope: no such file"), "{e}");
        std::fs::remove_dir_all(&d).unwrap();
    }

    #[test]
    fn non_regular_files_are_refused_without_blocking() {
        let d = tmp("kinds");
        let e = format!("{:#}", read_text(&d, Limit::CONFIG).unwrap_err());
        assert!(e.contains("is a directory, not a regular file"), "{e}");
        let e = format!(
            "{:#}",
            read_text(Path::new("/dev/zero"), Limit::CONFIG).unwrap_err()
        );
        assert!(e.contains("is a character device"), "{e}");
        // A symbolic link to /dev/zero is refused too (its target is what counts).
        let link = d.join("zero.json");
        std::os::unix::fs::symlink("/dev/zero", &link).unwrap();
        let e = format!("{:#}", read_text(&link, Limit::CONFIG).unwrap_err());
        assert!(e.contains("zero.json: is a character device"), "{e}");
        // The same without opening, for the callers that check a path first.
        let exr = d.join("zero.exr");
        std::os::unix::fs::symlink("/dev/zero", &exr).unwrap();
        let e = format!("{:#}", check_regular(&exr).unwrap_err());
        assert!(
            e.ends_with("zero.exr: is a character device, not a regular file"),
            "{e}"
        );
        let e = format!("{:#}", check_regular(&d).unwrap_err());
        assert!(e.ends_with("is a directory, not a regular file"), "{e}");
        let dangling = d.join("gone.exr");
        std::os::unix::fs::symlink(d.join("nowhere"), &dangling).unwrap();
        let e = format!("{:#}", check_regular(&dangling).unwrap_err());
        assert!(e.ends_with("gone.exr: is a dangling symbolic link"), "{e}");
        let e = format!("{:#}", check_regular(&d.join("nope")).unwrap_err());
        assert!(e.ends_with("nope: no such file"), "{e}");
        check_regular(&p_regular(&d)).unwrap();
        // A FIFO with no writer: opening must not block.
        let fifo = d.join("pipe");
        let c = std::ffi::CString::new(fifo.as_os_str().as_encoded_bytes()).unwrap();
        assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0);
        let e = format!("{:#}", read_text(&fifo, Limit::CONFIG).unwrap_err());
        assert!(e.contains("pipe: is a FIFO"), "{e}");
        std::fs::remove_dir_all(&d).unwrap();
    }

    fn p_regular(d: &Path) -> std::path::PathBuf {
        let p = d.join("plain.txt");
        std::fs::write(&p, "x").unwrap();
        p
    }

    #[test]
    fn human_sizes() {
        assert_eq!(human_bytes(1 << 30), "1 GiB");
        assert_eq!(human_bytes(16 << 20), "16 MiB");
        assert_eq!(human_bytes(1000), "1000 bytes");
    }
}
