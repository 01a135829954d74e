//! The size of rayon's thread pool: `RAYON_NUM_THREADS` if set (rayon reads it itself), else
//! `SLURM_CPUS_PER_TASK` inside a Slurm job (the CPUs the job was given, not the node's), else
//! rayon's default (all CPUs the process may use).

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

/// Configure rayon's global pool from the environment (call once, before any parallel work).
pub fn init_from_env() -> Result<()> {
    let rayon = std::env::var("RAYON_NUM_THREADS").ok();
    let slurm = std::env::var("SLURM_CPUS_PER_TASK").ok();
    if let Some(n) = threads_from(rayon.as_deref(), slurm.as_deref())? {
        rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build_global()
            .map_err(|e| anyhow::anyhow!("thread pool of {n} threads: {e}"))?;
        eprintln!(
            "momentlab: {n} thread{} (SLURM_CPUS_PER_TASK)",
            if n == 1 { "" } else { "s" }
        );
    }
    Ok(())
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
}
