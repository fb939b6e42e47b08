//! Splitting a study over a cluster: `plan` writes the study, the FMU's hash and the shard
//! assignment; `run-shard` runs one shard's points into its own folder (resumable, nothing
//! shared with other shards); `merge` checks that every point is present exactly once and
//! that every shard belongs to the plan, then writes the same outputs as `uq-driver run`.
//!
//! Layout of a plan folder `DIR`:
//! ```text
//! DIR/plan.json            study text, FMU path and SHA-256, driver version, shard count
//! DIR/design.csv           index, shard, parameter values of every point
//! DIR/shards/K/store/      shard K's results store (only shard K writes here)
//! DIR/result/              merge output (summary.json, CSVs, plots, index.html)
//! ```
//! Point i belongs to shard i mod N (round robin, so every shard gets a share of the
//! expensive and the cheap regions of the design).

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::spec::Study;
use crate::study::outcome::{StudyResult, StudyRunError};
use crate::study::plan::fingerprint;
use crate::study::plan::ranges;
use crate::study::run::open_fmu;
use crate::study::run::{self, RunError, RunOptions, RunOutcome};
use crate::study::single::finish;
use crate::study::store::lock::FolderLock;
use crate::study::store::{Manifest, Store, StoreError, StoredRuns};
use crate::uq::method::{Design, Evaluation, Sampling};

/// Version of the plan layout.
pub const PLAN_VERSION: u32 = 1;

/// `plan.json`.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct Plan {
    /// Layout version.
    pub version: u32,
    /// uq-driver version that wrote the plan.
    pub driver_version: String,
    /// Where the study came from.
    pub study_origin: String,
    /// The study's TOML text.
    pub study_source: String,
    /// Folder relative paths of the study start from.
    pub study_base: Option<PathBuf>,
    /// Absolute path of the FMU.
    pub fmu_path: PathBuf,
    /// The results-store manifest every shard must have (study hash, FMU SHA-256, sizes).
    pub manifest: Manifest,
    /// Number of shards.
    pub shards: usize,
}

/// Shard failures.
#[derive(Debug, thiserror::Error)]
pub enum ShardError {
    /// File system error.
    #[error("{path}: {source}")]
    Io {
        /// File.
        path: PathBuf,
        /// Cause.
        source: std::io::Error,
    },
    /// plan.json is unreadable or of another version.
    #[error("{path}: {message}")]
    BadPlan {
        /// plan.json.
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
    /// Wrong arguments.
    #[error("{0}")]
    Usage(String),
    /// The study cannot be read back from the plan.
    #[error(transparent)]
    Study(#[from] crate::spec::StudyError),
    /// A shard does not belong to this plan, is missing, or overlaps another.
    #[error("{0}")]
    Shard(String),
    /// Running or writing failed.
    #[error(transparent)]
    Run(#[from] StudyRunError),
}

impl From<RunError> for ShardError {
    fn from(e: RunError) -> Self {
        ShardError::Run(StudyRunError::Run(e))
    }
}

fn io(path: &Path) -> impl FnOnce(std::io::Error) -> ShardError + '_ {
    move |source| ShardError::Io {
        path: path.to_path_buf(),
        source,
    }
}

/// The points of shard `k` of `n` in a design of `len` points.
pub fn shard_points(len: usize, n: usize, k: usize) -> Vec<usize> {
    (k..len).step_by(n.max(1)).collect()
}

/// "a" or "an" before `word` (by its first letter: `an importance_sampling study`).
fn article(word: &str) -> &'static str {
    match word.chars().next() {
        Some('a' | 'e' | 'i' | 'o' | 'u') => "an",
        _ => "a",
    }
}

/// The study's sampling method, or a usage error for a method that runs no design.
fn sampling(study: &Study) -> Result<&dyn Sampling, ShardError> {
    match study.method().evaluation() {
        Evaluation::Sampling(m) => Ok(m),
        Evaluation::Intrusive(_) => Err(ShardError::Usage(format!(
            "a {} study solves its own system without running a model: nothing to shard",
            study.method().kind()
        ))),
        Evaluation::Adaptive(_) => Err(ShardError::Usage(format!(
            "{} {} study chooses its points from the values of the runs before (batch after \
             batch): it cannot be split into shards planned in advance; run it with `uq-driver \
             run` (each batch runs in parallel on the threads of one machine)",
            article(study.method().kind()),
            study.method().kind()
        ))),
    }
}

/// The study's design.
fn design(study: &Study) -> Result<Design, ShardError> {
    let d = sampling(study)?.design(&study.random_inputs(), study.seed);
    Ok(d.map_err(RunError::from)?)
}

/// `uq-driver plan`: writes `DIR/plan.json` and `DIR/design.csv`.
pub fn plan(study: &Study, shards: usize, dir: &Path) -> Result<Plan, ShardError> {
    if shards == 0 {
        return Err(ShardError::Usage("--shards must be at least 1".into()));
    }
    if study.is_suite() {
        return Err(ShardError::Usage(
            "a suite (a study with [[variants]]) cannot be planned as one; plan each variant's study".into(),
        ));
    }
    let design = design(study)?;
    let given = study.fmu_path.clone().unwrap_or_default();
    let fmu_path = std::fs::canonicalize(&given).map_err(io(&given))?;
    let mut study = study.clone();
    study.fmu_path = Some(fmu_path.clone());
    let fmu = open_fmu(&study)?;
    ranges::check_supports(&study, &fmu).map_err(RunError::from)?;
    for w in ranges::range_warnings(&study, &fmu, &design) {
        crate::study::progress::message(&format!("uq-driver: warning: {w}"));
    }
    let manifest = fingerprint::manifest(&study, &fmu, &design)?;
    let p = Plan {
        version: PLAN_VERSION,
        driver_version: env!("CARGO_PKG_VERSION").into(),
        study_origin: study.origin.clone(),
        study_source: study.source.clone(),
        study_base: study
            .base
            .as_ref()
            .and_then(|b| std::fs::canonicalize(b).ok()),
        fmu_path,
        manifest,
        shards,
    };
    std::fs::create_dir_all(dir).map_err(io(dir))?;
    let path = dir.join("plan.json");
    if path.exists() {
        let old = load_plan(dir)?;
        if old != p {
            return Err(ShardError::Usage(format!(
                "{} already holds another plan; use another folder",
                dir.display()
            )));
        }
    }
    out_file::write(
        &path,
        serde_json::to_string_pretty(&p).expect("json").as_bytes(),
    )
    .map_err(io(&path))?;
    let mut csv = String::from("index,shard");
    for par in &study.parameters {
        csv.push(',');
        crate::text::csv::push_field(&mut csv, &par.name);
    }
    csv.push('\n');
    for (i, vals) in design.values.iter().enumerate() {
        csv.push_str(&format!("{i},{}", i % shards));
        for v in vals {
            csv.push(',');
            crate::text::csv::push_shortest(&mut csv, *v);
        }
        csv.push('\n');
    }
    let dpath = dir.join("design.csv");
    out_file::write(&dpath, csv.as_bytes()).map_err(io(&dpath))?;
    Ok(p)
}

/// Reads `DIR/plan.json`.
pub fn load_plan(dir: &Path) -> Result<Plan, ShardError> {
    let path = dir.join("plan.json");
    let text = std::fs::read_to_string(&path).map_err(io(&path))?;
    let p: Plan = serde_json::from_str(&text).map_err(|e| ShardError::BadPlan {
        path: path.clone(),
        message: e.to_string(),
    })?;
    if p.version != PLAN_VERSION {
        return Err(ShardError::BadPlan {
            path,
            message: format!(
                "plan layout version {}, this uq-driver reads {PLAN_VERSION}",
                p.version
            ),
        });
    }
    Ok(p)
}

fn plan_study(p: &Plan) -> Result<Study, ShardError> {
    let mut study = Study::parse(&p.study_source, &p.study_origin, p.study_base.as_deref())?;
    study.fmu_path = Some(p.fmu_path.clone());
    Ok(study)
}

/// Refuses a plan whose study or FMU is no longer the one it was planned with: the manifest
/// the plan's study gives now (its hash, the FMU's SHA-256, the sizes) must be the one
/// `plan.json` recorded, which every shard's store carries too. A `plan.json` whose study
/// was edited (another seed: another design, paired with the shards' outputs of the
/// planned one) or an FMU replaced since is refused, naming what differs.
fn check_plan(
    dir: &Path,
    p: &Plan,
    study: &Study,
    fmu: &crate::fmu::Fmu,
    design: &Design,
) -> Result<(), ShardError> {
    let now = fingerprint::manifest(study, fmu, design)?;
    if now == p.manifest {
        return Ok(());
    }
    let what = if now.fmu_sha256 != p.manifest.fmu_sha256 {
        format!(
            "the FMU {} changed since the plan was written (SHA-256 now {}, planned {})",
            p.fmu_path.display(),
            now.fmu_sha256,
            p.manifest.fmu_sha256
        )
    } else if now.study_hash != p.manifest.study_hash {
        format!(
            "the study in plan.json is not the one that was planned (study hash now {}, \
             planned {}): plan.json was edited, or the study's input file changed; plan \
             again into a new folder",
            now.study_hash, p.manifest.study_hash
        )
    } else {
        format!(
            "the design has {} points of {} values, the plan {} of {}",
            now.n_points, now.n_values, p.manifest.n_points, p.manifest.n_values
        )
    };
    Err(ShardError::Shard(format!("{}: {what}", dir.display())))
}

/// Why shard `k` of a plan of `shards` shards cannot run: `shard 3 does not exist: the plan
/// has shards 0 to 2` (the last index written out, not Rust's exclusive range `0..3`).
fn no_such_shard(k: usize, shards: usize) -> String {
    match shards {
        0 => format!("shard {k} does not exist: the plan has no shards"),
        1 => format!("shard {k} does not exist: the plan has one shard, 0"),
        n => format!(
            "shard {k} does not exist: the plan has shards 0 to {}",
            n - 1
        ),
    }
}

/// `uq-driver run-shard`: runs shard `k` of the plan in `dir`.
pub fn run_shard(dir: &Path, k: usize, opts: &RunOptions) -> Result<RunOutcome, ShardError> {
    let p = load_plan(dir)?;
    if k >= p.shards {
        return Err(ShardError::Usage(no_such_shard(k, p.shards)));
    }
    let study = plan_study(&p)?;
    let fmu = open_fmu(&study)?;
    let design = design(&study)?;
    check_plan(dir, &p, &study, &fmu, &design)?;
    let opts = RunOptions {
        points: Some(shard_points(design.len(), p.shards, k)),
        ..opts.clone()
    };
    let sdir = dir.join("shards").join(k.to_string());
    let outcome = run::run_points(&study, &fmu, &design, &sdir, &opts)?;
    run::check_failures(
        &study,
        &design,
        outcome.runs.entries(),
        opts.allow_failures(&study),
        opts.points.as_deref(),
    )?;
    Ok(outcome)
}

/// `uq-driver merge`: checks the shards and writes the study's outputs into `out`.
pub fn merge(dir: &Path, out: &Path, opts: &RunOptions) -> Result<StudyResult, ShardError> {
    let p = load_plan(dir)?;
    let study = plan_study(&p)?;
    let method = sampling(&study)?;
    let fmu = open_fmu(&study)?;
    let design = design(&study)?;
    check_plan(dir, &p, &study, &fmu, &design)?;
    let iface = crate::study::plan::resolve::interface(&study, &fmu).map_err(RunError::from)?;
    let rules = run::record_rules(&iface, &study.times());
    let n = design.len();
    // The analysis's memory, checked as `run` checks it (refused, or large: `--yes`).
    crate::study::plan::size::check_runs(&study, n, opts).map_err(StudyRunError::from)?;
    // Each shard's results, read in place: the merge holds no series in memory.
    let mut shard_runs: Vec<Option<StoredRuns>> = Vec::new();
    let mut owner: Vec<Option<usize>> = vec![None; n];
    let mut incomplete = Vec::new();
    for k in 0..p.shards {
        let sdir = dir.join("shards").join(k.to_string());
        if !sdir.join("store").join("manifest.json").exists() {
            incomplete.push(format!(
                "shard {k}: missing ({} has no results)",
                sdir.display()
            ));
            continue;
        }
        shard_runs.resize_with(k + 1, || None);
        let opened =
            Store::open_checked(&sdir, &p.manifest, false, Some(&rules)).map(|(_, runs)| runs);
        let recs = opened.map_err(|e| match e {
            StoreError::Mismatch { what, .. } => ShardError::Shard(format!(
                "shard {k} ({}) does not belong to this plan: {what}",
                sdir.display()
            )),
            other => ShardError::Run(StudyRunError::Run(RunError::Store(other))),
        })?;
        let mut missing = 0;
        for i in shard_points(n, p.shards, k) {
            if recs.entries()[i].is_none() {
                missing += 1;
            }
        }
        for (i, r) in recs.entries().iter().enumerate() {
            if r.is_none() {
                continue;
            }
            if i % p.shards != k {
                return Err(ShardError::Shard(format!(
                    "point {i} appears in shard {k}, but belongs to shard {}",
                    i % p.shards
                )));
            }
            if let Some(other) = owner[i] {
                return Err(ShardError::Shard(format!(
                    "point {i} appears in shards {other} and {k}"
                )));
            }
            owner[i] = Some(k);
        }
        shard_runs[k] = Some(recs);
        if missing > 0 {
            incomplete.push(format!(
                "shard {k}: {missing} points not finished (run it again: it resumes)"
            ));
        }
    }
    if !incomplete.is_empty() {
        return Err(ShardError::Shard(format!(
            "cannot merge {}: {}",
            dir.display(),
            incomplete.join("; ")
        )));
    }
    // The merged store makes `out` look like (and resume like) a single-machine run.
    run::prepare_out_dir(out).map_err(StudyRunError::Run)?;
    let lock = FolderLock::acquire(out).map_err(|e| StudyRunError::Run(e.into()))?;
    let (store, mut runs) = Store::open_in_place(out, &p.manifest, true).map_err(RunError::from)?;
    for (i, k) in owner.iter().enumerate() {
        let shard = k.and_then(|k| shard_runs[k].as_ref());
        let rec = shard
            .map(|r| r.record(i))
            .transpose()
            .map_err(RunError::from)?;
        let rec = rec.flatten().expect("checked complete");
        runs.set(i, store.append(i, &rec).map_err(RunError::from)?);
    }
    drop(shard_runs);
    let outcome = RunOutcome {
        runs,
        _lock: Some(lock),
        n_new: 0,
        n_resumed: n,
        wall_time: 0.0,
        threads: 0,
        fmu_sha256: p.manifest.fmu_sha256.clone(),
        warnings: Vec::new(),
    };
    finish(&study, method, &fmu, &design, outcome, out, opts).map_err(ShardError::Run)
}

/// Options of `uq-driver slurm`.
#[derive(Clone, Debug, Default)]
pub struct SlurmOptions {
    /// Partition (`--partition`).
    pub partition: Option<String>,
    /// Time limit per task (`--time`).
    pub time: Option<String>,
    /// CPUs per shard task (`--cpus-per-task`), also the threads of each shard.
    pub cpus_per_task: Option<usize>,
    /// Extra `#SBATCH` lines.
    pub extra: Vec<String>,
    /// The merge writes the CSV files and `summary.json` only (`merge --no-report`).
    pub no_report: bool,
    /// Options of every `run-shard` (e.g. `--isolate`, `--fresh-instances`): words without
    /// blanks or quotes, written after the command.
    pub shard_args: Vec<String>,
}

/// Writes `DIR/slurm/shard.sbatch` and `DIR/slurm/merge.sbatch`; returns their paths.
pub fn write_sbatch(
    dir: &Path,
    driver: &Path,
    shards: usize,
    o: &SlurmOptions,
) -> Result<(PathBuf, PathBuf), ShardError> {
    let sdir = dir.join("slurm");
    out_file::sub_folder(&sdir).map_err(io(&sdir))?;
    let dir = std::fs::canonicalize(dir).map_err(io(dir))?;
    if dir.to_string_lossy().contains(char::is_whitespace) {
        // #SBATCH lines are not parsed by a shell: a path with blanks cannot be written there.
        return Err(ShardError::Usage(format!(
            "{}: the plan folder's path must not contain blanks for #SBATCH --output",
            dir.display()
        )));
    }
    let q = |p: &Path| format!("'{}'", p.display().to_string().replace('\'', "'\\''"));
    let mut common = String::new();
    if let Some(p) = &o.partition {
        common.push_str(&format!("#SBATCH --partition={p}\n"));
    }
    if let Some(t) = &o.time {
        common.push_str(&format!("#SBATCH --time={t}\n"));
    }
    for e in &o.extra {
        common.push_str(&format!("#SBATCH {e}\n"));
    }
    let cpus = o.cpus_per_task.unwrap_or(1);
    let shard = format!(
        "#!/bin/bash\n#SBATCH --job-name=uq-shard\n#SBATCH --array=0-{last}\n#SBATCH --cpus-per-task={cpus}\n#SBATCH --output={log}/shard-%a.out\n{common}\
         # One array task per shard; a re-submitted task resumes from its own store.\n\
         exec {driver} run-shard {dir} --shard \"$SLURM_ARRAY_TASK_ID\" --threads \"${{SLURM_CPUS_PER_TASK:-{cpus}}}\"{args}\n",
        args = o.shard_args.iter().map(|a| format!(" {}", q(Path::new(a)))).collect::<String>(),
        last = shards - 1,
        log = dir.join("slurm").display(),
        driver = q(driver),
        dir = q(&dir),
    );
    let merge = format!(
        "#!/bin/bash\n#SBATCH --job-name=uq-merge\n#SBATCH --cpus-per-task={cpus}\n#SBATCH --kill-on-invalid-dep=yes\n#SBATCH --output={log}/merge.out\n{common}\
         # The study was checked (and confirmed, if large) when it was planned.\n\
         exec {driver} merge {dir} --out {out} --yes{no_report}\n",
        log = dir.join("slurm").display(),
        driver = q(driver),
        dir = q(&dir),
        out = q(&dir.join("result")),
        no_report = if o.no_report { " --no-report" } else { "" },
    );
    let (a, b) = (sdir.join("shard.sbatch"), sdir.join("merge.sbatch"));
    out_file::write(&a, shard.as_bytes()).map_err(io(&a))?;
    out_file::write(&b, merge.as_bytes()).map_err(io(&b))?;
    Ok((a, b))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_missing_shard_names_the_last_shard_not_an_exclusive_range() {
        assert_eq!(
            no_such_shard(3, 3),
            "shard 3 does not exist: the plan has shards 0 to 2"
        );
        assert!(!no_such_shard(3, 3).contains(".."));
        assert_eq!(
            no_such_shard(1, 1),
            "shard 1 does not exist: the plan has one shard, 0"
        );
    }

    #[test]
    fn the_array_job_runs_its_shards_with_the_options_given_to_slurm() {
        // `slurm --isolate` (or --fresh-instances, --fmu-logging) planned shards
        // that ran without them.
        let d = tempfile::tempdir().unwrap();
        let o = SlurmOptions {
            shard_args: vec!["--isolate".into(), "--timeout-per-run=2.5".into()],
            ..SlurmOptions::default()
        };
        let (shard, merge) = write_sbatch(d.path(), Path::new("/bin/uq-driver"), 3, &o).unwrap();
        let text = std::fs::read_to_string(shard).unwrap();
        let exec = text.lines().last().unwrap();
        assert!(
            exec.starts_with("exec '/bin/uq-driver' run-shard"),
            "{exec}"
        );
        assert!(
            exec.ends_with(" '--isolate' '--timeout-per-run=2.5'"),
            "{exec}"
        );
        let merge = std::fs::read_to_string(merge).unwrap();
        assert!(!merge.contains("--isolate"));
    }

    #[test]
    fn shards_partition_the_design() {
        let mut all: Vec<usize> = (0..4).flat_map(|k| shard_points(10, 4, k)).collect();
        all.sort_unstable();
        assert_eq!(all, (0..10).collect::<Vec<_>>());
        assert_eq!(shard_points(10, 4, 1), vec![1, 5, 9]);
        assert!(shard_points(2, 4, 3).is_empty());
    }
}
