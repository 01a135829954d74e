//! The one output writer. Every file a command writes goes through an [`OutDir`]:
//!
//! * confined: names are relative paths of plain components (no `..`, no absolute paths, no
//!   control characters); sub-folders are created inside the folder and a symbolic link on
//!   the way is refused, never followed out; the file itself is replaced by `rename`, which
//!   replaces a link rather than writing through it;
//! * refuse-to-overwrite unless `force` (the `--force` flag), checked up front by
//!   [`OutDir::reserve`] and again, race-free, when the file is put in place (`link(2)` fails on
//!   an existing name);
//! * atomic: temporary file in the same folder, fsync, then rename (or link) into place, so a
//!   killed run never leaves a torn file;
//! * one name, one file per run: a name written (or reserved) twice is an error before the
//!   second write, so two inputs with one name are never silently collapsed into one file;
//! * an advisory lock ([`OutDir::lock`]) so that a second writer on the same results folder gets
//!   a one-line error instead of interleaving its rows.

use anyhow::{anyhow, bail, Context, Result};
use serde::Serialize;
use std::collections::BTreeSet;
use std::fs::{self, File};
use std::io::{Read, Seek, Write};
use std::os::unix::fs::{MetadataExt, OpenOptionsExt};
use std::path::{Component, Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Mutex;

/// An output folder: the only way commands write files (see the module docs).
#[derive(Debug)]
pub struct OutDir {
    root: PathBuf,
    force: bool,
    names: Mutex<Names>,
    lock: Mutex<Option<DirLock>>,
}

#[derive(Debug, Default)]
struct Names {
    /// Checked by `reserve` (may be written once).
    reserved: BTreeSet<PathBuf>,
    /// Written in this run.
    written: BTreeSet<PathBuf>,
}

impl OutDir {
    /// The folder `root` (created on the first write or [`lock`](Self::lock); nothing is created
    /// here). `force`: existing files may be replaced. Error if `root` exists and is not a
    /// folder.
    pub fn new(root: impl Into<PathBuf>, force: bool) -> Result<OutDir> {
        let root = root.into();
        if root.as_os_str().is_empty() {
            bail!("empty output folder name");
        }
        match fs::metadata(&root) {
            Ok(m) if !m.is_dir() => bail!("{}: exists and is not a folder", root.display()),
            _ => {}
        }
        Ok(OutDir {
            root,
            force,
            names: Mutex::new(Names::default()),
            lock: Mutex::new(None),
        })
    }

    /// The folder of the single output file `path` and the file's name in it (for commands
    /// whose `--out` is a file): `OutDir::for_file(p, force)?.0.write(&name, …)`.
    pub fn for_file(path: &Path, force: bool) -> Result<(OutDir, String)> {
        let name = match path.file_name() {
            Some(n) if !path.as_os_str().to_string_lossy().ends_with('/') => {
                n.to_string_lossy().into_owned()
            }
            _ => bail!("{}: not a file name", path.display()),
        };
        let dir = match path.parent() {
            Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
            _ => PathBuf::from("."),
        };
        if fs::symlink_metadata(path).is_ok_and(|m| m.is_dir()) {
            bail!("{}: is a folder, not a file", path.display());
        }
        Ok((OutDir::new(dir, force)?, name))
    }

    /// The folder.
    pub fn root(&self) -> &Path {
        &self.root
    }

    /// Whether existing files may be replaced.
    pub fn force(&self) -> bool {
        self.force
    }

    /// The path of output `name` inside the folder, after checking the name (relative, plain
    /// components only). Does not touch the file system.
    pub fn path(&self, name: &str) -> Result<PathBuf> {
        Ok(self.root.join(check_name(name)?))
    }

    /// Whether output `name` exists already (as anything, a dangling link included).
    pub fn exists(&self, name: &str) -> Result<bool> {
        Ok(fs::symlink_metadata(self.path(name)?).is_ok())
    }

    /// Check, before any expensive work, that the outputs `names` can be written: valid names,
    /// no name twice (in `names` or among names reserved or written before), and — unless
    /// `force` — none of them exists already. Reserved names may then be written once each.
    pub fn reserve<S: AsRef<str>>(&self, names: impl IntoIterator<Item = S>) -> Result<()> {
        let mut st = self.names.lock().unwrap();
        let mut new = BTreeSet::new();
        for n in names {
            let n = n.as_ref();
            let rel = check_name(n)?;
            if st.reserved.contains(&rel) || st.written.contains(&rel) || !new.insert(rel.clone()) {
                bail!("two outputs named '{n}' in one run (the second would replace the first)");
            }
            self.check_target(&rel)?;
        }
        st.reserved.extend(new);
        Ok(())
    }

    /// Refuse an existing target (unless forced) and any symbolic link on the way to it.
    fn check_target(&self, rel: &Path) -> Result<()> {
        let path = self.root.join(rel);
        self.check_parents(rel)?;
        match fs::symlink_metadata(&path) {
            Ok(m) if m.is_dir() => bail!("{}: is a folder", path.display()),
            Ok(_) if !self.force => {
                bail!(
                    "{} exists already (pass --force to replace it)",
                    path.display()
                )
            }
            _ => Ok(()),
        }
    }

    /// Every existing folder between the root and `rel` is a real folder, not a link.
    fn check_parents(&self, rel: &Path) -> Result<()> {
        let mut at = self.root.clone();
        let comps: Vec<_> = rel.components().collect();
        for c in &comps[..comps.len().saturating_sub(1)] {
            at.push(c);
            match fs::symlink_metadata(&at) {
                Ok(m) if m.file_type().is_symlink() => bail!(
                    "{}: is a symbolic link; refusing to follow it out of {}",
                    at.display(),
                    self.root.display()
                ),
                Ok(m) if !m.is_dir() => bail!("{}: exists and is not a folder", at.display()),
                _ => {}
            }
        }
        Ok(())
    }

    /// Create the folder `rel` (and the root) inside the output folder, refusing links.
    pub fn create_dir(&self, rel: &str) -> Result<PathBuf> {
        let rel = if rel.is_empty() || rel == "." {
            PathBuf::new()
        } else {
            check_name(rel)?
        };
        self.make_dirs(&rel.join("x"))?;
        Ok(self.root.join(rel))
    }

    /// Create the root and the folders leading to file `rel`, each a real folder (no links).
    fn make_dirs(&self, rel: &Path) -> Result<PathBuf> {
        fs::create_dir_all(&self.root)
            .with_context(|| format!("creating {}", self.root.display()))?;
        let mut at = self.root.clone();
        let comps: Vec<_> = rel.components().collect();
        for c in &comps[..comps.len().saturating_sub(1)] {
            at.push(c);
            match fs::create_dir(&at) {
                Ok(()) => {}
                Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => {
                    let m = fs::symlink_metadata(&at)
                        .with_context(|| format!("creating {}", at.display()))?;
                    if m.file_type().is_symlink() {
                        bail!(
                            "{}: is a symbolic link; refusing to follow it out of {}",
                            at.display(),
                            self.root.display()
                        );
                    }
                    if !m.is_dir() {
                        bail!("{}: exists and is not a folder", at.display());
                    }
                }
                Err(e) => return Err(e).with_context(|| format!("creating {}", at.display())),
            }
        }
        Ok(at)
    }

    /// Mark `rel` as written in this run; error if it was already.
    fn claim(&self, name: &str, rel: &Path) -> Result<()> {
        let mut st = self.names.lock().unwrap();
        if !st.written.insert(rel.to_path_buf()) {
            bail!("two outputs named '{name}' in one run (the second would replace the first)");
        }
        Ok(())
    }

    /// Write output `name` through `fill`, which receives the temporary file (Write + Seek);
    /// then fsync and put it in place atomically. Returns the final path.
    pub fn write_with(
        &self,
        name: &str,
        fill: impl FnOnce(&mut File) -> Result<()>,
    ) -> Result<PathBuf> {
        let rel = check_name(name)?;
        self.claim(name, &rel)?;
        self.check_target(&rel)?;
        let dir = self.make_dirs(&rel)?;
        let file = rel.file_name().unwrap().to_string_lossy().into_owned();
        put_atomically(&dir, &file, self.force, fill)
    }

    /// Write `bytes` as output `name`.
    pub fn write(&self, name: &str, bytes: &[u8]) -> Result<PathBuf> {
        self.write_with(name, |f| Ok(f.write_all(bytes)?))
    }

    /// Write `text` as output `name`.
    pub fn write_text(&self, name: &str, text: &str) -> Result<PathBuf> {
        self.write(name, text.as_bytes())
    }

    /// Write `value` as pretty JSON (with a final newline) as output `name`.
    pub fn write_json<T: Serialize + ?Sized>(&self, name: &str, value: &T) -> Result<PathBuf> {
        self.write_text(name, &(serde_json::to_string_pretty(value)? + "\n"))
    }

    /// Append rows (one JSON line each) to output `name` and flush: the one file kind that
    /// grows across runs (resumable sweeps). Never follows a link; take [`lock`](Self::lock)
    /// first so that no other run appends at the same time.
    pub fn append_jsonl<T: Serialize>(&self, name: &str, rows: &[T]) -> Result<PathBuf> {
        let rel = check_name(name)?;
        self.check_parents(&rel)?;
        self.make_dirs(&rel)?;
        let path = self.root.join(&rel);
        if !rows.is_empty() {
            append_jsonl_nofollow(&path, rows)?;
        }
        Ok(path)
    }

    /// Remove output `name` if it exists (a file of this run, such as a marker); a link is
    /// removed, never followed.
    pub fn remove(&self, name: &str) -> Result<()> {
        let rel = check_name(name)?;
        self.check_parents(&rel)?;
        let path = self.root.join(&rel);
        match fs::remove_file(&path) {
            Err(e) if e.kind() != std::io::ErrorKind::NotFound => {
                Err(e).with_context(|| format!("removing {}", path.display()))
            }
            _ => Ok(()),
        }
    }

    /// Remove output `name` if it exists: a file, a link (the link itself, never its target) or
    /// a folder with everything in it (links inside are removed, not followed). A link on the
    /// way to `name` is refused.
    pub fn remove_all(&self, name: &str) -> Result<()> {
        let rel = check_name(name)?;
        self.check_parents(&rel)?;
        let path = self.root.join(&rel);
        let removed = match fs::symlink_metadata(&path) {
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(()),
            Err(e) => Err(e),
            // std's remove_dir_all removes links inside the folder without following them.
            Ok(m) if m.is_dir() => fs::remove_dir_all(&path),
            Ok(_) => fs::remove_file(&path),
        };
        removed.with_context(|| format!("removing {}", path.display()))
    }

    /// The first file (or link) under the folder in name order, skipping the lock and `skip`;
    /// None when the folder is missing or holds no file. For commands that write many files into
    /// one folder and refuse a folder holding outputs already.
    pub fn first_file(&self, skip: &[&str]) -> Result<Option<PathBuf>> {
        fn walk(d: &Path, skip: &[&str], top: bool) -> Result<Option<PathBuf>> {
            let mut entries: Vec<_> = match fs::read_dir(d) {
                Ok(rd) => rd
                    .collect::<std::io::Result<Vec<_>>>()
                    .with_context(|| format!("reading {}", d.display()))?,
                Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
                Err(e) => return Err(e).with_context(|| format!("reading {}", d.display())),
            };
            entries.sort_by_key(|e| e.file_name());
            for e in entries {
                let name = e.file_name();
                if top && (name == LOCK_FILE || skip.iter().any(|s| name == *s)) {
                    continue;
                }
                let t = e
                    .file_type()
                    .with_context(|| format!("reading {}", e.path().display()))?;
                if t.is_dir() {
                    if let Some(f) = walk(&e.path(), skip, false)? {
                        return Ok(Some(f));
                    }
                } else {
                    return Ok(Some(e.path()));
                }
            }
            Ok(None)
        }
        walk(&self.root, skip, true)
    }

    /// Take the advisory lock of the folder (created if needed), held until this `OutDir` is
    /// dropped. A second writer — another process, or another `OutDir` on the same folder — gets
    /// a one-line error naming the holder. Idempotent.
    pub fn lock(&self) -> Result<()> {
        let mut l = self.lock.lock().unwrap();
        if l.is_none() {
            fs::create_dir_all(&self.root)
                .with_context(|| format!("creating {}", self.root.display()))?;
            *l = Some(DirLock::acquire(&self.root)?);
        }
        Ok(())
    }
}

/// A name made safe as one path component: `/`, `\` and control characters become `_`, a
/// leading `.` gets a `_` in front (so `..` and hidden names cannot appear), empty becomes `_`,
/// and it is cut to 200 bytes. Distinct inputs may map to one name: the writer's duplicate
/// check then reports it.
pub fn safe_name(s: &str) -> String {
    let mut out: String = s
        .chars()
        .map(|c| {
            if c == '/' || c == '\\' || c.is_control() {
                '_'
            } else {
                c
            }
        })
        .collect();
    if out.starts_with('.') {
        out.insert(0, '_');
    }
    if out.is_empty() {
        out.push('_');
    }
    if out.len() > 200 {
        let mut cut = 200;
        while !out.is_char_boundary(cut) {
            cut -= 1;
        }
        out.truncate(cut);
    }
    out
}

/// A relative path of plain components: no root, no `.`/`..`, no empty, control-character or
/// backslash component, each at most 255 bytes.
pub fn check_name(name: &str) -> Result<PathBuf> {
    let bad = |why: &str| anyhow!("output name '{}' {why}", name.escape_debug());
    if name.is_empty() {
        return Err(bad("is empty"));
    }
    let p = Path::new(name);
    if p.is_absolute() {
        return Err(bad("is an absolute path; outputs stay inside their folder"));
    }
    let mut rel = PathBuf::new();
    for c in name.split('/') {
        match Path::new(c).components().next() {
            _ if c.is_empty() => return Err(bad("has an empty component")),
            Some(Component::Normal(_)) if c != "." && c != ".." => {}
            _ => return Err(bad("leaves its folder ('.' or '..')")),
        }
        if c.chars().any(|ch| ch.is_control() || ch == '\\') {
            return Err(bad("contains a control character or a backslash"));
        }
        if c.len() > 255 {
            return Err(bad("has a component longer than 255 bytes"));
        }
        rel.push(c);
    }
    Ok(rel)
}

static TMP_COUNTER: AtomicU64 = AtomicU64::new(0);

/// Write `file` in `dir` atomically: a new temporary file in `dir` filled by `fill`, fsynced,
/// then renamed over the target (`replace`) or linked to it, which fails if the name exists.
fn put_atomically(
    dir: &Path,
    file: &str,
    replace: bool,
    fill: impl FnOnce(&mut File) -> Result<()>,
) -> Result<PathBuf> {
    let _writing = super::interrupt::begin_write();
    let target = dir.join(file);
    let (tmp, mut f) = loop {
        let n = TMP_COUNTER.fetch_add(1, Ordering::Relaxed);
        // At most 64 bytes of the name: the temporary name stays within NAME_MAX (255 bytes)
        // for every output name the writer accepts.
        let tmp = dir.join(format!(
            "{}{}.{n}.tmp",
            tmp_prefix(file),
            std::process::id()
        ));
        match fs::OpenOptions::new()
            .write(true)
            .read(true)
            .create_new(true)
            .custom_flags(libc::O_NOFOLLOW)
            .open(&tmp)
        {
            Ok(f) => break (tmp, f),
            Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => continue,
            Err(e) => return Err(e).with_context(|| format!("writing {}", target.display())),
        }
    };
    let result = (|| -> Result<()> {
        fill(&mut f)?;
        f.flush()?;
        f.sync_all()?;
        drop(f);
        if replace {
            fs::rename(&tmp, &target)?;
        } else {
            match fs::hard_link(&tmp, &target) {
                Ok(()) => fs::remove_file(&tmp)?,
                Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => {
                    bail!(
                        "{} exists already (pass --force to replace it)",
                        target.display()
                    )
                }
                // A file system without hard links: check, then rename.
                Err(_) => {
                    if fs::symlink_metadata(&target).is_ok() {
                        bail!(
                            "{} exists already (pass --force to replace it)",
                            target.display()
                        )
                    }
                    fs::rename(&tmp, &target)?;
                }
            }
        }
        // Make the new name durable too (best effort: not every file system allows it).
        if let Ok(d) = File::open(dir) {
            let _ = d.sync_all();
        }
        Ok(())
    })();
    match result {
        Ok(()) => {
            remove_stale_tmps(dir, file);
            Ok(target)
        }
        Err(e) => {
            let _ = fs::remove_file(&tmp);
            if e.to_string().contains("exists already") {
                Err(e)
            } else {
                Err(e).with_context(|| format!("writing {}", target.display()))
            }
        }
    }
}

/// Append rows as JSON lines to `path` (created if missing) without following a link.
pub(crate) fn append_jsonl_nofollow<T: Serialize>(path: &Path, rows: &[T]) -> Result<()> {
    let _writing = super::interrupt::begin_write();
    let mut buf = Vec::new();
    for r in rows {
        serde_json::to_writer(&mut buf, r)?;
        buf.push(b'\n');
    }
    let mut f = fs::OpenOptions::new()
        .create(true)
        .append(true)
        .custom_flags(libc::O_NOFOLLOW)
        .open(path)
        .map_err(|e| {
            if e.raw_os_error() == Some(libc::ELOOP) {
                anyhow!(
                    "{}: is a symbolic link; refusing to follow it",
                    path.display()
                )
            } else {
                anyhow!("opening {}: {e}", path.display())
            }
        })?;
    f.write_all(&buf)
        .and_then(|_| f.flush())
        .with_context(|| format!("writing {}", path.display()))
}

/// Name of the advisory lock file inside a locked folder.
pub const LOCK_FILE: &str = ".momentlab.lock";

/// An advisory lock on a folder: `flock` on `<dir>/.momentlab.lock` (released by the kernel if
/// the process dies; the file, holding "pid N on HOST", is removed on drop).
/// Re-entrant within one process: a folder this process holds already is not locked twice (a
/// command that locks its results folder early, then runs the sweep that locks it again).
#[derive(Debug)]
pub struct DirLock {
    path: PathBuf,
    /// None: nested in a lock this process holds already.
    file: Option<File>,
    key: PathBuf,
}

/// Folders this process holds the lock of (canonical paths).
static HELD: Mutex<BTreeSet<PathBuf>> = Mutex::new(BTreeSet::new());

impl DirLock {
    /// Take the lock of `dir` or fail with a one-line error naming the holder.
    pub fn acquire(dir: &Path) -> Result<DirLock> {
        let path = dir.join(LOCK_FILE);
        let key = dir
            .canonicalize()
            .with_context(|| format!("locking {}", dir.display()))?;
        if HELD.lock().unwrap().contains(&key) {
            return Ok(DirLock {
                path,
                file: None,
                key,
            });
        }
        let lock = Self::acquire_file(dir, path, key.clone())?;
        HELD.lock().unwrap().insert(key);
        Ok(lock)
    }

    fn acquire_file(dir: &Path, path: PathBuf, key: PathBuf) -> Result<DirLock> {
        for _ in 0..100 {
            let mut f = fs::OpenOptions::new()
                .read(true)
                .write(true)
                .create(true)
                .truncate(false)
                .custom_flags(libc::O_NOFOLLOW)
                .open(&path)
                .with_context(|| {
                    format!("locking {}: opening {}", dir.display(), path.display())
                })?;
            match f.try_lock() {
                Ok(()) => {}
                Err(std::fs::TryLockError::WouldBlock) => {
                    let mut holder = String::new();
                    let _ = (&f).take(200).read_to_string(&mut holder);
                    let holder = holder.trim();
                    bail!(
                        "{} is in use by another momentlab run ({}); wait for it to finish or \
                         write elsewhere",
                        dir.display(),
                        if holder.is_empty() {
                            "starting"
                        } else {
                            holder
                        }
                    );
                }
                // No locking on this file system: go on unlocked rather than not at all, and
                // say so.
                Err(std::fs::TryLockError::Error(e))
                    if e.kind() == std::io::ErrorKind::Unsupported =>
                {
                    eprintln!(
                        "warning: {}: this file system cannot lock files; a second run writing \
                         this folder at the same time would not be refused",
                        dir.display()
                    );
                    return Ok(DirLock {
                        path,
                        file: Some(f),
                        key,
                    });
                }
                Err(std::fs::TryLockError::Error(e)) => {
                    return Err(e).with_context(|| format!("locking {}", dir.display()))
                }
            }
            // The file may have been removed by the previous holder between our open and our
            // lock: then we hold a lock on an unlinked file, and must try again.
            let mine = f.metadata()?;
            match fs::symlink_metadata(&path) {
                Ok(m) if m.ino() == mine.ino() && m.dev() == mine.dev() => {
                    f.set_len(0)?;
                    f.seek(std::io::SeekFrom::Start(0))?;
                    writeln!(f, "pid {} on {}", std::process::id(), host())?;
                    let _ = f.flush();
                    return Ok(DirLock {
                        path,
                        file: Some(f),
                        key,
                    });
                }
                _ => continue,
            }
        }
        bail!("locking {}: the lock file keeps changing", dir.display())
    }
}

impl Drop for DirLock {
    fn drop(&mut self) {
        if let Some(f) = self.file.take() {
            // Remove while still holding the lock: a waiter that opened the old file sees it
            // unlinked and retries (see `acquire`).
            let _ = fs::remove_file(&self.path);
            HELD.lock().unwrap().remove(&self.key);
            drop(f);
        }
    }
}

/// The start of the temporary names of output `file`: `.<file>.<host>.` with at most 64 bytes
/// of the name and 32 of the host, so that a temporary name `<prefix><pid>.<n>.tmp` stays
/// within NAME_MAX (255 bytes) for every name the writer accepts.
fn tmp_prefix(file: &str) -> String {
    let cut = |s: &str, max: usize| {
        let mut c = s.len().min(max);
        while !s.is_char_boundary(c) {
            c -= 1;
        }
        s[..c].to_string()
    };
    format!(".{}.{}.", cut(file, 64), cut(&safe_name(&host()), 32))
}

/// Remove the temporary files of output `file` in `dir` that a process of this host left when
/// it was killed mid-write (its pid no longer runs); called once `file` is written.
fn remove_stale_tmps(dir: &Path, file: &str) {
    let prefix = tmp_prefix(file);
    let Ok(entries) = fs::read_dir(dir) else {
        return;
    };
    for e in entries.flatten() {
        let name = e.file_name();
        let Some(rest) = name
            .to_str()
            .and_then(|n| n.strip_prefix(prefix.as_str()))
            .and_then(|r| r.strip_suffix(".tmp"))
        else {
            continue;
        };
        let Some((pid, n)) = rest.split_once('.') else {
            continue;
        };
        let Ok(pid) = pid.parse::<i32>() else {
            continue;
        };
        if n.is_empty()
            || !n.bytes().all(|b| b.is_ascii_digit())
            || pid as u32 == std::process::id()
        {
            continue;
        }
        // SAFETY: signal 0 only asks whether the process exists.
        let gone = unsafe { libc::kill(pid, 0) } == -1
            && std::io::Error::last_os_error().raw_os_error() == Some(libc::ESRCH);
        if gone {
            let _ = fs::remove_file(e.path());
        }
    }
}

fn host() -> String {
    fs::read_to_string("/proc/sys/kernel/hostname")
        .map(|s| s.trim().to_string())
        .unwrap_or_else(|_| "this host".to_string())
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    fn tmp(tag: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("momentlab-out-{tag}-{}", std::process::id()));
        let _ = fs::remove_dir_all(&d);
        d
    }

    /// A temporary file of a killed writer of this host is removed when its output is
    /// written; those of running processes (this one, pid 1) stay.
    #[test]
    fn temporary_files_of_killed_writers_are_removed() {
        let d = tmp("stale");
        fs::create_dir_all(&d).unwrap();
        let mut child = std::process::Command::new("true").spawn().unwrap();
        let dead = child.id();
        child.wait().unwrap();
        let name = |pid: u32| format!("{}{pid}.0.tmp", tmp_prefix("x.json"));
        for pid in [dead, 1, std::process::id()] {
            fs::write(d.join(name(pid)), "").unwrap();
        }
        fs::write(d.join(".y.json.other.7.0.tmp"), "").unwrap();
        let out = OutDir::new(&d, false).unwrap();
        out.write_text("x.json", "{}").unwrap();
        let mut want = vec![
            name(1),
            name(std::process::id()),
            ".y.json.other.7.0.tmp".into(),
            "x.json".into(),
        ];
        want.sort();
        assert_eq!(listing(&d), want);
        fs::remove_dir_all(&d).unwrap();
    }

    /// The names in folder `d`, sorted (test helper of the modules that write folders).
    pub(crate) fn listing(d: &Path) -> Vec<String> {
        let mut v: Vec<String> = fs::read_dir(d)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        v.sort();
        v
    }

    #[test]
    fn names_stay_inside() {
        for bad in [
            "",
            "/etc/passwd",
            "..",
            "../x",
            "a/../../x",
            "a//b",
            "./a",
            "a/.",
            "a\nb",
            "a\\b",
        ] {
            assert!(check_name(bad).is_err(), "{bad:?} accepted");
        }
        for good in ["a", "a.json", "figs/a.svg", "..a", "a..", "θ-table.md"] {
            assert!(check_name(good).is_ok(), "{good:?} refused");
        }
        assert_eq!(safe_name("../../evil"), "_.._.._evil");
        assert_eq!(safe_name("a/b\nc"), "a_b_c");
        assert_eq!(safe_name(""), "_");
        assert!(check_name(&safe_name(&"é".repeat(300))).is_ok());
        for s in ["..", ".", "/", "a\\..\\b", "\u{0}"] {
            assert!(check_name(&safe_name(s)).is_ok(), "{s:?}");
        }
    }

    #[test]
    fn refuses_overwrite_and_duplicates_unless_forced() {
        let d = tmp("force");
        let out = OutDir::new(&d, false).unwrap();
        assert!(!d.exists(), "new creates nothing");
        out.reserve(["a.json", "sub/b.txt"]).unwrap();
        out.write_json("a.json", &[1, 2]).unwrap();
        out.write_text("sub/b.txt", "hi").unwrap();
        let e = out.write_text("a.json", "x").unwrap_err().to_string();
        assert!(e.contains("two outputs named 'a.json'"), "{e}");
        assert!(out.reserve(["c", "c"]).is_err());
        // A second run without force: refused up front and at write time; file untouched.
        let again = OutDir::new(&d, false).unwrap();
        let e = again.reserve(["a.json"]).unwrap_err().to_string();
        assert!(e.contains("exists already") && e.contains("--force"), "{e}");
        let e = format!("{:#}", again.write_text("a.json", "x").unwrap_err());
        assert!(e.contains("exists already"), "{e}");
        assert_eq!(
            fs::read_to_string(d.join("a.json")).unwrap(),
            "[\n  1,\n  2\n]\n"
        );
        // With force: replaced.
        let forced = OutDir::new(&d, true).unwrap();
        forced.reserve(["a.json"]).unwrap();
        forced.write_text("a.json", "x").unwrap();
        assert_eq!(fs::read_to_string(d.join("a.json")).unwrap(), "x");
        assert_eq!(listing(&d), vec!["a.json", "sub"], "temporary files left");
        fs::remove_dir_all(&d).unwrap();
    }

    #[test]
    fn links_are_never_followed_out() {
        let d = tmp("links");
        let outside = tmp("links-outside");
        fs::create_dir_all(&d).unwrap();
        fs::create_dir_all(&outside).unwrap();
        // A dangling link as the output file: refused without force, replaced (not followed)
        // with force.
        std::os::unix::fs::symlink(outside.join("victim"), d.join("a.txt")).unwrap();
        let out = OutDir::new(&d, false).unwrap();
        assert!(out.write_text("a.txt", "x").is_err());
        let forced = OutDir::new(&d, true).unwrap();
        forced.write_text("a.txt", "x").unwrap();
        assert!(!outside.join("victim").exists());
        assert!(!fs::symlink_metadata(d.join("a.txt"))
            .unwrap()
            .file_type()
            .is_symlink());
        // A link as a sub-folder: refused, with or without force.
        std::os::unix::fs::symlink(&outside, d.join("sub")).unwrap();
        let e = format!("{:#}", forced.write_text("sub/b.txt", "x").unwrap_err());
        assert!(e.contains("symbolic link"), "{e}");
        assert!(forced.reserve(["sub/c.txt"]).is_err());
        // Appending never follows a link either.
        std::os::unix::fs::symlink(outside.join("rows"), d.join("r.jsonl")).unwrap();
        assert!(forced.append_jsonl("r.jsonl", &[1]).is_err());
        assert!(
            listing(&outside).is_empty(),
            "written outside: {:?}",
            listing(&outside)
        );
        fs::remove_dir_all(&d).unwrap();
        fs::remove_dir_all(&outside).unwrap();
    }

    #[test]
    fn remove_all_removes_links_never_their_targets() {
        let d = tmp("remove");
        let outside = tmp("remove-outside");
        fs::create_dir_all(d.join("sub/deep")).unwrap();
        fs::create_dir_all(outside.join("kept")).unwrap();
        fs::write(outside.join("kept/file"), "x").unwrap();
        fs::write(d.join("sub/deep/f"), "x").unwrap();
        std::os::unix::fs::symlink(&outside, d.join("sub/deep/link")).unwrap();
        std::os::unix::fs::symlink(&outside, d.join("top-link")).unwrap();
        fs::write(d.join("other"), "x").unwrap();
        let out = OutDir::new(&d, false).unwrap();
        out.remove_all("sub").unwrap();
        out.remove_all("top-link").unwrap();
        out.remove_all("missing").unwrap();
        assert_eq!(listing(&d), vec!["other"]);
        assert_eq!(fs::read_to_string(outside.join("kept/file")).unwrap(), "x");
        // A link on the way is refused, not followed.
        std::os::unix::fs::symlink(&outside, d.join("via")).unwrap();
        let e = format!("{:#}", out.remove_all("via/kept").unwrap_err());
        assert!(e.contains("symbolic link"), "{e}");
        assert!(outside.join("kept/file").exists());
        assert!(out.remove_all("../x").is_err());
        fs::remove_dir_all(&d).unwrap();
        fs::remove_dir_all(&outside).unwrap();
    }

    #[test]
    fn lock_nests_within_a_process_and_is_released_by_the_outer_holder() {
        let d = tmp("lock");
        let a = OutDir::new(&d, false).unwrap();
        a.lock().unwrap();
        a.lock().unwrap();
        // Within one process the lock nests (the sweep takes it again under search's lock);
        // the nested holder leaves the lock file to the outer one. Another process is refused:
        // tests/project/bad_input/shards.rs starts two writers on one results folder.
        let b = OutDir::new(&d, false).unwrap();
        b.lock().unwrap();
        drop(b);
        assert!(d.join(LOCK_FILE).exists());
        drop(a);
        assert!(!d.join(LOCK_FILE).exists());
        let c = OutDir::new(&d, false).unwrap();
        c.lock().unwrap();
        assert!(d.join(LOCK_FILE).exists());
        drop(c);
        fs::remove_dir_all(&d).unwrap();
    }

    #[test]
    fn single_files_and_failed_fills() {
        let d = tmp("file");
        fs::create_dir_all(&d).unwrap();
        let (out, name) = OutDir::for_file(&d.join("t.json"), false).unwrap();
        assert_eq!(name, "t.json");
        let e = out.write_with(&name, |_| bail!("boom")).unwrap_err();
        assert!(format!("{e:#}").contains("boom"));
        assert!(listing(&d).is_empty(), "a failed fill leaves nothing");
        assert!(OutDir::for_file(&d, false).is_err());
        let f = d.join("plain");
        fs::write(&f, "").unwrap();
        assert!(OutDir::new(&f, false).is_err());
        fs::remove_dir_all(&d).unwrap();
    }

    /// Calls that open, create, replace, fill, cut or remove a file or folder directly,
    /// bypassing [`OutDir`], and that read a file bypassing the bounded reader.
    const DIRECT_WRITES: [&str; 17] = [
        "File::create",
        "fs::write",
        "OpenOptions",
        "fs::copy",
        "fs::rename",
        "hard_link",
        "SVGBackend::new",
        "BitMapBackend",
        "write_to_file",
        "save_buffer",
        "create_dir_all",
        "remove_file",
        "remove_dir",
        ".set_len(",
        "fs::read(",
        "read_to_string(",
        "File::open",
    ];

    /// (line number, call) of every direct write in `code` before its `#[cfg(test)]` module
    /// (test fixtures may write files directly).
    fn direct_writes(code: &str) -> Vec<(usize, &'static str)> {
        let body = code.split("#[cfg(test)]\nmod tests").next().unwrap_or("");
        let mut hits = Vec::new();
        for (i, line) in body.lines().enumerate() {
            let code_part = line.split("//").next().unwrap_or("");
            for call in DIRECT_WRITES {
                if code_part.contains(call) {
                    hits.push((i + 1, call));
                }
            }
        }
        hits
    }

    #[test]
    fn only_the_writer_opens_files_for_writing() {
        // The scanner finds a planted write, and ignores comments and test modules.
        let planted = "fn f() {\n    // fs::write in a comment\n    let root = SVGBackend::new(p, (1, 1));\n}\n#[cfg(test)]\nmod tests {\n    fn t() { std::fs::write(\"x\", \"\").unwrap(); }\n}\n";
        assert_eq!(direct_writes(planted), vec![(3, "SVGBackend::new")]);
        let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
        let mut todo = vec![src.clone()];
        let mut found = Vec::new();
        let mut files = 0;
        while let Some(d) = todo.pop() {
            for e in fs::read_dir(&d).unwrap() {
                let p = e.unwrap().path();
                let rel = p.strip_prefix(&src).unwrap().to_path_buf();
                if rel.starts_with("artefact") || rel == Path::new("artefact.rs") {
                    continue;
                }
                if p.is_dir() {
                    todo.push(p);
                } else if p.extension().is_some_and(|x| x == "rs") {
                    files += 1;
                    let code = fs::read_to_string(&p).unwrap();
                    for (line, call) in direct_writes(&code) {
                        found.push(format!("src/{}:{line}: {call}", rel.display()));
                    }
                }
            }
        }
        assert!(files > 50, "scanned only {files} files");
        assert!(
            found.is_empty(),
            "files written past artefact::OutDir or read past artefact::input:\n{}",
            found.join("\n")
        );
    }
}
