//! FMU import against a Co-Simulation FMU written in C (`tests/c_fmu/`), and the errors for bad
//! FMUs.
//!
//! The C FMU is compiled at test time with the system C compiler (`cc`) against the FMI 2.0
//! headers that fmpy ships: `$FMI2_HEADERS`, else `../.venv/lib/python3*/site-packages/fmpy/c-code`.
//! Without headers the tests that need the C FMU are skipped, unless `CI` is set: then they fail.

use std::fs;
use std::io::{Cursor, Write};
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::OnceLock;

use uq_driver::fmu::{
    Causality, Fmu, FmuError, InstanceState, Status, StatusKind, Variability, VariableKind,
};
use zip::write::SimpleFileOptions;

use crate::support::{assert_contains, failed, run, run_study, stderr, test_fmus, utf8};

const MANIFEST_DIR: &str = env!("CARGO_MANIFEST_DIR");
const GUID: &str = "{6a1c2d9e-3b7f-4e0a-9d51-uq-driver-test}";
/// Value references of the C FMU.
const VR_X: u32 = 0;
const VR_K: u32 = 1;
const VR_X0: u32 = 2;
const VR_TIME: u32 = 3;

fn c_fmu_dir() -> PathBuf {
    Path::new(MANIFEST_DIR).join("tests/c_fmu")
}

fn model_description() -> String {
    fs::read_to_string(c_fmu_dir().join("modelDescription.xml")).unwrap()
}

// ---------------------------------------------------------------------------------------------
// Building the C FMU.

/// The C FMU compiled twice: complete, and without `fmi2DoStep`.
struct Binaries {
    full: PathBuf,
    no_do_step: PathBuf,
}

fn compile(headers: &Path, out: &Path, defines: &[&str]) -> Result<(), String> {
    // Compile to a private name, then rename: concurrent test runs never see a partial file.
    let partial = out.with_extension(format!("so.{}", std::process::id()));
    let compiler = std::env::var("CC").unwrap_or_else(|_| "cc".to_string());
    let mut cmd = Command::new(&compiler);
    cmd.args(["-std=c99", "-Wall", "-Wextra", "-shared", "-fPIC", "-O1"])
        .arg("-I")
        .arg(headers)
        .args(defines)
        .arg(c_fmu_dir().join("dahlquist.c"))
        .arg("-o")
        .arg(&partial)
        .arg("-lm");
    let output = cmd
        .output()
        .map_err(|e| format!("cannot run the C compiler '{compiler}': {e}"))?;
    if !output.status.success() {
        return Err(format!(
            "compiling dahlquist.c failed:\n{}",
            String::from_utf8_lossy(&output.stderr)
        ));
    }
    fs::rename(&partial, out).map_err(|e| e.to_string())
}

fn build_binaries() -> Result<Binaries, String> {
    let headers = test_fmus::find_headers()?;
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("c_fmu");
    fs::create_dir_all(&dir).map_err(|e| e.to_string())?;
    let full = dir.join("dahlquist.so");
    let no_do_step = dir.join("dahlquist_no_do_step.so");
    compile(&headers, &full, &[])?;
    compile(&headers, &no_do_step, &["-DOMIT_DO_STEP"])?;
    Ok(Binaries { full, no_do_step })
}

/// The compiled C FMU, or `None` (with a printed reason) when it cannot be built outside CI.
fn binaries() -> Option<&'static Binaries> {
    static BUILT: OnceLock<Result<Binaries, String>> = OnceLock::new();
    test_fmus::available("C test FMU binaries", BUILT.get_or_init(build_binaries))
}

// ---------------------------------------------------------------------------------------------
// Packaging.

enum Entry<'a> {
    File(&'a str, &'a [u8]),
    Symlink(&'a str, &'a str),
}

fn write_zip(path: &Path, entries: &[Entry<'_>]) {
    let mut w = zip::ZipWriter::new(Cursor::new(Vec::new()));
    for entry in entries {
        match entry {
            Entry::File(name, data) => {
                w.start_file(*name, SimpleFileOptions::default()).unwrap();
                w.write_all(data).unwrap();
            }
            Entry::Symlink(name, target) => {
                w.add_symlink(*name, *target, SimpleFileOptions::default())
                    .unwrap();
            }
        }
    }
    fs::write(path, w.finish().unwrap().into_inner()).unwrap();
}

/// The error of opening the FMU `name` (without a binary) whose model description is the C
/// FMU's with `from` replaced by `to`.
fn open_edited(name: &str, from: &str, to: &str) -> FmuError {
    let dir = tempfile::tempdir().unwrap();
    let xml = model_description().replace(from, to);
    Fmu::open(&write_fmu(dir.path(), name, &xml, None)).unwrap_err()
}

/// The error of opening `dir/name`, an archive of the C FMU's model description and `entry`.
fn open_with_entry(dir: &Path, name: &str, entry: Entry<'_>) -> FmuError {
    let path = dir.join(name);
    let xml = model_description();
    write_zip(
        &path,
        &[Entry::File("modelDescription.xml", xml.as_bytes()), entry],
    );
    Fmu::open(&path).unwrap_err()
}

/// Packs `xml` and optionally a binary as `binaries/linux64/dahlquist.so` into `dir/name`.
fn write_fmu(dir: &Path, name: &str, xml: &str, binary: Option<&Path>) -> PathBuf {
    let path = dir.join(name);
    let bytes = binary.map(|b| fs::read(b).unwrap());
    let mut entries = vec![
        Entry::File("modelDescription.xml", xml.as_bytes()),
        Entry::File("resources/readme.txt", b"resources of the test FMU"),
    ];
    if let Some(bytes) = &bytes {
        entries.push(Entry::File("binaries/linux64/dahlquist.so", bytes));
    }
    write_zip(&path, &entries);
    path
}

fn open_dahlquist(dir: &Path) -> Option<Fmu> {
    let bins = binaries()?;
    let path = write_fmu(dir, "Dahlquist.fmu", &model_description(), Some(&bins.full));
    Some(Fmu::open(&path).unwrap())
}

/// Calls the C FMU's test hook `dahlquist_live_instances` in the library `fmu` loaded.
fn live_instances(fmu: &Fmu) -> i32 {
    // SAFETY: opening the already loaded library only adds a reference to it.
    let lib = unsafe { libloading::Library::new(fmu.binary_path()) }.unwrap();
    // SAFETY: the test hook is `int dahlquist_live_instances(void)`.
    let hook =
        unsafe { lib.get::<unsafe extern "C" fn() -> i32>(b"dahlquist_live_instances\0") }.unwrap();
    // SAFETY: it takes no argument and only reads an atomic counter.
    unsafe { hook() }
}

// ---------------------------------------------------------------------------------------------
// The C FMU through the import layer.

#[test]
fn c_fmu_description_is_read() {
    let dir = tempfile::tempdir().unwrap();
    let Some(fmu) = open_dahlquist(dir.path()) else {
        return;
    };
    let md = fmu.description();
    assert_eq!(md.model_name, "Dahlquist");
    assert_eq!(md.guid, GUID);
    assert_eq!(md.co_simulation.model_identifier, "dahlquist");
    assert!(md.co_simulation.can_get_and_set_fmu_state);
    assert!(md.co_simulation.can_handle_variable_communication_step_size);
    assert_eq!(md.default_experiment.unwrap().step_size, Some(0.1));
    assert_eq!(md.variables.len(), 7);
    assert_eq!(md.outputs, vec![1, 5]);
    let k = md.variable("k").unwrap();
    assert_eq!(
        (k.causality, k.variability, k.value_reference),
        (Causality::Parameter, Variability::Tunable, VR_K)
    );
    assert!(
        matches!(&k.kind, VariableKind::Real { start: Some(s), unit: Some(u), .. } if *s == 1.0 && u == "1/s")
    );
    assert!(k.settable_before_init() && k.settable_after_init());
    let x0 = md.variable("x0").unwrap();
    assert!(x0.settable_before_init() && !x0.settable_after_init());
    assert_eq!(fmu.library().version(), "2.0");
    assert!(fmu.resource_uri().starts_with("file:///"));
    assert!(fmu.resource_uri().ends_with("/resources/"));
    assert!(fmu.root().join("resources/readme.txt").is_file());
}

#[test]
fn c_fmu_matches_the_exact_solution() {
    let dir = tempfile::tempdir().unwrap();
    let Some(fmu) = open_dahlquist(dir.path()) else {
        return;
    };
    let mut inst = fmu.instantiate("w0", false).unwrap();
    assert_eq!(inst.state(), InstanceState::Instantiated);
    inst.set_real_by_name("k", 2.5).unwrap();
    inst.set_real(&[VR_X0], &[3.0]).unwrap();
    inst.setup_experiment(Some(1e-6), 0.0, Some(1.0)).unwrap();
    inst.enter_initialization_mode().unwrap();
    inst.exit_initialization_mode().unwrap();
    assert_eq!(inst.state(), InstanceState::Stepping);

    let h = 0.01;
    for i in 0..100 {
        let t = f64::from(i) * h;
        inst.do_step(t, h, true).unwrap();
        let mut v = [0.0; 2];
        inst.get_real(&[VR_X, VR_TIME], &mut v).unwrap();
        let t1 = t + h;
        let exact = 3.0 * (-2.5 * t1).exp();
        assert!(
            (v[0] - exact).abs() <= 1e-12 * exact,
            "x({t1}) = {}, exact {exact}",
            v[0]
        );
        assert!((v[1] - t1).abs() < 1e-12);
    }
    let mut steps = [0];
    inst.get_integer(&[0], &mut steps).unwrap();
    assert_eq!(steps[0], 100);
    let mut label = [String::new()];
    inst.get_string(&[0], &mut label).unwrap();
    assert_eq!(label[0], "dahlquist");
    assert!(
        (inst
            .get_real_status(StatusKind::LastSuccessfulTime)
            .unwrap()
            - 1.0)
            .abs()
            < 1e-12
    );
    assert!(!inst.get_boolean_status(StatusKind::Terminated).unwrap());

    // A tunable parameter and an input may change at communication points.
    let x_before = inst.get_real_by_name("x").unwrap();
    inst.set_real_by_name("k", 0.0).unwrap();
    inst.do_step(1.0, 0.5, true).unwrap();
    assert_eq!(inst.get_real_by_name("x").unwrap(), x_before);
    inst.set_real_by_name("k", 1.0).unwrap();
    inst.set_boolean(&[0], &[true]).unwrap();
    let mut frozen = [false];
    inst.get_boolean(&[0], &mut frozen).unwrap();
    assert!(frozen[0]);
    inst.do_step(1.5, 0.5, true).unwrap();
    assert_eq!(inst.get_real_by_name("x").unwrap(), x_before);

    // A fixed parameter may not: the importer refuses before calling the FMU.
    let err = inst.set_real_by_name("x0", 1.0).unwrap_err();
    assert!(
        matches!(&err, FmuError::NotSettable { name, why } if name == "x0" && why.contains("tunable")),
        "{err}"
    );
    assert!(matches!(
        inst.set_real_by_name("nope", 1.0),
        Err(FmuError::UnknownVariable { .. })
    ));
    assert!(matches!(
        inst.set_real_by_name("frozen", 1.0),
        Err(FmuError::WrongType {
            expected: "Real",
            found: "Boolean",
            ..
        })
    ));
    assert!(matches!(
        inst.set_real(&[VR_K], &[]),
        Err(FmuError::InvalidArgument { .. })
    ));

    inst.terminate().unwrap();
    assert_eq!(inst.state(), InstanceState::Terminated);
    // Reset brings back the start values.
    inst.reset().unwrap();
    assert_eq!(inst.get_real_by_name("k").unwrap(), 1.0);
}

#[test]
fn fmu_log_messages_arrive_in_errors() {
    let dir = tempfile::tempdir().unwrap();
    let Some(fmu) = open_dahlquist(dir.path()) else {
        return;
    };
    // Errors are logged even with logging off.
    let mut inst = fmu.instantiate("quiet", false).unwrap();
    let err = inst.set_real(&[99], &[1.0]).unwrap_err();
    match &err {
        FmuError::Call {
            function,
            status,
            messages,
            instance,
            ..
        } => {
            assert_eq!(*function, "fmi2SetReal");
            assert_eq!(*status, Status::Error);
            assert_eq!(instance, "quiet");
            assert_eq!(messages.len(), 1, "{messages:?}");
            assert_eq!(messages[0].status, Status::Error);
            assert_eq!(messages[0].category, "logStatusError");
            assert_eq!(
                messages[0].message,
                "fmi2SetReal: unknown or read-only value reference 99"
            );
        }
        other => panic!("unexpected error {other}"),
    }
    let text = err.to_string();
    assert_contains(
        &text,
        "Dahlquist.fmu: fmi2SetReal returned Error for instance 'quiet'",
    );
    assert_contains(
        &text,
        "[Error] logStatusError: fmi2SetReal: unknown or read-only value reference 99",
    );
    assert_eq!(inst.state(), InstanceState::Error);
    inst.reset().unwrap();
    assert_eq!(inst.state(), InstanceState::Instantiated);

    // A message longer than the shim's stack buffer (512 bytes) and within the 4 KiB a kept
    // message may have arrives whole; Discard is an error too.
    let long = "L".repeat(3000);
    let err = inst.set_string(&[0], &[&long]).unwrap_err();
    let messages = err.fmu_messages();
    assert!(
        matches!(
            err,
            FmuError::Call {
                status: Status::Discard,
                ..
            }
        ),
        "{err}"
    );
    assert_eq!(messages.len(), 1);
    assert!(messages[0].message.ends_with(&format!("'{long}'")));
    assert!(matches!(
        inst.set_string(&[0], &["a\0b"]),
        Err(FmuError::InvalidArgument { .. })
    ));

    // Errors during a step name the function and carry the FMU's explanation.
    inst.setup_experiment(None, 0.0, None).unwrap();
    inst.enter_initialization_mode().unwrap();
    inst.exit_initialization_mode().unwrap();
    let err = inst.do_step(0.0, -0.1, true).unwrap_err();
    assert_contains(&err.to_string(), "fmi2DoStep returned Error");
    assert_contains(&err.to_string(), "step size must be positive, got -0.1");
    drop(inst);

    // With logging on, the FMU's informational messages are kept too.
    let mut chatty = fmu.instantiate("chatty", true).unwrap();
    chatty.set_log_echo(false);
    let messages = chatty.messages();
    assert!(
        messages
            .iter()
            .any(|m| m.status == Status::Ok && m.message.contains(fmu.resource_uri())),
        "{messages:?}"
    );
    chatty.clear_messages();
    assert!(chatty.messages().is_empty());
    chatty.set_debug_logging(false, &["logAll"]).unwrap();
}

#[test]
fn fmu_state_round_trips_and_serializes() {
    let dir = tempfile::tempdir().unwrap();
    let Some(fmu) = open_dahlquist(dir.path()) else {
        return;
    };
    let mut inst = fmu.instantiate("s", false).unwrap();
    inst.setup_experiment(None, 0.0, None).unwrap();
    inst.enter_initialization_mode().unwrap();
    inst.exit_initialization_mode().unwrap();
    inst.do_step(0.0, 0.5, false).unwrap();
    let saved = inst.get_fmu_state().unwrap();
    let x_saved = inst.get_real_by_name("x").unwrap();
    let bytes = inst.serialize_fmu_state(&saved).unwrap();
    inst.do_step(0.5, 0.5, false).unwrap();
    assert_ne!(inst.get_real_by_name("x").unwrap(), x_saved);
    inst.set_fmu_state(&saved).unwrap();
    assert_eq!(inst.get_real_by_name("x").unwrap(), x_saved);
    inst.do_step(0.5, 0.5, false).unwrap();
    let restored = inst.deserialize_fmu_state(&bytes).unwrap();
    inst.set_fmu_state(&restored).unwrap();
    assert_eq!(inst.get_real_by_name("x").unwrap(), x_saved);
    inst.free_fmu_state(saved).unwrap();
    inst.free_fmu_state(restored).unwrap();

    // A state belongs to the instance that made it.
    let mut other = fmu.instantiate("o", false).unwrap();
    let foreign = other.get_fmu_state().unwrap();
    assert!(matches!(
        inst.set_fmu_state(&foreign),
        Err(FmuError::InvalidArgument { .. })
    ));
    other.free_fmu_state(foreign).unwrap();

    // Unsupported optional functions are refused from the capability flags.
    let mut out = [0.0];
    assert!(matches!(
        inst.get_directional_derivative(&[VR_X], &[VR_K], &[1.0], &mut out),
        Err(FmuError::Unsupported { .. })
    ));
    // ... or return the FMU's error.
    let err = inst.cancel_step().unwrap_err();
    assert_contains(&err.to_string(), "fmi2CancelStep is not supported");
}

#[test]
fn drop_frees_every_instance() {
    let dir = tempfile::tempdir().unwrap();
    let Some(fmu) = open_dahlquist(dir.path()) else {
        return;
    };
    for i in 0..1000 {
        let mut inst = fmu.instantiate(&format!("i{i}"), false).unwrap();
        if i % 2 == 0 {
            inst.setup_experiment(None, 0.0, None).unwrap();
            inst.enter_initialization_mode().unwrap();
            inst.exit_initialization_mode().unwrap();
            inst.do_step(0.0, 0.1, true).unwrap();
        }
        if i % 3 == 0 {
            let _ = inst.set_real(&[42], &[0.0]); // leaves the instance in Error
        }
    }
    assert_eq!(live_instances(&fmu), 0);
    let kept: Vec<_> = (0..5)
        .map(|i| fmu.instantiate(&format!("k{i}"), false).unwrap())
        .collect();
    assert_eq!(live_instances(&fmu), 5);
    drop(kept);
    assert_eq!(live_instances(&fmu), 0);
}

#[test]
fn instances_outlive_the_fmu_handle_and_run_on_worker_threads() {
    let dir = tempfile::tempdir().unwrap();
    let Some(fmu) = open_dahlquist(dir.path()) else {
        return;
    };
    let handles: Vec<_> = (0..4)
        .map(|w| {
            let fmu = fmu.clone();
            std::thread::spawn(move || {
                let k = 0.5 * f64::from(w + 1);
                let mut inst = fmu.instantiate(&format!("worker{w}"), false).unwrap();
                inst.set_real(&[VR_K], &[k]).unwrap();
                inst.setup_experiment(None, 0.0, Some(1.0)).unwrap();
                inst.enter_initialization_mode().unwrap();
                inst.exit_initialization_mode().unwrap();
                for i in 0..10 {
                    inst.do_step(f64::from(i) * 0.1, 0.1, true).unwrap();
                }
                (k, inst)
            })
        })
        .collect();
    let root = fmu.root().to_path_buf();
    drop(fmu);
    for h in handles {
        let (k, mut inst) = h.join().unwrap();
        assert!(root.is_dir(), "the extraction lives while instances do");
        let x = inst.get_real_by_name("x").unwrap();
        assert!((x - (-k).exp()).abs() < 1e-12, "k={k}: x={x}");
    }
    assert!(
        !root.exists(),
        "the extraction is deleted with the last instance"
    );
}

#[test]
fn binary_missing_a_function_is_refused_by_name() {
    let dir = tempfile::tempdir().unwrap();
    let Some(bins) = binaries() else {
        return;
    };
    let path = write_fmu(
        dir.path(),
        "NoStep.fmu",
        &model_description(),
        Some(&bins.no_do_step),
    );
    let err = Fmu::open(&path).unwrap_err();
    assert!(
        matches!(
            &err,
            FmuError::MissingSymbol {
                symbol: "fmi2DoStep",
                ..
            }
        ),
        "{err}"
    );
    let text = err.to_string();
    assert_contains(&text, "NoStep.fmu/binaries/linux64/dahlquist.so");
    assert_contains(&text, "does not export the required function fmi2DoStep");
}

#[test]
fn wrong_guid_makes_instantiation_fail_with_the_fmu_message() {
    let dir = tempfile::tempdir().unwrap();
    let Some(bins) = binaries() else {
        return;
    };
    let xml = model_description().replace(GUID, "{another-guid}");
    let path = write_fmu(dir.path(), "Guid.fmu", &xml, Some(&bins.full));
    let fmu = Fmu::open(&path).unwrap();
    let err = fmu.instantiate("g", false).unwrap_err();
    assert!(matches!(err, FmuError::InstantiateFailed { .. }), "{err}");
    assert_contains(&err.to_string(), "wrong GUID {another-guid}");
    assert_eq!(live_instances(&fmu), 0);
}

// ---------------------------------------------------------------------------------------------
// Bad inputs: clear, typed errors (no C compiler needed).

#[test]
fn not_a_zip_is_reported() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("text.fmu");
    fs::write(&path, "this is not a zip archive").unwrap();
    let err = Fmu::open(&path).unwrap_err();
    assert!(matches!(err, FmuError::NotAZip { .. }), "{err}");
    assert!(
        err.to_string()
            .starts_with(&format!("{}: not a zip archive (", path.display())),
        "{err}"
    );
}

#[test]
fn zip_without_model_description_is_reported() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("empty.fmu");
    write_zip(&path, &[Entry::File("resources/x.txt", b"x")]);
    let err = Fmu::open(&path).unwrap_err();
    assert!(
        matches!(err, FmuError::MissingModelDescription { .. }),
        "{err}"
    );
    assert_contains(&err.to_string(), "no modelDescription.xml");
}

#[test]
fn malformed_xml_is_reported_with_its_position() {
    let err = open_edited("bad.fmu", "</ModelVariables>", "</ModelVariablez>");
    assert!(
        matches!(err, FmuError::MalformedXml { line, .. } if line > 40),
        "{err}"
    );
    assert_contains(&err.to_string(), "malformed modelDescription.xml at line");
}

#[test]
fn fmi_1_0_is_refused_naming_the_version() {
    let err = open_edited("v1.fmu", "fmiVersion=\"2.0\"", "fmiVersion=\"1.0\"");
    assert!(
        matches!(&err, FmuError::UnsupportedFmiVersion { found, .. } if found == "1.0"),
        "{err}"
    );
    assert_contains(&err.to_string(), "unsupported FMI version \"1.0\"");
}

#[test]
fn model_exchange_only_is_refused() {
    let err = open_edited("me.fmu", "<CoSimulation", "<ModelExchange");
    assert!(
        matches!(
            err,
            FmuError::NoCoSimulation {
                model_exchange_present: true,
                ..
            }
        ),
        "{err}"
    );
    assert_contains(&err.to_string(), "Model Exchange FMU only");
}

#[test]
fn missing_binary_names_the_expected_file() {
    let dir = tempfile::tempdir().unwrap();
    let err = open_with_entry(
        dir.path(),
        "nobin.fmu",
        Entry::File("binaries/win64/dahlquist.dll", b"MZ"),
    );
    assert!(matches!(err, FmuError::MissingBinary { .. }), "{err}");
    let text = err.to_string();
    assert_contains(&text, "binaries/linux64/dahlquist.so");
    assert_contains(&text, "binaries/ has: win64");
}

#[test]
fn binary_that_is_not_a_library_is_a_load_error() {
    let dir = tempfile::tempdir().unwrap();
    let junk = dir.path().join("junk.so");
    fs::write(&junk, b"not an ELF file").unwrap();
    let path = write_fmu(dir.path(), "junk.fmu", &model_description(), Some(&junk));
    let err = Fmu::open(&path).unwrap_err();
    assert!(matches!(err, FmuError::Load { .. }), "{err}");
    assert_contains(&err.to_string(), "cannot load the FMU binary");
}

#[test]
fn zip_slip_entry_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let probe = std::env::temp_dir().join("uq-driver-zip-slip-probe.txt");
    let err = open_with_entry(
        dir.path(),
        "slip.fmu",
        Entry::File("../uq-driver-zip-slip-probe.txt", b"escaped"),
    );
    assert!(
        matches!(&err, FmuError::UnsafeEntry { entry, .. } if entry == "../uq-driver-zip-slip-probe.txt"),
        "{err}"
    );
    assert_contains(&err.to_string(), "escapes the extraction folder");
    assert!(!probe.exists());
}

#[test]
fn absolute_path_entry_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let target = dir.path().join("absolute-target.txt");
    let name = target.to_string_lossy().into_owned();
    let err = open_with_entry(dir.path(), "abs.fmu", Entry::File(&name, b"absolute"));
    assert!(matches!(err, FmuError::UnsafeEntry { .. }), "{err}");
    assert_contains(&err.to_string(), "absolute path");
    assert!(!target.exists());
}

#[test]
fn symlink_entry_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let err = open_with_entry(
        dir.path(),
        "link.fmu",
        Entry::Symlink("resources/passwd", "/etc/passwd"),
    );
    assert!(
        matches!(&err, FmuError::UnsafeEntry { entry, reason, .. } if entry == "resources/passwd" && reason == "symbolic link"),
        "{err}"
    );
}

#[test]
fn a_shorter_last_step_is_refused_for_an_fmu_that_cannot_vary_its_step() {
    // An FMU declaring canHandleVariableCommunicationStepSize="false" was sent
    // a shorter last step (stop - start not a whole number of steps) without a word; fmpy ends
    // such a run at the last whole step instead. Now `simulate` and `run` refuse, naming the
    // stop times that fit; a whole number of steps runs as before.
    let Some(bins) = binaries() else { return };
    let dir = tempfile::tempdir().unwrap();
    let xml = model_description().replace(
        "canHandleVariableCommunicationStepSize=\"true\"",
        "canHandleVariableCommunicationStepSize=\"false\"",
    );
    let fmu = write_fmu(dir.path(), "Fixed.fmu", &xml, Some(&bins.full));
    let simulate = |stop: &str| run(&["simulate", utf8(&fmu), "--stop", stop, "--step", "0.1"]);
    let o = simulate("1.05");
    let err = failed(&o);
    assert_contains(&err, "canHandleVariableCommunicationStepSize");
    assert_contains(&err, "give a stop time of 1 or 1.1 s");
    assert!(simulate("1.0").status.success());
    let study = dir.path().join("s.toml");
    fs::write(
        &study,
        format!(
            "name = \"fixed\"\nfmu = {:?}\n[experiment]\nstop = 1.05\nstep = 0.1\n\
             [method]\nkind = \"mc\"\nsamples = 4\n\
             [[parameters]]\nname = \"k\"\ndistribution = \"uniform\"\nlow = 1.0\nhigh = 2.0\n\
             [outputs]\nvariables = [\"x\"]\n",
            utf8(&fmu)
        ),
    )
    .unwrap();
    let o = run_study(&study, &dir.path().join("out"), &[]);
    let err = failed(&o);
    assert_contains(&err, "canHandleVariableCommunicationStepSize");
}

/// An FMU whose `<ModelStructure/>` is empty although it has outputs was read as having no
/// output: `simulate` warned "nothing to record" and exited 0. fmpy's validation refuses it.
#[test]
fn an_empty_model_structure_with_outputs_is_an_invalid_model_description() {
    let dir = tempfile::tempdir().unwrap();
    let xml = model_description();
    let start = xml.find("<ModelStructure>").unwrap();
    let end = xml.find("</ModelStructure>").unwrap() + "</ModelStructure>".len();
    let empty = format!("{}<ModelStructure/>{}", &xml[..start], &xml[end..]);
    // No binary needed: the description is refused before any library is loaded.
    let fmu = write_fmu(dir.path(), "Empty.fmu", &empty, None);
    let o = run(&["simulate", utf8(&fmu), "--stop", "1", "--step", "0.5"]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert_contains(
        &err,
        "invalid modelDescription.xml: variable 'x' (index 1) has causality=\"output\", \
             but ModelStructure/Outputs does not list it",
    );
    assert!(!err.contains("nothing to record"), "{err}");
}

/// `simulate --output time` wrote the time column twice (`time,time,x`).
#[test]
fn simulate_output_time_writes_the_time_column_once() {
    let Some(bins) = binaries() else { return };
    let dir = tempfile::tempdir().unwrap();
    let fmu = write_fmu(
        dir.path(),
        "Dahlquist.fmu",
        &model_description(),
        Some(&bins.full),
    );
    let args = ["simulate", utf8(&fmu), "--stop", "0.2", "--step", "0.1"];
    let o = run(&[&args[..], &["--output", "time", "--output", "x"]].concat());
    let err = stderr(&o);
    assert!(o.status.success(), "{err}");
    let out = String::from_utf8(o.stdout).unwrap();
    let lines: Vec<&str> = out.lines().collect();
    assert_eq!(lines[0], "time,x", "{out}");
    assert_eq!(lines.len(), 4, "{out}");
    // x = exp(-t) exactly at the communication points (the C FMU's exact update).
    let x: f64 = lines[2].split(',').nth(1).unwrap().parse().unwrap();
    assert!((x - (-0.1f64).exp()).abs() < 1e-12, "{x}");
    assert_contains(&err, "--output time adds no second one");
    // Only the time: the FMU's independent variable, one column.
    let o = run(&[&args[..], &["--output", "time"]].concat());
    assert!(o.status.success(), "{}", stderr(&o));
    let out = String::from_utf8(o.stdout).unwrap();
    assert_eq!(out, "time\n0\n0.1\n0.2\n");
}

/// An FMU without a default step size could not be simulated without `--step`; fmpy's
/// `simulate_fmu` picks one (`auto_interval`: 0.002 s for 1 s, 500 steps).
#[test]
fn simulate_without_a_default_step_takes_the_step_fmpy_takes() {
    let Some(bins) = binaries() else { return };
    let dir = tempfile::tempdir().unwrap();
    let xml = model_description().replace(" stepSize=\"0.1\"", "");
    assert!(!xml.contains("stepSize"));
    let fmu = write_fmu(dir.path(), "NoStep.fmu", &xml, Some(&bins.full));
    let o = run(&["simulate", utf8(&fmu), "--output", "x"]);
    let err = stderr(&o);
    assert!(o.status.success(), "{err}");
    let out = String::from_utf8(o.stdout).unwrap();
    let rows: Vec<&str> = out.lines().skip(1).collect();
    assert_eq!(rows.len(), 501, "0 to 1 s by 0.002 s");
    assert_eq!(rows[1].split(',').next(), Some("0.002"));
    assert_contains(&err, "communication step 0.002 s (500 steps");
}
