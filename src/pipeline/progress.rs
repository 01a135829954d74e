//! What the study shows while it runs: numbered step lines and progress bars on stderr (bars
//! hidden when `CI` is set).

use indicatif::{ProgressBar, ProgressStyle};
use std::time::Instant;

/// A progress bar with a label (hidden under CI).
pub fn bar(len: u64, what: &str) -> ProgressBar {
    let b = if std::env::var_os("CI").is_some() {
        ProgressBar::hidden()
    } else {
        ProgressBar::new(len)
    };
    b.set_style(
        ProgressStyle::with_template("  {msg:<38} {wide_bar} {pos}/{len} ({eta})")
            .expect("valid template"),
    );
    b.set_message(what.to_string());
    b
}

/// The numbered steps of a run: "[k/total] what (elapsed s)".
pub struct Steps {
    k: usize,
    total: usize,
    t0: Instant,
}

impl Steps {
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
