//! `--isolate`: each point runs in a worker process, so that an FMU that segfaults, aborts,
//! calls `exit()` or blocks fails that point instead of taking the driver with it.
//!
//! A worker is the uq-driver executable started with the hidden subcommand `worker`
//! ([`serve`]). It opens the FMU from the folder the parent already extracted, creates one
//! instance at a time, and runs points one after the other exactly as the in-process runner
//! does ([`run_point`]; fresh or reset instances by the setup's [`InstancePolicy`], and the
//! reset self-check of [`super::instances`] when the parent asks), so results are
//! bit-identical. Parent and worker speak a small binary
//! protocol over the worker's stdin and stdout (the worker moves its own stdout to stderr
//! first, so an FMU that prints cannot garble it): frames of a tag byte, a little-endian u64
//! length and the payload.
//!
//! | tag | from | payload |
//! | --- | --- | --- |
//! | `S` | parent | the setup, JSON ([`Setup`]) |
//! | `P` | parent | a point's parameter values, f64 LE |
//! | `C` | parent | the reset self-check: the last point's values again, to run after `fmi2Reset` |
//! | `R` | worker | ready (empty) |
//! | `O` | worker | the point's record values, f64 LE |
//! | `V` | worker | the self-check's verdict: a byte (0 passed, 1 failed, 2 failed and the worker ends after fmi2Fatal), then the reason, UTF-8 |
//! | `N` | worker | before an answer: `fmi2Reset` failed and the point ran on a fresh instance; the reason, UTF-8 |
//! | `F` | worker | the point failed: the message, UTF-8 |
//! | `X` | worker | the point failed and the FMU is unusable (fmi2Fatal): the worker ends |
//! | `E` | worker | the setup failed: the message, UTF-8 |
//!
//! What the worker writes to stderr (the FMU's log messages, which the worker echoes, and
//! anything the FMU prints) is kept by the parent, the last lines of it going into the message
//! of a point whose worker died. A worker that dies (signal or exit; noticed by its exit
//! status, not by the end of its pipes, which a program the FMU started may keep open) or
//! outlives `--timeout-per-run` (then it is killed) fails its point; the next point starts a
//! new worker. A worker killed by SIGINT, SIGTERM or SIGHUP while the driver itself is being
//! stopped (Ctrl-C, `kill`, `scancel`) fails nothing: the study stops and a re-run computes
//! the point; a worker that dies of such a signal otherwise (an FMU that raises SIGTERM on
//! itself) fails its point like any crash. Workers ignore SIGINT (the
//! terminal sends it to the whole process group; the parent handles it) and, on Linux, are
//! killed when the parent dies.

use std::collections::VecDeque;
use std::io::{BufReader, Read, Write};
use std::path::PathBuf;
use std::process::{Child, ChildStdin, Command, ExitStatus, Stdio};
use std::sync::mpsc::{self, Receiver, RecvTimeoutError};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use serde::{Deserialize, Serialize};

use super::instances::{InstancePolicy, ResetCheck, Slot};
use super::interface::Interface;
use super::point::check_reset;
use super::runner::run_point;
use crate::fmu::Fmu;

/// How many of a worker's last stderr lines a failure message quotes.
const TAIL_LINES: usize = 12;
/// Largest frame accepted (bytes): far above any record, small enough to refuse garbage.
const MAX_FRAME: u64 = 1 << 34;
/// The worker's protocol descriptors are moved to this number or above, out of the way of an
/// FMU that writes to (or closes) low descriptors.
pub const PROTOCOL_FD_MIN: i32 = 100;
/// How often a waiting parent checks whether its worker is still alive.
const POLL: Duration = Duration::from_millis(20);
/// How long the parent waits for the last frames and output of a worker that has ended, and
/// for a worker that closed its answer pipe to end.
const GRACE: Duration = Duration::from_millis(500);

/// What a worker needs to run points.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Setup {
    /// The extracted FMU folder.
    pub fmu_root: PathBuf,
    /// The FMU as the user named it (for messages).
    pub fmu_shown: PathBuf,
    /// The study's variables.
    pub interface: Interface,
    /// The communication points (s).
    pub times: Vec<f64>,
    /// How the worker's runs get their instance.
    #[serde(default)]
    pub policy: InstancePolicy,
}

/// How workers are started.
#[derive(Clone, Debug)]
pub struct IsolateOptions {
    /// The uq-driver executable (which has the `worker` subcommand).
    pub exe: PathBuf,
    /// Longest a run may take before its worker is killed.
    pub timeout: Option<Duration>,
}

/// Why a point run in a worker has no result.
#[derive(Debug)]
pub enum WorkerFailure {
    /// The run failed normally (an FMI error, NaN outputs, ...); the worker lives on.
    Point(String),
    /// The worker died or was killed: the point failed; the worker is gone.
    Died(String),
    /// The worker was stopped from outside (SIGINT/SIGTERM/SIGHUP): the point has no result.
    Interrupted(String),
}

/// A frame read by the reader thread.
type Frame = (u8, Vec<u8>);

/// What the reader thread passes on: a frame, or why the bytes were not one.
type Answer = Result<Frame, String>;

/// The last lines a worker wrote to stderr.
#[derive(Debug)]
struct Tail {
    lines: VecDeque<String>,
    /// The start of a line not yet ended.
    partial: Vec<u8>,
    /// When the last bytes came.
    last: Instant,
}

impl Tail {
    fn push(&mut self, bytes: &[u8]) {
        self.last = Instant::now();
        for chunk in bytes.split_inclusive(|b| *b == b'\n') {
            self.partial.extend_from_slice(chunk);
            if chunk.ends_with(b"\n") {
                let line =
                    String::from_utf8_lossy(&self.partial[..self.partial.len() - 1]).into_owned();
                self.partial.clear();
                if self.lines.len() == TAIL_LINES {
                    self.lines.pop_front();
                }
                self.lines.push_back(line);
            } else if self.partial.len() > 4096 {
                self.partial.drain(..self.partial.len() - 4096);
            }
        }
    }
}

/// A running worker process.
pub struct Worker {
    child: Child,
    stdin: Option<ChildStdin>,
    frames: Receiver<Answer>,
    tail: Arc<Mutex<Tail>>,
    stderr_done: Receiver<()>,
}

impl std::fmt::Debug for Worker {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Worker")
            .field("pid", &self.child.id())
            .finish_non_exhaustive()
    }
}

fn f64s_to_bytes(v: &[f64]) -> Vec<u8> {
    v.iter().flat_map(|x| x.to_le_bytes()).collect()
}

fn bytes_to_f64s(b: &[u8]) -> Vec<f64> {
    b.chunks_exact(8)
        .map(|c| f64::from_le_bytes(c.try_into().expect("8 bytes")))
        .collect()
}

/// Writes one frame.
pub fn write_frame(w: &mut impl Write, tag: u8, payload: &[u8]) -> std::io::Result<()> {
    let mut head = [0u8; 9];
    head[0] = tag;
    head[1..].copy_from_slice(&(payload.len() as u64).to_le_bytes());
    w.write_all(&head)?;
    w.write_all(payload)?;
    w.flush()
}

/// Reads one frame; `None` at a clean end of the stream.
pub fn read_frame(r: &mut impl Read) -> std::io::Result<Option<Frame>> {
    let mut head = [0u8; 9];
    let mut got = 0;
    while got < head.len() {
        match r.read(&mut head[got..])? {
            0 if got == 0 => return Ok(None),
            0 => return Err(std::io::ErrorKind::UnexpectedEof.into()),
            n => got += n,
        }
    }
    let len = u64::from_le_bytes(head[1..].try_into().expect("8 bytes"));
    if len > MAX_FRAME {
        return Err(std::io::Error::new(
            std::io::ErrorKind::InvalidData,
            format!("frame of {len} bytes"),
        ));
    }
    // Grown as the bytes come: a garbage length allocates nothing up front.
    let mut payload = Vec::new();
    r.take(len).read_to_end(&mut payload)?;
    if payload.len() as u64 != len {
        return Err(std::io::ErrorKind::UnexpectedEof.into());
    }
    Ok(Some((head[0], payload)))
}

/// A signal's name, for messages.
#[cfg(unix)]
fn signal_name(sig: i32) -> String {
    let name = match sig {
        libc::SIGSEGV => "SIGSEGV, a segmentation fault",
        libc::SIGABRT => "SIGABRT, abort()",
        libc::SIGBUS => "SIGBUS, a bus error",
        libc::SIGFPE => "SIGFPE, an arithmetic fault",
        libc::SIGILL => "SIGILL, an illegal instruction",
        libc::SIGKILL => "SIGKILL",
        libc::SIGTERM => "SIGTERM",
        libc::SIGINT => "SIGINT",
        libc::SIGHUP => "SIGHUP",
        libc::SIGPIPE => "SIGPIPE",
        _ => "",
    };
    if name.is_empty() {
        format!("signal {sig}")
    } else {
        format!("signal {sig} ({name})")
    }
}

/// How the worker ended: a description and whether it was stopped from outside (by a signal
/// that stops the driver too, while the driver is being stopped).
fn describe_exit(status: ExitStatus) -> (String, bool) {
    #[cfg(unix)]
    {
        use std::os::unix::process::ExitStatusExt;
        if let Some(sig) = status.signal() {
            let outside = [libc::SIGINT, libc::SIGTERM, libc::SIGHUP].contains(&sig)
                && super::guard::stop_requested_within(GRACE);
            return (
                format!(
                    "the worker process running the FMU was killed by {}",
                    signal_name(sig)
                ),
                outside,
            );
        }
    }
    match status.code() {
        Some(code) => (
            format!(
                "the worker process running the FMU exited with status {code} in the middle of \
                 the run (the FMU called exit()?)"
            ),
            false,
        ),
        None => (format!("the worker process ended ({status})"), false),
    }
}

impl Worker {
    /// Starts a worker and sends it `setup`.
    pub fn start(opts: &IsolateOptions, setup: &[u8]) -> Result<Worker, WorkerFailure> {
        let mut child = Command::new(&opts.exe)
            .arg("worker")
            .env("UQ_DRIVER_PARENT_PID", std::process::id().to_string())
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .map_err(|e| {
                WorkerFailure::Died(format!(
                    "cannot start a worker process ({}): {e}",
                    opts.exe.display()
                ))
            })?;
        let stdin = child.stdin.take();
        let mut stdout = child.stdout.take().expect("piped");
        let stderr = child.stderr.take().expect("piped");
        let (tx, frames) = mpsc::channel();
        std::thread::spawn(move || loop {
            let answer = match read_frame(&mut stdout) {
                Ok(Some(frame)) => Ok(frame),
                Ok(None) => break,
                Err(e) => Err(e.to_string()),
            };
            let end = answer.is_err();
            if tx.send(answer).is_err() || end {
                break;
            }
        });
        let tail = Arc::new(Mutex::new(Tail {
            lines: VecDeque::with_capacity(TAIL_LINES),
            partial: Vec::new(),
            last: Instant::now(),
        }));
        let (done_tx, stderr_done) = mpsc::channel();
        let t = Arc::clone(&tail);
        std::thread::spawn(move || {
            let mut stderr = stderr;
            let mut buf = [0u8; 8192];
            loop {
                match stderr.read(&mut buf) {
                    Ok(0) => break,
                    Ok(n) => t.lock().unwrap_or_else(|e| e.into_inner()).push(&buf[..n]),
                    Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
                    Err(_) => break,
                }
            }
            let _ = done_tx.send(());
        });
        let mut w = Worker {
            child,
            stdin,
            frames,
            tail,
            stderr_done,
        };
        match w.request(b'S', setup, opts.timeout, "starting")? {
            (b'R', _) => Ok(w),
            (b'E', msg) => Err(WorkerFailure::Died(
                String::from_utf8_lossy(&msg).into_owned(),
            )),
            (tag, _) => Err(w.protocol_error(tag)),
        }
    }

    /// Runs one point: its record values, or why there are none; with the reason of a failed
    /// `fmi2Reset` before it, if one failed.
    pub fn run(
        &mut self,
        values: &[f64],
        timeout: Option<Duration>,
    ) -> (Result<Vec<f64>, WorkerFailure>, Option<String>) {
        let mut note = None;
        let mut answer = self.request(b'P', &f64s_to_bytes(values), timeout, "running the point");
        while let Ok((b'N', why)) = &answer {
            note.get_or_insert_with(|| String::from_utf8_lossy(why).into_owned());
            answer = self.receive(timeout, "running the point");
        }
        (answer.and_then(|a| self.record(a)), note)
    }

    /// The record of a point's answer.
    fn record(&mut self, answer: Frame) -> Result<Vec<f64>, WorkerFailure> {
        match answer {
            (b'O', v) if v.len() % 8 == 0 => Ok(bytes_to_f64s(&v)),
            (b'O', v) => Err(self.malformed(
                &format!("a record of {} bytes", v.len()),
                "running the point",
            )),
            (b'F', msg) => Err(WorkerFailure::Point(
                String::from_utf8_lossy(&msg).into_owned(),
            )),
            // fmi2Fatal: this worker's copy of the FMU is unusable; the next point gets a new one.
            (b'X', msg) => Err(WorkerFailure::Died(
                String::from_utf8_lossy(&msg).into_owned(),
            )),
            (tag, _) => Err(self.protocol_error(tag)),
        }
    }

    /// The second half of the reset self-check: the point just run, again after `fmi2Reset`.
    /// Returns the verdict and whether the worker lives on, or the message of a worker stopped
    /// from outside (the driver is being stopped).
    pub fn check_reset(
        &mut self,
        values: &[f64],
        timeout: Option<Duration>,
    ) -> Result<(ResetCheck, bool), String> {
        let doing = "running the point again after fmi2Reset (the reset self-check)";
        Ok(
            match self.request(b'C', &f64s_to_bytes(values), timeout, doing) {
                Ok((b'V', v)) if !v.is_empty() => {
                    let why = String::from_utf8_lossy(&v[1..]).into_owned();
                    match v[0] {
                        0 => (ResetCheck::Passed, true),
                        1 => (ResetCheck::Failed(why), true),
                        _ => (ResetCheck::Failed(why), false),
                    }
                }
                Ok((tag, _)) => {
                    let WorkerFailure::Died(m) = self.protocol_error(tag) else {
                        unreachable!("protocol errors are deaths")
                    };
                    (ResetCheck::Failed(m), false)
                }
                Err(WorkerFailure::Interrupted(m)) => return Err(m),
                Err(WorkerFailure::Point(m) | WorkerFailure::Died(m)) => (
                    ResetCheck::Failed(format!(
                    "the FMU's run after fmi2Reset failed where a fresh instance's succeeded: {m}"
                )),
                    false,
                ),
            },
        )
    }

    fn protocol_error(&mut self, tag: u8) -> WorkerFailure {
        self.stop();
        WorkerFailure::Died(format!(
            "the worker process answered with an unknown frame '{}'",
            char::from(tag).escape_default()
        ))
    }

    /// Sends a frame and waits (at most `timeout`) for the answer. The worker's own end is
    /// watched (its exit status, polled), not the end of its pipes, which a program the FMU
    /// started may hold open; the watchdog stays armed until a well-formed answer arrives.
    fn request(
        &mut self,
        tag: u8,
        payload: &[u8],
        timeout: Option<Duration>,
        doing: &str,
    ) -> Result<Frame, WorkerFailure> {
        // The lines of earlier points are not this point's last words.
        {
            let mut t = self.tail.lock().unwrap_or_else(|e| e.into_inner());
            t.lines.clear();
            t.partial.clear();
        }
        // A write error means the worker is gone: the wait below reports how it ended.
        if let Some(stdin) = self.stdin.as_mut() {
            let _ = write_frame(stdin, tag, payload);
        }
        self.receive(timeout, doing)
    }

    /// Waits (at most `timeout`) for the worker's next frame.
    fn receive(&mut self, timeout: Option<Duration>, doing: &str) -> Result<Frame, WorkerFailure> {
        let deadline = timeout.map(|t| Instant::now() + t);
        // When the answer pipe reached its end while the worker still ran.
        let mut pipe_closed: Option<Instant> = None;
        loop {
            let now = Instant::now();
            if deadline.is_some_and(|d| now >= d) {
                self.stop();
                let t = timeout.expect("only with a timeout").as_secs_f64();
                return Err(WorkerFailure::Died(format!(
                    "the run took longer than --timeout-per-run {t} s and its worker process \
                     was killed while {doing}{}",
                    self.tail_text()
                )));
            }
            let slice = deadline.map_or(POLL, |d| POLL.min(d - now));
            let answer = if pipe_closed.is_some() {
                std::thread::sleep(slice);
                Err(RecvTimeoutError::Disconnected)
            } else {
                self.frames.recv_timeout(slice)
            };
            match answer {
                Ok(Ok(frame)) => return Ok(frame),
                Ok(Err(why)) => return Err(self.malformed(&why, doing)),
                Err(RecvTimeoutError::Disconnected) if pipe_closed.is_none() => {
                    pipe_closed = Some(Instant::now());
                }
                Err(_) => {}
            }
            match self.child.try_wait() {
                Ok(Some(status)) => {
                    // Its last frame (fmi2Fatal's 'X' comes just before the end) may still be
                    // in the pipe.
                    if pipe_closed.is_none() {
                        if let Ok(answer) = self.frames.recv_timeout(GRACE) {
                            return answer.map_err(|why| self.malformed(&why, doing));
                        }
                    }
                    return Err(self.ended(Ok(status), doing));
                }
                Ok(None) => {}
                Err(e) => return Err(self.ended(Err(e), doing)),
            }
            if pipe_closed.is_some_and(|t| t.elapsed() > GRACE) {
                self.stop();
                return Err(WorkerFailure::Died(format!(
                    "the worker process closed its answer pipe while {doing} (the FMU closed \
                     file descriptors it does not own?) and was stopped{}",
                    self.tail_text()
                )));
            }
        }
    }

    /// Kills the worker and waits for it.
    fn stop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }

    /// The failure of a worker whose answer was not a well-formed frame (it is stopped).
    fn malformed(&mut self, why: &str, doing: &str) -> WorkerFailure {
        self.stop();
        WorkerFailure::Died(format!(
            "the worker process sent a malformed answer ({why}) while {doing} (the FMU wrote \
             into its answer pipe?) and was stopped{}",
            self.tail_text()
        ))
    }

    /// The failure of a worker that ended by itself.
    fn ended(&mut self, status: std::io::Result<ExitStatus>, doing: &str) -> WorkerFailure {
        let (what, outside) = match status {
            Ok(s) => describe_exit(s),
            Err(e) => (format!("the worker process was lost: {e}"), false),
        };
        let message = format!("{what} while {doing}{}", self.tail_text());
        if outside {
            WorkerFailure::Interrupted(message)
        } else {
            WorkerFailure::Died(message)
        }
    }

    /// "; its last output: ..." from the worker's stderr, once it has been read to its end
    /// (or has been quiet for a moment: a program the FMU started may keep it open).
    fn tail_text(&self) -> String {
        let start = Instant::now();
        while start.elapsed() < Duration::from_secs(2) {
            if self.stderr_done.recv_timeout(POLL).is_ok() {
                break;
            }
            let last = self.tail.lock().unwrap_or_else(|e| e.into_inner()).last;
            // Quiet since the wait began too: the last bytes may not have been read yet.
            if last.elapsed().min(start.elapsed()) > Duration::from_millis(200) {
                break;
            }
        }
        let t = self.tail.lock().unwrap_or_else(|e| e.into_inner());
        let mut lines: Vec<String> = t.lines.iter().cloned().collect();
        if !t.partial.is_empty() {
            lines.push(String::from_utf8_lossy(&t.partial).into_owned());
        }
        if lines.len() > TAIL_LINES {
            lines.remove(0);
        }
        if lines.is_empty() {
            String::new()
        } else {
            format!("; its last output: {}", lines.join(" | "))
        }
    }
}

impl Drop for Worker {
    fn drop(&mut self) {
        // Closing stdin ends a worker that waits for a point; one still busy after a moment
        // (in an FMU call) is killed.
        drop(self.stdin.take());
        for _ in 0..50 {
            if !matches!(self.child.try_wait(), Ok(None)) {
                return;
            }
            std::thread::sleep(Duration::from_millis(2));
        }
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// Workers shared by the runner's threads: a point takes an idle one (or starts one) and gives
/// it back when its run ends normally.
#[derive(Debug)]
pub struct WorkerPool {
    opts: IsolateOptions,
    /// The setup new workers get (JSON), and what it says.
    setup: Mutex<(Setup, Vec<u8>)>,
    idle: Mutex<Vec<Worker>>,
    /// Why a worker's `fmi2Reset` failed, since the last [`WorkerPool::take_reset_failure`].
    reset_failure: Mutex<Option<String>>,
}

impl WorkerPool {
    /// A pool that starts workers for `setup`.
    pub fn new(opts: IsolateOptions, setup: &Setup) -> WorkerPool {
        let json = serde_json::to_vec(setup).expect("serializable");
        WorkerPool {
            opts,
            setup: Mutex::new((setup.clone(), json)),
            idle: Mutex::new(Vec::new()),
            reset_failure: Mutex::new(None),
        }
    }

    /// Whether workers started from now on reuse instances (the reset self-check's verdict;
    /// the worker that ran the check knows it already).
    pub fn set_reuse(&self, reuse: bool) {
        let mut setup = self.setup.lock().unwrap_or_else(|e| e.into_inner());
        setup.0.policy.reuse = reuse;
        setup.1 = serde_json::to_vec(&setup.0).expect("serializable");
    }

    fn take_idle(&self) -> Option<Worker> {
        self.idle.lock().unwrap_or_else(|e| e.into_inner()).pop()
    }

    fn give_back(&self, worker: Worker) {
        self.idle
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .push(worker);
    }

    /// Runs one point in a worker.
    pub fn run(&self, values: &[f64]) -> Result<Vec<f64>, WorkerFailure> {
        let mut worker = match self.take_idle() {
            Some(w) => w,
            None => {
                let setup = self
                    .setup
                    .lock()
                    .unwrap_or_else(|e| e.into_inner())
                    .1
                    .clone();
                Worker::start(&self.opts, &setup)?
            }
        };
        let (result, note) = worker.run(values, self.opts.timeout);
        if let Some(why) = note {
            self.reset_failure
                .lock()
                .unwrap_or_else(|e| e.into_inner())
                .get_or_insert(why);
        }
        if matches!(result, Ok(_) | Err(WorkerFailure::Point(_))) {
            self.give_back(worker);
        }
        result
    }

    /// The reset self-check's second run, of the point `values` the pool has just run (alone)
    /// successfully, in the worker that ran it; `Err` when the worker was stopped from outside
    /// (the driver is being stopped).
    pub fn check_reset(&self, values: &[f64]) -> Result<ResetCheck, String> {
        let Some(mut worker) = self.take_idle() else {
            return Ok(ResetCheck::NotRun);
        };
        let (check, lives) = worker.check_reset(values, self.opts.timeout)?;
        if lives {
            self.give_back(worker);
        }
        Ok(check)
    }

    /// Why a worker's `fmi2Reset` failed (its point then ran on a fresh instance), once.
    pub fn take_reset_failure(&self) -> Option<String> {
        self.reset_failure
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .take()
    }
}

// ------------------------------------------------------------------------------------------
// The worker side.

/// Makes the protocol channel safe from the FMU: moves the worker's stdin and stdout (the
/// pipes to the parent) to descriptors at or above [`PROTOCOL_FD_MIN`], close-on-exec, and
/// points descriptor 0 at /dev/null and descriptor 1 at stderr, so that whatever the FMU
/// prints goes to stderr, a write to a low descriptor misses the pipes and a program the FMU
/// starts does not inherit them. Returns (input, output).
#[cfg(unix)]
fn protocol_fds() -> std::io::Result<(std::fs::File, std::fs::File)> {
    use std::os::fd::FromRawFd;
    let last = std::io::Error::last_os_error;
    // SAFETY: fcntl(F_DUPFD_CLOEXEC) on the process's own stdout/stdin; results are checked.
    let out = unsafe { libc::fcntl(1, libc::F_DUPFD_CLOEXEC, PROTOCOL_FD_MIN) };
    if out < 0 {
        return Err(last());
    }
    // SAFETY: `out` is a fresh descriptor owned by nothing else.
    let out = unsafe { std::fs::File::from_raw_fd(out) };
    // SAFETY: as above, for stdin.
    let input = unsafe { libc::fcntl(0, libc::F_DUPFD_CLOEXEC, PROTOCOL_FD_MIN) };
    if input < 0 {
        return Err(last());
    }
    // SAFETY: `input` is a fresh descriptor owned by nothing else.
    let input = unsafe { std::fs::File::from_raw_fd(input) };
    // SAFETY: 2 and 1 are the process's own stderr and stdout; nothing in this process holds a
    // Rust handle that relies on fd 1 staying the pipe (only `out` is used for the protocol).
    if unsafe { libc::dup2(2, 1) } < 0 {
        return Err(last());
    }
    let null = std::fs::File::open("/dev/null")?;
    // SAFETY: `null` is an open descriptor; fd 0 is the process's stdin, which nothing reads
    // any more (the protocol reads `input`).
    if unsafe { libc::dup2(std::os::fd::AsRawFd::as_raw_fd(&null), 0) } < 0 {
        return Err(last());
    }
    Ok((input, out))
}

/// Ignores SIGINT and, on Linux, asks to be killed when the parent dies.
#[cfg(unix)]
fn detach_from_terminal_signals() {
    // SAFETY: setting SIGINT's disposition to ignore is async-signal-safe and affects only this
    // process.
    unsafe {
        libc::signal(libc::SIGINT, libc::SIG_IGN);
    }
    #[cfg(target_os = "linux")]
    {
        // SAFETY: PR_SET_PDEATHSIG with a valid signal number; no pointers involved.
        unsafe {
            libc::prctl(libc::PR_SET_PDEATHSIG, libc::SIGKILL);
        }
        // The parent may have died before the prctl: then nobody reads our answers.
        let expected = std::env::var("UQ_DRIVER_PARENT_PID")
            .ok()
            .and_then(|p| p.parse::<i32>().ok());
        // SAFETY: getppid has no preconditions.
        let parent = unsafe { libc::getppid() };
        if expected.is_some_and(|p| p != parent) {
            std::process::exit(0);
        }
    }
}

/// The `uq-driver worker` subcommand: serves points until stdin closes. Returns the exit
/// status.
#[cfg(unix)]
pub fn serve() -> i32 {
    detach_from_terminal_signals();
    let (mut input, mut out) = match protocol_fds() {
        Ok((i, o)) => (BufReader::new(i), std::io::BufWriter::new(o)),
        Err(e) => {
            eprintln!("uq-driver worker: {e}");
            return 1;
        }
    };
    let setup: Setup = match read_frame(&mut input) {
        Ok(Some((b'S', payload))) => match serde_json::from_slice(&payload) {
            Ok(s) => s,
            Err(e) => {
                let _ = write_frame(&mut out, b'E', format!("bad setup: {e}").as_bytes());
                return 1;
            }
        },
        _ => {
            eprintln!("uq-driver worker: expected a setup frame on stdin");
            return 1;
        }
    };
    let fmu = match Fmu::open_extracted(&setup.fmu_root, &setup.fmu_shown) {
        Ok(f) => f,
        Err(e) => {
            let _ = write_frame(&mut out, b'E', e.to_string().as_bytes());
            return 1;
        }
    };
    if write_frame(&mut out, b'R', &[]).is_err() {
        return 1;
    }
    // The FMU's messages go to stderr, where the parent keeps the last lines.
    let mut slot = Slot::new(setup.policy, true);
    // The last point run successfully: its values and record (for the reset self-check).
    let mut last: Option<(Vec<f64>, Vec<f64>)> = None;
    while let Ok(Some((tag, payload))) = read_frame(&mut input) {
        let values = bytes_to_f64s(&payload);
        let sent = match tag {
            b'P' => {
                let result = run_point(&fmu, &mut slot, &setup.interface, &values, &setup.times);
                if let Some(why) = slot.take_reset_failure() {
                    if write_frame(&mut out, b'N', why.as_bytes()).is_err() {
                        return 1;
                    }
                }
                last = None;
                match result {
                    Ok(v) => {
                        let sent = write_frame(&mut out, b'O', &f64s_to_bytes(&v));
                        last = Some((values, v));
                        sent
                    }
                    Err(e) if fmu.is_unusable() => {
                        let _ = write_frame(&mut out, b'X', e.to_string().as_bytes());
                        return 0;
                    }
                    Err(e) => write_frame(&mut out, b'F', e.to_string().as_bytes()),
                }
            }
            b'C' => {
                let (check, _) = match &last {
                    Some((v, first)) if *v == values => {
                        check_reset(&fmu, &mut slot, &setup.interface, v, &setup.times, first)
                    }
                    _ => (ResetCheck::Failed("no run to compare with".into()), None),
                };
                let ends = fmu.is_unusable();
                let (code, why) = match check {
                    ResetCheck::Passed => (0, String::new()),
                    ResetCheck::Failed(why) => (if ends { 2 } else { 1 }, why),
                    ResetCheck::NotRun => (1, "not run".to_owned()),
                };
                let mut payload = vec![code];
                payload.extend_from_slice(why.as_bytes());
                let sent = write_frame(&mut out, b'V', &payload);
                if ends {
                    return 0;
                }
                sent
            }
            _ => {
                eprintln!("uq-driver worker: unexpected frame '{}'", char::from(tag));
                return 1;
            }
        };
        if sent.is_err() {
            return 1;
        }
    }
    0
}

/// The `uq-driver worker` subcommand (not available on this platform).
#[cfg(not(unix))]
pub fn serve() -> i32 {
    eprintln!("uq-driver worker: --isolate is supported on Unix only");
    1
}

/// The worker setup of a study on `fmu`, whose runs get their instance by `policy`.
pub fn setup(fmu: &Fmu, iface: &Interface, times: &[f64], policy: InstancePolicy) -> Setup {
    Setup {
        fmu_root: fmu.root().to_path_buf(),
        fmu_shown: fmu.path().to_path_buf(),
        interface: iface.clone(),
        times: times.to_vec(),
        policy,
    }
}

/// The uq-driver executable to start workers from: `$UQ_DRIVER_EXE` if set, else this
/// program.
pub fn default_exe() -> std::io::Result<PathBuf> {
    match std::env::var_os("UQ_DRIVER_EXE") {
        Some(p) => Ok(PathBuf::from(p)),
        None => std::env::current_exe(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frames_round_trip_and_a_torn_frame_is_an_error() {
        let mut buf = Vec::new();
        write_frame(&mut buf, b'P', &f64s_to_bytes(&[1.5, -0.0, f64::NAN])).unwrap();
        write_frame(&mut buf, b'R', &[]).unwrap();
        let mut r = &buf[..];
        let (tag, p) = read_frame(&mut r).unwrap().unwrap();
        assert_eq!(tag, b'P');
        let v = bytes_to_f64s(&p);
        assert_eq!(v[0], 1.5);
        assert!(v[1] == 0.0 && v[1].is_sign_negative());
        assert!(v[2].is_nan());
        assert_eq!(read_frame(&mut r).unwrap(), Some((b'R', Vec::new())));
        assert_eq!(read_frame(&mut r).unwrap(), None);
        let torn = &buf[..12];
        assert!(read_frame(&mut &torn[..]).is_err());
        let mut huge = vec![b'O'];
        huge.extend_from_slice(&u64::MAX.to_le_bytes());
        assert!(read_frame(&mut &huge[..]).is_err());
    }

    /// A fake worker: a shell script that reads the setup, answers "ready", then `then`.
    #[cfg(unix)]
    fn fake_worker(dir: &std::path::Path, then: &str) -> IsolateOptions {
        use std::os::unix::fs::PermissionsExt;
        let exe = dir.join("fake-worker");
        std::fs::write(
            &exe,
            format!(
                "#!/bin/sh\nhead -c 9 >/dev/null\nprintf 'R\\0\\0\\0\\0\\0\\0\\0\\0'\n{then}\n"
            ),
        )
        .unwrap();
        std::fs::set_permissions(&exe, std::fs::Permissions::from_mode(0o755)).unwrap();
        IsolateOptions {
            exe,
            timeout: Some(Duration::from_secs(2)),
        }
    }

    #[cfg(unix)]
    #[test]
    fn a_malformed_answer_fails_the_point_and_a_torn_one_is_stopped_by_the_watchdog() {
        // QA finding 6: stray bytes on the answer pipe hung the driver forever.
        let dir = tempfile::tempdir().unwrap();
        // A length far beyond any frame: refused at once.
        let opts = fake_worker(dir.path(), "printf 'garbage12345'; sleep 30");
        let mut w = Worker::start(&opts, b"{}").unwrap_or_else(|_| panic!("starts"));
        let t0 = Instant::now();
        match w.run(&[1.0], opts.timeout).0 {
            Err(WorkerFailure::Died(m)) => assert!(m.contains("malformed answer"), "{m}"),
            other => panic!("{other:?}"),
        }
        assert!(t0.elapsed() < Duration::from_secs(2));
        // A plausible length whose bytes never come: the watchdog still fires.
        let opts = fake_worker(
            dir.path(),
            "printf 'O\\20\\0\\0\\0\\0\\0\\0\\0abc'; sleep 30",
        );
        let mut w = Worker::start(&opts, b"{}").unwrap_or_else(|_| panic!("starts"));
        match w.run(&[1.0], opts.timeout).0 {
            Err(WorkerFailure::Died(m)) => assert!(m.contains("--timeout-per-run"), "{m}"),
            other => panic!("{other:?}"),
        }
    }

    #[cfg(unix)]
    #[test]
    fn a_dead_worker_is_noticed_though_a_process_it_started_keeps_its_pipes_open() {
        // QA finding 7: only the end of the pipes was noticed.
        let dir = tempfile::tempdir().unwrap();
        let mut opts = fake_worker(dir.path(), "sleep 20 & kill -SEGV $$");
        opts.timeout = None;
        let mut w = Worker::start(&opts, b"{}").unwrap_or_else(|_| panic!("starts"));
        let t0 = Instant::now();
        match w.run(&[1.0], None).0 {
            Err(WorkerFailure::Died(m)) => assert!(m.contains("SIGSEGV"), "{m}"),
            other => panic!("{other:?}"),
        }
        assert!(t0.elapsed() < Duration::from_secs(5), "{:?}", t0.elapsed());
    }
}
