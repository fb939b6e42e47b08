//! The command line's arguments (clap).

use std::path::PathBuf;

use anyhow::{Context, Result};
use clap::{Args, Parser, Subcommand};

use crate::study::RunOptions;

#[derive(Parser)]
#[command(
    name = "uq-driver",
    version,
    about = "Propagate parameter uncertainty through FMI 2.0 Co-Simulation FMUs"
)]
pub(crate) struct Cli {
    #[command(subcommand)]
    pub(crate) command: Command,
}

#[derive(Subcommand)]
pub(crate) enum Command {
    /// Run a study (a TOML file or builtin:NAME) and write its results to --out.
    Run(RunArgs),
    /// Split a study into shards for a cluster: writes DIR/plan.json and DIR/design.csv.
    Plan {
        /// Study file, or builtin:NAME.
        study: String,
        /// Number of shards.
        #[arg(long)]
        shards: usize,
        /// Plan folder.
        #[arg(long, short)]
        out: PathBuf,
        /// Plan a large study (more than 100 000 runs, or much memory or time) anyway.
        #[arg(long)]
        yes: bool,
    },
    /// Run one shard of a plan (resumable); K defaults to $SLURM_ARRAY_TASK_ID.
    RunShard {
        /// Plan folder.
        dir: PathBuf,
        /// Shard number (0-based).
        #[arg(long)]
        shard: Option<usize>,
        /// Worker threads (default: all cores).
        #[arg(long, short, value_parser = parse_threads)]
        threads: Option<usize>,
        /// MC, LHS, QMC, pce_regression, sobol_sampling: continue past failed points (collocation and sparse grids stop: they cannot leave a point out).
        #[arg(long)]
        allow_failures: bool,
        #[command(flatten)]
        safety: SafetyArgs,
    },
    /// Check a plan's shards (every point exactly once, same study and FMU) and write the
    /// study's outputs, as `run` would.
    Merge {
        /// Plan folder.
        dir: PathBuf,
        /// Output folder (default DIR/result).
        #[arg(long, short)]
        out: Option<PathBuf>,
        /// MC, LHS, QMC, pce_regression, sobol_sampling: accept failed points and report how many (collocation and sparse grids stop: they cannot leave a point out).
        #[arg(long)]
        allow_failures: bool,
        /// Write the CSV files and summary.json only: no plots, no index.html (as `run`).
        #[arg(long)]
        no_report: bool,
        /// Analyse a study that needs much memory without asking (as `run --yes`).
        #[arg(long)]
        yes: bool,
    },
    /// Plan a study and submit it to Slurm: a job array of shards and a dependent merge job.
    Slurm(SlurmArgs),
    /// List the built-in studies.
    List,
    /// Print a built-in study's TOML (a starting point for your own).
    Show {
        /// builtin:NAME or NAME.
        name: String,
    },
    /// Print an FMU's variables and capabilities.
    Inspect {
        /// The .fmu file.
        fmu: PathBuf,
    },
    /// Run an FMU once at given parameter values and write its outputs as CSV.
    Simulate(SimulateArgs),
    /// Compare finished study folders on one page: DIR/index.html with a table of the
    /// studies and their outputs and quantities side by side.
    Compare {
        /// Study (or suite) folders written by `run`.
        #[arg(required = true)]
        dirs: Vec<PathBuf>,
        /// Folder of the page.
        #[arg(long, short)]
        out: PathBuf,
    },
    /// Write every run's time series of a finished study folder: DIR/runs/runs.csv (long
    /// format run,time,<outputs>) and DIR/runs/runs.npz (NumPy arrays).
    Export {
        /// Study folder written by `run`.
        dir: PathBuf,
        /// Every run's time series (the only export so far).
        #[arg(long)]
        runs: bool,
        /// Folder of the files (default DIR/runs).
        #[arg(long, short)]
        out: Option<PathBuf>,
    },
    /// Serve points to a parent uq-driver (`--isolate`) over stdin/stdout.
    #[command(hide = true)]
    Worker,
    /// Evaluate or sample the chaos surrogate a study exported (DIR/surrogate.json).
    #[command(subcommand)]
    Surrogate(SurrogateCommand),
}

#[derive(Subcommand)]
pub(crate) enum SurrogateCommand {
    /// The surrogate at one point, as CSV `name,time,value` (time empty for a scalar
    /// quantity); inputs not given take their nominal value.
    Eval {
        /// Study output folder (with surrogate.json), or the file itself.
        dir: PathBuf,
        /// Input value, NAME=VALUE (repeatable).
        #[arg(long = "at", value_parser = parse_number_assignment)]
        at: Vec<(String, f64)>,
        /// CSV file to write (default, or `-`: standard output; a device or a named pipe is
        /// written into, never replaced).
        #[arg(long, short)]
        out: Option<PathBuf>,
    },
    /// N random draws of the inputs (their joint law, correlation included) with the
    /// surrogate's values: CSV with the inputs, the scalar quantities and each output at the
    /// chosen times (`NAME@TIME`).
    Sample {
        /// Study output folder (with surrogate.json), or the file itself.
        dir: PathBuf,
        /// Number of draws.
        #[arg(short = 'n', long)]
        n: usize,
        /// Seed (draw i comes from the stream (seed, i) only).
        #[arg(long, default_value_t = 0)]
        seed: u64,
        /// Output times to write, s (repeatable; the nearest communication point; default:
        /// the last).
        #[arg(long = "time")]
        times: Vec<f64>,
        /// CSV file to write (default, or `-`: standard output; a device or a named pipe is
        /// written into, never replaced).
        #[arg(long, short)]
        out: Option<PathBuf>,
    },
}

#[derive(Args)]
pub(crate) struct RunArgs {
    /// Study file, or builtin:NAME or just NAME (see `uq-driver list`).
    pub(crate) study: String,
    /// Output folder (re-running into the same folder resumes an interrupted study).
    #[arg(long, short)]
    pub(crate) out: PathBuf,
    /// Worker threads (default: all cores).
    #[arg(long, short, value_parser = parse_threads)]
    pub(crate) threads: Option<usize>,
    /// MC, LHS, QMC, pce_regression, sobol_sampling: continue past failed points and report how many failed (collocation and sparse grids stop: they cannot leave a point out).
    #[arg(long)]
    pub(crate) allow_failures: bool,
    /// Discard earlier results in --out instead of resuming.
    #[arg(long)]
    pub(crate) fresh: bool,
    /// Stop after this many new points (the study can be resumed later).
    #[arg(long, hide = true)]
    pub(crate) max_points: Option<usize>,
    /// Start a large study (more than 100 000 runs, or much memory or time) without asking.
    #[arg(long)]
    pub(crate) yes: bool,
    /// Write the CSV files and summary.json only: no plots, no index.html.
    #[arg(long)]
    pub(crate) no_report: bool,
    /// The seed of every random stream, instead of the study file's `seed`.
    #[arg(long, value_name = "N")]
    pub(crate) seed: Option<u64>,
    /// Set a study-file key before the study is validated: a dotted path and a TOML value,
    /// e.g. method.order=3, parameters.k1.std=0.1, 'method.kind="lhs"' (repeatable; kept in
    /// the stored study).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub(crate) set: Vec<String>,
    #[command(flatten)]
    pub(crate) safety: SafetyArgs,
}

impl RunArgs {
    /// The `--set` settings, then `--seed` as `seed=N`.
    pub(crate) fn settings(&self) -> Vec<String> {
        let mut sets = self.set.clone();
        sets.extend(self.seed.map(|n| format!("seed={n}")));
        sets
    }
}

/// How points are run: isolation, time limit, retries.
#[derive(Args)]
pub(crate) struct SafetyArgs {
    /// Run each point in a worker process: an FMU that crashes, aborts, calls exit() or
    /// outlives --timeout-per-run fails its point instead of ending the study.
    #[arg(long)]
    pub(crate) isolate: bool,
    /// Longest a run may take (s). With --isolate the run is killed and fails its point;
    /// in-process the study stops with a message naming the point.
    #[arg(long, value_name = "SECONDS", value_parser = parse_timeout)]
    pub(crate) timeout_per_run: Option<std::time::Duration>,
    /// Run again the points that failed in an earlier run into the same folder.
    #[arg(long)]
    pub(crate) retry_failed: bool,
    /// Run every point on a fresh FMU instance (fmi2FreeInstance, then fmi2Instantiate)
    /// instead of reusing one through fmi2Reset.
    #[arg(long)]
    pub(crate) fresh_instances: bool,
    /// Instantiate the FMU with loggingOn = true (many FMUs log only then); its messages are
    /// kept with failed points.
    #[arg(long)]
    pub(crate) fmu_logging: bool,
}

impl SafetyArgs {
    /// The same options as `run-shard` arguments (for the Slurm array job).
    pub(crate) fn as_args(&self) -> Vec<String> {
        let mut v = Vec::new();
        if self.isolate {
            v.push("--isolate".to_owned());
        }
        if let Some(t) = self.timeout_per_run {
            v.push(format!("--timeout-per-run={}", t.as_secs_f64()));
        }
        for (on, flag) in [
            (self.retry_failed, "--retry-failed"),
            (self.fresh_instances, "--fresh-instances"),
            (self.fmu_logging, "--fmu-logging"),
        ] {
            if on {
                v.push(flag.to_owned());
            }
        }
        v
    }

    /// Fills the runner options.
    pub(crate) fn apply(&self, opts: &mut RunOptions) -> Result<()> {
        opts.retry_failed = self.retry_failed;
        opts.timeout_per_run = self.timeout_per_run;
        opts.fresh_instances = self.fresh_instances;
        opts.fmu_logging = self.fmu_logging;
        if self.isolate {
            opts.isolate = Some(
                crate::study::run::isolate::default_exe()
                    .context("locating the uq-driver executable for --isolate")?,
            );
        }
        Ok(())
    }
}

/// `--threads N`: a whole number, at least 1. The message says what to do in the command's
/// terms (`--threads 0` used to be refused naming a Rust type's field).
pub(crate) fn parse_threads(s: &str) -> Result<usize, String> {
    at_least_one(s, "or leave --threads out to use every core")
}

/// `--cpus-per-task N`: a whole number, at least 1.
pub(crate) fn parse_cpus(s: &str) -> Result<usize, String> {
    at_least_one(s, "or leave --cpus-per-task out for 1")
}

fn at_least_one(s: &str, otherwise: &str) -> Result<usize, String> {
    match s.trim().parse::<usize>() {
        Ok(0) => Err(format!(
            "0 threads cannot run anything: give at least 1, {otherwise}"
        )),
        Ok(n) => Ok(n),
        Err(_) => Err(format!(
            "a whole number at least 1 is expected, {otherwise}"
        )),
    }
}

pub(crate) fn parse_timeout(s: &str) -> Result<std::time::Duration, String> {
    let v: f64 = s.trim().parse().map_err(|e| format!("{e}"))?;
    if !(v.is_finite() && v > 0.0) {
        return Err(format!("must be a positive number of seconds, got {s}"));
    }
    std::time::Duration::try_from_secs_f64(v).map_err(|e| e.to_string())
}

#[derive(Args)]
pub(crate) struct SlurmArgs {
    /// Study file, or builtin:NAME.
    pub(crate) study: String,
    /// Number of shards (array tasks).
    #[arg(long)]
    pub(crate) shards: usize,
    /// Plan folder (on a filesystem every node sees).
    #[arg(long, short)]
    pub(crate) out: PathBuf,
    /// Slurm partition.
    #[arg(long)]
    pub(crate) partition: Option<String>,
    /// Time limit per task (e.g. 01:00:00).
    #[arg(long)]
    pub(crate) time: Option<String>,
    /// CPUs per shard task (also its threads).
    #[arg(long, value_parser = parse_cpus)]
    pub(crate) cpus_per_task: Option<usize>,
    /// Extra #SBATCH option (repeatable), e.g. --sbatch=--account=rail.
    #[arg(long = "sbatch")]
    pub(crate) sbatch: Vec<String>,
    /// Write the scripts but do not submit.
    #[arg(long)]
    pub(crate) dry_run: bool,
    /// Plan a large study (more than 100 000 runs, or much memory or time) anyway.
    #[arg(long)]
    pub(crate) yes: bool,
    /// The merge job writes the CSV files and summary.json only: no plots, no index.html.
    #[arg(long)]
    pub(crate) no_report: bool,
    /// How each shard runs its points (passed on to `run-shard`).
    #[command(flatten)]
    pub(crate) safety: SafetyArgs,
}

#[derive(Args)]
pub(crate) struct SimulateArgs {
    /// The .fmu file.
    pub(crate) fmu: PathBuf,
    /// Parameter values, NAME=VALUE (repeatable): a number, true/false or a text, as the
    /// variable's type (Real, Integer, Enumeration, Boolean, String) needs.
    #[arg(long = "set", value_parser = parse_assignment)]
    pub(crate) set: Vec<(String, String)>,
    /// Outputs to record (repeatable; default: every output that is a Real, Integer,
    /// Enumeration or Boolean).
    #[arg(long = "output")]
    pub(crate) outputs: Vec<String>,
    /// Time-varying inputs: a CSV file with a time column, then one column per input
    /// (Real ones interpolated linearly, the others held, as fmpy's input= does).
    #[arg(long)]
    pub(crate) input: Option<PathBuf>,
    /// Start time (s; default: the FMU's default experiment, else 0).
    #[arg(long)]
    pub(crate) start: Option<f64>,
    /// Stop time (s; default: the FMU's default experiment).
    #[arg(long)]
    pub(crate) stop: Option<f64>,
    /// Communication step (s; default: the FMU's default experiment).
    #[arg(long)]
    pub(crate) step: Option<f64>,
    /// CSV file to write (default, or `-`: standard output; a device or a named pipe is
    /// written into, never replaced); beside a file, FILE.meta.json: the FMU, the experiment,
    /// the values set and the FMU's String calculated parameters.
    #[arg(long, short)]
    pub(crate) out: Option<PathBuf>,
    /// Instantiate the FMU with loggingOn = true (many FMUs log only then) and print its
    /// messages on stderr as they come.
    #[arg(long)]
    pub(crate) fmu_logging: bool,
}

pub(crate) fn parse_assignment(s: &str) -> Result<(String, String), String> {
    let (name, value) = s
        .split_once('=')
        .ok_or_else(|| format!("expected NAME=VALUE, got '{s}'"))?;
    Ok((name.trim().to_owned(), value.to_owned()))
}

/// `NAME=NUMBER`.
pub(crate) fn parse_number_assignment(s: &str) -> Result<(String, f64), String> {
    let (name, value) = parse_assignment(s)?;
    let v: f64 = value
        .trim()
        .parse()
        .map_err(|e| format!("value of {name}: {e}"))?;
    Ok((name, v))
}
