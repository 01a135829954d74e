//! What the study shows while it runs: numbered step lines and progress ([`crate::progress`]:
//! a bar on a terminal, periodic lines in logs) on stderr.

use crate::progress::Bar;
use std::time::Instant;

/// A progress display with a label.
pub fn bar(len: u64, what: &str) -> Bar {
    Bar::new(&format!("  {what}"), len)
}

/// The numbered steps of a run: "[k/total] what (elapsed s)".
pub struct Steps {
    k: usize,
    total: usize,
    t0: Instant,
}

impl Steps {
    /// Steps numbered 1..=`total`; the clock starts now.
    pub fn new(total: usize) -> Steps {
        Steps {
            k: 0,
            total,
            t0: Instant::now(),
        }
    }

    /// Announce the next step.
    pub fn start(&mut self, what: &str) {
        self.k += 1;
        eprintln!(
            "[{}/{}] {what} (elapsed {:.0} s)",
            self.k,
            self.total,
            self.t0.elapsed().as_secs_f64()
        );
    }

    /// Seconds since the run started.
    pub fn elapsed(&self) -> f64 {
        self.t0.elapsed().as_secs_f64()
    }
}

/// A percentage with three decimals, or "n/a".
pub fn pct(x: f64) -> String {
    if x.is_finite() {
        format!("{:.3} %", 100.0 * x)
    } else {
        "n/a".into()
    }
}
