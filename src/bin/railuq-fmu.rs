//! Build helper: `railuq-fmu xml DIR` writes the model descriptions; `railuq-fmu package LIB
//! OUT_DIR [MODEL...]` writes one `.fmu` per model from the cdylib LIB.

use std::path::PathBuf;
use std::process::ExitCode;

use railuq::models::registry;
use railuq::package::{model_info, package, write_descriptions};

fn usage() -> ExitCode {
    eprintln!("usage: railuq-fmu xml DIR | railuq-fmu package LIBRARY OUT_DIR [MODEL...]");
    ExitCode::from(2)
}

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let result = match args.first().map(String::as_str) {
        Some("xml") if args.len() == 2 => {
            write_descriptions(&PathBuf::from(&args[1])).map(|paths| {
                for p in paths {
                    println!("wrote {}", p.display());
                }
            })
        }
        Some("package") if args.len() >= 3 => {
            let lib = PathBuf::from(&args[1]);
            let out = PathBuf::from(&args[2]);
            let names: Vec<&str> = if args.len() > 3 {
                args[3..].iter().map(String::as_str).collect()
            } else {
                registry().iter().map(|e| e.info.name).collect()
            };
            names.iter().try_for_each(|n| {
                let path = package(model_info(n)?, &lib, &out)?;
                println!("wrote {}", path.display());
                Ok(())
            })
        }
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
