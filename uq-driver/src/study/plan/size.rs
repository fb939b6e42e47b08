//! Guards against designs too large to run, checked before anything is allocated or run.
//!
//! A study is estimated first ([`Footprint`]): its model runs (from the method, without
//! building the design: [`Sampling::planned_runs_for`](crate::uq::method::Sampling), e.g. a
//! sparse grid's points counted from its rules), the memory the driver will hold, and the wall time. Then:
//! - it is **refused** (whatever `--yes` says) when the memory estimate exceeds the memory
//!   available to the process ([`available_memory`]): it could not be allocated;
//! - it **needs `--yes`** when it has more than [`MAX_RUNS`] model runs, when the memory
//!   estimate exceeds [`MEMORY_FRACTION`] of the available memory, or when the time estimate
//!   exceeds [`MAX_SECONDS`].
//!
//! Memory (bytes), with `n` runs, `nt` communication points, `s` stored outputs, `q` scalar
//! quantities, `g` signals read per step, `d` random parameters, `T` threads, `P` columns
//! whose densities are shown (`pdf_times + 1`), `k` quantile levels, `S` surrogate draws of
//! a series (`min(series_samples, surrogate_samples)`, for a method that may build a chaos;
//! else 0), `B` the analysis's block budget ([`blocks::block_bytes`](crate::study::analysis::blocks::block_bytes), 256 MiB unless
//! `RAILUQ_ANALYSIS_BLOCK_BYTES` says otherwise):
//! - the records: the series of the runs are written to the results store as each run
//!   finishes and are not held; per run, where its values are and its place in the analysis,
//!   `n (96 + 16 q)` ([`Memory::records`]);
//! - the results store is read in place (a resumed study scans it through a memory map: page
//!   cache, not the process's memory), so nothing is counted for it ([`Memory::store`] is 0);
//!   only repairing a damaged store copies its valid records into memory;
//! - the analysis of one output, a block of `w` time columns at a time
//!   ([`blocks::block_width`](crate::study::analysis::blocks::block_width): `w = nt` when `2 × 8 n nt ≤ B`, else the largest multiple of
//!   32 columns within `B`, at least 32): the block, the buffer it is read through and the
//!   estimator's copy, `3 × 8 n w`; for a method that may build a chaos, a block of surrogate
//!   draws, `2 × 8 S w_S`; the draws kept for the densities, `8 P max(n, S)`; the column
//!   summaries of that output, `8 nt (10 + k)`; and, kept for every output until the report,
//!   its statistics over time, `8 s nt (8 + k + σ)` (`σ = 6d + 20` for a method with
//!   Sobol' indices: a chaos or `sobol_sampling`, else 0), and its densities,
//!   `1.5 × 8 s P' G` (`P' = min(P, nt)` columns of `G = pdf_grid` points, with their rows
//!   and text). A nested study analyses the whole series of an output at once:
//!   `2.5 × 8 n nt` instead of the blocks (its runs are the outer samples × the inner
//!   points, counted before the design).
//! - for `sparse_grid` and `pce_regression`, what grows with the chaos terms: the fit, the
//!   surrogate's basis at its draws and the coefficients (`size/chaos.rs`, [`Memory::chaos`]);
//! - the design (coordinates and values) and its copy in the report: `4 n (8 d + 24)`;
//! - per worker thread, the signals of one run three times over: `3 × 8 T g nt` (freed
//!   before the analysis: the larger of the two counts);
//! - the time grid (a few copies): `4 × 8 nt`.
//!
//! The peak is the design, grid and records plus the analysis (or the worker buffers) and
//! the chaos.
//!
//! Time: measured, for studies of at least [`PROBE_MIN_STEPS`] communication steps in all
//! (runs × steps; a smaller study reaches an hour only if one step costs more than 0.36 ms on
//! one thread, and is not timed). The FMU is run at the parameters' means on short grids: a
//! warm-up of one communication step, then 1 step (best of 3), then [`PROBE_STEPS`], 4×, 16×,
//! … steps (best of 2) until a run takes 4 times the one-step run and [`PROBE_MIN_SECONDS`]
//! more (the steps show above the initialisation and the timer's noise), the whole
//! experiment or [`PROBE_SECONDS`]; the cost of a run is the cost of the one-step run
//! plus that of the other steps at the measured rate, and the study takes `n` such
//! runs on `T` threads (the runner's own work, e.g. writing the store, is not included: the
//! wheel's runs take about twice the estimate). A `hunting_speed` quantity adds its own runs to
//! every point: the point then costs as much as its simulated time, the experiment plus
//! 2 + ⌈log2((high − low)/tolerance)⌉ runs of `duration` ([`Shape::cost_factor`]). An FMU that fails the probe gives no time
//! estimate (the study then reports the failure itself). With `--isolate` or
//! `--timeout-per-run` the study is not timed (the timing run would run the FMU in-process,
//! without a limit).

mod available;
mod chaos;
mod disk;
mod shape;

pub use shape::Shape;

use std::fmt;
use std::path::Path;
use std::time::Instant;

use crate::spec::Study;
use crate::study::plan::interface::Interface;
use crate::study::run;
use crate::study::run::guard::StudyGuard;
use crate::study::run::options::RunOptions;
use crate::uq::method::Evaluation;

/// More model runs than this need `--yes`.
pub const MAX_RUNS: f64 = 100_000.0;
/// A memory estimate above this fraction of the available memory needs `--yes`.
pub const MEMORY_FRACTION: f64 = 0.5;
/// A time estimate above this (s; one hour) needs `--yes`.
pub const MAX_SECONDS: f64 = 3600.0;
/// Communication steps of the first timed run of the probe (then 4×, 16×, … as needed).
pub const PROBE_STEPS: usize = 50;
/// The probe's runs stop growing once one takes this long (s).
pub const PROBE_SECONDS: f64 = 1.0;
/// ... or once the steps of one take this long beyond the one-step run (s).
pub const PROBE_MIN_SECONDS: f64 = 0.02;
/// Studies of fewer communication steps in all (runs × steps) are not timed.
pub const PROBE_MIN_STEPS: f64 = 1e7;
/// Memory assumed available where the system does not say (bytes; 4 GiB).
pub const ASSUMED_MEMORY: f64 = 4.0 * GIB;

const GIB: f64 = 1024.0 * 1024.0 * 1024.0;

pub use available::available_memory;
pub use disk::Disk;

/// Why a study does not start.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum SizeError {
    /// The study's results store needs more disk space than there is.
    #[error(
        "the study cannot run: {footprint}; its results store needs about {store} on disk, more \
         than the {free} free for it, so it is refused even with --yes. Use fewer samples, a \
         coarser communication step, a shorter experiment, fewer outputs or an --out folder on \
         a larger disk"
    )]
    NoDisk {
        /// The estimate.
        footprint: Box<Footprint>,
        /// The store's size (formatted).
        store: String,
        /// The free space (formatted).
        free: String,
    },
    /// The study needs more memory than there is.
    #[error(
        "the study cannot run: {footprint}; it needs more memory than the {limit} available \
         to this process, so it is refused even with --yes. Use fewer samples, a coarser \
         communication step, a shorter experiment or fewer outputs{suggest}"
    )]
    Refused {
        /// The estimate.
        footprint: Box<Footprint>,
        /// The memory available (formatted).
        limit: String,
        /// A hint for many random parameters.
        suggest: Suggestion,
    },
    /// A command's result needs more memory than there is (e.g. `surrogate sample -n`).
    #[error(
        "{what} needs about {need} of memory, more than the {limit} available to this process"
    )]
    NoMemory {
        /// What needs it.
        what: String,
        /// The memory it needs (formatted).
        need: String,
        /// The memory available (formatted).
        limit: String,
    },
    /// The study is large: it starts only with `--yes`.
    #[error(
        "the study is large ({reasons}): {footprint}. Run again with --yes to start it \
         anyway{suggest}"
    )]
    NeedsConfirmation {
        /// The estimate.
        footprint: Box<Footprint>,
        /// What is large.
        reasons: String,
        /// A hint for many random parameters.
        suggest: Suggestion,
    },
}

/// The hint that ends a refusal.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Suggestion {
    /// Cheaper methods exist.
    FewerRuns,
    /// The study is a chaos whose terms make it large.
    SmallerChaos,
}

impl Suggestion {
    /// The hint for the study estimated by `f`.
    fn for_footprint(f: &Footprint) -> Suggestion {
        if f.memory.chaos > 0.0 {
            Suggestion::SmallerChaos
        } else {
            Suggestion::FewerRuns
        }
    }
}

impl fmt::Display for Suggestion {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Suggestion::FewerRuns => write!(
                f,
                ", or use a method that needs far fewer runs for a smooth response in many \
                 random parameters: `kind = \"sparse_grid\"` or `kind = \"pce_regression\"`"
            ),
            Suggestion::SmallerChaos => write!(
                f,
                ", or a chaos of fewer terms: a lower `level` or `order` (or `q_norm`), fewer \
                 random parameters, or fewer `[analysis] series_samples` and \
                 `surrogate_samples`"
            ),
        }
    }
}

/// The estimated size of a study.
#[derive(Clone, Debug, PartialEq)]
pub struct Footprint {
    /// Model runs (`None`: only the design knows, see [`check_runs`]).
    pub runs: Option<f64>,
    /// Communication points per run.
    pub time_points: f64,
    /// Peak memory (bytes), by part.
    pub memory: Memory,
    /// Memory available to the process (bytes), and whether the system said so.
    pub available: (f64, bool),
    /// Time estimate, if measured.
    pub time: Option<TimeEstimate>,
    /// The results store against the free disk space, where known.
    pub disk: Option<Disk>,
}

/// The memory estimate by part (bytes).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Memory {
    /// Where the records of the runs are (their values stay in the store).
    pub records: f64,
    /// The store read back on resume: 0, it is read in place (kept for the summary's shape).
    pub store: f64,
    /// The analysis of one output in blocks, the statistics of all, and the workers' buffers.
    pub analysis: f64,
    /// The design and its copies.
    pub design: f64,
    /// The time grid.
    pub grid: f64,
    /// What grows with the terms of a chaos ([`ChaosShape::memory`]: the fit, the
    /// surrogate's basis at its draws, the coefficients).
    pub chaos: f64,
}

impl Memory {
    /// The peak (bytes).
    pub fn total(&self) -> f64 {
        self.design + self.grid + self.records + self.store.max(self.analysis) + self.chaos
    }
}

/// The wall-time estimate.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TimeEstimate {
    /// One run (s).
    pub per_run: f64,
    /// The study (s).
    pub total: f64,
    /// Threads it assumes.
    pub threads: usize,
}

impl fmt::Display for Footprint {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.runs {
            Some(n) => write!(f, "{} model runs", count(n))?,
            None => write!(f, "model runs not known before the design")?,
        }
        write!(
            f,
            " of {} communication points, about {} of memory (records {}, analysis {}, \
             design {}{}; {} {})",
            count(self.time_points),
            bytes(self.memory.total()),
            bytes(self.memory.records),
            bytes(self.memory.analysis),
            bytes(self.memory.design),
            if self.memory.chaos > 0.0 {
                format!(", chaos {}", bytes(self.memory.chaos))
            } else {
                String::new()
            },
            bytes(self.available.0),
            if self.available.1 {
                "available"
            } else {
                "assumed available: the system does not say"
            }
        )?;
        match self.time {
            Some(t) => write!(
                f,
                ", about {} on {} thread{} ({} per run, measured on a short run at the \
                 parameters' means)",
                duration(t.total),
                t.threads,
                if t.threads == 1 { "" } else { "s" },
                duration(t.per_run)
            ),
            None => write!(f, ", time not estimated"),
        }
    }
}

/// A count, exact below 10^15.
fn count(n: f64) -> String {
    if n < 1e15 {
        format!("{n:.0}")
    } else {
        format!("{n:.3e}")
    }
}

/// Bytes in binary units.
pub fn bytes(b: f64) -> String {
    const UNITS: [&str; 7] = ["B", "KiB", "MiB", "GiB", "TiB", "PiB", "EiB"];
    let mut v = b;
    let mut unit = 0;
    while v >= 1024.0 && unit + 1 < UNITS.len() {
        v /= 1024.0;
        unit += 1;
    }
    if unit + 1 == UNITS.len() && v >= 1024.0 {
        return format!("{b:.3e} B");
    }
    format!("{v:.1} {}", UNITS[unit])
}

/// Seconds in the largest sensible unit.
pub fn duration(s: f64) -> String {
    if s < 1e-3 {
        format!("{:.0} µs", s * 1e6)
    } else if s < 1.0 {
        format!("{:.1} ms", s * 1e3)
    } else if s < 120.0 {
        format!("{s:.1} s")
    } else if s < 7200.0 {
        format!("{:.0} min", s / 60.0)
    } else if s < 3.0 * 86400.0 {
        format!("{:.1} h", s / 3600.0)
    } else if s < 3.0 * 365.25 * 86400.0 {
        format!("{:.0} days", s / 86400.0)
    } else {
        format!("{:.2e} years", s / (365.25 * 86400.0))
    }
}

/// Checks `study` (to be written to `out_dir`) before anything is allocated or run (a suite:
/// each variant). Opens the FMU to time a short run, unless the points are to run isolated
/// or under a time limit (`--isolate`, `--timeout-per-run`: the timing run would run the FMU
/// in-process, without a limit). `Ok` with the estimate when it may start.
pub fn check(
    study: &Study,
    out_dir: &Path,
    opts: &RunOptions,
) -> Result<Vec<Footprint>, SizeError> {
    let studies: Vec<&Study> = match &study.suite {
        Some(s) => s.variants.iter().collect(),
        None => vec![study],
    };
    studies
        .into_iter()
        .map(|s| check_one(s, out_dir, opts))
        .collect()
}

fn check_one(study: &Study, out_dir: &Path, opts: &RunOptions) -> Result<Footprint, SizeError> {
    let threads = opts
        .threads
        .unwrap_or_else(rayon::current_num_threads)
        .max(1);
    let shape = Shape::of(study, threads);
    let mut footprint = estimate(&shape, shape.runs);
    let runs_model = !matches!(study.method().evaluation(), Evaluation::Intrusive(_));
    if let (Some(n), true) = (shape.runs, runs_model) {
        let values = shape.outputs as f64 * shape.time_points + 2.0 * shape.quantities as f64;
        footprint.disk = disk::free_bytes(out_dir).map(|free| Disk {
            store: disk::store_bytes(n, values),
            free,
        });
    }
    judge(&footprint, true)?;
    let timed = opts.isolate.is_none() && opts.timeout_per_run.is_none();
    if let (Some(n), true) = (shape.runs, runs_model) {
        let steps = n * (shape.time_points - 1.0).max(1.0) * shape.cost_factor;
        if timed && steps >= PROBE_MIN_STEPS {
            let per_point = probe(study, out_dir).map(|run| run * shape.cost_factor);
            footprint.time = per_point.map(|per_run| TimeEstimate {
                per_run,
                total: per_run * (n / threads as f64).ceil(),
                threads,
            });
        }
    }
    judge(&footprint, opts.yes)?;
    Ok(footprint)
}

/// Checks a design whose size only the design knew (a method without
/// [`planned_runs`](crate::uq::method::Sampling::planned_runs)), before it runs.
pub fn check_runs(study: &Study, runs: usize, opts: &RunOptions) -> Result<Footprint, SizeError> {
    let threads = opts
        .threads
        .unwrap_or_else(rayon::current_num_threads)
        .max(1);
    let shape = Shape::of(study, threads);
    let footprint = estimate(&shape, Some(runs as f64));
    judge(&footprint, opts.yes)?;
    Ok(footprint)
}

/// Checks one deterministic run (`uq-driver simulate`) of `time_points` communication points
/// recording `series` variables, written as CSV text: refused when it cannot be held in
/// memory (the series, twice, and about 25 bytes of text per value).
pub fn check_simulation(time_points: f64, series: usize) -> Result<Footprint, SizeError> {
    let values = time_points * (series as f64 + 1.0);
    let footprint = Footprint {
        runs: Some(1.0),
        time_points,
        memory: Memory {
            records: 2.0 * 8.0 * values,
            analysis: 25.0 * values,
            grid: 4.0 * 8.0 * time_points,
            ..Memory::default()
        },
        available: memory_available(),
        time: None,
        disk: None,
    };
    judge(&footprint, true)?;
    Ok(footprint)
}

/// The footprint of `shape` with `runs` runs (none known: the grid and one run's buffers).
pub fn estimate(shape: &Shape, runs: Option<f64>) -> Footprint {
    Footprint {
        runs,
        time_points: shape.time_points,
        memory: shape.memory(runs.unwrap_or(1.0)),
        available: memory_available(),
        time: None,
        disk: None,
    }
}

/// The memory available to the process (bytes), and whether the system said so (else
/// [`ASSUMED_MEMORY`]).
fn memory_available() -> (f64, bool) {
    match available_memory() {
        Some(b) => (b, true),
        None => (ASSUMED_MEMORY, false),
    }
}

/// Refuses what cannot be allocated; asks for `--yes` (unless `yes`) for what is large.
pub fn judge(f: &Footprint, yes: bool) -> Result<(), SizeError> {
    let total = f.memory.total();
    let available = f.available.0;
    if total.is_nan() || total > available {
        return Err(SizeError::Refused {
            footprint: Box::new(f.clone()),
            limit: bytes(available),
            suggest: Suggestion::for_footprint(f),
        });
    }
    if let Some(d) = f.disk.filter(|d| d.store.is_nan() || d.store > d.free) {
        return Err(SizeError::NoDisk {
            footprint: Box::new(f.clone()),
            store: bytes(d.store),
            free: bytes(d.free),
        });
    }
    if yes {
        return Ok(());
    }
    let mut reasons = Vec::new();
    if let Some(n) = f.runs.filter(|&n| n > MAX_RUNS) {
        reasons.push(format!(
            "{} model runs, more than {}",
            count(n),
            count(MAX_RUNS)
        ));
    }
    if total > MEMORY_FRACTION * available {
        reasons.push(format!(
            "about {} of memory, more than half of the {} available",
            bytes(total),
            bytes(available)
        ));
    }
    if let Some(t) = f.time.filter(|t| t.total > MAX_SECONDS) {
        reasons.push(format!(
            "about {}, more than {}",
            duration(t.total),
            duration(MAX_SECONDS)
        ));
    }
    if reasons.is_empty() {
        return Ok(());
    }
    Err(SizeError::NeedsConfirmation {
        footprint: Box::new(f.clone()),
        reasons: reasons.join("; "),
        suggest: Suggestion::for_footprint(f),
    })
}

/// The cost of one run of `study` (s), measured on a short run at the parameters' means, or
/// `None` when the FMU cannot be opened or fails the short run.
fn probe(study: &Study, out_dir: &Path) -> Option<f64> {
    // An FMU that calls exit() here is reported as during a study.
    let study_guard = StudyGuard::begin(&study.name, out_dir, true);
    let _running = study_guard.running(
        0,
        "a short timing run at the parameters' means, before the study".to_owned(),
    );
    let fmu = run::open_fmu(study).ok()?;
    let iface = Interface {
        qois: Vec::new(),
        ..crate::study::plan::resolve::interface(study, &fmu).ok()?
    };
    let values: Vec<f64> = study
        .parameters
        .iter()
        .map(|p| p.distribution.mean())
        .collect();
    let e = &study.experiment;
    let steps = ((e.stop - e.start) / e.step).round();
    let grid = |m: usize| -> Vec<f64> { (0..=m).map(|i| e.start + i as f64 * e.step).collect() };
    // Reused through fmi2Reset (a failed reset gets a fresh instance): the timing of a run,
    // not of an instantiation.
    let policy = crate::study::run::instances::InstancePolicy {
        reuse: true,
        logging_on: false,
    };
    let mut slot = crate::study::run::instances::Slot::new(policy, false);
    // The best of a few repeats: other work on the machine only ever adds time.
    let mut time = |m: usize, repeats: usize| -> Option<f64> {
        let times = grid(m);
        let mut best = f64::INFINITY;
        for _ in 0..repeats {
            let started = Instant::now();
            run::point::run_point(&fmu, &mut slot, &iface, &values, &times).ok()?;
            best = best.min(started.elapsed().as_secs_f64());
        }
        Some(best)
    };
    time(1, 1)?; // warm-up: the instance is created here
    let one = time(1, 3)?;
    if steps <= 1.0 {
        return Some(one);
    }
    // Longer runs until the steps show well above the start-up (initialisation may cost as
    // much as thousands of steps) and above timer noise, at most the whole run or a second.
    let mut k = (steps as usize).clamp(2, PROBE_STEPS);
    loop {
        let many = time(k, 2)?;
        let clear = many >= 4.0 * one && many - one >= PROBE_MIN_SECONDS;
        if clear || k as f64 >= steps || many > PROBE_SECONDS {
            let per_step = ((many - one) / (k - 1) as f64).max(0.0);
            return Some(one + per_step * (steps - 1.0));
        }
        k = (k * 4).min(steps as usize);
    }
}

#[cfg(test)]
mod tests {
    use super::shape::block_columns;
    use super::*;
    use crate::study::analysis::blocks;
    use crate::uq::method::MethodSpec;

    fn wheel_shape(runs: f64) -> Shape {
        Shape {
            runs: Some(runs),
            time_points: 501.0,
            outputs: 1,
            quantities: 0,
            signals: 1,
            dim: 2,
            threads: 2,
            surrogate_samples: 20_000,
            cost_factor: 1.0,
            series_draws: 4_000,
            pdf_columns: 151,
            pdf_grid: 200,
            sobol: false,
            quantile_levels: 3,
            block_bytes: 256.0 * 1024.0 * 1024.0,
            whole_series: false,
            chaos: None,
        }
    }

    #[test]
    fn hunting_speed_runs_count_in_the_cost_of_a_point() {
        let s = Study::load("builtin:bogie-nominal").unwrap();
        let shape = Shape::of(&s, 1);
        // v_cr, v_cr_linear, v_hunt, v_hunt_decay.
        assert_eq!(shape.quantities, 4);
        // The 650 s ramp plus 14 runs of 300 s (40–100 m/s to 0.02 m/s).
        assert_eq!(shape.cost_factor, 1.0 + 14.0 * 300.0 / 650.0);
        let s = Study::load("builtin:bogie-lhs-500").unwrap();
        assert_eq!(Shape::of(&s, 1).cost_factor, 1.0);
    }

    fn footprint(shape: &Shape, available: f64) -> Footprint {
        Footprint {
            available: (available, true),
            ..estimate(shape, shape.runs)
        }
    }

    #[test]
    fn memory_estimate_counts_records_analysis_and_design() {
        let m = wheel_shape(1000.0).memory(1000.0);
        // Where the 1000 records are (their values stay in the store).
        assert_eq!(m.records, 1000.0 * 96.0);
        assert_eq!(m.store, 0.0);
        // One block of all 501 columns, the draws likewise, the kept draws, the statistics.
        let blocks = 3.0 * 8.0 * 1000.0 * 501.0 + 2.0 * 8.0 * 4000.0 * 501.0;
        let kept = 8.0 * 151.0 * 4000.0;
        let columns = 8.0 * 501.0 * (10.0 + 3.0);
        let stats = 8.0 * 501.0 * (8.0 + 3.0) + 1.5 * 8.0 * 151.0 * 200.0;
        let workers: f64 = 3.0 * 8.0 * 2.0 * 501.0;
        assert_eq!(m.analysis, workers.max(blocks + kept + columns + stats));
        assert_eq!(m.design, 4.0 * 1000.0 * (16.0 + 24.0));
        assert_eq!(m.total(), m.design + m.grid + m.records + m.analysis);
        // Quantities only (no output): no surrogate draws over time.
        let q = Shape {
            outputs: 0,
            quantities: 2,
            ..wheel_shape(10.0)
        };
        assert!(q.memory(10.0).analysis < 1e7);
    }

    /// The many-output studies (`Many<N>.fmu`, 2 fixed-parameter inputs, lhs) of `s`
    /// outputs, `nt` times and `n` runs.
    fn many_outputs(s: usize, nt: f64, n: f64) -> Shape {
        Shape {
            outputs: s,
            signals: s,
            time_points: nt,
            surrogate_samples: 0,
            series_draws: 0,
            ..wheel_shape(n)
        }
    }

    #[test]
    fn many_outputs_count_the_densities_and_statistics_kept_per_output() {
        // Peak RSS 224 MB (1000 outputs × 101 times × 200 runs) and 429 MB
        // (2000 × 101 × 100), estimated 26 and 51 MiB: the densities of every output
        // (101 columns × 200 grid points) were not counted.
        for (s, n, peak) in [(1000, 200.0, 224e6), (2000, 100.0, 429e6)] {
            let total = many_outputs(s, 101.0, n).memory(n).total();
            assert!(
                total >= peak && total <= 2.0 * peak,
                "{s}: {}",
                bytes(total)
            );
        }
        // Few outputs keep their estimates (28 MB and 87 MB measured).
        for (s, peak) in [(20, 28e6), (200, 87e6)] {
            let total = many_outputs(s, 1001.0, 500.0).memory(500.0).total();
            assert!(total <= 2.0 * peak, "{s}: {}", bytes(total));
        }
    }

    #[test]
    fn many_outputs_with_long_series_are_estimated_by_what_the_analysis_holds() {
        // 100 and 200 outputs × 100 001 times × 10 runs peaked at 791 MB and
        // 1.55 GB, estimated 2.5 and 4.9 GiB (refused under a 2 GiB cap).
        for (s, peak) in [(100, 791e6), (200, 1.55e9)] {
            let total = many_outputs(s, 100_001.0, 10.0).memory(10.0).total();
            assert!(
                total >= peak && total <= 1.5 * peak,
                "{s}: {}",
                bytes(total)
            );
        }
        let f = footprint(&many_outputs(100, 100_001.0, 10.0), 1.8 * GIB);
        assert!(judge(&f, true).is_ok(), "{f}");
    }

    fn nested_study(outer: usize, inner: usize, step: f64) -> Study {
        let text = format!(
            "name = \"n\"\nfmu = \"Functions.fmu\"\n[experiment]\nstart = 0.0\nstop = 1.0\n\
             step = {step}\n[[parameters]]\nname = \"a\"\ndistribution = \"uniform\"\n\
             low = 0.0\nhigh = 1.0\nlevel = \"outer\"\n[[parameters]]\nname = \"b\"\n\
             distribution = \"normal\"\nmean = 0.0\nstd = 1.0\n[outputs]\n\
             variables = [\"y_t\"]\n[method]\nkind = \"nested\"\n\
             outer = {{ kind = \"mc\", samples = {outer} }}\n\
             inner = {{ kind = \"lhs\", samples = {inner} }}\n"
        );
        Study::parse(&text, "test", None).unwrap()
    }

    #[test]
    fn nested_studies_count_their_runs_before_the_design_and_the_pooled_series() {
        // "model runs not known before the design" and a fixed 3.0 GiB for any
        // outer × inner; H2: 20 000 runs × 10 001 times estimated 2.5 GiB, peak 3.23 GB,
        // and 1000 × 100 001 peaked at 1.65 GB.
        for (outer, inner, step, peak) in [(100, 200, 1e-4, 3.23e9), (20, 50, 1e-5, 1.65e9)] {
            let shape = Shape::of(&nested_study(outer, inner, step), 2);
            let n = (outer * inner) as f64;
            assert_eq!(shape.runs, Some(n));
            let f = estimate(&shape, shape.runs);
            assert_eq!(f.runs, Some(n));
            let total = f.memory.total();
            assert!(total >= peak && total <= 2.0 * peak, "{f} {shape:?}");
        }
    }

    #[test]
    fn series_larger_than_memory_are_accepted_when_their_blocks_fit() {
        // 20 000 runs of 200 001 points: 32 GB of series; the analysis reads blocks of 192
        // columns under a 64 MiB budget (31 MB each).
        let shape = Shape {
            time_points: 200_001.0,
            surrogate_samples: 0,
            series_draws: 0,
            block_bytes: 64.0 * 1024.0 * 1024.0,
            ..wheel_shape(20_000.0)
        };
        let m = shape.memory(20_000.0);
        assert_eq!(block_columns(200_001.0, 20_000.0, shape.block_bytes), 192.0);
        assert!(m.total() < 0.5 * GIB, "{}", bytes(m.total()));
        assert!(judge(&footprint(&shape, 1.0 * GIB), true).is_ok());
        // A nested study still holds the series of one output.
        let nested = Shape {
            whole_series: true,
            ..shape
        };
        assert!(judge(&footprint(&nested, 1.0 * GIB), true).is_err());
    }

    #[test]
    fn a_store_larger_than_the_free_disk_is_refused_even_with_yes() {
        // The series are not held in memory: the disk is what long series run out of.
        let shape = Shape {
            time_points: 2e7,
            ..wheel_shape(2000.0)
        };
        let mut f = footprint(&shape, 1e15);
        f.disk = Some(Disk {
            store: disk::store_bytes(2000.0, 2e7),
            free: 40e9,
        });
        let e = judge(&f, true).unwrap_err();
        assert!(matches!(e, SizeError::NoDisk { .. }));
        let text = e.to_string();
        assert!(text.contains("2000 model runs"), "{text}");
        assert!(
            text.contains("298.0 GiB on disk, more than the 37.3 GiB free"),
            "{text}"
        );
        assert!(text.contains("refused even with --yes"), "{text}");
        f.disk = Some(Disk {
            store: 1e9,
            free: 40e9,
        });
        assert!(judge(&f, true).is_ok());
    }

    #[test]
    fn block_columns_agree_with_the_analysis() {
        for (nt, rows) in [(501, 10_000), (100_000, 1_000_000), (70_000, 3_000), (5, 1)] {
            let budget = blocks::block_bytes();
            assert_eq!(
                block_columns(nt as f64, rows as f64, budget as f64),
                blocks::block_width_in(nt, rows, budget) as f64,
                "{nt} x {rows}"
            );
        }
    }

    #[test]
    fn a_huge_design_is_refused_even_with_yes() {
        let shape = wheel_shape(1e12);
        let f = footprint(&shape, 16.0 * GIB);
        let e = judge(&f, true).unwrap_err();
        let text = e.to_string();
        assert!(matches!(e, SizeError::Refused { .. }));
        assert!(text.contains("1000000000000 model runs"), "{text}");
        assert!(text.contains("16.0 GiB available"), "{text}");
        assert!(text.contains("refused even with --yes"), "{text}");
        assert!(text.contains("sparse_grid") && text.contains("pce_regression"));
    }

    #[test]
    fn many_runs_need_yes() {
        let f = footprint(&wheel_shape(100_001.0), 1e15);
        let e = judge(&f, false).unwrap_err();
        assert!(matches!(e, SizeError::NeedsConfirmation { .. }));
        assert!(e
            .to_string()
            .contains("100001 model runs, more than 100000"));
        assert!(e.to_string().contains("--yes"));
        assert!(judge(&f, true).is_ok());
        assert!(judge(&footprint(&wheel_shape(100_000.0), 1e15), false).is_ok());
    }

    #[test]
    fn much_memory_or_time_needs_yes() {
        let shape = wheel_shape(10_000.0);
        let need = shape.memory(10_000.0).total();
        let f = footprint(&shape, 1.5 * need);
        let e = judge(&f, false).unwrap_err().to_string();
        assert!(e.contains("of memory, more than half"), "{e}");
        assert!(judge(&f, true).is_ok());
        let mut f = footprint(&shape, 1e15);
        f.time = Some(TimeEstimate {
            per_run: 1.0,
            total: 5000.0,
            threads: 2,
        });
        let e = judge(&f, false).unwrap_err().to_string();
        assert!(e.contains("about 83 min, more than 60 min"), "{e}");
        assert!(e.contains("1.0 s per run"), "{e}");
    }

    #[test]
    fn a_nan_estimate_is_refused() {
        let mut f = footprint(&wheel_shape(1.0), 1e12);
        f.memory.records = f64::NAN;
        assert!(matches!(judge(&f, true), Err(SizeError::Refused { .. })));
    }

    /// `builtin:wheel-sparse` with `dim` uniform inputs and the method `method` (TOML).
    fn chaos_study(dim: usize, method: &str) -> Study {
        let mut s = Study::load("builtin:wheel-sparse").unwrap();
        s.parameters = (0..dim)
            .map(|i| crate::uq::RandomParameter {
                name: format!("x{i}"),
                distribution: crate::uq::Distribution::uniform(0.0, 1.0).unwrap(),
            })
            .collect();
        s.method = toml::from_str(method).unwrap();
        s
    }

    fn binomial(n: usize, k: usize) -> f64 {
        (0..k).fold(1.0, |acc, i| acc * (n - i) as f64 / (i + 1) as f64)
    }

    #[test]
    fn the_qa_chaos_studies_are_estimated_above_their_largest_allocations() {
        // 300 LHS runs, 30 inputs, order 5: the candidates of degree 5 at the runs,
        // 300 × C(35, 5) × 8 B = 779 MB, was the allocation that failed (estimate: 5.1 MiB).
        let s = chaos_study(
            30,
            "kind = \"pce_regression\"\nsamples = 300\norder = 5\nsparse = true",
        );
        let shape = Shape::of(&s, 2);
        assert_eq!(shape.runs, Some(300.0));
        let m = shape.memory(300.0);
        let failed = 300.0 * binomial(35, 5) * 8.0;
        assert_eq!(failed, 779_116_800.0);
        // Every degree's candidates (sum_p C(29 + p, p) = C(35, 5) - 1), their copies.
        assert!(
            m.chaos >= 4.0 * 300.0 * (binomial(35, 5) - 1.0) * 8.0,
            "{}",
            m.chaos
        );
        // Least squares on the same basis (were there runs enough): the design four times.
        let s = chaos_study(30, "kind = \"pce_regression\"\nsamples = 400000\norder = 5");
        let ls = Shape::of(&s, 2).memory(400_000.0);
        assert!(ls.chaos >= 4.0 * 8.0 * 400_000.0 * binomial(35, 5));
        // A level-3 sparse grid in 30 uniform inputs (Gauss–Patterson): 41 601 runs (an earlier
        // count), and the basis of the 4 000 draws of the series twice (once while built):
        // the chaos terms from the degrees 0, 2, 5, 11 projected at levels 0..=3 (new degrees
        // 1, 2, 3, 6 per level), summed over the levels with |l| <= 3.
        fn terms(d: usize, budget: usize) -> f64 {
            const NEW: [f64; 4] = [1.0, 2.0, 3.0, 6.0];
            if d == 0 {
                return 1.0;
            }
            (0..=budget)
                .map(|j| NEW[j] * terms(d - 1, budget - j))
                .sum()
        }
        let s = chaos_study(30, "kind = \"sparse_grid\"\nlevel = 3");
        let shape = Shape::of(&s, 2);
        assert_eq!(shape.runs, Some(41_601.0));
        let m = shape.memory(41_601.0);
        let basis = 4000.0 * terms(30, 3) * 8.0;
        assert!(m.chaos >= 2.0 * basis, "{} {}", m.chaos, basis);
        // The study (3 time points) peaked at 2.59 GB and was estimated at 97 MiB.
        assert!(m.total() > 2.5e9, "{}", bytes(m.total()));
        let f = Footprint {
            available: (1.5e9, true),
            ..estimate(&shape, shape.runs)
        };
        let e = judge(&f, true).unwrap_err().to_string();
        assert!(
            e.contains(", chaos ") && e.contains("a lower `level`"),
            "{e}"
        );
    }

    #[test]
    fn other_methods_keep_their_estimates_and_no_built_in_needs_yes() {
        for (name, _) in crate::spec::BUILTINS {
            let study = Study::load(&format!("builtin:{name}")).unwrap();
            let variants = match &study.suite {
                Some(s) => s.variants.clone(),
                None => vec![study],
            };
            for s in variants {
                let shape = Shape::of(&s, 2);
                let chaos = matches!(
                    s.method,
                    MethodSpec::SparseGrid(_) | MethodSpec::PceRegression(_)
                );
                assert_eq!(shape.chaos.is_some(), chaos, "{name}");
                if !chaos {
                    assert_eq!(shape.memory(1000.0).chaos, 0.0, "{name}");
                }
                // Memory and runs, on a machine of 4 GiB (the time is not estimated here).
                let f = footprint(&shape, ASSUMED_MEMORY);
                assert!(judge(&f, false).is_ok(), "{name}: {f}");
            }
        }
    }

    #[test]
    fn units() {
        assert_eq!(bytes(512.0), "512.0 B");
        assert_eq!(bytes(1.5 * GIB), "1.5 GiB");
        assert!(bytes(1e30).ends_with(" B"));
        assert_eq!(duration(5400.0), "90 min");
        assert_eq!(duration(3.0 * 3600.0), "3.0 h");
        assert!(duration(1e12).ends_with("years"));
    }

    #[test]
    fn available_memory_is_positive_where_known() {
        if let Some(m) = available_memory() {
            assert!(m > 0.0 && m.is_finite());
        }
    }
}
