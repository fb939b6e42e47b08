//! `uq-driver`: the command line over the uq_driver library.

use std::io::{IsTerminal, Write};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::{Context, Result};
use clap::{Args, Parser, Subcommand};

use uq_driver::fmu::{Fmu, VariableKind};
use uq_driver::report::csv::push_shortest;
use uq_driver::report::units::with_unit;
use uq_driver::results::sig;
use uq_driver::spec::{
    builtin, fmu_candidates, Experiment, FixedValue, InvalidExperiment, Study, StudyError, BUILTINS,
};
use uq_driver::study::interface::{InterfaceError, VariableProblem};
use uq_driver::study::{
    run_study, runner, shard, size, Outcome, RunError, RunOptions, StudyResult, StudyRunError,
    SuiteResult,
};
use uq_driver::suggest;
use uq_driver::uq::surrogate::Surrogate;

#[derive(Parser)]
#[command(
    name = "uq-driver",
    version,
    about = "Propagate parameter uncertainty through FMI 2.0 Co-Simulation FMUs"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
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
        #[arg(long, short)]
        threads: Option<usize>,
        /// MC/LHS: continue past failed points.
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
        /// MC/LHS: accept failed points and report how many.
        #[arg(long)]
        allow_failures: bool,
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
enum SurrogateCommand {
    /// The surrogate at one point, as CSV `name,time,value` (time empty for a scalar
    /// quantity); inputs not given take their nominal value.
    Eval {
        /// Study output folder (with surrogate.json), or the file itself.
        dir: PathBuf,
        /// Input value, NAME=VALUE (repeatable).
        #[arg(long = "at", value_parser = parse_number_assignment)]
        at: Vec<(String, f64)>,
        /// CSV file to write (default: standard output).
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
        /// CSV file to write (default: standard output).
        #[arg(long, short)]
        out: Option<PathBuf>,
    },
}

#[derive(Args)]
struct RunArgs {
    /// Study file, or builtin:NAME or just NAME (see `uq-driver list`).
    study: String,
    /// Output folder (re-running into the same folder resumes an interrupted study).
    #[arg(long, short)]
    out: PathBuf,
    /// Worker threads (default: all cores).
    #[arg(long, short)]
    threads: Option<usize>,
    /// MC/LHS: continue past failed points and report how many failed.
    #[arg(long)]
    allow_failures: bool,
    /// Discard earlier results in --out instead of resuming.
    #[arg(long)]
    fresh: bool,
    /// Stop after this many new points (the study can be resumed later).
    #[arg(long, hide = true)]
    max_points: Option<usize>,
    /// Start a large study (more than 100 000 runs, or much memory or time) without asking.
    #[arg(long)]
    yes: bool,
    /// Write the CSV files and summary.json only: no plots, no index.html.
    #[arg(long)]
    no_report: bool,
    #[command(flatten)]
    safety: SafetyArgs,
}

/// How points are run: isolation, time limit, retries.
#[derive(Args)]
struct SafetyArgs {
    /// Run each point in a worker process: an FMU that crashes, aborts, calls exit() or
    /// outlives --timeout-per-run fails its point instead of ending the study.
    #[arg(long)]
    isolate: bool,
    /// Longest a run may take (s). With --isolate the run is killed and fails its point;
    /// in-process the study stops with a message naming the point.
    #[arg(long, value_name = "SECONDS", value_parser = parse_timeout)]
    timeout_per_run: Option<std::time::Duration>,
    /// Run again the points that failed in an earlier run into the same folder.
    #[arg(long)]
    retry_failed: bool,
}

impl SafetyArgs {
    /// Fills the runner options.
    fn apply(&self, opts: &mut RunOptions) -> Result<()> {
        opts.retry_failed = self.retry_failed;
        opts.timeout_per_run = self.timeout_per_run;
        if self.isolate {
            opts.isolate = Some(
                uq_driver::study::isolate::default_exe()
                    .context("locating the uq-driver executable for --isolate")?,
            );
        }
        Ok(())
    }
}

fn parse_timeout(s: &str) -> Result<std::time::Duration, String> {
    let v: f64 = s.trim().parse().map_err(|e| format!("{e}"))?;
    if !(v.is_finite() && v > 0.0) {
        return Err(format!("must be a positive number of seconds, got {s}"));
    }
    std::time::Duration::try_from_secs_f64(v).map_err(|e| e.to_string())
}

#[derive(Args)]
struct SlurmArgs {
    /// Study file, or builtin:NAME.
    study: String,
    /// Number of shards (array tasks).
    #[arg(long)]
    shards: usize,
    /// Plan folder (on a filesystem every node sees).
    #[arg(long, short)]
    out: PathBuf,
    /// Slurm partition.
    #[arg(long)]
    partition: Option<String>,
    /// Time limit per task (e.g. 01:00:00).
    #[arg(long)]
    time: Option<String>,
    /// CPUs per shard task (also its threads).
    #[arg(long)]
    cpus_per_task: Option<usize>,
    /// Extra #SBATCH option (repeatable), e.g. --sbatch=--account=rail.
    #[arg(long = "sbatch")]
    sbatch: Vec<String>,
    /// Write the scripts but do not submit.
    #[arg(long)]
    dry_run: bool,
    /// Plan a large study (more than 100 000 runs, or much memory or time) anyway.
    #[arg(long)]
    yes: bool,
}

#[derive(Args)]
struct SimulateArgs {
    /// The .fmu file.
    fmu: PathBuf,
    /// Parameter values, NAME=VALUE (repeatable): a number, true/false or a text, as the
    /// variable's type (Real, Integer, Enumeration, Boolean, String) needs.
    #[arg(long = "set", value_parser = parse_assignment)]
    set: Vec<(String, String)>,
    /// Outputs to record (repeatable; default: every output that is a Real, Integer,
    /// Enumeration or Boolean).
    #[arg(long = "output")]
    outputs: Vec<String>,
    /// Time-varying inputs: a CSV file with a time column, then one column per input
    /// (Real ones interpolated linearly, the others held, as fmpy's input= does).
    #[arg(long)]
    input: Option<PathBuf>,
    /// Start time (s; default: the FMU's default experiment, else 0).
    #[arg(long)]
    start: Option<f64>,
    /// Stop time (s; default: the FMU's default experiment).
    #[arg(long)]
    stop: Option<f64>,
    /// Communication step (s; default: the FMU's default experiment).
    #[arg(long)]
    step: Option<f64>,
    /// CSV file to write (default: standard output).
    #[arg(long, short)]
    out: Option<PathBuf>,
}

fn parse_assignment(s: &str) -> Result<(String, String), String> {
    let (name, value) = s
        .split_once('=')
        .ok_or_else(|| format!("expected NAME=VALUE, got '{s}'"))?;
    Ok((name.trim().to_owned(), value.to_owned()))
}

/// `NAME=NUMBER`.
fn parse_number_assignment(s: &str) -> Result<(String, f64), String> {
    let (name, value) = parse_assignment(s)?;
    let v: f64 = value
        .trim()
        .parse()
        .map_err(|e| format!("value of {name}: {e}"))?;
    Ok((name, v))
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    if matches!(cli.command, Command::Worker) {
        return ExitCode::from(u8::try_from(uq_driver::study::isolate::serve()).unwrap_or(1));
    }
    uq_driver::study::guard::install_signal_handler();
    match dispatch(cli.command) {
        Ok(()) => ExitCode::SUCCESS,
        // `uq-driver inspect X | head`: the reader went away; nothing left to say.
        Err(e)
            if e.downcast_ref::<std::io::Error>()
                .is_some_and(|io| io.kind() == std::io::ErrorKind::BrokenPipe) =>
        {
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("uq-driver: error: {}", causes(&e));
            for h in hints(&e) {
                eprintln!("uq-driver: hint: {h}");
            }
            ExitCode::FAILURE
        }
    }
}

/// The error and its causes, each once: a cause whose text an outer message already
/// contains (libraries that print their source in their own message) is not repeated.
fn causes(e: &anyhow::Error) -> String {
    let mut text = String::new();
    for cause in e.chain() {
        let msg = cause.to_string();
        if text.contains(&msg) {
            continue;
        }
        if !text.is_empty() {
            text.push_str(": ");
        }
        text.push_str(&msg);
    }
    text
}

/// "Did you mean" for the errors that name something misspelt: a TOML key or kind, a
/// variable the FMU does not have.
fn hints(e: &anyhow::Error) -> Vec<String> {
    let mut out = Vec::new();
    for cause in e.chain() {
        if let Some(StudyError::Parse { message, .. }) = cause.downcast_ref::<StudyError>() {
            out.extend(suggest::for_serde_message(message));
        }
        // `transparent` errors hide their inner error from the chain: look inside.
        let ie = cause
            .downcast_ref::<InterfaceError>()
            .or_else(|| match cause.downcast_ref::<RunError>() {
                Some(RunError::Interface(ie)) => Some(ie),
                _ => None,
            })
            .or_else(|| match cause.downcast_ref::<StudyRunError>() {
                Some(StudyRunError::Run(RunError::Interface(ie))) => Some(ie),
                _ => None,
            });
        if let Some(ie) = ie {
            if let VariableProblem::Unknown { name, .. } = &ie.problem {
                if let Ok(fmu) = Fmu::open(&ie.fmu) {
                    let names = fmu.description().variables.iter().map(|v| v.name.as_str());
                    if let Some(c) = suggest::closest(name, names) {
                        out.push(format!("'{name}': did you mean '{c}'?"));
                    }
                }
            }
        }
    }
    out
}

/// A study argument as `Study::load` takes it: a file, `builtin:NAME`, or a bare built-in
/// NAME when no file of that name exists; a misspelt name gets the closest built-in.
fn study_spec(arg: &str) -> Result<String> {
    let names = || BUILTINS.iter().map(|(n, _)| *n);
    if let Some(name) = arg.strip_prefix("builtin:") {
        if names().any(|n| n == name) {
            return Ok(arg.to_owned());
        }
        let hint = suggest::closest(name, names())
            .map(|c| format!(" (did you mean builtin:{c}?)"))
            .unwrap_or_default();
        anyhow::bail!("no built-in study '{name}'{hint}; `uq-driver list` shows them all");
    }
    let is_builtin = names().any(|n| n == arg);
    let exists = Path::new(arg).exists();
    match (exists, is_builtin) {
        (true, true) => anyhow::bail!(
            "'{arg}' is both a file here and a built-in study: write ./{arg} for the file or \
             builtin:{arg} for the built-in"
        ),
        (true, false) => Ok(arg.to_owned()),
        (false, true) => Ok(format!("builtin:{arg}")),
        (false, false) => {
            let hint = suggest::closest(arg, names())
                .map(|c| format!("; did you mean the built-in study {c}?"))
                .unwrap_or_else(|| "; `uq-driver list` shows the built-in studies".into());
            anyhow::bail!("no study file '{arg}' and no built-in study of that name{hint}")
        }
    }
}

/// Loads a study argument (file, builtin:NAME or NAME), warns about `cov` values that look
/// like percentages and checks that its FMU (and every variant's) can be found.
fn load_study(arg: &str) -> Result<Study> {
    let s = Study::load(&study_spec(arg)?)?;
    for w in cov_warnings(&s.source) {
        eprintln!("uq-driver: warning: {w}");
    }
    let mut studies = vec![&s];
    if let Some(suite) = &s.suite {
        studies.extend(&suite.variants);
    }
    for st in studies {
        check_fmu_found(st)?;
    }
    Ok(s)
}

/// `cov` is a fraction: a value above 1 is most likely a percentage.
fn cov_warnings(source: &str) -> Vec<String> {
    let Ok(table) = source.parse::<toml::Table>() else {
        return Vec::new();
    };
    let mut params: Vec<&toml::Value> = Vec::new();
    let arrays = |t: &toml::Table| -> Vec<toml::Value> {
        t.get("parameters")
            .and_then(|p| p.as_array())
            .cloned()
            .unwrap_or_default()
    };
    let mut all = arrays(&table);
    for v in table
        .get("variants")
        .and_then(|v| v.as_array())
        .into_iter()
        .flatten()
    {
        if let Some(t) = v.as_table() {
            all.extend(arrays(t));
        }
    }
    params.extend(all.iter());
    let mut out: Vec<String> = params
        .iter()
        .filter_map(|p| {
            let cov = p
                .get("cov")?
                .as_float()
                .or_else(|| p.get("cov").and_then(|c| c.as_integer()).map(|i| i as f64))?;
            let name = p.get("name").and_then(|n| n.as_str()).unwrap_or("?");
            (cov > 1.0).then(|| {
                format!(
                    "parameter '{name}': cov = {cov} is a coefficient of variation of {} %; \
                     `cov` is a fraction (did you mean cov = {}?)",
                    cov * 100.0,
                    cov / 100.0
                )
            })
        })
        .collect();
    out.dedup();
    out
}

/// An error listing every place searched when a study's FMU is not found.
fn check_fmu_found(s: &Study) -> Result<()> {
    let Some(path) = &s.fmu_path else {
        return Ok(());
    };
    if path.exists() {
        return Ok(());
    }
    let given = s
        .base
        .as_ref()
        .and_then(|b| path.strip_prefix(b).ok())
        .unwrap_or(path);
    let places: Vec<String> = fmu_candidates(&given.to_string_lossy(), s.base.as_deref())
        .iter()
        .map(|p| format!("  {}", p.display()))
        .collect();
    anyhow::bail!(
        "{}: FMU {} not found; looked in:\n{}\n(set RAILUQ_FMU_DIR to the folder of the FMUs, \
         e.g. target/fmu after `make fmu`)",
        s.origin,
        given.display(),
        places.join("\n")
    )
}

fn dispatch(cmd: Command) -> Result<()> {
    match cmd {
        Command::Run(args) => run(args),
        Command::Plan {
            study,
            shards,
            out,
            yes,
        } => {
            let s = load_study(&study)?;
            check_plan_size(&s, &out, yes)?;
            let p = shard::plan(&s, shards, &out)?;
            println!(
                "planned {}: {} points in {} shards (point i in shard i mod {}); next: uq-driver run-shard {} --shard K, then uq-driver merge {}",
                s.name,
                p.manifest.n_points,
                p.shards,
                p.shards,
                out.display(),
                out.display()
            );
            Ok(())
        }
        Command::RunShard {
            dir,
            shard,
            threads,
            allow_failures,
            safety,
        } => run_shard(&dir, shard, threads, allow_failures, &safety),
        Command::Merge {
            dir,
            out,
            allow_failures,
        } => {
            let out = out.unwrap_or_else(|| dir.join("result"));
            let opts = RunOptions {
                allow_failures,
                ..RunOptions::default()
            };
            let r = shard::merge(&dir, &out, &opts)?;
            println!(
                "merged {} points; report: {}",
                r.summary.model_runs,
                out.join("index.html").display()
            );
            Ok(())
        }
        Command::Slurm(args) => slurm(args),
        Command::List => {
            let mut o = std::io::stdout().lock();
            for (name, text) in BUILTINS {
                let s = Study::parse(text, name, None)?;
                writeln!(o, "builtin:{name:<24} {}", s.description)?;
            }
            Ok(())
        }
        Command::Show { name } => {
            let spec = study_spec(&format!(
                "builtin:{}",
                name.strip_prefix("builtin:").unwrap_or(&name)
            ))?;
            let text = builtin(spec.strip_prefix("builtin:").unwrap_or(&spec))?;
            std::io::stdout().lock().write_all(text.as_bytes())?;
            Ok(())
        }
        Command::Inspect { fmu } => inspect(&fmu),
        Command::Simulate(args) => simulate(args),
        Command::Surrogate(cmd) => surrogate(cmd),
        Command::Compare { dirs, out } => {
            uq_driver::report::compare::write(&dirs, &out)?;
            println!(
                "compared {} folders: {}",
                dirs.len(),
                out.join("index.html").display()
            );
            Ok(())
        }
        Command::Export { dir, runs, out } => {
            anyhow::ensure!(runs, "say what to export: --runs (every run's time series)");
            let out = out.unwrap_or_else(|| dir.join("runs"));
            let e = uq_driver::study::export::runs(&dir, &out)?;
            println!(
                "exported {} runs × {} times of {}: {} and {}",
                e.runs,
                e.times,
                e.outputs.join(", "),
                e.csv.display(),
                e.npz.display()
            );
            Ok(())
        }
        Command::Worker => unreachable!("handled in main"),
    }
}

/// Writes `text` to `out`, or to standard output.
fn emit(text: &str, out: Option<&Path>) -> Result<()> {
    match out {
        Some(p) => std::fs::write(p, text).with_context(|| format!("writing {}", p.display())),
        None => Ok(std::io::stdout().lock().write_all(text.as_bytes())?),
    }
}

/// `uq-driver surrogate eval|sample`.
fn surrogate(cmd: SurrogateCommand) -> Result<()> {
    match cmd {
        SurrogateCommand::Eval { dir, at, out } => {
            let s = Surrogate::load(&dir)?;
            let x = s.point(&at)?;
            emit(&s.eval_csv(&x), out.as_deref())
        }
        SurrogateCommand::Sample {
            dir,
            n,
            seed,
            times,
            out,
        } => {
            let s = Surrogate::load(&dir)?;
            emit(&s.sample_csv(n, seed, &times), out.as_deref())
        }
    }
}

/// `uq-driver run`.
fn run(a: RunArgs) -> Result<()> {
    let s = load_study(&a.study)?;
    let mut opts = RunOptions {
        threads: a.threads,
        progress: std::io::stderr().is_terminal(),
        progress_lines: !std::io::stderr().is_terminal(),
        allow_failures: a.allow_failures,
        fresh: a.fresh,
        max_new_points: a.max_points,
        yes: a.yes,
        no_report: a.no_report,
        ..RunOptions::default()
    };
    a.safety.apply(&mut opts)?;
    let outcome = run_study(&s, &a.out, &opts).with_context(|| format!("study {}", s.origin))?;
    match outcome {
        Outcome::Study(r) => print_study(&r, &a.out),
        Outcome::Suite(r) => print_suite(&r, &a.out),
    }
    Ok(())
}

/// The size checks of `run` for a plan (whose shards run with the default thread count).
fn check_plan_size(s: &Study, dir: &Path, yes: bool) -> Result<()> {
    let opts = RunOptions {
        yes,
        ..RunOptions::default()
    };
    size::check(s, dir, &opts).with_context(|| format!("study {}", s.origin))?;
    Ok(())
}

/// `uq-driver run-shard`.
fn run_shard(
    dir: &Path,
    shard: Option<usize>,
    threads: Option<usize>,
    allow_failures: bool,
    safety: &SafetyArgs,
) -> Result<()> {
    let k = match shard {
        Some(k) => k,
        None => std::env::var("SLURM_ARRAY_TASK_ID")
            .context("no --shard and no SLURM_ARRAY_TASK_ID")?
            .parse()
            .context("SLURM_ARRAY_TASK_ID is not a number")?,
    };
    let mut opts = RunOptions {
        threads,
        progress: std::io::stderr().is_terminal(),
        progress_lines: !std::io::stderr().is_terminal(),
        allow_failures,
        ..RunOptions::default()
    };
    safety.apply(&mut opts)?;
    let o = shard::run_shard(dir, k, &opts)?;
    println!(
        "shard {k}: {} points run, {} resumed, wall time {:.2} s",
        o.n_new, o.n_resumed, o.wall_time
    );
    Ok(())
}

/// `uq-driver slurm`: plan, write the batch scripts and (unless --dry-run) submit them.
fn slurm(a: SlurmArgs) -> Result<()> {
    let s = load_study(&a.study)?;
    check_plan_size(&s, &a.out, a.yes)?;
    shard::plan(&s, a.shards, &a.out)?;
    let driver = std::env::current_exe().context("locating the uq-driver executable")?;
    let o = shard::SlurmOptions {
        partition: a.partition,
        time: a.time,
        cpus_per_task: a.cpus_per_task,
        extra: a.sbatch,
    };
    let (array_script, merge_script) = shard::write_sbatch(&a.out, &driver, a.shards, &o)?;
    if a.dry_run {
        println!(
            "wrote {} and {} (not submitted)",
            array_script.display(),
            merge_script.display()
        );
        return Ok(());
    }
    let array = sbatch(&[array_script.to_str().context("path")?])?;
    let dep = format!("--dependency=afterok:{array}");
    let merge = sbatch(&[&dep, merge_script.to_str().context("path")?])?;
    println!("array job {array}");
    println!("merge job {merge}");
    println!("results will be in {}", a.out.join("result").display());
    Ok(())
}

/// Submits with `sbatch --parsable ARGS`; returns the job id.
fn sbatch(args: &[&str]) -> Result<String> {
    let o = std::process::Command::new("sbatch")
        .arg("--parsable")
        .args(args)
        .output()
        .context("running sbatch (is Slurm installed and SLURM_CONF set?)")?;
    anyhow::ensure!(
        o.status.success(),
        "sbatch failed: {}",
        String::from_utf8_lossy(&o.stderr).trim()
    );
    let id = String::from_utf8_lossy(&o.stdout)
        .trim()
        .split(';')
        .next()
        .unwrap_or("")
        .to_string();
    anyhow::ensure!(!id.is_empty(), "sbatch printed no job id");
    Ok(id)
}

/// The result of `run` on the terminal: runs, wall time, the scalar quantities, warnings.
fn print_study(r: &StudyResult, out: &Path) {
    let s = &r.summary;
    for w in &s.warnings {
        eprintln!("uq-driver: warning: {w}");
    }
    let t = &s.timing;
    println!(
        "{}: {} model runs ({} resumed); wall time: runs {:.2} s, analysis {:.2} s, report \
         {:.2} s; report: {}",
        s.study,
        s.model_runs,
        s.runs_resumed,
        t.runs_s,
        t.analysis_s,
        t.report_s,
        out.join("index.html").display()
    );
    for q in &r.quantities {
        let u = q.unit.as_deref();
        let v = |x: f64| with_unit(&format!("{x:.6}"), u);
        if q.deterministic {
            println!(
                "  {} = {} (every run; {})",
                q.name,
                v(q.mean),
                q.definition.text
            );
        } else {
            println!(
                "  {}: mean {}, Std {} ({} valid runs; {})",
                q.name,
                v(q.mean),
                v(q.std),
                q.n_valid,
                q.definition.text
            );
            for e in &q.exceedance_counts {
                println!("  P({} > {}): {}", q.name, sig(e.limit), e.describe());
            }
        }
    }
    if s.failed_runs > 0 {
        println!("{} points failed (see points.csv)", s.failed_runs);
    }
}

/// The result of `run` for a suite: one line per variant.
fn print_suite(r: &SuiteResult, out: &Path) {
    for v in &r.variants {
        for w in &v.summary.warnings {
            eprintln!("uq-driver: warning: {}: {w}", v.summary.study);
        }
    }
    println!(
        "{}: report {}",
        r.summary.suite,
        out.join("index.html").display()
    );
    for v in &r.summary.variants {
        println!(
            "  {:<12} {:<16} {:>7} model runs, wall time {:.2} s",
            v.name, v.method, v.model_runs, v.wall_time_s
        );
    }
}

/// `uq-driver simulate`: one run as CSV.
fn simulate(a: SimulateArgs) -> Result<()> {
    let fmu = Fmu::open(&a.fmu)?;
    let de = fmu.description().default_experiment.unwrap_or_default();
    let start = a.start.or(de.start_time).unwrap_or(0.0);
    let stop = a
        .stop
        .or(de.stop_time)
        .context("no --stop and no default stop time in the FMU")?;
    let step = a
        .step
        .or(de.step_size)
        .context("no --step and no default step size in the FMU")?;
    let experiment = Experiment { start, stop, step };
    experiment.check().map_err(|e| match e {
        InvalidExperiment::ZeroStep => anyhow::anyhow!(
            "--step 0: the communication step must be positive (s), e.g. --step 0.01"
        ),
        other => other.into(),
    })?;
    let series = if a.outputs.is_empty() {
        fmu.description().output_variables().count()
    } else {
        a.outputs.len()
    };
    size::check_simulation(experiment.n_steps() as f64 + 1.0, series)?;
    let times = experiment.times();
    let params: Vec<(String, FixedValue)> = a
        .set
        .into_iter()
        .map(|(n, v)| (n, FixedValue::Text(v)))
        .collect();
    let sim = runner::simulate(&fmu, &params, &a.outputs, a.input.as_deref(), &times)?;
    for (name, why) in &sim.skipped {
        eprintln!("uq-driver: note: output '{name}' not recorded: {why}");
    }
    if sim.names.is_empty() {
        eprintln!(
            "uq-driver: warning: nothing to record: the FMU has no output that can be written \
             as a number (name variables with --output)"
        );
    }
    if let Some(t) = sim.ended_at {
        eprintln!(
            "uq-driver: note: the FMU ended the simulation at t = {t} s (before the stop time \
             {stop} s); the output ends there"
        );
    }
    let mut text = String::from("time");
    for n in &sim.names {
        text.push(',');
        text.push_str(n);
    }
    text.push('\n');
    for (k, t) in sim.times.iter().enumerate() {
        push_shortest(&mut text, *t);
        for s in &sim.series {
            text.push(',');
            push_shortest(&mut text, s[k]);
        }
        text.push('\n');
    }
    match a.out.as_deref() {
        Some(p) => std::fs::write(p, text).with_context(|| format!("writing {}", p.display()))?,
        None => std::io::stdout().lock().write_all(text.as_bytes())?,
    }
    Ok(())
}

fn inspect(path: &Path) -> Result<()> {
    let fmu = Fmu::open(path)?;
    // Buffered: one write per line would cost a system call per variable.
    let mut o = std::io::BufWriter::new(std::io::stdout().lock());
    let md = fmu.description();
    let cs = &md.co_simulation;
    writeln!(
        o,
        "{} — {}",
        md.model_name,
        md.description.as_deref().unwrap_or("")
    )?;
    writeln!(
        o,
        "  FMI {}  GUID {}  generated by {}",
        md.fmi_version,
        md.guid,
        md.generation_tool.as_deref().unwrap_or("?")
    )?;
    writeln!(
        o,
        "  Co-Simulation: modelIdentifier {}, variable step {}, get/set state {}, serialize state {}, directional derivatives {}",
        cs.model_identifier,
        cs.can_handle_variable_communication_step_size,
        cs.can_get_and_set_fmu_state,
        cs.can_serialize_fmu_state,
        cs.provides_directional_derivative
    )?;
    if let Some(de) = &md.default_experiment {
        let plain = |v: Option<f64>| v.map_or_else(|| "–".to_string(), |x| x.to_string());
        writeln!(
            o,
            "  default experiment: start {} s, stop {} s, step {} s",
            plain(de.start_time),
            plain(de.stop_time),
            plain(de.step_size)
        )?;
    }
    writeln!(
        o,
        "  {:<16} {:>5} {:<8} {:<20} {:<11} {:>12} {:<8} description",
        "name", "vr", "type", "causality", "variability", "start", "unit"
    )?;
    for v in &md.variables {
        let (start, unit) = match &v.kind {
            VariableKind::Real { start, unit, .. } => (start.map(|s| s.to_string()), unit.clone()),
            VariableKind::Integer { start, .. } | VariableKind::Enumeration { start, .. } => {
                (start.map(|s| s.to_string()), None)
            }
            VariableKind::Boolean { start } => (start.map(|s| s.to_string()), None),
            VariableKind::String { start } => (start.clone(), None),
        };
        writeln!(
            o,
            "  {:<16} {:>5} {:<8} {:<20} {:<11} {:>12} {:<8} {}",
            v.name,
            v.value_reference,
            v.kind.type_name(),
            v.causality.as_str(),
            v.variability.as_str(),
            start.unwrap_or_default(),
            unit.unwrap_or_default(),
            v.description.as_deref().unwrap_or("")
        )?;
    }
    o.flush()?;
    Ok(())
}
