//! Build helper: `railuq-fmu xml DIR` writes the model descriptions; `railuq-fmu readme FILE`
//! rewrites the marked variable tables of a Markdown file (the guide's variables page);
//! `railuq-fmu package [--library LIB]... [--keep-debug] LIB OUT_DIR [MODEL...]` writes one
//! `.fmu` per model carrying every library given, each under the platform folder its header
//! names;
//! `railuq-fmu contact --out FILE [...]` writes a wheel–rail contact table and its plot.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

mod contact;
mod package;
mod svg;

use package::{model_info, package, write_descriptions, Library, PackageError};
use railuq::models::registry;

const USAGE: &str = "usage: railuq-fmu xml DIR
       railuq-fmu readme FILE
       railuq-fmu package [--library LIB]... [--keep-debug] LIB OUT_DIR [MODEL...]
       ";

const PACKAGE_HELP: &str =
    "package writes OUT_DIR/<Model>.fmu for each MODEL (default: every model) with the shared
library LIB and each --library LIB (e.g. a Windows DLL beside the Linux .so), one per platform,
stripped of symbols and debug info with binutils' strip ($STRIP if set) unless --keep-debug.";

fn usage() -> ExitCode {
    eprintln!(
        "{USAGE}{}\n\n{PACKAGE_HELP}\n\n{}",
        contact::USAGE,
        contact::HELP
    );
    ExitCode::from(2)
}

/// The parsed `package` command line.
struct PackageArgs {
    libraries: Vec<PathBuf>,
    out: PathBuf,
    models: Vec<String>,
    strip: bool,
}

fn parse_package(args: &[String]) -> Option<PackageArgs> {
    let mut extra = Vec::new();
    let mut positional = Vec::new();
    let mut strip = true;
    let mut it = args.iter();
    while let Some(a) = it.next() {
        match a.as_str() {
            "--library" => extra.push(PathBuf::from(it.next()?)),
            "--keep-debug" => strip = false,
            s if s.starts_with("--") => return None,
            _ => positional.push(a.clone()),
        }
    }
    if positional.len() < 2 {
        return None;
    }
    let mut libraries = vec![PathBuf::from(&positional[0])];
    libraries.extend(extra);
    Some(PackageArgs {
        libraries,
        out: PathBuf::from(&positional[1]),
        models: positional[2..].to_vec(),
        strip,
    })
}

fn run_package(a: &PackageArgs) -> Result<(), PackageError> {
    let libs = a
        .libraries
        .iter()
        .map(|p| Library::load(p, a.strip, &a.out))
        .collect::<Result<Vec<_>, _>>()?;
    let names: Vec<&str> = if a.models.is_empty() {
        registry().iter().map(|e| e.info.name).collect()
    } else {
        a.models.iter().map(String::as_str).collect()
    };
    for n in names {
        let path = package(model_info(n)?, &libs, &a.out)?;
        let platforms: Vec<&str> = libs.iter().map(|l| l.platform.folder()).collect();
        println!("wrote {} ({})", path.display(), platforms.join(", "));
    }
    Ok(())
}

/// Rewrites the marked variable tables of `path` (docs/src/reference/fmu-variables.md) from
/// the models' tables.
fn update_readme(path: &Path) -> Result<(), PackageError> {
    let io = |source| PackageError::Io {
        path: path.to_path_buf(),
        source,
    };
    let text = std::fs::read_to_string(path).map_err(io)?;
    let infos: Vec<_> = registry().iter().map(|e| e.info).collect();
    let (new, found) = railuq::fmi2::xml::update_readme_tables(&text, &infos);
    if new != text {
        out_file::write(path, new.as_bytes()).map_err(io)?;
    }
    println!("{}: {found} variable tables up to date", path.display());
    Ok(())
}

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let result: Result<(), Box<dyn std::error::Error>> = match args.first().map(String::as_str) {
        Some("xml") if args.len() == 2 => write_descriptions(Path::new(&args[1]))
            .map(|paths| {
                for p in paths {
                    println!("wrote {}", p.display());
                }
            })
            .map_err(Into::into),
        Some("readme") if args.len() == 2 => update_readme(Path::new(&args[1])).map_err(Into::into),
        Some("package") => match parse_package(&args[1..]) {
            Some(a) => run_package(&a).map_err(Into::into),
            None => return usage(),
        },
        Some("contact") => match contact::parse(&args[1..]) {
            Ok(a) => contact::run(&a).map_err(Into::into),
            Err(e) => {
                eprintln!("railuq-fmu contact: {e}");
                return usage();
            }
        },
        _ => return usage(),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("railuq-fmu: {e}");
            ExitCode::FAILURE
        }
    }
}
