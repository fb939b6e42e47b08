//! `--isolate`: each point runs in a worker process, so that an FMU that segfaults, aborts,
//! calls `exit()` or blocks fails that point instead of taking the driver with it.
//!
//! A worker is the uq-driver executable started with the hidden subcommand `worker`
//! ([`serve`]). It opens the FMU from the folder the parent already extracted, creates one
//! instance, and runs points one after the other exactly as the in-process runner does
//! ([`run_point`]), so results are bit-identical. Parent and worker speak a small binary
//! protocol over the worker's stdin and stdout (the worker moves its own stdout to stderr
//! first, so an FMU that prints cannot garble it): frames of a tag byte, a little-endian u64
//! length and the payload.
//!
//! | tag | from | payload |
//! | --- | --- | --- |
//! | `S` | parent | the setup, JSON ([`Setup`]) |
//! | `P` | parent | a point's parameter values, f64 LE |
//! | `R` | worker | ready (empty) |
//! | `O` | worker | the point's record values, f64 LE |
//! | `F` | worker | the point failed: the message, UTF-8 |
//! | `X` | worker | the point failed and the FMU is unusable (fmi2Fatal): the worker ends |
//! | `E` | worker | the setup failed: the message, UTF-8 |
//!
//! What the worker writes to stderr (the FMU's log messages, which the worker echoes, and
//! anything the FMU prints) is kept by the parent, the last lines of it going into the message
//! of a point whose worker died. A worker that dies (signal or exit) or outlives
//! `--timeout-per-run` (then it is killed) fails its point; the next point starts a new worker.
//! A worker killed by SIGINT, SIGTERM or SIGHUP from outside (Ctrl-C, `kill`, `scancel`)
//! fails nothing: the study stops and a re-run computes the point. Workers ignore SIGINT (the
//! terminal sends it to the whole process group; the parent handles it) and, on Linux, are
//! killed when the parent dies.

use std::collections::VecDeque;
use std::io::{BufRead, BufReader, Read, Write};
use std::path::PathBuf;
use std::process::{Child, ChildStdin, Command, ExitStatus, Stdio};
use std::sync::mpsc::{self, Receiver, RecvTimeoutError};
use std::sync::{Arc, Mutex};
use std::time::Duration;

use serde::{Deserialize, Serialize};

use super::interface::Interface;
use super::runner::run_point;
use crate::fmu::{Fmu, Instance};

/// How many of a worker's last stderr lines a failure message quotes.
const TAIL_LINES: usize = 12;
/// Largest frame accepted (bytes): far above any record, small enough to refuse garbage.
const MAX_FRAME: u64 = 1 << 34;

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

/// A running worker process.
pub struct Worker {
    child: Child,
    stdin: Option<ChildStdin>,
    frames: Receiver<Frame>,
    tail: Arc<Mutex<VecDeque<String>>>,
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
    let mut payload = vec![0u8; len as usize];
    r.read_exact(&mut payload)?;
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

/// How the worker ended: a description and whether it was stopped from outside.
fn describe_exit(status: ExitStatus) -> (String, bool) {
    #[cfg(unix)]
    {
        use std::os::unix::process::ExitStatusExt;
        if let Some(sig) = status.signal() {
            let outside = [libc::SIGINT, libc::SIGTERM, libc::SIGHUP].contains(&sig);
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
        std::thread::spawn(move || {
            while let Ok(Some(frame)) = read_frame(&mut stdout) {
                if tx.send(frame).is_err() {
                    break;
                }
            }
        });
        let tail = Arc::new(Mutex::new(VecDeque::with_capacity(TAIL_LINES)));
        let (done_tx, stderr_done) = mpsc::channel();
        let t = Arc::clone(&tail);
        std::thread::spawn(move || {
            for line in BufReader::new(stderr).lines().map_while(Result::ok) {
                let mut t = t.lock().unwrap_or_else(|e| e.into_inner());
                if t.len() == TAIL_LINES {
                    t.pop_front();
                }
                t.push_back(line);
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

    /// Runs one point: its record values, or why there are none.
    pub fn run(
        &mut self,
        values: &[f64],
        timeout: Option<Duration>,
    ) -> Result<Vec<f64>, WorkerFailure> {
        match self.request(b'P', &f64s_to_bytes(values), timeout, "running the point")? {
            (b'O', v) => Ok(bytes_to_f64s(&v)),
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

    fn protocol_error(&mut self, tag: u8) -> WorkerFailure {
        let _ = self.child.kill();
        let _ = self.child.wait();
        WorkerFailure::Died(format!(
            "the worker process answered with an unknown frame '{}'",
            char::from(tag).escape_default()
        ))
    }

    /// Sends a frame and waits (at most `timeout`) for the answer.
    fn request(
        &mut self,
        tag: u8,
        payload: &[u8],
        timeout: Option<Duration>,
        doing: &str,
    ) -> Result<Frame, WorkerFailure> {
        // The lines of earlier points are not this point's last words.
        self.tail.lock().unwrap_or_else(|e| e.into_inner()).clear();
        // A write error means the worker is gone: the receive below reports how it ended.
        if let Some(stdin) = self.stdin.as_mut() {
            let _ = write_frame(stdin, tag, payload);
        }
        let answer = match timeout {
            Some(t) => self.frames.recv_timeout(t),
            None => self
                .frames
                .recv()
                .map_err(|_| RecvTimeoutError::Disconnected),
        };
        match answer {
            Ok(frame) => Ok(frame),
            Err(RecvTimeoutError::Timeout) => {
                let _ = self.child.kill();
                let _ = self.child.wait();
                let t = timeout.expect("only with a timeout").as_secs_f64();
                Err(WorkerFailure::Died(format!(
                    "the run took longer than --timeout-per-run {t} s and its worker process \
                     was killed while {doing}{}",
                    self.tail_text()
                )))
            }
            Err(RecvTimeoutError::Disconnected) => {
                let status = self.child.wait();
                let (what, outside) = match status {
                    Ok(s) => describe_exit(s),
                    Err(e) => (format!("the worker process was lost: {e}"), false),
                };
                let message = format!("{what} while {doing}{}", self.tail_text());
                Err(if outside {
                    WorkerFailure::Interrupted(message)
                } else {
                    WorkerFailure::Died(message)
                })
            }
        }
    }

    /// "; its last output: ..." from the worker's stderr, once it has been read to its end.
    fn tail_text(&self) -> String {
        let _ = self.stderr_done.recv_timeout(Duration::from_secs(2));
        let t = self.tail.lock().unwrap_or_else(|e| e.into_inner());
        if t.is_empty() {
            String::new()
        } else {
            format!(
                "; its last output: {}",
                t.iter().cloned().collect::<Vec<_>>().join(" | ")
            )
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
    setup: Vec<u8>,
    idle: Mutex<Vec<Worker>>,
}

impl WorkerPool {
    /// A pool that starts workers for `setup`.
    pub fn new(opts: IsolateOptions, setup: &Setup) -> WorkerPool {
        WorkerPool {
            opts,
            setup: serde_json::to_vec(setup).expect("serializable"),
            idle: Mutex::new(Vec::new()),
        }
    }

    /// Runs one point in a worker.
    pub fn run(&self, values: &[f64]) -> Result<Vec<f64>, WorkerFailure> {
        let idle = self.idle.lock().unwrap_or_else(|e| e.into_inner()).pop();
        let mut worker = match idle {
            Some(w) => w,
            None => Worker::start(&self.opts, &self.setup)?,
        };
        let result = worker.run(values, self.opts.timeout);
        if matches!(result, Ok(_) | Err(WorkerFailure::Point(_))) {
            self.idle
                .lock()
                .unwrap_or_else(|e| e.into_inner())
                .push(worker);
        }
        result
    }
}

// ------------------------------------------------------------------------------------------
// The worker side.

/// Makes the protocol channel safe from the FMU: returns a handle on the original stdout and
/// points file descriptor 1 at stderr, so that whatever the FMU prints goes to stderr.
#[cfg(unix)]
fn protocol_out() -> std::io::Result<std::fs::File> {
    use std::os::fd::FromRawFd;
    // SAFETY: dup of the process's stdout; a negative result is checked.
    let fd = unsafe { libc::dup(1) };
    if fd < 0 {
        return Err(std::io::Error::last_os_error());
    }
    // SAFETY: 2 and 1 are the process's own stderr and stdout; nothing in this process holds a
    // Rust handle that relies on fd 1 staying the pipe (only `fd` is used for the protocol).
    if unsafe { libc::dup2(2, 1) } < 0 {
        return Err(std::io::Error::last_os_error());
    }
    // SAFETY: `fd` is a fresh descriptor owned by nothing else.
    Ok(unsafe { std::fs::File::from_raw_fd(fd) })
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
    let mut out = match protocol_out() {
        Ok(f) => std::io::BufWriter::new(f),
        Err(e) => {
            eprintln!("uq-driver worker: {e}");
            return 1;
        }
    };
    let mut input = std::io::stdin().lock();
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
    let mut slot: Option<Instance> = None;
    while let Ok(Some((tag, payload))) = read_frame(&mut input) {
        if tag != b'P' {
            eprintln!("uq-driver worker: unexpected frame '{}'", char::from(tag));
            return 1;
        }
        if slot.is_none() {
            // The FMU's messages go to stderr, where the parent keeps the last lines.
            if let Ok(inst) = fmu.instantiate("uq-driver", false) {
                inst.set_log_echo(true);
                slot = Some(inst);
            }
        }
        let values = bytes_to_f64s(&payload);
        let sent = match run_point(&fmu, &mut slot, &setup.interface, &values, &setup.times) {
            Ok(v) => write_frame(&mut out, b'O', &f64s_to_bytes(&v)),
            Err(e) if fmu.is_unusable() => {
                let _ = write_frame(&mut out, b'X', e.to_string().as_bytes());
                return 0;
            }
            Err(e) => write_frame(&mut out, b'F', e.to_string().as_bytes()),
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

/// The worker setup of a study on `fmu`.
pub fn setup(fmu: &Fmu, iface: &Interface, times: &[f64]) -> Setup {
    Setup {
        fmu_root: fmu.root().to_path_buf(),
        fmu_shown: fmu.path().to_path_buf(),
        interface: iface.clone(),
        times: times.to_vec(),
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
}
