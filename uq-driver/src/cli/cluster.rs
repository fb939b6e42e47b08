//! `plan` size checks, `run-shard` and `slurm`.

use std::io::IsTerminal;
use std::path::Path;

use anyhow::{Context, Result};

use super::args::*;
use super::load::*;
use crate::spec::Study;
use crate::study::plan::size;
use crate::study::{shard, RunOptions};

/// The size checks of `run` for a plan (whose shards run with the default thread count).
pub(crate) fn check_plan_size(s: &Study, dir: &Path, yes: bool) -> Result<()> {
    let opts = RunOptions {
        yes,
        ..RunOptions::default()
    };
    size::check(s, dir, &opts).with_context(|| format!("study {}", s.origin))?;
    Ok(())
}

/// `uq-driver run-shard`.
pub(crate) fn run_shard(
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
pub(crate) fn slurm(a: SlurmArgs) -> Result<()> {
    let s = load_study(&a.study)?;
    check_plan_size(&s, &a.out, a.yes)?;
    shard::plan(&s, a.shards, &a.out)?;
    // `$UQ_DRIVER_EXE` when set (a host such as the Python package, whose own program is not
    // uq-driver, names the command to run), else this program.
    let driver =
        crate::study::run::isolate::default_exe().context("locating the uq-driver executable")?;
    let o = shard::SlurmOptions {
        partition: a.partition,
        time: a.time,
        cpus_per_task: a.cpus_per_task,
        extra: a.sbatch,
        no_report: a.no_report,
        shard_args: a.safety.as_args(),
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
pub(crate) fn sbatch(args: &[&str]) -> Result<String> {
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
