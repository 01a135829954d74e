//! The size of rayon's thread pool: `RAYON_NUM_THREADS` if set, else `SLURM_CPUS_PER_TASK`
//! inside a Slurm job (the CPUs the job was given, not the node's), else rayon's default (all
//! CPUs the process may use). A request above the CPUs this process may use is clamped to them;
//! the note saying so is shown when the command has succeeded (never ahead of an error line).

use anyhow::{bail, Result};

/// Threads to configure from the two variables' values; None: leave rayon's default.
pub fn threads_from(rayon: Option<&str>, slurm_cpus: Option<&str>) -> Result<Option<usize>> {
    if rayon.is_some_and(|s| !s.trim().is_empty()) {
        return Ok(None);
    }
    let Some(s) = slurm_cpus.map(str::trim).filter(|s| !s.is_empty()) else {
        return Ok(None);
    };
    match s.parse::<usize>() {
        Ok(n) if (1..=65536).contains(&n) => Ok(Some(n)),
        _ => bail!("SLURM_CPUS_PER_TASK = '{s}': expected a CPU count between 1 and 65536"),
    }
}

/// `RAYON_NUM_THREADS` as a thread count (None: unset, empty or 0 = rayon's default).
pub fn rayon_threads(rayon: Option<&str>) -> Result<Option<usize>> {
    let Some(s) = rayon.map(str::trim).filter(|s| !s.is_empty()) else {
        return Ok(None);
    };
    match s.parse::<usize>() {
        Ok(0) => Ok(None),
        Ok(n) if n <= 65536 => Ok(Some(n)),
        _ => bail!("RAYON_NUM_THREADS = '{s}': expected a thread count between 0 and 65536"),
    }
}

/// The pool size for a request of `want` threads (from `var`) with `cores` CPUs available:
/// (threads, note when clamped).
pub fn clamp(want: usize, cores: usize, var: &str) -> (usize, Option<String>) {
    let cores = cores.max(1);
    if want <= cores {
        return (want, None);
    }
    let note = format!(
        "momentlab: {var} asks for {want} threads, {cores} CPU{} available: used {cores}",
        if cores == 1 { "" } else { "s" }
    );
    (cores, Some(note))
}

/// "momentlab: N threads (VAR)": the pool size and where it came from.
pub fn pool_note(n: usize, var: &str) -> String {
    format!(
        "momentlab: {n} thread{} ({var})",
        if n == 1 { "" } else { "s" }
    )
}

/// Configure rayon's global pool from the environment (call once, before any parallel work).
/// Returns the note to show after the command succeeded: the pool size taken from
/// `SLURM_CPUS_PER_TASK` (so a batch log says what a task ran on), or the clamp of a request.
pub fn init_from_env() -> Result<Option<String>> {
    let rayon = std::env::var("RAYON_NUM_THREADS").ok();
    let slurm = std::env::var("SLURM_CPUS_PER_TASK").ok();
    let want = match rayon_threads(rayon.as_deref())? {
        Some(n) => Some((n, "RAYON_NUM_THREADS")),
        None => {
            threads_from(rayon.as_deref(), slurm.as_deref())?.map(|n| (n, "SLURM_CPUS_PER_TASK"))
        }
    };
    let Some((want, var)) = want else {
        return Ok(None);
    };
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let (n, note) = clamp(want, cores, var);
    let note = note.or_else(|| (var == "SLURM_CPUS_PER_TASK").then(|| pool_note(n, var)));
    rayon::ThreadPoolBuilder::new()
        .num_threads(n)
        .build_global()
        .map_err(|e| anyhow::anyhow!("thread pool of {n} threads: {e}"))?;
    Ok(note)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn slurm_cpus_sets_the_pool_unless_rayon_is_explicit() {
        assert_eq!(threads_from(None, None).unwrap(), None);
        assert_eq!(threads_from(None, Some("8")).unwrap(), Some(8));
        assert_eq!(threads_from(None, Some(" 3\n")).unwrap(), Some(3));
        assert_eq!(threads_from(Some("2"), Some("8")).unwrap(), None);
        assert_eq!(threads_from(Some(""), Some("4")).unwrap(), Some(4));
        assert_eq!(threads_from(None, Some("")).unwrap(), None);
        for bad in ["0", "-1", "two", "1e3", "99999999"] {
            let e = threads_from(None, Some(bad)).unwrap_err().to_string();
            assert!(e.contains("SLURM_CPUS_PER_TASK") && e.contains(bad), "{e}");
        }
    }

    #[test]
    fn requests_above_the_cores_are_clamped_with_a_note() {
        assert_eq!(clamp(2, 4, "X"), (2, None));
        assert_eq!(clamp(4, 4, "X"), (4, None));
        assert_eq!(
            pool_note(1, "SLURM_CPUS_PER_TASK"),
            "momentlab: 1 thread (SLURM_CPUS_PER_TASK)"
        );
        assert_eq!(pool_note(2, "X"), "momentlab: 2 threads (X)");
        let (n, note) = clamp(20000, 2, "SLURM_CPUS_PER_TASK");
        assert_eq!(n, 2);
        let note = note.unwrap();
        assert!(note.contains("20000") && note.contains("2 CPUs"), "{note}");
        assert_eq!(rayon_threads(Some("0")).unwrap(), None);
        assert_eq!(rayon_threads(Some("20000")).unwrap(), Some(20000));
        assert!(rayon_threads(Some("x")).is_err());
    }
}
