//! What the process knows about a study in progress, so that an abnormal end still says what
//! happened: an FMU that calls `exit()` in-process (detected by an `atexit` handler), a run
//! longer than `--timeout-per-run` in-process (a watchdog: an FMU call cannot be interrupted
//! inside the process, so the study stops), and SIGINT/SIGTERM/SIGHUP (temporary folders
//! removed, the running points named). Finished points are in the store in every case (records
//! are appended as they finish), so a re-run resumes.
//!
//! All of this acts on the whole process (an `atexit` handler, signal handlers, `_exit`), so
//! it is opt-in: [`install_process_guards`], which the command line calls once at start. A
//! library host that does not call it keeps its own process: its `exit()` is its own, no
//! signal handler is installed, and `RunOptions::timeout_per_run` needs `RunOptions::isolate`
//! (it is refused in-process with [`crate::study::RunError::Options`]).

use std::collections::BTreeMap;
use std::io::Write;
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
/// Set by [`install_process_guards`].
static PROCESS_GUARDS: AtomicBool = AtomicBool::new(false);
static SIGNALS: Once = Once::new();
/// The FMU of a `simulate` in progress (for the `exit()` message).
static SIMULATION: Mutex<Option<String>> = Mutex::new(None);

struct State {
    /// Study token → (name, output folder, in-process).
    studies: BTreeMap<u64, (String, PathBuf, bool)>,
    /// Run token → (study token, point, description of its values, started).
    running: BTreeMap<u64, (u64, usize, String, Instant)>,
}

fn state() -> std::sync::MutexGuard<'static, State> {
    STATE.lock().unwrap_or_else(|e| e.into_inner())
}

/// Opts this process in to the process-wide guards of a study in progress, for a program that
/// owns its process (the `uq-driver` command line calls it first thing):
/// - SIGINT, SIGTERM and SIGHUP end the process after naming the study in progress and
///   removing the FMUs' temporary folders (`install_signal_handler`);
/// - while an in-process study or simulation runs, an `atexit` handler reports an FMU that
///   calls `exit()` (and makes the exit status 1), and SIGSEGV, SIGBUS, SIGILL, SIGFPE and
///   SIGABRT handlers name the running points before passing the signal on;
/// - an in-process run longer than `RunOptions::timeout_per_run` ends the process (an FMU
///   call cannot be interrupted inside it) after naming the point.
///
/// Without it (the default for a library), none of these is installed, and `timeout_per_run`
/// without `RunOptions::isolate` is refused. Calling it again does nothing more.
pub fn install_process_guards() {
    PROCESS_GUARDS.store(true, Ordering::Release);
    SIGNALS.call_once(install_signal_handler);
}

/// Whether [`install_process_guards`] was called in this process.
pub fn process_guards() -> bool {
    PROCESS_GUARDS.load(Ordering::Acquire)
}

/// A study in progress; dropping it ends it.
#[derive(Debug)]
pub struct StudyGuard {
    token: u64,
}

impl StudyGuard {
    /// Starts a study named `name` writing to `out_dir`; `in_process` FMUs can end the process
    /// with `exit()`, which the guard then reports (with [`install_process_guards`] only).
    pub fn begin(name: &str, out_dir: &Path, in_process: bool) -> StudyGuard {
        if in_process && process_guards() {
            ATEXIT.call_once(register_atexit);
            crate::sys::crash::install();
        }
        let token = NEXT_TOKEN.fetch_add(1, Ordering::Relaxed);
        let mut s = state();
        s.studies
            .insert(token, (name.to_owned(), out_dir.to_path_buf(), in_process));
        ACTIVE.fetch_add(1, Ordering::AcqRel);
        changed(&s);
        StudyGuard { token }
    }

    /// Marks `point` (with its values described by `values`) as running until the returned
    /// guard is dropped.
    pub fn running(&self, point: usize, values: String) -> RunningPoint {
        let token = NEXT_TOKEN.fetch_add(1, Ordering::Relaxed);
        let mut s = state();
        s.running
            .insert(token, (self.token, point, values, Instant::now()));
        changed(&s);
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
        changed(&s);
    }
}

/// A point being run; dropping it marks it finished.
#[derive(Debug)]
pub struct RunningPoint {
    token: u64,
}

impl Drop for RunningPoint {
    fn drop(&mut self) {
        let mut s = state();
        s.running.remove(&self.token);
        changed(&s);
    }
}

/// What is running now, for a message: "study S (output folder D): point 3 (K = 1, C = 2), …".
/// `None` when no study is in progress; never blocks for long (a process on its way out must
/// not wait for a thread that holds the registry): another thread holds it only while it
/// registers or ends a point, so a few tries over up to 50 ms find it free, unless that thread
/// is stuck (then the points are said to be unknown). One try alone lost the points about
/// once in six when two threads' FMUs called exit() together.
fn describe_running() -> Option<String> {
    if ACTIVE.load(Ordering::Acquire) == 0 {
        return None;
    }
    for _ in 0..50 {
        match STATE.try_lock() {
            Ok(s) => return Some(describe(&s)),
            Err(std::sync::TryLockError::Poisoned(e)) => return Some(describe(&e.into_inner())),
            Err(std::sync::TryLockError::WouldBlock) => {
                std::thread::sleep(std::time::Duration::from_millis(1))
            }
        }
    }
    Some("a study (its running points are unknown)".to_owned())
}

/// Prepares the message of a crash in-process for what runs now (called with the registry
/// held, as it changes).
fn changed(s: &State) {
    let in_process = s.studies.values().any(|(_, _, p)| *p);
    crate::sys::crash::prepare(in_process.then(|| describe(s)).as_deref());
}

/// "study S (output folder D): running point 3 (K = 1, C = 2), …" for every study.
fn describe(s: &State) -> String {
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
    parts.join("; ")
}

/// Ends the process on purpose: prints `message`, removes the temporary folders of opened
/// FMUs, flushes the C streams and ends with `code` by `_exit`. The results store needs no
/// closing: every record was written whole when its point finished.
///
/// Not `exit()`: another thread may still be inside an FMU (a run past `--timeout-per-run`,
/// a study interrupted by Ctrl-C), and the exit handlers and library destructors that `exit()`
/// runs can tear down a runtime under it (an embedded-Python FMU then ended the process with
/// "FATAL: exception not rethrown" and SIGABRT, exit status 134, instead of the status meant).
pub fn exit_now(code: i32, message: &str) -> ! {
    DELIBERATE.store(true, Ordering::Release);
    eprintln!("{message}");
    crate::fmu::cleanup::remove_all();
    // Every C stream flushed (what FMU code printed), then `_exit`: no exit handlers or
    // destructors, which is the point. Rust's stdout is line-buffered: whole lines were
    // written already.
    crate::sys::flush_c_streams();
    crate::sys::exit_immediately(code)
}

/// Installs the handler of SIGINT, SIGTERM and SIGHUP: it names a study in progress (its
/// finished points are kept and a re-run resumes), removes the temporary folders of opened FMUs
/// (e.g. `inspect` stopped while it extracts) and exits with [`EXIT_INTERRUPTED`]. Call once,
/// from the command line program ([`install_process_guards`] calls it).
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

/// A `simulate` run of an FMU in progress: an FMU that calls `exit()` meanwhile is reported
/// (exit status 1) instead of ending the process quietly with its own status.
#[derive(Debug)]
pub struct SimulationGuard(());

impl SimulationGuard {
    /// Starts watching a simulation of `fmu` (as the user named it); the `atexit` handler is
    /// registered with [`install_process_guards`] only.
    pub fn begin(fmu: &Path) -> SimulationGuard {
        if process_guards() {
            ATEXIT.call_once(register_atexit);
        }
        *SIMULATION.lock().unwrap_or_else(|e| e.into_inner()) = Some(fmu.display().to_string());
        SimulationGuard(())
    }
}

impl Drop for SimulationGuard {
    fn drop(&mut self) {
        *SIMULATION.lock().unwrap_or_else(|e| e.into_inner()) = None;
    }
}

/// While alive, file descriptor 1 points at stderr, so that what FMU code prints cannot mix
/// with output the program writes to stdout (a CSV); dropping it flushes the C streams and
/// puts stdout back.
#[derive(Debug)]
pub struct StdoutToStderr {
    saved: Option<std::os::fd::OwnedFd>,
}

impl StdoutToStderr {
    /// Points fd 1 at stderr (when that fails, stdout stays as it is).
    pub fn begin() -> StdoutToStderr {
        let _ = std::io::stdout().flush();
        let Ok(saved) = crate::sys::dup_cloexec(1, 3) else {
            return StdoutToStderr { saved: None };
        };
        // Rust's stdout was flushed: nothing of it is waiting for the old fd 1.
        if crate::sys::dup2(2, 1).is_err() {
            return StdoutToStderr { saved: None };
        }
        StdoutToStderr { saved: Some(saved) }
    }
}

impl Drop for StdoutToStderr {
    fn drop(&mut self) {
        use std::os::fd::AsRawFd;
        if let Some(saved) = self.saved.take() {
            // What the FMU printed goes where fd 1 points now (stderr), then stdout is back.
            crate::sys::flush_c_streams();
            let _ = crate::sys::dup2(saved.as_raw_fd(), 1);
        }
    }
}

/// Registers [`on_exit`] with the C library.
fn register_atexit() {
    crate::sys::at_exit(on_exit);
}

/// Runs when the process calls `exit()`. A study in progress that did not end on purpose means
/// an FMU (running in-process) called `exit()`: say so and make the exit status non-zero.
extern "C" fn on_exit() {
    if DELIBERATE.load(Ordering::Acquire) {
        return;
    }
    let simulation = SIMULATION.try_lock().ok().and_then(|s| s.clone());
    if ACTIVE.load(Ordering::Acquire) == 0 && simulation.is_none() {
        return;
    }
    // Hold another thread's exit() before anything that may wait (describe_running): that
    // exit finds the handler list already taken and would otherwise end the process with the
    // FMU's status (0) while this one still writes its message.
    crate::sys::hold_other_exits();
    let what = describe_running();
    if what.is_none() && simulation.is_none() {
        return;
    }
    let _ = std::panic::catch_unwind(|| match (what, simulation) {
        (Some(what), _) => eprintln!(
            "uq-driver: error: the process was ended by a call to exit() during {what}: an FMU \
             running in-process called exit(). Finished points are kept in the results store. \
             Run with --isolate to have such a run marked failed and the study go on."
        ),
        (None, Some(fmu)) => eprintln!(
            "uq-driver: error: the process was ended by a call to exit() while simulating \
             {fmu}: the FMU called exit() before the run was done; no result was written"
        ),
        (None, None) => {}
    });
    crate::fmu::cleanup::remove_all();
    // At once with this status (an exit() already in progress would otherwise report the
    // FMU's status).
    crate::sys::exit_immediately(EXIT_FAILURE)
}
