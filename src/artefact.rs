//! Artefact files: JSON written atomically (parent folders created, temporary file + rename, so
//! a killed run never leaves a torn file) and JSON lines appended and flushed per batch. The one
//! place where the pipeline, the sweep and the commands read and write their JSON.

use anyhow::{Context, Result};
use serde::de::DeserializeOwned;
use serde::Serialize;
use std::fs;
use std::io::Write;
use std::path::Path;

/// Write `value` as pretty JSON (with a final newline) to `path`, atomically.
pub fn write_json<T: Serialize + ?Sized>(path: &Path, value: &T) -> Result<()> {
    write_text(path, &(serde_json::to_string_pretty(value)? + "\n"))
}

/// Write `text` to `path` atomically, creating the parent folders.
pub fn write_text(path: &Path, text: &str) -> Result<()> {
    if let Some(d) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        fs::create_dir_all(d).with_context(|| format!("creating {}", d.display()))?;
    }
    let mut tmp = path.as_os_str().to_owned();
    tmp.push(".tmp");
    let tmp = std::path::PathBuf::from(tmp);
    fs::write(&tmp, text).with_context(|| format!("writing {}", tmp.display()))?;
    fs::rename(&tmp, path).with_context(|| format!("writing {}", path.display()))
}

/// Read a JSON file.
pub fn read_json<T: DeserializeOwned>(path: &Path) -> Result<T> {
    let text = fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
    serde_json::from_str(&text).with_context(|| format!("{}: invalid", path.display()))
}

/// Read a JSON-lines file. A last line without '\n' is a torn write: it is ignored and, with
/// `repair`, cut off the file. A missing file reads as empty.
pub fn read_jsonl<T: DeserializeOwned>(path: &Path, repair: bool) -> Result<Vec<T>> {
    let text = match fs::read(path) {
        Ok(t) => t,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(Vec::new()),
        Err(e) => return Err(e).with_context(|| format!("reading {}", path.display())),
    };
    let keep = text.iter().rposition(|&c| c == b'\n').map_or(0, |p| p + 1);
    if keep < text.len() && repair {
        let f = fs::OpenOptions::new()
            .write(true)
            .open(path)
            .with_context(|| format!("repairing {}", path.display()))?;
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

/// Append rows (one JSON line each) and flush.
pub fn append_jsonl<T: Serialize>(path: &Path, rows: &[T]) -> Result<()> {
    if rows.is_empty() {
        return Ok(());
    }
    let mut buf = Vec::new();
    for r in rows {
        serde_json::to_writer(&mut buf, r)?;
        buf.push(b'\n');
    }
    let mut f = fs::OpenOptions::new()
        .create(true)
        .append(true)
        .open(path)
        .with_context(|| format!("opening {}", path.display()))?;
    f.write_all(&buf)
        .and_then(|_| f.flush())
        .with_context(|| format!("writing {}", path.display()))
}

#[cfg(test)]
mod tests {
    use super::*;

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
