//! Progress of long commands, shown the same way everywhere: a bar when stderr is a terminal,
//! and in batch logs (Slurm, CI, `2> log`) one line every few seconds with done/total, rate and
//! ETA — never carriage-return redraws in a file.
//!
//! The mode is chosen once per [`Bar`]: `MOMENTLAB_PROGRESS=bar|lines|off` overrides the
//! terminal test; `MOMENTLAB_PROGRESS_INTERVAL` (seconds, default 10) sets the line period.
//! Every method takes `&self` and is cheap enough to call from rayon workers (one atomic add;
//! the line writer is only locked when a line is due).

use indicatif::{ProgressBar, ProgressStyle};
use std::io::{IsTerminal, Write};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Mutex;
use std::time::{Duration, Instant};

/// Default seconds between two progress lines in a log.
pub const DEFAULT_INTERVAL: f64 = 10.0;

/// How progress is shown.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mode {
    /// An indicatif bar on stderr (a terminal).
    Bar,
    /// Periodic plain lines (logs).
    Lines,
    /// Nothing.
    Off,
}

impl Mode {
    /// The mode from `MOMENTLAB_PROGRESS` (`bar`, `lines`, `off`; anything else: automatic),
    /// else `Bar` on a terminal stderr and `Lines` otherwise.
    pub fn from_env() -> Mode {
        match std::env::var("MOMENTLAB_PROGRESS").as_deref() {
            Ok("bar") => Mode::Bar,
            Ok("lines") => Mode::Lines,
            Ok("off") | Ok("none") => Mode::Off,
            _ if std::io::stderr().is_terminal() => Mode::Bar,
            _ => Mode::Lines,
        }
    }
}

/// The line period from `MOMENTLAB_PROGRESS_INTERVAL` (seconds ≥ 0), else [`DEFAULT_INTERVAL`].
pub fn interval_from_env() -> Duration {
    std::env::var("MOMENTLAB_PROGRESS_INTERVAL")
        .ok()
        .and_then(|s| s.trim().parse::<f64>().ok())
        .filter(|s| s.is_finite() && *s >= 0.0 && *s < 1e9)
        .map_or(
            Duration::from_secs_f64(DEFAULT_INTERVAL),
            Duration::from_secs_f64,
        )
}

/// A progress display over `total` units of work (see the module docs).
pub struct Bar {
    inner: Inner,
}

/// Set by [`silence`]: no progress is shown any more in this process.
static SILENCED: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);

/// The terminal bars on screen, so that [`silence`] can clear them.
static ON_SCREEN: Mutex<Vec<ProgressBar>> = Mutex::new(Vec::new());

/// End all progress output of this process before its last line (an error, or the interrupt
/// line): terminal bars are cleared and no further progress line is written, so the line that
/// follows is the last one on stderr.
pub fn silence() {
    SILENCED.store(true, Ordering::SeqCst);
    let bars = std::mem::take(&mut *ON_SCREEN.lock().unwrap_or_else(|e| e.into_inner()));
    for b in bars {
        b.finish_and_clear();
    }
}

impl Drop for Bar {
    /// A bar dropped without [`Bar::finish`] (an error left the command) is cleared, never
    /// left on screen or redrawn after the error line.
    fn drop(&mut self) {
        if let Inner::Bar(b) = &self.inner {
            b.finish_and_clear();
            ON_SCREEN
                .lock()
                .unwrap_or_else(|e| e.into_inner())
                .retain(|x| !x.is_finished());
        }
    }
}

enum Inner {
    Bar(ProgressBar),
    Lines(Box<Lines>),
    Off,
}

/// The line writer's state. `done` / `total` are atomics so that `inc` never locks.
struct Lines {
    done: AtomicU64,
    total: AtomicU64,
    /// Fixed time origin of `due_ms`.
    origin: Instant,
    /// Milliseconds since `origin` at which the next line is due.
    due_ms: AtomicU64,
    interval: Duration,
    phase: Mutex<Phase>,
    out: Mutex<Box<dyn Write + Send>>,
}

struct Phase {
    label: String,
    start: Instant,
    /// A line for the current state has been written by `finish`.
    finished: bool,
}

impl Bar {
    /// A display of `total` units labelled `label`, in the mode of [`Mode::from_env`].
    pub fn new(label: &str, total: u64) -> Bar {
        Bar::with_mode(Mode::from_env(), label, total)
    }

    /// A display in an explicit mode (lines go to stderr every [`interval_from_env`]).
    pub fn with_mode(mode: Mode, label: &str, total: u64) -> Bar {
        match mode {
            _ if SILENCED.load(Ordering::SeqCst) => Bar::hidden(),
            Mode::Bar => {
                let b = ProgressBar::new(total);
                ON_SCREEN
                    .lock()
                    .unwrap_or_else(|e| e.into_inner())
                    .push(b.clone());
                if let Ok(style) = ProgressStyle::with_template(
                    "{msg} [{elapsed_precise}] {wide_bar} {human_pos}/{human_len} ({per_sec}, ETA {eta})",
                ) {
                    b.set_style(style);
                }
                b.set_message(label.to_string());
                Bar {
                    inner: Inner::Bar(b),
                }
            }
            Mode::Lines => Bar::lines_to(
                Box::new(std::io::stderr()),
                interval_from_env(),
                label,
                total,
            ),
            Mode::Off => Bar::hidden(),
        }
    }

    /// Lines written to `out` at most every `interval` (and once by [`Bar::finish`]).
    pub fn lines_to(
        out: Box<dyn Write + Send>,
        interval: Duration,
        label: &str,
        total: u64,
    ) -> Bar {
        Bar {
            inner: Inner::Lines(Box::new(Lines {
                done: AtomicU64::new(0),
                total: AtomicU64::new(total),
                origin: Instant::now(),
                due_ms: AtomicU64::new(interval.as_millis() as u64),
                interval,
                phase: Mutex::new(Phase {
                    label: label.to_string(),
                    start: Instant::now(),
                    finished: false,
                }),
                out: Mutex::new(out),
            })),
        }
    }

    /// Shows nothing.
    pub fn hidden() -> Bar {
        Bar { inner: Inner::Off }
    }

    /// `n` more units done.
    pub fn inc(&self, n: u64) {
        match &self.inner {
            Inner::Bar(b) => b.inc(n),
            Inner::Lines(l) => {
                l.done.fetch_add(n, Ordering::Relaxed);
                l.maybe_line();
            }
            Inner::Off => {}
        }
    }

    /// Set the units done (for callbacks that report `done` of `total`).
    pub fn set_done(&self, done: u64) {
        match &self.inner {
            Inner::Bar(b) => b.set_position(done),
            Inner::Lines(l) => {
                l.done.store(done, Ordering::Relaxed);
                l.maybe_line();
            }
            Inner::Off => {}
        }
    }

    /// Change the total.
    pub fn set_total(&self, total: u64) {
        match &self.inner {
            Inner::Bar(b) => b.set_length(total),
            Inner::Lines(l) => l.total.store(total, Ordering::Relaxed),
            Inner::Off => {}
        }
    }

    /// Change the label (the rate and ETA keep running).
    pub fn set_label(&self, label: &str) {
        match &self.inner {
            Inner::Bar(b) => b.set_message(label.to_string()),
            Inner::Lines(l) => l.lock_phase().label = label.to_string(),
            Inner::Off => {}
        }
    }

    /// Start a new phase: new label and total, counters, rate and ETA reset. In line mode the
    /// previous phase, if it did any work, gets its closing line first.
    pub fn phase(&self, label: &str, total: u64) {
        match &self.inner {
            Inner::Bar(b) => {
                b.set_message(label.to_string());
                b.set_length(total);
                b.set_position(0);
                b.reset_eta();
                b.reset_elapsed();
            }
            Inner::Lines(l) => {
                if l.done.load(Ordering::Relaxed) > 0 {
                    l.write_line(true);
                }
                let mut p = l.lock_phase();
                p.label = label.to_string();
                p.start = Instant::now();
                p.finished = false;
                l.done.store(0, Ordering::Relaxed);
                l.total.store(total, Ordering::Relaxed);
                l.due_ms.store(
                    l.now_ms() + l.interval.as_millis() as u64,
                    Ordering::Relaxed,
                );
            }
            Inner::Off => {}
        }
    }

    /// The work is over: the bar is cleared; in line mode a closing line with the totals is
    /// written (once).
    pub fn finish(&self) {
        match &self.inner {
            Inner::Bar(b) => b.finish_and_clear(),
            Inner::Lines(l) => l.write_line(true),
            Inner::Off => {}
        }
    }
}

impl Lines {
    fn lock_phase(&self) -> std::sync::MutexGuard<'_, Phase> {
        self.phase.lock().unwrap_or_else(|e| e.into_inner())
    }

    fn now_ms(&self) -> u64 {
        self.origin.elapsed().as_millis() as u64
    }

    /// Write a line if one is due; only one thread wins the slot.
    fn maybe_line(&self) {
        let due = self.due_ms.load(Ordering::Relaxed);
        let now = self.now_ms();
        if now < due {
            return;
        }
        let next = now + (self.interval.as_millis() as u64).max(1);
        if self
            .due_ms
            .compare_exchange(due, next, Ordering::Relaxed, Ordering::Relaxed)
            .is_ok()
        {
            self.write_line(false);
        }
    }

    /// Lines are formatted under the output lock, so their counts never go backwards.
    fn write_line(&self, closing: bool) {
        let mut out = self.out.lock().unwrap_or_else(|e| e.into_inner());
        if SILENCED.load(Ordering::SeqCst) {
            return;
        }
        let text = {
            let mut p = self.lock_phase();
            if closing && p.finished {
                return;
            }
            p.finished = closing;
            line(
                &p.label,
                self.done.load(Ordering::Relaxed),
                self.total.load(Ordering::Relaxed),
                p.start.elapsed(),
            )
        };
        // A log that cannot be written must not stop the computation.
        let _ = writeln!(out, "{text}").and_then(|_| out.flush());
    }
}

/// One progress line: `label: done/total (p %), rate/s, elapsed …, ETA …` (ETA from the mean
/// rate of the phase; omitted when unknown or done).
pub fn line(label: &str, done: u64, total: u64, elapsed: Duration) -> String {
    let secs = elapsed.as_secs_f64();
    let rate = if secs > 0.0 { done as f64 / secs } else { 0.0 };
    let mut s = format!("{label}: {}/{}", group(done), group(total));
    if total > 0 {
        s += &format!(" ({:.1} %)", 100.0 * done as f64 / total as f64);
    }
    s += &format!(", {}/s, elapsed {}", group(rate.round() as u64), hms(secs));
    if done < total && rate > 0.0 {
        s += &format!(", ETA {}", hms((total - done) as f64 / rate));
    }
    s
}

/// 1234567 → "1 234 567".
fn group(n: u64) -> String {
    let d = n.to_string();
    let mut out = String::with_capacity(d.len() + d.len() / 3);
    for (i, c) in d.chars().enumerate() {
        if i > 0 && (d.len() - i).is_multiple_of(3) {
            out.push(' ');
        }
        out.push(c);
    }
    out
}

/// Seconds as "42s", "3m05s" or "2h07m".
fn hms(secs: f64) -> String {
    let s = secs.max(0.0).round() as u64;
    match s {
        0..=59 => format!("{s}s"),
        60..=3599 => format!("{}m{:02}s", s / 60, s % 60),
        _ => format!("{}h{:02}m", s / 3600, (s % 3600) / 60),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::Arc;

    /// A `Write` into a shared buffer.
    #[derive(Clone, Default)]
    struct Sink(Arc<Mutex<Vec<u8>>>);

    impl Write for Sink {
        fn write(&mut self, b: &[u8]) -> std::io::Result<usize> {
            self.0.lock().unwrap().extend_from_slice(b);
            Ok(b.len())
        }
        fn flush(&mut self) -> std::io::Result<()> {
            Ok(())
        }
    }

    impl Sink {
        fn lines(&self) -> Vec<String> {
            let text = String::from_utf8(self.0.lock().unwrap().clone()).unwrap();
            text.lines().map(str::to_string).collect()
        }
    }

    #[test]
    fn line_has_done_total_rate_and_eta() {
        let l = line("stage 0", 250, 1000, Duration::from_secs(5));
        assert_eq!(l, "stage 0: 250/1 000 (25.0 %), 50/s, elapsed 5s, ETA 15s");
        let l = line("x", 1_234_567, 1_234_567, Duration::from_secs(3700));
        assert_eq!(l, "x: 1 234 567/1 234 567 (100.0 %), 334/s, elapsed 1h01m");
        assert_eq!(line("y", 0, 0, Duration::ZERO), "y: 0/0, 0/s, elapsed 0s");
        assert_eq!(hms(125.0), "2m05s");
    }

    #[test]
    fn lines_are_periodic_and_closed_once() {
        let sink = Sink::default();
        let bar = Bar::lines_to(Box::new(sink.clone()), Duration::from_secs(3600), "a", 10);
        for _ in 0..10 {
            bar.inc(1);
        }
        assert!(sink.lines().is_empty(), "no line before the interval");
        bar.finish();
        bar.finish();
        assert_eq!(sink.lines().len(), 1);
        assert!(
            sink.lines()[0].starts_with("a: 10/10 (100.0 %)"),
            "{:?}",
            sink.lines()
        );

        let sink = Sink::default();
        let bar = Bar::lines_to(Box::new(sink.clone()), Duration::ZERO, "b", 4);
        for _ in 0..4 {
            std::thread::sleep(Duration::from_millis(2));
            bar.inc(1);
        }
        let lines = sink.lines();
        assert_eq!(lines.len(), 4, "{lines:?}");
        for (k, l) in lines.iter().enumerate() {
            assert!(l.starts_with(&format!("b: {}/4", k + 1)), "{l}");
            assert!(!l.contains('\r'));
        }
        assert!(lines[0].contains("ETA"), "{}", lines[0]);
        assert!(!lines[3].contains("ETA"), "{}", lines[3]);
    }

    #[test]
    fn phases_close_the_previous_one_and_reset() {
        let sink = Sink::default();
        let bar = Bar::lines_to(Box::new(sink.clone()), Duration::from_secs(3600), "one", 5);
        bar.inc(5);
        bar.phase("two", 8);
        bar.phase("three", 2); // "two" did nothing: no line
        bar.set_done(1);
        bar.set_label("three'");
        bar.finish();
        assert_eq!(sink.lines().len(), 2, "{:?}", sink.lines());
        assert!(sink.lines()[0].starts_with("one: 5/5"));
        assert!(sink.lines()[1].starts_with("three': 1/2 (50.0 %)"));
    }

    #[test]
    fn concurrent_increments_are_all_counted() {
        let sink = Sink::default();
        let bar = Bar::lines_to(Box::new(sink.clone()), Duration::ZERO, "c", 8000);
        std::thread::scope(|s| {
            for _ in 0..8 {
                s.spawn(|| (0..1000).for_each(|_| bar.inc(1)));
            }
        });
        bar.finish();
        let last = sink.lines().pop().unwrap();
        assert!(last.starts_with("c: 8 000/8 000"), "{last}");
        // Each written line's count never decreases.
        let counts: Vec<u64> = sink
            .lines()
            .iter()
            .map(|l| {
                l[3..]
                    .split('/')
                    .next()
                    .unwrap()
                    .replace(' ', "")
                    .parse()
                    .unwrap()
            })
            .collect();
        assert!(counts.windows(2).all(|w| w[0] <= w[1]), "{counts:?}");
    }
}
