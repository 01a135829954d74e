//! SIGINT and SIGTERM for long commands. The handler only records the signal (an atomic store,
//! async-signal-safe); a watcher thread then stops the process between two writes of the one
//! writer: every atomic file put in place and every JSON-lines append runs inside
//! [`begin_write`], and the watcher exits only when none is in flight, after which no new one
//! starts. So an interrupt abandons the current unit of work, leaves every output file whole
//! (the state a resumable command continues from), ends progress output and prints one line;
//! the exit status is 130.

use std::cell::Cell;
use std::sync::atomic::{AtomicBool, AtomicI32, AtomicUsize, Ordering};
use std::time::Duration;

/// The signal received (0: none).
static SIGNAL: AtomicI32 = AtomicI32::new(0);
/// Writes in flight.
static ACTIVE: AtomicUsize = AtomicUsize::new(0);
/// Set by the watcher: no write may start any more.
static STOPPING: AtomicBool = AtomicBool::new(false);

thread_local! {
    /// Nesting depth of [`begin_write`] on this thread.
    static DEPTH: Cell<usize> = const { Cell::new(0) };
}

/// A write in flight (see [`begin_write`]).
pub struct WriteGuard(());

impl Drop for WriteGuard {
    fn drop(&mut self) {
        DEPTH.with(|d| d.set(d.get() - 1));
        ACTIVE.fetch_sub(1, Ordering::SeqCst);
    }
}

/// Mark a write in flight until the guard is dropped. Once an interrupt is being handled, a
/// new (outermost) write waits for the exit instead of starting.
pub fn begin_write() -> WriteGuard {
    let nested = DEPTH.with(|d| d.get()) > 0;
    ACTIVE.fetch_add(1, Ordering::SeqCst);
    if !nested && STOPPING.load(Ordering::SeqCst) {
        ACTIVE.fetch_sub(1, Ordering::SeqCst);
        loop {
            std::thread::sleep(Duration::from_secs(1));
        }
    }
    DEPTH.with(|d| d.set(d.get() + 1));
    WriteGuard(())
}

extern "C" fn on_signal(sig: libc::c_int) {
    SIGNAL.store(sig, Ordering::SeqCst);
}

/// Install the handlers for `command` (named in the line); `resumes`: whether rerunning the
/// same command continues from the files written so far (said in the line).
pub fn install(command: &'static str, resumes: bool) {
    let handler = on_signal as extern "C" fn(libc::c_int) as libc::sighandler_t;
    // SAFETY: the handler only performs an atomic store.
    unsafe {
        libc::signal(libc::SIGINT, handler);
        libc::signal(libc::SIGTERM, handler);
    }
    std::thread::spawn(move || loop {
        std::thread::sleep(Duration::from_millis(20));
        let sig = SIGNAL.load(Ordering::SeqCst);
        if sig == 0 {
            continue;
        }
        STOPPING.store(true, Ordering::SeqCst);
        while ACTIVE.load(Ordering::SeqCst) != 0 {
            std::thread::sleep(Duration::from_millis(2));
        }
        crate::progress::silence();
        let name = if sig == libc::SIGTERM {
            "SIGTERM"
        } else {
            "SIGINT"
        };
        let then = if resumes {
            "the same command resumes from them"
        } else {
            "the command starts over when run again"
        };
        use std::io::Write;
        let _ = writeln!(
            std::io::stderr().lock(),
            "error: {command}: interrupted by {name}; files written so far are whole, {then}"
        );
        std::process::exit(130);
    });
}
