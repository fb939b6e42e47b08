//! Cost of one `fmi2DoStep` and of one `fmi2GetReal` (3 outputs) through the FMI 2.0 C ABI.
//!
//! ```text
//! cargo build --release -p railuq --lib      # target/release/librailuq.so
//! cargo bench --bench fmi_step               # [[bench]] name = "fmi_step", harness = false
//! cargo bench --bench fmi_step -- --json out.json --budget 1.5
//! ```
//!
//! The shared library is `dlopen`ed exactly as an importer does it (libloading, `RTLD_NOW`),
//! the functions are called through C function pointers, and the time is taken with
//! `std::time::Instant` around whole batches of calls (never around a single call: the clock
//! itself costs tens of ns). Nothing here asserts a speed; it measures and prints.
//!
//! The library is `target/release/librailuq.so` (or `$CARGO_TARGET_DIR/release/...`), or the
//! file named by `RAILUQ_SO`.
//!
//! Per model, one instance is created once. A *round* resets it (`fmi2Reset`, set-up,
//! initialisation: not timed), then times one *episode* of consecutive `fmi2DoStep` calls from
//! t = 0 and, separately, a batch of `fmi2GetReal` calls of three outputs. Episodes are short
//! enough to stay in the model's physical range (the wheel's free response would otherwise
//! decay into subnormal numbers, whose arithmetic is much slower). Rounds repeat until the time
//! budget per model is spent (at least 5 rounds); the median and the best round are printed,
//! as ns per call. Options: `--budget SECONDS` per model (default 1.5), `--json FILE` (the
//! results as JSON, for `bench/run.py`). Any other argument (cargo passes `--bench`) is ignored.
//!
//! Then the VehicleTrack stepping in detail ([`vt_kernels`], through the Rust API of the same
//! library, `--vt-json FILE` for its JSON): µs per substep at the default resolution (N = 255,
//! NM = 255, dt = 1e-4 s), a fine one (N = 511, NM = 511, dt = 2e-5 s) and the one that
//! resolves the sleeper-passing force (N = 255, NM = 511, dt = 2e-5 s), for
//! the plain kernel and the fast one on each instruction set, measured interleaved; the
//! real-time factors; the arithmetic bound (a flop count per substep over a measured loop
//! throughput) and the fraction of it reached; and the largest relative difference of the
//! fast kernel from the plain one over 6 s runs.

use std::ffi::CString;
use std::hint::black_box;
use std::path::{Path, PathBuf};
use std::ptr::null;
use std::time::{Duration, Instant};

use libloading::Library;

// ---------------------------------------------------------------- C ABI (fmi2FunctionTypes.h)

#[path = "../tests/common/fmi2.rs"]
#[allow(dead_code)] // the constants and types this benchmark does not use
mod fmi2;
use fmi2::*;

/// The functions this benchmark calls, as C function pointers.
struct Api {
    instantiate: InstantiateFn,
    free_instance: FreeInstanceFn,
    setup_experiment: SetupExperimentFn,
    enter_initialization_mode: ComponentFn,
    exit_initialization_mode: ComponentFn,
    reset: ComponentFn,
    get_real: GetRealFn,
    do_step: DoStepFn,
    /// Last field: the pointers above are valid while the library stays loaded.
    _lib: Library,
}

/// Copies a symbol's value (a function pointer) out of the library.
///
/// # Safety
/// `T` must be the C type of the symbol `name`.
unsafe fn sym<T: Copy>(lib: &Library, path: &Path, name: &str) -> T {
    // SAFETY: the caller guarantees that `T` is the symbol's type.
    match unsafe { lib.get::<T>(name.as_bytes()) } {
        Ok(s) => *s,
        Err(e) => fail(&format!(
            "{}: symbol {name} is missing: {e}",
            path.display()
        )),
    }
}

fn fail(msg: &str) -> ! {
    eprintln!("fmi_step: {msg}");
    std::process::exit(1)
}

impl Api {
    fn load(path: &Path) -> Api {
        if !path.is_file() {
            fail(&format!(
                "{} does not exist: build it first with `cargo build --release -p railuq --lib` \
                 (or `make build`), or set RAILUQ_SO",
                path.display()
            ));
        }
        use libloading::os::unix::{Library as UnixLibrary, RTLD_LOCAL, RTLD_NOW};
        // SAFETY: loading runs the library's initialisers; a Rust cdylib has none that matter.
        let lib: Library = match unsafe { UnixLibrary::open(Some(path), RTLD_NOW | RTLD_LOCAL) } {
            Ok(l) => l.into(),
            Err(e) => fail(&format!("dlopen {}: {e}", path.display())),
        };
        // SAFETY: each field's type is the fmi2FunctionTypes.h type of its symbol; the pointers
        // are used only while `_lib`, stored in the same struct, stays loaded.
        unsafe {
            Api {
                instantiate: sym(&lib, path, "fmi2Instantiate"),
                free_instance: sym(&lib, path, "fmi2FreeInstance"),
                setup_experiment: sym(&lib, path, "fmi2SetupExperiment"),
                enter_initialization_mode: sym(&lib, path, "fmi2EnterInitializationMode"),
                exit_initialization_mode: sym(&lib, path, "fmi2ExitInitializationMode"),
                reset: sym(&lib, path, "fmi2Reset"),
                get_real: sym(&lib, path, "fmi2GetReal"),
                do_step: sym(&lib, path, "fmi2DoStep"),
                _lib: lib,
            }
        }
    }
}

/// One FMU instance, freed on drop.
struct Inst<'a> {
    api: &'a Api,
    c: Component,
    model: &'static str,
}

impl<'a> Inst<'a> {
    fn new(api: &'a Api, model: &'static str, guid: &str) -> Inst<'a> {
        let name = CString::new(format!("bench-{model}")).expect("name");
        let guid = CString::new(guid).expect("guid");
        // SAFETY: NUL-terminated strings that outlive the call; NULL resource location and
        // NULL callbacks are allowed by this FMU (it then logs nowhere); visible and logging
        // off.
        let c = unsafe {
            (api.instantiate)(
                name.as_ptr(),
                CO_SIMULATION,
                guid.as_ptr(),
                null(),
                null(),
                FMI2_FALSE,
                FMI2_FALSE,
            )
        };
        if c.is_null() {
            fail(&format!(
                "fmi2Instantiate of {model} returned NULL (GUID mismatch?)"
            ));
        }
        Inst { api, c, model }
    }

    fn check(&self, what: &str, status: Status) {
        if status != OK {
            fail(&format!("{}: {what} returned status {status}", self.model));
        }
    }

    /// fmi2Reset (except the first time), set-up from t = 0 without stop time, initialise.
    fn restart(&self, first: bool) {
        let api = self.api;
        // SAFETY: `self.c` is a live instance of this library (created in `new`, freed on drop).
        unsafe {
            if !first {
                self.check("fmi2Reset", (api.reset)(self.c));
            }
            self.check(
                "fmi2SetupExperiment",
                (api.setup_experiment)(self.c, FMI2_FALSE, 0.0, 0.0, FMI2_FALSE, 0.0),
            );
            self.check(
                "fmi2EnterInitializationMode",
                (api.enter_initialization_mode)(self.c),
            );
            self.check(
                "fmi2ExitInitializationMode",
                (api.exit_initialization_mode)(self.c),
            );
        }
    }
}

impl Drop for Inst<'_> {
    fn drop(&mut self) {
        // SAFETY: `self.c` came from fmi2Instantiate and is not used afterwards.
        unsafe { (self.api.free_instance)(self.c) }
    }
}

// ---------------------------------------------------------------- the cases

struct Case {
    model: &'static str,
    guid: String,
    /// Communication step (s).
    step: f64,
    /// Default internal step of the model (s), for the printout.
    internal: f64,
    /// fmi2DoStep calls per timed episode, from t = 0.
    episode: usize,
    /// Three outputs read by the fmi2GetReal benchmark.
    outputs: [(&'static str, Vr); 3],
}

fn cases() -> Vec<Case> {
    use railuq::fmi2::xml::guid;
    use railuq::models::{bogie, vehicle, vehicle_track, wheel};
    vec![
        Case {
            model: "Wheel",
            guid: guid(&wheel::INFO),
            step: 0.01,
            internal: 1e-3,
            episode: 500, // 0-5 s, the wheel study's horizon
            outputs: [("q", 10), ("v", 11), ("a", 12)],
        },
        Case {
            model: "Bogie",
            guid: guid(&bogie::INFO),
            step: 0.01,
            internal: 1e-3,
            episode: 45_000, // 0-450 s, the full speed ramp of the default experiment
            outputs: [("Y", 100), ("phi", 101), ("F_T", 107)],
        },
        Case {
            model: "VehicleTrack",
            guid: guid(&vehicle_track::INFO),
            step: 1e-3,
            internal: 1e-4,
            episode: 500, // 0-0.5 s
            outputs: [("Zc", 100), ("Zc_acc", 101), ("Zw1", 108)],
        },
        Case {
            model: "Vehicle",
            guid: guid(&vehicle::INFO),
            step: 0.01,
            internal: 5.7e-4, // RK4 substep at the default 40 m/s (1.8/rho, rho = 3169 1/s)
            episode: 1000,    // 0-10 s on straight track from the default disturbance
            outputs: [("y_w1", 102), ("Y_1L", 110), ("Q_1L", 118)],
        },
    ]
}

/// ns per call: the median and the best of the rounds, the number of calls timed.
struct Stat {
    median_ns: f64,
    best_ns: f64,
    calls: u64,
    rounds: usize,
}

fn stat(mut per_call_ns: Vec<f64>, calls: u64) -> Stat {
    per_call_ns.sort_by(f64::total_cmp);
    let n = per_call_ns.len();
    let median_ns = if n % 2 == 1 {
        per_call_ns[n / 2]
    } else {
        0.5 * (per_call_ns[n / 2 - 1] + per_call_ns[n / 2])
    };
    Stat {
        median_ns,
        best_ns: per_call_ns[0],
        calls,
        rounds: n,
    }
}

const GET_REAL_BATCH: usize = 20_000;
const MIN_ROUNDS: usize = 5;
const MAX_ROUNDS: usize = 10_000;

fn run_case(api: &Api, case: &Case, budget: Duration) -> (Stat, Stat) {
    let inst = Inst::new(api, case.model, &case.guid);
    let vrs: [Vr; 3] = case.outputs.map(|(_, vr)| vr);
    let mut values = [0.0f64; 3];
    let (mut step_ns, mut get_ns) = (Vec::new(), Vec::new());
    let (mut step_calls, mut get_calls) = (0u64, 0u64);
    let mut spent = Duration::ZERO;
    let mut round = 0;
    while round < MIN_ROUNDS || (spent < budget && round < MAX_ROUNDS) {
        inst.restart(round == 0);
        round += 1;

        let mut t = 0.0;
        let start = Instant::now();
        for _ in 0..case.episode {
            // SAFETY: live initialised instance; `t` is the FMU's current time.
            let s = unsafe { (api.do_step)(inst.c, black_box(t), case.step, FMI2_TRUE) };
            if s != OK {
                inst.check(&format!("fmi2DoStep at t = {t}"), s);
            }
            t += case.step;
        }
        let dt = start.elapsed();
        spent += dt;
        step_ns.push(dt.as_nanos() as f64 / case.episode as f64);
        step_calls += case.episode as u64;

        let start = Instant::now();
        for _ in 0..GET_REAL_BATCH {
            // SAFETY: live instance; `vrs` and `values` hold 3 elements each.
            let s = unsafe { (api.get_real)(inst.c, vrs.as_ptr(), 3, values.as_mut_ptr()) };
            if s != OK {
                inst.check("fmi2GetReal", s);
            }
            black_box(&mut values);
        }
        let dt = start.elapsed();
        spent += dt;
        get_ns.push(dt.as_nanos() as f64 / GET_REAL_BATCH as f64);
        get_calls += GET_REAL_BATCH as u64;
    }
    if values.iter().any(|v| !v.is_finite()) {
        fail(&format!("{}: non-finite outputs {values:?}", case.model));
    }
    (stat(step_ns, step_calls), stat(get_ns, get_calls))
}

fn json_row(case: &Case, call: &str, s: &Stat) -> String {
    let outputs: Vec<String> = case
        .outputs
        .iter()
        .map(|(n, _)| format!("\"{n}\""))
        .collect();
    format!(
        "{{\"model\": \"{}\", \"call\": \"{call}\", \"step\": {:e}, \"internal_step\": {:e}, \
         \"substeps\": {}, \"episode_steps\": {}, \"outputs\": [{}], \"median_ns\": {:.3}, \
         \"best_ns\": {:.3}, \"calls\": {}, \"rounds\": {}}}",
        case.model,
        case.step,
        case.internal,
        (case.step / case.internal).round() as u64,
        case.episode,
        outputs.join(", "),
        s.median_ns,
        s.best_ns,
        s.calls,
        s.rounds
    )
}

fn main() {
    let mut json: Option<PathBuf> = None;
    let mut vt_json: Option<PathBuf> = None;
    let mut budget = Duration::from_secs_f64(1.5);
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        match a.as_str() {
            "--json" => json = args.next().map(PathBuf::from),
            "--vt-json" => vt_json = args.next().map(PathBuf::from),
            "--budget" => {
                let v = args.next().and_then(|v| v.parse::<f64>().ok());
                match v {
                    Some(s) if s > 0.0 && s.is_finite() => budget = Duration::from_secs_f64(s),
                    _ => fail("--budget needs a positive number of seconds"),
                }
            }
            _ => {} // cargo bench passes --bench; nothing else is ours
        }
    }

    let path = fmi2::library_path("release");
    let api = Api::load(&path);
    println!(
        "fmi_step: {} (budget {:.1} s per model)",
        path.display(),
        budget.as_secs_f64()
    );
    println!(
        "{:<13} {:<12} {:>16} {:>8} {:>12} {:>12} {:>10} {:>7}",
        "model", "call", "step s | outputs", "substeps", "median ns", "best ns", "calls", "rounds"
    );
    let mut rows = Vec::new();
    for case in cases() {
        let (step, get) = run_case(&api, &case, budget);
        let substeps = (case.step / case.internal).round() as u64;
        let outs: Vec<&str> = case.outputs.iter().map(|(n, _)| *n).collect();
        for (call, s, st, sub) in [
            (
                "fmi2DoStep",
                &step,
                format!("{}", case.step),
                substeps.to_string(),
            ),
            (
                "fmi2GetReal",
                &get,
                format!("[{}]", outs.join(",")),
                "-".into(),
            ),
        ] {
            println!(
                "{:<13} {:<12} {:>16} {:>8} {:>12.1} {:>12.1} {:>10} {:>7}",
                case.model, call, st, sub, s.median_ns, s.best_ns, s.calls, s.rounds
            );
            rows.push(json_row(&case, call, s));
        }
    }
    if let Some(p) = json {
        let text = format!("[\n  {}\n]\n", rows.join(",\n  "));
        if let Err(e) = std::fs::write(&p, text) {
            fail(&format!("cannot write {}: {e}", p.display()));
        }
    }
    let vt = vt_kernels::run(budget);
    if let Some(p) = vt_json {
        if let Err(e) = std::fs::write(&p, vt) {
            fail(&format!("cannot write {}: {e}", p.display()));
        }
    }
}

#[path = "fmi_step/vt_kernels.rs"]
mod vt_kernels;
