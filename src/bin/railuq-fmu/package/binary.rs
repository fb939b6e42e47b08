//! The shared libraries an FMU carries: the FMI platform of each, read from its header (ELF,
//! PE or Mach-O), and the stripping of symbols and debug info before packaging.

use std::path::Path;
use std::process::Command;

/// An FMI 2.0 platform folder under `binaries/`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Platform {
    /// `linux64`: x86-64 ELF.
    Linux64,
    /// `linux32`: i386 ELF.
    Linux32,
    /// `win64`: x86-64 PE (a DLL).
    Win64,
    /// `win32`: i386 PE (a DLL).
    Win32,
    /// `darwin64`: x86-64 or arm64 Mach-O.
    Darwin64,
}

impl Platform {
    /// The folder name, e.g. `win64`.
    pub fn folder(self) -> &'static str {
        match self {
            Platform::Linux64 => "linux64",
            Platform::Linux32 => "linux32",
            Platform::Win64 => "win64",
            Platform::Win32 => "win32",
            Platform::Darwin64 => "darwin64",
        }
    }

    /// The shared-library extension, without the dot.
    pub fn extension(self) -> &'static str {
        match self {
            Platform::Linux64 | Platform::Linux32 => "so",
            Platform::Win64 | Platform::Win32 => "dll",
            Platform::Darwin64 => "dylib",
        }
    }

    /// The platform of a shared library from its first bytes; an error says why the file is
    /// not a shared library of an FMI 2.0 platform.
    pub fn of_library(bytes: &[u8]) -> Result<Platform, String> {
        let u16_le = |at: usize| {
            bytes
                .get(at..at + 2)
                .map(|b| u16::from_le_bytes([b[0], b[1]]))
        };
        let u32_le = |at: usize| {
            bytes
                .get(at..at + 4)
                .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        };
        if bytes.starts_with(b"\x7fELF") {
            // e_ident[EI_CLASS], [EI_DATA]; e_type at 16, e_machine at 18 (little endian).
            if bytes.get(5) != Some(&1) {
                return Err("a big-endian ELF file".into());
            }
            if u16_le(16) != Some(3) {
                return Err("an ELF file that is not a shared object (e_type != ET_DYN)".into());
            }
            return match (bytes.get(4), u16_le(18)) {
                (Some(2), Some(0x3e)) => Ok(Platform::Linux64),
                (Some(1), Some(0x03)) => Ok(Platform::Linux32),
                (_, m) => Err(format!(
                    "an ELF shared object for machine {m:?}, which has no FMI 2.0 platform folder"
                )),
            };
        }
        if bytes.starts_with(b"MZ") {
            let pe = u32_le(0x3c).ok_or("a truncated PE file")? as usize;
            if bytes.get(pe..pe + 4) != Some(b"PE\0\0") {
                return Err("an MZ file without a PE header".into());
            }
            // COFF header: Machine at +4, Characteristics at +22; IMAGE_FILE_DLL = 0x2000.
            let characteristics = u16_le(pe + 22).ok_or("a truncated PE file")?;
            if characteristics & 0x2000 == 0 {
                return Err("a PE file that is not a DLL".into());
            }
            return match u16_le(pe + 4) {
                Some(0x8664) => Ok(Platform::Win64),
                Some(0x014c) => Ok(Platform::Win32),
                m => Err(format!(
                    "a DLL for machine {m:?}, which has no FMI 2.0 platform folder"
                )),
            };
        }
        if bytes.starts_with(&[0xcf, 0xfa, 0xed, 0xfe]) {
            return Ok(Platform::Darwin64);
        }
        Err("not a shared library (no ELF, PE or Mach-O header)".into())
    }
}

/// The strip programs to try for a platform, in order: `$STRIP` alone if set; else binutils'
/// `strip` (Debian's reads ELF and PE alike), then the mingw-w64 one for a DLL.
fn strip_tools(platform: Platform) -> Vec<String> {
    if let Some(tool) = std::env::var_os("STRIP").filter(|t| !t.is_empty()) {
        return vec![tool.to_string_lossy().into_owned()];
    }
    let mut tools = vec!["strip".to_owned()];
    match platform {
        Platform::Win64 => tools.push("x86_64-w64-mingw32-strip".into()),
        Platform::Win32 => tools.push("i686-w64-mingw32-strip".into()),
        _ => {}
    }
    tools
}

/// Writes `input` with every symbol and all debug info removed to `output` (`strip
/// --strip-all`: a shared library keeps its dynamic symbols / export table). The error names
/// each program tried and what it said.
pub fn strip(input: &Path, output: &Path, platform: Platform) -> Result<(), String> {
    strip_with(&strip_tools(platform), input, output)
}

/// [`strip`] with the first of `tools` that succeeds.
fn strip_with(tools: &[String], input: &Path, output: &Path) -> Result<(), String> {
    let mut tried = Vec::new();
    for tool in tools {
        let result = Command::new(tool)
            .arg("--strip-all")
            .arg("-o")
            .arg(output)
            .arg(input)
            .output();
        match result {
            Ok(out) if out.status.success() => return Ok(()),
            Ok(out) => tried.push(format!(
                "{tool} exited with {}: {}",
                out.status,
                String::from_utf8_lossy(&out.stderr).trim()
            )),
            Err(e) => tried.push(format!("{tool}: {e}")),
        }
    }
    let _ = std::fs::remove_file(output);
    Err(tried.join("; "))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn elf(class: u8, data: u8, e_type: u16, machine: u16) -> Vec<u8> {
        let mut b = vec![0u8; 64];
        b[..4].copy_from_slice(b"\x7fELF");
        b[4] = class;
        b[5] = data;
        b[16..18].copy_from_slice(&e_type.to_le_bytes());
        b[18..20].copy_from_slice(&machine.to_le_bytes());
        b
    }

    fn pe(machine: u16, characteristics: u16) -> Vec<u8> {
        let mut b = vec![0u8; 0x80 + 24];
        b[..2].copy_from_slice(b"MZ");
        b[0x3c..0x40].copy_from_slice(&0x80u32.to_le_bytes());
        b[0x80..0x84].copy_from_slice(b"PE\0\0");
        b[0x84..0x86].copy_from_slice(&machine.to_le_bytes());
        b[0x96..0x98].copy_from_slice(&characteristics.to_le_bytes());
        b
    }

    #[test]
    fn platform_comes_from_the_header() {
        assert_eq!(
            Platform::of_library(&elf(2, 1, 3, 0x3e)),
            Ok(Platform::Linux64)
        );
        assert_eq!(
            Platform::of_library(&elf(1, 1, 3, 0x03)),
            Ok(Platform::Linux32)
        );
        assert_eq!(
            Platform::of_library(&pe(0x8664, 0x2022)),
            Ok(Platform::Win64)
        );
        assert_eq!(
            Platform::of_library(&pe(0x014c, 0x2102)),
            Ok(Platform::Win32)
        );
        assert_eq!(
            Platform::of_library(&[0xcf, 0xfa, 0xed, 0xfe, 0, 0]),
            Ok(Platform::Darwin64)
        );
    }

    #[test]
    fn executables_and_foreign_files_are_refused_with_the_reason() {
        let err = |b: &[u8]| Platform::of_library(b).unwrap_err();
        assert!(err(&elf(2, 1, 2, 0x3e)).contains("not a shared object"));
        assert!(err(&elf(2, 1, 3, 0xb7)).contains("no FMI 2.0 platform"));
        assert!(err(&elf(2, 2, 3, 0x3e)).contains("big-endian"));
        assert!(err(&pe(0x8664, 0x0022)).contains("not a DLL"));
        assert!(err(&pe(0xaa64, 0x2022)).contains("no FMI 2.0 platform"));
        assert!(err(b"MZ").contains("truncated"));
        assert!(err(b"<?xml").contains("no ELF, PE or Mach-O"));
        assert!(err(b"").contains("no ELF, PE or Mach-O"));
    }

    /// Section names of a little-endian ELF64 file (section headers and .shstrtab).
    fn elf64_section_names(b: &[u8]) -> Vec<String> {
        let u16_at = |at: usize| usize::from(u16::from_le_bytes([b[at], b[at + 1]]));
        let u32_at = |at: usize| u32::from_le_bytes(b[at..at + 4].try_into().unwrap()) as usize;
        let u64_at = |at: usize| u64::from_le_bytes(b[at..at + 8].try_into().unwrap()) as usize;
        let (shoff, shentsize, shnum, shstrndx) =
            (u64_at(0x28), u16_at(0x3a), u16_at(0x3c), u16_at(0x3e));
        let strtab = u64_at(shoff + shstrndx * shentsize + 0x18);
        (0..shnum)
            .map(|i| {
                let start = strtab + u32_at(shoff + i * shentsize);
                let len = b[start..].iter().position(|&c| c == 0).unwrap();
                String::from_utf8_lossy(&b[start..start + len]).into_owned()
            })
            .collect()
    }

    #[test]
    fn strip_removes_the_symbol_table_and_debug_info() {
        // This test program is an ELF file with symbols and (in a debug build) debug info.
        let exe = std::env::current_exe().unwrap();
        let dir = std::env::temp_dir().join(format!("railuq-strip-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let out = dir.join("stripped");
        strip_with(&["strip".to_owned()], &exe, &out).unwrap();
        let before = std::fs::read(&exe).unwrap();
        let after = std::fs::read(&out).unwrap();
        assert!(
            after.len() < before.len(),
            "{} -> {}",
            before.len(),
            after.len()
        );
        let debug = |b: &[u8]| {
            let names = elf64_section_names(b);
            assert!(names.iter().any(|n| n == ".text"), "{names:?}");
            names
                .into_iter()
                // .debug_gdb_scripts is loaded data (a pointer to pretty-printers), not debug info.
                .filter(|n| n == ".symtab" || n.starts_with(".debug") && n != ".debug_gdb_scripts")
                .count()
        };
        assert!(debug(&before) > 0);
        assert_eq!(debug(&after), 0);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn a_missing_strip_program_is_named_in_the_error() {
        let dir = std::env::temp_dir();
        let tools = ["no-such-strip-program".to_owned()];
        let err = strip_with(&tools, &dir.join("in"), &dir.join("out")).unwrap_err();
        assert!(err.contains("no-such-strip-program"), "{err}");
    }

    #[test]
    fn each_platform_has_its_folder_and_extension() {
        let all = [
            (Platform::Linux64, "linux64", "so"),
            (Platform::Linux32, "linux32", "so"),
            (Platform::Win64, "win64", "dll"),
            (Platform::Win32, "win32", "dll"),
            (Platform::Darwin64, "darwin64", "dylib"),
        ];
        for (p, folder, ext) in all {
            assert_eq!((p.folder(), p.extension()), (folder, ext));
        }
    }
}
