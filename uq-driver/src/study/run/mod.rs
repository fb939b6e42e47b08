//! Running a study's points: the one place that runs them. The options ([`options`]), the
//! errors ([`error`]), the output folder (its lock, its store and the in-process time limit)
//! and the failure policy are here; a batch of points runs in [`batch`] (one FMU instance per
//! worker, reused through `fmi2Reset` once the reset self-check has passed: [`instances`]),
//! one point in [`point`] (the runs of its own of a `hunting_speed` quantity in `speed_runs`),
//! or each in a worker process ([`isolate`]); [`guard`] keeps what
//! the process must know of a study in progress.

pub mod batch;
pub mod error;
pub mod guard;
pub mod instances;
pub mod isolate;
pub mod options;
pub mod point;
pub(crate) mod session;
mod speed_runs;
pub mod worker_fmu;

use std::path::Path;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

use crate::fmu::Fmu;
use crate::spec::Study;
use crate::study::plan::fingerprint;
use crate::study::plan::interface::Interface;
use crate::study::store::lock::FolderLock;
use crate::study::store::valid::RecordRules;
use crate::study::store::{Entry, StoreError, StoredRuns};
use crate::uq::method::Design;
pub(crate) use batch::Job;
pub use error::{FailedPoint, PointError, RunError};
use guard::StudyGuard;
pub use options::{RunControl, RunOptions};
pub use point::{simulate, simulate_with, Simulation};
pub(crate) use session::Session;

/// What a run produced: every point's record, in design order, read in place from the
/// results store (the series of the runs are not held in memory).
#[derive(Debug)]
pub struct RunOutcome {
    /// Records by point index (all present unless stopped early).
    pub runs: StoredRuns,
    /// The output folder's lock, held while the records are read (None: not locked).
    pub _lock: Option<FolderLock>,
    /// Points run in this invocation.
    pub n_new: usize,
    /// Points found finished in the store.
    pub n_resumed: usize,
    /// Wall time of this invocation (s).
    pub wall_time: f64,
    /// Threads used.
    pub threads: usize,
    /// SHA-256 of the FMU.
    pub fmu_sha256: String,
    /// Warnings of the runs (printed when they arose): a failed reset self-check or
    /// `fmi2Reset`, for `summary.json`.
    pub warnings: Vec<String>,
}

/// Runs every point of `design` not yet in the store of `out_dir` (with
/// [`RunOptions::retry_failed`], also the points that failed before), holding the folder's
/// lock ([`FolderLock`]) meanwhile.
pub fn run_points(
    study: &Study,
    fmu: &Fmu,
    design: &Design,
    out_dir: &Path,
    opts: &RunOptions,
) -> Result<RunOutcome, RunError> {
    opts.check()?;
    if let Some(&bad) = opts
        .points
        .as_ref()
        .and_then(|p| p.iter().find(|&&i| i >= design.len()))
    {
        return Err(RunError::Options(format!(
            "RunOptions::points names point {bad}, but the design has {} points (0 to {})",
            design.len(),
            design.len().saturating_sub(1)
        )));
    }
    let manifest = fingerprint::manifest(study, fmu, design)?;
    let stop_on_failure = !opts.allow_failures(study) || design.is_weighted();
    let mut session = Session::open(study, fmu, manifest, out_dir, opts, stop_on_failure)?;
    let records = session.runs.entries();
    let wanted: Vec<usize> = match &opts.points {
        Some(p) => p.clone(),
        None => (0..design.len()).collect(),
    };
    let failed_before = wanted
        .iter()
        .filter(|&&i| matches!(records[i], Some(Entry::Failed(_))))
        .count();
    if failed_before > 0 && !opts.retry_failed {
        crate::study::progress::message(&format!(
            "note: {failed_before} point{} failed in an earlier run and {} not run again \
             (--retry-failed runs {} again)",
            if failed_before == 1 { "" } else { "s" },
            if failed_before == 1 { "is" } else { "are" },
            if failed_before == 1 { "it" } else { "them" },
        ));
    }
    let missing: Vec<usize> = wanted
        .iter()
        .copied()
        .filter(|&i| match records[i] {
            None => true,
            Some(Entry::Failed(_)) => opts.retry_failed,
            Some(Entry::Ok(_)) => false,
        })
        .collect();
    session.iface.check_design(fmu, &design.values)?;
    let jobs: Vec<Job> = missing
        .iter()
        .map(|&i| (i, design.values[i].as_slice()))
        .collect();
    if let Some(c) = &opts.control {
        c.begin(missing.len());
    }
    session.run(&jobs)?;
    let (n_new, threads, opened) = (session.new, session.threads, session.opened);
    let fmu_sha256 = session.manifest.fmu_sha256.clone();
    let (runs, lock, warnings) = session.into_warnings();
    Ok(RunOutcome {
        runs,
        _lock: Some(lock),
        n_new,
        n_resumed: wanted.len() - missing.len(),
        wall_time: opened.elapsed().as_secs_f64(),
        threads,
        fmu_sha256,
        warnings,
    })
}

/// What the records of runs of `iface` over `times` (s) must hold (finite outputs, valid
/// quantity pairs), checked before a record is stored and when a store is opened.
pub(crate) fn record_rules(iface: &Interface, times: &[f64]) -> RecordRules {
    let quantities = iface.qois.iter().flat_map(|q| q.quantity_names()).collect();
    RecordRules::new(&iface.signal_names[..iface.n_stored], times, quantities)
}

/// Opens the study's FMU.
pub fn open_fmu(study: &Study) -> Result<Fmu, RunError> {
    let path = study.fmu_path.as_deref().unwrap_or(Path::new(""));
    Ok(Fmu::open(path)?)
}

/// Checks, before a study is sized or run, that its output folder can be written: `dir`
/// itself if it exists, else the nearest folder above it that exists, must let a folder be
/// made in it. The test makes a hidden folder there and removes it at once: nothing is left
/// behind, and `dir` is not created. Without it a folder that cannot be created (`/sys/x`,
/// on a file system of size 0) was refused as "more than the 0.0 B free … use a larger
/// disk".
pub fn check_out_dir(dir: &Path) -> Result<(), RunError> {
    if dir.as_os_str().is_empty() {
        return Err(RunError::NoOutDir);
    }
    if dir.exists() && !dir.is_dir() {
        return Err(RunError::NotAFolder(dir.to_path_buf()));
    }
    // The nearest existing path at or above `dir` ("." for a relative path's first part).
    let existing = dir
        .ancestors()
        .map(|p| {
            if p.as_os_str().is_empty() {
                Path::new(".")
            } else {
                p
            }
        })
        .find(|p| p.exists())
        .unwrap_or(Path::new("."));
    let probe = existing.join(format!(".uq-driver-write-test-{}", std::process::id()));
    match std::fs::create_dir(&probe) {
        Ok(()) => {
            // Best effort: the folder was made, which is all the check asks.
            let _ = std::fs::remove_dir(&probe);
            Ok(())
        }
        // Left by an earlier process of this id (killed between the two calls): the folder
        // is not the problem; remove the litter.
        Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => {
            let _ = std::fs::remove_dir(&probe);
            Ok(())
        }
        Err(source) => Err(RunError::OutDirNotWritable {
            path: dir.to_path_buf(),
            existing: existing.to_path_buf(),
            source,
        }),
    }
}

/// Creates the output folder, or checks that the existing path is one.
pub fn prepare_out_dir(dir: &Path) -> Result<(), RunError> {
    if dir.as_os_str().is_empty() {
        return Err(RunError::NoOutDir);
    }
    if dir.exists() && !dir.is_dir() {
        return Err(RunError::NotAFolder(dir.to_path_buf()));
    }
    std::fs::create_dir_all(dir).map_err(|source| {
        RunError::Store(StoreError::Io {
            path: dir.to_path_buf(),
            source,
        })
    })
}

/// In-process runs cannot be interrupted: when one outlives `limit`, name it and end the
/// process (the store keeps every finished point).
fn watchdog(guard: &StudyGuard, limit: Duration, done: &AtomicBool) {
    let tick = (limit / 10).clamp(Duration::from_millis(10), Duration::from_millis(250));
    while !done.load(Ordering::Acquire) {
        std::thread::sleep(tick);
        let overdue = guard.overdue(limit);
        if overdue.is_empty() {
            continue;
        }
        let points: Vec<String> = overdue
            .iter()
            .map(|(p, v, t)| format!("point {p} ({v}) has run for {:.1} s", t.as_secs_f64()))
            .collect();
        guard::exit_now(
            guard::EXIT_FAILURE,
            &format!(
                "uq-driver: error: {}, longer than --timeout-per-run {} s. An FMU call cannot be \
                 interrupted inside this process, so the study stops here; finished points are \
                 kept in the results store. Run again with --isolate to have such runs killed \
                 and marked failed while the study goes on.",
                points.join("; "),
                limit.as_secs_f64()
            ),
        );
    }
}

/// The number of failed points; an error naming the first when failures are not allowed
/// (or the design is weighted: dropping a weighted point would bias every moment silently),
/// with how many of the `points` (None: every point) were not run (the study stops at the
/// first failure).
pub fn check_failures(
    study: &Study,
    design: &Design,
    records: &[Option<Entry>],
    allow: bool,
    points: Option<&[usize]>,
) -> Result<usize, RunError> {
    let failed: Vec<(usize, &String)> = records
        .iter()
        .enumerate()
        .filter_map(|(i, r)| match r {
            Some(Entry::Failed(m)) => Some((i, m)),
            _ => None,
        })
        .collect();
    let Some(&(index, message)) = failed.first() else {
        return Ok(0);
    };
    if allow && !design.is_weighted() {
        return Ok(failed.len());
    }
    let parameters = study
        .parameters
        .iter()
        .zip(&design.values[index])
        .map(|(p, v)| (p.name.clone(), *v))
        .collect();
    let wanted: Vec<usize> = match points {
        Some(p) => p.iter().copied().filter(|&i| i < records.len()).collect(),
        None => (0..records.len()).collect(),
    };
    Err(RunError::PointsFailed {
        failed: failed.len(),
        total: wanted.len(),
        not_run: wanted.iter().filter(|&&i| records[i].is_none()).count(),
        first: FailedPoint {
            index,
            parameters,
            message: message.clone(),
        },
        allow_failures_applies: !design.is_weighted(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_out_folder_that_cannot_be_created_is_refused_as_such_not_as_a_full_disk() {
        let dir = tempfile::tempdir().unwrap();
        // A file where a folder of the path should be: nothing can be created under it.
        let file = dir.path().join("file");
        std::fs::write(&file, "x").unwrap();
        let e = check_out_dir(&file.join("out")).unwrap_err();
        let text = e.to_string();
        assert!(matches!(e, RunError::OutDirNotWritable { .. }), "{text}");
        assert!(text.contains("cannot be created or written"), "{text}");
        assert!(!text.contains("disk"), "{text}");
        assert!(!text.contains("write-test"), "{text}");
        // A folder to be made under an existing one passes, and is not made by the check;
        // nothing is left behind.
        let out = dir.path().join("a/b");
        check_out_dir(&out).unwrap();
        assert!(!out.exists());
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
        check_out_dir(dir.path()).unwrap();
        assert!(matches!(check_out_dir(&file), Err(RunError::NotAFolder(_))));
        // A pseudo file system where no folder can be made (sysfs), where there is one.
        let sys = Path::new("/sys/uq-driver-out");
        if Path::new("/sys/kernel").is_dir() && !sys.exists() {
            let text = check_out_dir(sys).unwrap_err().to_string();
            assert!(text.contains("cannot be created or written"), "{text}");
        }
    }

    /// A study stopped at its first failures said "2 of 200 points failed" although
    /// 103 of them fail; the points not started are not counted as successes.
    #[test]
    fn failure_message_says_the_study_stopped_and_how_many_points_were_not_started() {
        let first = FailedPoint {
            index: 4,
            parameters: vec![("K".into(), 1.5)],
            message: "NaN".into(),
        };
        let err = |failed, not_run| {
            RunError::PointsFailed {
                failed,
                total: 200,
                not_run,
                first: first.clone(),
                allow_failures_applies: true,
            }
            .to_string()
        };
        let one = err(1, 197);
        assert!(
            one.starts_with(
                "stopped at the first failure of 200 points (runs not started: 197; how many \
                 of those would fail is not known); first: point 4 with K = 1.5: NaN."
            ),
            "{one}"
        );
        let two = err(2, 150);
        assert!(
            two.starts_with(
                "stopped after the first 2 failures of 200 points (runs not started: 150;"
            ),
            "{two}"
        );
        assert!(!two.contains("2 of 200 points failed"));
        // Every point run: the count is the whole truth.
        assert!(err(103, 0).starts_with("103 of 200 points failed; first: point 4"));
    }

    /// SCM run with --allow-failures stopped at a failed point and still advised "(or
    /// --allow-failures ...)": a weighted design cannot leave a point out, so the flag is not
    /// offered there; a sampling design's message offers it.
    #[test]
    fn a_weighted_design_that_stops_at_a_failure_does_not_advise_allow_failures() {
        let failed = |method: &str| {
            let base = include_str!("../../../studies/wheel-scm.toml");
            let text = base.replace("kind = \"scm\"\nnodes = 6\norder = 5", method);
            let study = Study::parse(&text, "t.toml", None).unwrap();
            let crate::uq::method::Evaluation::Sampling(m) = study.method().evaluation() else {
                panic!("{method}: a sampling method");
            };
            let design = m.design(&study.random_inputs(), study.seed).unwrap();
            let mut records: Vec<Option<Entry>> = vec![Some(Entry::Ok(0..0)); design.len()];
            records[1] = Some(Entry::Failed("C < 0".into()));
            // With --allow-failures given.
            check_failures(&study, &design, &records, true, None)
        };
        let scm = failed("kind = \"scm\"\nnodes = 3").unwrap_err().to_string();
        assert!(!scm.contains("(or --allow-failures"), "{scm}");
        assert!(
            scm.contains("--allow-failures does not apply: this method's design is weighted"),
            "{scm}"
        );
        assert_eq!(failed("kind = \"lhs\"\nsamples = 20").unwrap(), 1);
    }
}
