//! The `uq-driver` command line: arguments, and the commands that are more than a call into
//! the library.

pub(crate) mod args;
pub(crate) mod cluster;
pub(crate) mod load;
pub(crate) mod print;
pub(crate) mod tools;

use std::io::{IsTerminal, Write};
use std::process::ExitCode;

use anyhow::{Context, Result};
use clap::Parser;

use crate::fmu::Fmu;
use crate::spec::{builtin, Study, StudyError, BUILTINS};
use crate::study::plan::interface::{InterfaceError, VariableProblem};
use crate::study::{run_study, shard, Outcome, RunError, RunOptions, StudyRunError};
use crate::suggest;

use args::*;
use cluster::*;
use load::*;
use print::*;
use tools::*;

/// The width of `uq-driver list`'s lines (characters).
const LIST_WIDTH: usize = 100;

/// `text` in lines of at most `width` characters, broken between words (a longer word
/// has a line of its own).
fn wrap(text: &str, width: usize) -> Vec<String> {
    let mut lines = vec![String::new()];
    for word in text.split_whitespace() {
        let last = lines.last_mut().expect("at least one line");
        if last.is_empty() {
            last.push_str(word);
        } else if last.chars().count() + 1 + word.chars().count() <= width {
            last.push(' ');
            last.push_str(word);
        } else {
            lines.push(word.to_owned());
        }
    }
    lines
}

/// clap's error for an unknown subcommand, with a "did you mean" where clap found none
/// (`rnu` for `run`: clap's similarity misses swapped letters; [`crate::suggest::closest`]
/// takes one edit as a likely typo).
fn with_subcommand_suggestion(mut e: clap::Error) -> clap::Error {
    use clap::error::{ContextKind, ContextValue, ErrorKind};
    if e.kind() != ErrorKind::InvalidSubcommand || e.get(ContextKind::SuggestedSubcommand).is_some()
    {
        return e;
    }
    let Some(ContextValue::String(wrong)) = e.get(ContextKind::InvalidSubcommand).cloned() else {
        return e;
    };
    let command = <Cli as clap::CommandFactory>::command();
    let names = command
        .get_subcommands()
        .filter(|c| !c.is_hide_set())
        .map(|c| c.get_name().to_owned())
        .collect::<Vec<_>>();
    if let Some(name) = crate::suggest::closest(&wrong, names.iter().map(String::as_str)) {
        e.insert(
            ContextKind::SuggestedSubcommand,
            ContextValue::Strings(vec![name.to_owned()]),
        );
    }
    e
}

/// The `uq-driver` program: parses the command line, runs the command, prints errors (with
/// hints) and returns the exit status.
pub fn main() -> ExitCode {
    main_with(std::env::args_os())
}

/// [`main`] with the arguments given (the first one names the program in usage messages),
/// for a host that is not the `uq-driver` executable: `python -m railuq ARGS...` calls it.
/// It is the whole program: it installs the process guards (Ctrl-C ends the process, as
/// for `uq-driver`), prints on stdout and stderr, and `--help`, `--version` and a bad
/// argument end the process as clap does.
pub fn main_with<I, T>(args: I) -> ExitCode
where
    I: IntoIterator<Item = T>,
    T: Into<std::ffi::OsString> + Clone,
{
    let cli = Cli::try_parse_from(args).unwrap_or_else(|e| with_subcommand_suggestion(e).exit());
    // Under `ulimit -v`, threads' own malloc arenas cannot be reserved and every allocation
    // becomes a system call (runs 50 times slower): the command line owns its process, so it
    // keeps the allocator to a few arenas there (library hosts are left alone).
    crate::sys::fewer_arenas_under_an_address_limit();
    if matches!(cli.command, Command::Worker) {
        return ExitCode::from(u8::try_from(crate::study::run::isolate::serve()).unwrap_or(1));
    }
    // The CLI owns its process: signal handlers, the atexit check of an FMU calling exit(),
    // and the in-process --timeout-per-run (library hosts leave them off).
    crate::study::run::guard::install_process_guards();
    // The library's notes and warnings (silent by default) go to stderr.
    crate::study::progress::print_messages();
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

/// The text the command line prints for an error: the error and its causes on one line,
/// then a line `hint: ...` for each "did you mean" (a misspelt TOML key, kind or FMU
/// variable). A host reports errors in the command line's words with it (the Python
/// package's exceptions carry it).
pub fn error_message(e: &anyhow::Error) -> String {
    let mut text = causes(e);
    for h in hints(e) {
        text.push_str("\nhint: ");
        text.push_str(&h);
    }
    text
}

/// What `uq-driver simulate FMU` does before it writes its CSV, for a host: one run of the
/// FMU at `fmu` with `set` set before initialization, recording `outputs` (every output
/// that can be recorded when empty) from `start` to `stop` every `step` (s; each `None`
/// takes the FMU's default experiment, `start` else 0). The same checks and errors as the
/// command; its notes and warnings go to the sink of [`crate::study::set_message_sink`].
pub fn simulate(
    fmu: &std::path::Path,
    set: &[(String, crate::fmu::FixedValue)],
    outputs: &[String],
    start: Option<f64>,
    stop: Option<f64>,
    step: Option<f64>,
) -> Result<crate::study::Simulation> {
    let a = SimulateArgs {
        fmu: fmu.to_path_buf(),
        set: Vec::new(),
        outputs: outputs.to_vec(),
        input: None,
        start,
        stop,
        step,
        out: None,
        fmu_logging: false,
    };
    simulation(&a, set, false).map(|(sim, _)| sim)
}

/// The checks `uq-driver run` makes on a study it loaded, before running it: every FMU it
/// names (a suite's variants too) exists, else an error lists every place searched; `cov`
/// values that look like percentages are warned about (to the sink of
/// [`crate::study::set_message_sink`]).
pub fn check_study(s: &Study) -> Result<()> {
    for w in cov_warnings(&s.source) {
        crate::study::progress::message(&format!("uq-driver: warning: {w}"));
    }
    let mut studies = vec![s];
    if let Some(suite) = &s.suite {
        studies.extend(&suite.variants);
    }
    for st in studies {
        check_fmu_found(st)?;
    }
    Ok(())
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
        // A parse error of a `--set` comes as `Invalid` (its place in the rewritten text
        // would mean nothing to the user), with the parser's words.
        if let Some(StudyError::Parse { message, .. } | StudyError::Invalid { message, .. }) =
            cause.downcast_ref::<StudyError>()
        {
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
            no_report,
            yes,
        } => {
            let out = out.unwrap_or_else(|| dir.join("result"));
            let opts = RunOptions {
                allow_failures,
                no_report,
                yes,
                ..RunOptions::default()
            };
            let r = shard::merge(&dir, &out, &opts)?;
            if no_report {
                println!(
                    "merged {} points; results (no report): {}",
                    r.summary.model_runs,
                    out.join("summary.json").display()
                );
            } else {
                println!(
                    "merged {} points; report: {}",
                    r.summary.model_runs,
                    out.join("index.html").display()
                );
            }
            Ok(())
        }
        Command::Slurm(args) => slurm(args),
        Command::List => {
            let mut o = std::io::stdout().lock();
            for (name, text) in BUILTINS {
                let s = Study::parse(text, name, None)?;
                writeln!(o, "builtin:{name}")?;
                for line in wrap(&s.description, LIST_WIDTH - 4) {
                    writeln!(o, "    {line}")?;
                }
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
        Command::Simulate(args) => tools::simulate(args),
        Command::Surrogate(cmd) => surrogate(cmd),
        Command::Compare { dirs, out } => {
            crate::report::compare::write(&dirs, &out)?;
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
            let e = crate::study::store::export::runs(&dir, &out)?;
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

/// `uq-driver run`.
fn run(a: RunArgs) -> Result<()> {
    let s = load_study_with(&a.study, &a.settings())?;
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
        Outcome::Study(r) => print_study(&r, &a.out, a.no_report),
        Outcome::Suite(r) => print_suite(&r, &a.out),
    }
    Ok(())
}
