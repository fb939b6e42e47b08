//! The parent's side of a worker process: starting it, sending it points and reading its
//! answers, its stderr tail, and noticing its death or a run past the time limit.

use std::collections::VecDeque;
use std::io::Read;
use std::process::{Child, ChildStdin, Command, ExitStatus, Stdio};
use std::sync::mpsc::{self, Receiver, RecvTimeoutError};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use super::protocol::{bytes_to_f64s, f64s_to_bytes, read_frame, write_frame, Frame};
use super::{IsolateOptions, WorkerFailure};
use crate::study::run::instances::ResetCheck;

/// How many of a worker's last stderr lines a failure message quotes.
const TAIL_LINES: usize = 12;
/// How often a waiting parent checks whether its worker is still alive.
const POLL: Duration = Duration::from_millis(20);
/// How long the parent waits for the last frames and output of a worker that has ended, and
/// for a worker that closed its answer pipe to end.
const GRACE: Duration = Duration::from_millis(500);

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
                && crate::study::run::guard::stop_requested_within(GRACE);
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

#[cfg(test)]
mod tests {
    use super::*;

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
        // Stray bytes on the answer pipe hung the driver forever.
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
        // Only the end of the pipes was noticed.
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
