//! What the process knows about a study in progress, so that an abnormal end still says what
//! happened: an FMU that calls `exit()` in-process (detected by an `atexit` handler), a run
//! longer than `--timeout-per-run` in-process (a watchdog: an FMU call cannot be interrupted
//! inside the process, so the study stops), and SIGINT/SIGTERM/SIGHUP (temporary folders
//! removed, the running points named). Finished points are in the store in every case (records
//! are appended as they finish), so a re-run resumes.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicU64, AtomicUsize, Ordering};
use std::sync::{Mutex, Once};
use std::time::{Duration, Instant};

/// Exit status of the process when an FMU ended it in-process, when a run timed out
/// in-process, or when a signal ended a study: like a failed command (1).
pub const EXIT_FAILURE: i32 = 1;
/// Exit status after SIGINT, SIGTERM or SIGHUP (128 + SIGINT, as shells report Ctrl-C).
pub const EXIT_INTERRUPTED: i32 = 130;

/// Studies in progress in this process.
static ACTIVE: AtomicUsize = AtomicUsize::new(0);
/// Set when the process ends on purpose (a signal, a timeout): the `atexit` handler is quiet.
static DELIBERATE: AtomicBool = AtomicBool::new(false);
/// Set as SIGINT, SIGTERM or SIGHUP reaches the driver (before it ends).
static STOPPING: AtomicBool = AtomicBool::new(false);
static NEXT_TOKEN: AtomicU64 = AtomicU64::new(0);
static STATE: Mutex<State> = Mutex::new(State {
    studies: BTreeMap::new(),
    running: BTreeMap::new(),
});
static ATEXIT: Once = Once::new();

struct State {
    /// Study token → (name, output folder, in-process).
    studies: BTreeMap<u64, (String, PathBuf, bool)>,
    /// Run token → (study token, point, description of its values, started).
    running: BTreeMap<u64, (u64, usize, String, Instant)>,
}

fn state() -> std::sync::MutexGuard<'static, State> {
    STATE.lock().unwrap_or_else(|e| e.into_inner())
}

/// A study in progress; dropping it ends it.
#[derive(Debug)]
pub struct StudyGuard {
    token: u64,
}

impl StudyGuard {
    /// Starts a study named `name` writing to `out_dir`; `in_process` FMUs can end the process
    /// with `exit()`, which the guard then reports.
    pub fn begin(name: &str, out_dir: &Path, in_process: bool) -> StudyGuard {
        if in_process {
            ATEXIT.call_once(register_atexit);
        }
        let token = NEXT_TOKEN.fetch_add(1, Ordering::Relaxed);
        state()
            .studies
            .insert(token, (name.to_owned(), out_dir.to_path_buf(), in_process));
        ACTIVE.fetch_add(1, Ordering::AcqRel);
        StudyGuard { token }
    }

    /// Marks `point` (with its values described by `values`) as running until the returned
    /// guard is dropped.
    pub fn running(&self, point: usize, values: String) -> RunningPoint {
        let token = NEXT_TOKEN.fetch_add(1, Ordering::Relaxed);
        state()
            .running
            .insert(token, (self.token, point, values, Instant::now()));
        RunningPoint { token }
    }

    /// The points of this study that have been running for longer than `limit`, with their
    /// descriptions.
    pub fn overdue(&self, limit: Duration) -> Vec<(usize, String, Duration)> {
        state()
            .running
            .values()
            .filter(|(s, _, _, t)| *s == self.token && t.elapsed() > limit)
            .map(|(_, p, v, t)| (*p, v.clone(), t.elapsed()))
            .collect()
    }
}

impl Drop for StudyGuard {
    fn drop(&mut self) {
        let mut s = state();
        s.studies.remove(&self.token);
        s.running.retain(|_, (st, ..)| *st != self.token);
        ACTIVE.fetch_sub(1, Ordering::AcqRel);
    }
}

/// A point being run; dropping it marks it finished.
#[derive(Debug)]
pub struct RunningPoint {
    token: u64,
}

impl Drop for RunningPoint {
    fn drop(&mut self) {
        state().running.remove(&self.token);
    }
}

/// What is running now, for a message: "study S (output folder D): point 3 (K = 1, C = 2), …".
/// `None` when no study is in progress; never blocks (a process on its way out must not wait
/// for a thread that holds the registry).
fn describe_running() -> Option<String> {
    if ACTIVE.load(Ordering::Acquire) == 0 {
        return None;
    }
    let Ok(s) = STATE.try_lock() else {
        return Some("a study (its running points are unknown)".to_owned());
    };
    let mut parts = Vec::new();
    for (token, (name, dir, _)) in &s.studies {
        let points: Vec<String> = s
            .running
            .values()
            .filter(|(st, ..)| st == token)
            .map(|(_, p, v, _)| format!("point {p} ({v})"))
            .collect();
        let running = if points.is_empty() {
            "no point running".to_owned()
        } else {
            format!("running {}", points.join(", "))
        };
        parts.push(format!(
            "study {name} (output folder {}): {running}",
            dir.display()
        ));
    }
    Some(parts.join("; "))
}

/// Ends the process on purpose: prints `message`, removes the temporary folders of opened
/// FMUs and exits with `code` (the `atexit` handler stays quiet). The results store needs no
/// closing: every record was written whole when its point finished.
pub fn exit_now(code: i32, message: &str) -> ! {
    DELIBERATE.store(true, Ordering::Release);
    eprintln!("{message}");
    crate::fmu::cleanup::remove_all();
    std::process::exit(code)
}

/// Installs the handler of SIGINT, SIGTERM and SIGHUP: it names a study in progress (its
/// finished points are kept and a re-run resumes), removes the temporary folders of opened FMUs
/// (e.g. `inspect` stopped while it extracts) and exits with [`EXIT_INTERRUPTED`]. Call once,
/// from the command line program.
pub fn install_signal_handler() {
    let _ = ctrlc::set_handler(|| {
        STOPPING.store(true, Ordering::Release);
        let message = match describe_running() {
            Some(what) => format!(
                "uq-driver: interrupted during {what}; finished points are kept in the \
                 results store: run the same command again to resume"
            ),
            None => "uq-driver: interrupted".to_owned(),
        };
        exit_now(EXIT_INTERRUPTED, &message)
    });
}

/// Whether the driver itself is being stopped by SIGINT, SIGTERM or SIGHUP, waiting up to
/// `wait` for the news (a signal sent to the whole process group reaches a worker and the
/// driver at about the same time; the driver's handler runs on its own thread). A worker that
/// died of such a signal while the driver was not asked to stop killed itself: its point
/// failed.
pub fn stop_requested_within(wait: Duration) -> bool {
    let start = Instant::now();
    loop {
        if STOPPING.load(Ordering::Acquire) {
            return true;
        }
        if start.elapsed() >= wait {
            return false;
        }
        std::thread::sleep(Duration::from_millis(10));
    }
}

/// Keeps another thread that calls `exit()` meanwhile (a second FMU instance misbehaving at
/// the same moment) from ending the process with its status first: after the exit handlers,
/// glibc's `exit()` flushes the C streams under the lock of the list of streams
/// (`_IO_cleanup`), so holding that lock parks such a thread until this one calls `_exit`.
/// (Without it, the other thread's `exit(0)` wins the race whenever two instances exit
/// together.) Rust's `eprintln!` writes to file descriptor 2 directly and needs no such lock.
fn hold_other_exits() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    {
        extern "C" {
            /// glibc: takes the (recursive) lock of the list of all `FILE` streams.
            fn _IO_list_lock();
        }
        // SAFETY: `_IO_list_lock` takes no arguments; the lock is never released because the
        // process ends with `_exit` right after.
        unsafe { _IO_list_lock() };
    }
}

/// Registers [`on_exit`] with the C library.
fn register_atexit() {
    // SAFETY: `on_exit` is an `extern "C" fn()` that lives as long as the program; `atexit`
    // only stores the pointer.
    unsafe {
        libc::atexit(on_exit);
    }
}

/// Runs when the process calls `exit()`. A study in progress that did not end on purpose means
/// an FMU (running in-process) called `exit()`: say so and make the exit status non-zero.
extern "C" fn on_exit() {
    if DELIBERATE.load(Ordering::Acquire) {
        return;
    }
    let Some(what) = describe_running() else {
        return;
    };
    hold_other_exits();
    let _ = std::panic::catch_unwind(|| {
        eprintln!(
            "uq-driver: error: the process was ended by a call to exit() during {what}: an FMU \
             running in-process called exit(). Finished points are kept in the results store. \
             Run with --isolate to have such a run marked failed and the study go on."
        );
    });
    crate::fmu::cleanup::remove_all();
    // SAFETY: `_exit` ends the process at once with this status, which is what is wanted here
    // (an exit() already in progress would otherwise report the FMU's status).
    unsafe { libc::_exit(EXIT_FAILURE) }
}
