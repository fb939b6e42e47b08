//! The C test FMUs (`tests/fmus/`) build and pack for the Rust tests (`tests/support/test_fmus.rs`):
//! each .fmu holds its model description, its binary exporting the 34 FMI 2.0 Co-Simulation
//! functions, and its resources. What the FMUs compute is checked against fmpy and closed forms in
//! `tests/python/test_test_fmus.py`.

use std::fs;
use std::io::Read;

use crate::support::test_fmus;

/// The FMI 2.0 C ABI shared with the railuq crate's ABI test; this test takes its list of the 34
/// functions.
#[allow(dead_code)] // the C types, used by that test only
#[path = "../../tests/common/fmi2.rs"]
mod fmi2;

fn entry(archive: &mut zip::ZipArchive<fs::File>, name: &str) -> Vec<u8> {
    let mut bytes = Vec::new();
    archive
        .by_name(name)
        .unwrap_or_else(|e| panic!("{name}: {e}"))
        .read_to_end(&mut bytes)
        .unwrap();
    bytes
}

#[test]
fn test_fmus_are_packed_with_description_binary_and_resources() {
    let Some(built) = test_fmus::built() else {
        return;
    };
    assert_eq!(
        built.keys().map(String::as_str).collect::<Vec<_>>(),
        ["Features", "Functions", "Once"]
    );
    for (name, identifier) in [
        ("Functions", "functions"),
        ("Features", "features"),
        ("Once", "once"),
    ] {
        let path = test_fmus::test_fmu(name).unwrap();
        let mut archive = zip::ZipArchive::new(fs::File::open(&path).unwrap()).unwrap();
        let mut names: Vec<&str> = archive.file_names().collect();
        names.sort_unstable();
        let mut expected = vec![
            format!("binaries/linux64/{identifier}.so"),
            "modelDescription.xml".to_string(),
        ];
        if name == "Features" {
            expected.push("resources/value.txt".to_string());
        }
        assert_eq!(names, expected);
        let xml = String::from_utf8(entry(&mut archive, "modelDescription.xml")).unwrap();
        assert!(xml.contains(&format!("modelName=\"{name}\"")));
        assert!(xml.contains(&format!("modelIdentifier=\"{identifier}\"")));
    }
}

#[test]
fn test_fmu_binaries_export_the_34_functions_and_report_fmi_2_0() {
    let Some(built) = test_fmus::built() else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    for (name, path) in built {
        let mut archive = zip::ZipArchive::new(fs::File::open(path).unwrap()).unwrap();
        let so_name = archive
            .file_names()
            .find(|n| n.starts_with("binaries/linux64/"))
            .unwrap()
            .to_string();
        let so = dir.path().join(format!("{name}.so"));
        fs::write(&so, entry(&mut archive, &so_name)).unwrap();
        // SAFETY: loading our own test library runs no initialisers beyond the C runtime's.
        let lib = unsafe { libloading::Library::new(&so) }.unwrap();
        for function in fmi2::FMI2_CS_SYMBOLS {
            // SAFETY: only the presence of the symbol is checked; it is not called.
            let symbol = unsafe { lib.get::<*const ()>(function.as_bytes()) };
            assert!(symbol.is_ok(), "{name} does not export {function}");
        }
        // SAFETY: fmi2GetVersion is `const char *fmi2GetVersion(void)`, returning a static string.
        let version = unsafe {
            let get = lib
                .get::<unsafe extern "C" fn() -> *const std::ffi::c_char>(b"fmi2GetVersion")
                .unwrap();
            std::ffi::CStr::from_ptr(get())
                .to_str()
                .unwrap()
                .to_string()
        };
        assert_eq!(version, "2.0");
        // The common layer's internals stay hidden.
        // SAFETY: only the presence of the symbol is checked.
        assert!(unsafe { lib.get::<*const ()>(b"MODEL") }.is_err());
    }
}
