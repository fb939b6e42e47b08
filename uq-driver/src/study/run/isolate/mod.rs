//! `--isolate`: each point runs in a worker process, so that an FMU that segfaults, aborts,
//! calls `exit()` or blocks fails that point instead of taking the driver with it.
//!
//! A worker is the uq-driver executable started with the hidden subcommand `worker`
//! ([`serve`], `serve.rs`). It opens the FMU from the folder the parent already extracted,
//! creates one instance at a time, and runs points one after the other exactly as the
//! in-process runner does ([`run_point`](crate::study::run::point::run_point); fresh or reset
//! instances by the setup's [`InstancePolicy`], and the reset self-check of
//! [`super::instances`] when the parent asks), so results are bit-identical. The parent's
//! side of one worker is [`Worker`] (`worker.rs`), shared by the runner's threads through
//! [`WorkerPool`]. Parent and worker speak a small binary
//! protocol over the worker's stdin and stdout (the worker moves its own stdout to stderr
//! first, so an FMU that prints cannot garble it): frames of a tag byte, a little-endian u64
//! length and the payload (`protocol.rs`).
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

mod protocol;
mod serve;
mod worker;

use std::path::PathBuf;
use std::sync::Mutex;
use std::time::Duration;

use serde::{Deserialize, Serialize};

use super::instances::{InstancePolicy, ResetCheck};
use crate::fmu::Fmu;
use crate::study::plan::interface::Interface;

pub use serve::serve;
pub use worker::Worker;

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

/// The uq-driver executable to start workers (and Slurm's shard jobs) from: `$UQ_DRIVER_EXE`
/// if set, else this program. A host whose program is not uq-driver (the Python package)
/// sets `$UQ_DRIVER_EXE` to its own command line.
pub fn default_exe() -> std::io::Result<PathBuf> {
    match std::env::var_os("UQ_DRIVER_EXE") {
        Some(p) => Ok(PathBuf::from(p)),
        None => std::env::current_exe(),
    }
}
