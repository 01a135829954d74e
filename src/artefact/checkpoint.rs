//! Checkpoints of long commands: a keyed store of completed units of work inside the output
//! folder, so that the same command after a kill continues where the killed run stopped and
//! ends with the results of an uninterrupted run.
//!
//! Layout, under the output folder `<out>`:
//!
//! * `checkpoint/<name>/run.json`: the parameters the units depend on (and the build);
//! * `checkpoint/<name>/units/<key>.json`: one completed unit each, `{"key": …, "value": …}`.
//!
//! Every file is put in place atomically by the one writer ([`OutDir`]), so a kill leaves a unit
//! whole or absent, and an interrupt ([`super::interrupt`]) stops the process between two unit
//! writes, never inside one. Lifecycle:
//!
//! 1. [`Checkpoint::open`] reads what is there and writes nothing. Same parameters: the run
//!    resumes ([`Checkpoint::resuming`]); the command may then replace the outputs the interrupted
//!    run wrote (they are its own). Other parameters: an error naming the differing fields,
//!    unless `discard` (the command's `--force`), which starts over.
//! 2. [`Checkpoint::start`], after the outputs are checked and before the work: takes the
//!    folder's lock, clears a discarded or stale state and writes `run.json`.
//! 3. [`Checkpoint::get`] returns a unit completed by an earlier run (counted as reused);
//!    [`Checkpoint::put`] records a unit as soon as it is complete (from any thread).
//! 4. [`Checkpoint::finish`], after the last output is written: removes the checkpoint.
//!
//! Unit values are JSON: a float that may be non-finite is stored by the caller as its bits
//! (`f64::to_bits`), since JSON has no NaN or infinity.

use super::{read_json, OutDir};
use anyhow::{bail, Context, Result};
use serde::de::DeserializeOwned;
use serde::Serialize;
use serde_json::{json, Value};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;

/// The folder of all checkpoints inside an output folder.
pub const FOLDER: &str = "checkpoint";

/// Format of `run.json` and the unit files.
const FORMAT: u32 = 1;

/// The checkpoint of one command in one output folder (see the module docs).
#[derive(Debug)]
pub struct Checkpoint {
    /// The output folder's writer (replacing: the checkpoint's files are its own).
    od: OutDir,
    /// `checkpoint/<name>`, relative to the output folder.
    rel: String,
    /// What `run.json` holds.
    run: Value,
    /// Units completed by earlier runs.
    units: BTreeMap<String, Value>,
    /// A checkpoint of these parameters was found.
    resuming: bool,
    /// Something is there that [`start`](Self::start) clears first.
    clear: bool,
    started: Mutex<bool>,
    /// The lock of the checkpoint's folder, held from [`start`](Self::start) on.
    lock: Mutex<Option<OutDir>>,
    reused: AtomicUsize,
    saved: AtomicUsize,
}

impl Checkpoint {
    /// Open the checkpoint `name` of output folder `out` for a run with `params` (everything
    /// the units depend on; the build is added). Writes nothing. A checkpoint of other
    /// parameters is an error naming the fields that differ, unless `discard`.
    pub fn open(out: &Path, name: &str, params: Value, discard: bool) -> Result<Checkpoint> {
        let rel = format!("{FOLDER}/{}", super::safe_name(name));
        let od = OutDir::new(out, true)?;
        let run = json!({
            "format": FORMAT,
            "command": name,
            "version": env!("CARGO_PKG_VERSION"),
            "commit": env!("MOMENTLAB_GIT_COMMIT"),
            "params": params,
        });
        let dir = od.path(&rel)?;
        let run_path = dir.join("run.json");
        let mut cp = Checkpoint {
            od,
            rel,
            run,
            units: BTreeMap::new(),
            resuming: false,
            clear: std::fs::symlink_metadata(&dir).is_ok(),
            started: Mutex::new(false),
            lock: Mutex::new(None),
            reused: AtomicUsize::new(0),
            saved: AtomicUsize::new(0),
        };
        if std::fs::symlink_metadata(&run_path).is_err() {
            // Nothing, or the leftovers of a removal cut short: start over.
            return Ok(cp);
        }
        let found: Value = read_json(&run_path).context("reading the checkpoint")?;
        if found != cp.run {
            if discard {
                return Ok(cp);
            }
            bail!(
                "{} holds an interrupted run with other parameters ({}); rerun that command to \
                 resume it, or pass --force to start over",
                dir.display(),
                differing(&found, &cp.run).join(", ")
            );
        }
        cp.units = read_units(&dir.join("units"))?;
        cp.resuming = true;
        cp.clear = false;
        Ok(cp)
    }

    /// Whether output folder `out` holds a checkpoint `name` (of any parameters): for a
    /// command that checks its outputs before it can tell its parameters in full (they include
    /// data it loads later). It may then let the outputs stand until [`open`](Self::open), with
    /// the full parameters, either resumes that run or refuses it.
    pub fn exists(out: &Path, name: &str) -> bool {
        let run = out
            .join(FOLDER)
            .join(super::safe_name(name))
            .join("run.json");
        std::fs::symlink_metadata(run).is_ok()
    }

    /// Whether a checkpoint of these parameters was found: the run continues it, and the
    /// outputs its interrupted run wrote may be replaced.
    pub fn resuming(&self) -> bool {
        self.resuming
    }

    /// Units completed by earlier runs (available to [`get`](Self::get)).
    pub fn done(&self) -> usize {
        self.units.len()
    }

    /// Units taken from earlier runs so far.
    pub fn reused(&self) -> usize {
        self.reused.load(Ordering::SeqCst)
    }

    /// Units recorded by this run so far.
    pub fn saved(&self) -> usize {
        self.saved.load(Ordering::SeqCst)
    }

    /// The checkpoint's folder.
    pub fn dir(&self) -> PathBuf {
        self.od.root().join(&self.rel)
    }

    /// The line a resuming command prints on stderr: `<command>: resuming the interrupted run
    /// in DIR: N of TOTAL <what> done` (None when not resuming).
    pub fn note(&self, command: &str, total: usize, what: &str) -> Option<String> {
        self.resuming.then(|| {
            format!(
                "{command}: resuming the interrupted run in {}: {} of {total} {what} done",
                self.dir().display(),
                self.units.len()
            )
        })
    }

    /// Take the folder's lock, clear a discarded or stale state and write `run.json`
    /// (idempotent). Call after the outputs are checked and before the work.
    pub fn start(&self) -> Result<()> {
        let mut started = self.started.lock().unwrap_or_else(|e| e.into_inner());
        if *started {
            return Ok(());
        }
        if self.clear {
            self.od.remove_all(&self.rel)?;
        }
        // A second run on the same checkpoint at the same time gets a one-line error.
        let lock = OutDir::new(self.dir(), true)?;
        lock.lock()?;
        *self.lock.lock().unwrap_or_else(|e| e.into_inner()) = Some(lock);
        if !self.resuming {
            self.od
                .write_json(&format!("{}/run.json", self.rel), &self.run)?;
        }
        *started = true;
        Ok(())
    }

    /// The value of unit `key` if an earlier run completed it.
    pub fn get<T: DeserializeOwned>(&self, key: &str) -> Result<Option<T>> {
        let Some(v) = self.units.get(key) else {
            return Ok(None);
        };
        let t = T::deserialize(v).with_context(|| {
            format!(
                "{}: unit '{key}' is unreadable (remove the folder to start over)",
                self.dir().display()
            )
        })?;
        self.reused.fetch_add(1, Ordering::SeqCst);
        Ok(Some(t))
    }

    /// Record unit `key` as complete with `value` (atomically; callable from any thread).
    pub fn put<T: Serialize + ?Sized>(&self, key: &str, value: &T) -> Result<()> {
        self.start()?;
        let name = format!("{}/units/{}", self.rel, unit_file(key));
        self.od
            .write_json(&name, &json!({ "key": key, "value": value }))?;
        self.saved.fetch_add(1, Ordering::SeqCst);
        Ok(())
    }

    /// Remove the checkpoint (the run is complete): `run.json` first, so that a removal cut
    /// short leaves no state that resumes, then the folder, and `checkpoint/` if it is empty.
    pub fn finish(self) -> Result<()> {
        let _writing = super::interrupt::begin_write();
        self.od.remove(&format!("{}/run.json", self.rel))?;
        self.od.remove_all(&self.rel)?;
        drop(self.lock.lock().unwrap_or_else(|e| e.into_inner()).take());
        let _ = std::fs::remove_dir(self.od.root().join(FOLDER));
        Ok(())
    }
}

/// The top-level fields of `run.json` (and of its `params`) that differ.
fn differing(a: &Value, b: &Value) -> Vec<String> {
    let mut out = Vec::new();
    let (Some(a), Some(b)) = (a.as_object(), b.as_object()) else {
        return vec!["format".into()];
    };
    let keys: std::collections::BTreeSet<&String> = a.keys().chain(b.keys()).collect();
    for k in keys {
        match (k.as_str(), a.get(k), b.get(k)) {
            ("params", Some(Value::Object(pa)), Some(Value::Object(pb))) => {
                let sub: std::collections::BTreeSet<&String> = pa.keys().chain(pb.keys()).collect();
                out.extend(
                    sub.into_iter()
                        .filter(|s| pa.get(*s) != pb.get(*s))
                        .map(|s| s.to_string()),
                );
            }
            (_, x, y) if x != y => out.push(k.to_string()),
            _ => {}
        }
    }
    out
}

/// The file of unit `key`: the key itself when it is a plain name, otherwise its characters
/// outside `[A-Za-z0-9._-]` replaced and an FNV-1a hash of the key appended (distinct keys,
/// distinct files).
fn unit_file(key: &str) -> String {
    let plain = |c: char| c.is_ascii_alphanumeric() || matches!(c, '.' | '_' | '-');
    if !key.is_empty() && key.len() <= 120 && !key.starts_with('.') && key.chars().all(plain) {
        return format!("{key}.json");
    }
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for b in key.bytes() {
        h = (h ^ b as u64).wrapping_mul(0x0100_0000_01b3);
    }
    let stem: String = key
        .chars()
        .take(80)
        .map(|c| if plain(c) { c } else { '_' })
        .collect();
    format!("_{stem}~{h:016x}.json")
}

/// The units in `dir` (missing: none); files other than `*.json` (a temporary file of a write
/// cut short) are ignored.
fn read_units(dir: &Path) -> Result<BTreeMap<String, Value>> {
    let mut units = BTreeMap::new();
    let entries = match std::fs::read_dir(dir) {
        Ok(rd) => rd,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(units),
        Err(e) => return Err(e).with_context(|| format!("reading {}", dir.display())),
    };
    for e in entries {
        let p = e
            .with_context(|| format!("reading {}", dir.display()))?
            .path();
        if p.extension().is_none_or(|x| x != "json") {
            continue;
        }
        #[derive(serde::Deserialize)]
        struct Unit {
            key: String,
            value: Value,
        }
        let u: Unit = read_json(&p).context("reading the checkpoint")?;
        units.insert(u.key, u.value);
    }
    Ok(units)
}

/// Floats stored exactly, non-finite ones included: the bits of each value.
pub fn bits(v: &[f64]) -> Vec<u64> {
    v.iter().map(|x| x.to_bits()).collect()
}

/// The floats of [`bits`].
pub fn from_bits(v: &[u64]) -> Vec<f64> {
    v.iter().map(|&b| f64::from_bits(b)).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scratch(tag: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("momentlab-cp-{tag}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        d
    }

    /// Units survive into the next run of the same parameters and are removed at the end.
    #[test]
    fn units_resume_with_the_same_parameters_only() {
        let d = scratch("resume");
        let p = json!({"seed": 1, "n": 4});
        let cp = Checkpoint::open(&d, "demo", p.clone(), false).unwrap();
        assert!(!cp.resuming());
        assert!(!d.exists(), "open wrote something");
        cp.start().unwrap();
        cp.put("a", &1.5f64).unwrap();
        cp.put("x/y z", &vec![1u64, 2]).unwrap();
        drop(cp);
        let cp = Checkpoint::open(&d, "demo", p.clone(), false).unwrap();
        assert!(cp.resuming());
        assert_eq!(cp.done(), 2);
        assert_eq!(cp.get::<f64>("a").unwrap(), Some(1.5));
        assert_eq!(cp.get::<Vec<u64>>("x/y z").unwrap(), Some(vec![1, 2]));
        assert_eq!(cp.get::<f64>("b").unwrap(), None);
        assert_eq!(cp.reused(), 2);
        assert!(cp
            .note("demo", 4, "units")
            .unwrap()
            .contains("2 of 4 units"));
        drop(cp);
        // Other parameters: refused, naming the field; with discard, a fresh start.
        let q = json!({"seed": 2, "n": 4});
        let e = format!(
            "{:#}",
            Checkpoint::open(&d, "demo", q.clone(), false).unwrap_err()
        );
        assert!(e.contains("other parameters (seed)"), "{e}");
        let cp = Checkpoint::open(&d, "demo", q.clone(), true).unwrap();
        assert!(!cp.resuming());
        assert_eq!(cp.get::<f64>("a").unwrap(), None);
        cp.start().unwrap();
        assert!(!d.join("checkpoint/demo/units/a.json").exists());
        cp.put("b", &2u32).unwrap();
        cp.finish().unwrap();
        assert!(!d.join("checkpoint").exists());
        let cp = Checkpoint::open(&d, "demo", q, false).unwrap();
        assert!(!cp.resuming());
        std::fs::remove_dir_all(&d).unwrap();
    }

    /// A unit file whose run.json is gone (a removal cut short) is not resumed.
    #[test]
    fn leftovers_without_run_json_start_over() {
        let d = scratch("left");
        let cp = Checkpoint::open(&d, "demo", json!(1), false).unwrap();
        cp.put("a", &1u32).unwrap();
        drop(cp);
        std::fs::remove_file(d.join("checkpoint/demo/run.json")).unwrap();
        let cp = Checkpoint::open(&d, "demo", json!(1), false).unwrap();
        assert!(!cp.resuming());
        cp.start().unwrap();
        assert!(!d.join("checkpoint/demo/units/a.json").exists());
        std::fs::remove_dir_all(&d).unwrap();
    }

    #[test]
    fn unit_files_are_distinct_and_plain() {
        assert_eq!(unit_file("start-3"), "start-3.json");
        let (a, b) = (unit_file("a/b"), unit_file("a_b"));
        assert_ne!(a, b);
        assert!(a.starts_with("_a_b~"));
        assert_eq!(unit_file(".."), unit_file(".."));
        assert!(!unit_file("..").starts_with('.'));
        let x = [f64::NAN, f64::INFINITY, -0.0, 1e-300];
        let y = from_bits(&bits(&x));
        assert!(x.iter().zip(&y).all(|(a, b)| a.to_bits() == b.to_bits()));
    }
}
