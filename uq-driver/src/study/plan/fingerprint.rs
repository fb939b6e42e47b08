//! What identifies the records of a study: the FMU's SHA-256 and the hash of every study
//! setting that changes a record, written into the results store's manifest, so that a
//! store of another study or FMU is never resumed.

use std::path::Path;

use sha2::{Digest, Sha256};

use crate::fmu::{Fmu, FmuError};
use crate::spec::Study;
use crate::study::run::error::RunError;
use crate::study::store::Manifest;
use crate::uq::method::Design;

/// SHA-256 of an FMU, hex: of the file, or, for an extracted FMU folder, of every file's
/// relative path and content in sorted order.
pub fn sha256_file(path: &Path) -> std::io::Result<String> {
    fn walk(dir: &Path, root: &Path, h: &mut Sha256) -> std::io::Result<()> {
        let mut entries: Vec<_> = std::fs::read_dir(dir)?.collect::<Result<_, _>>()?;
        entries.sort_by_key(|e| e.file_name());
        for e in entries {
            let p = e.path();
            if e.file_type()?.is_dir() {
                walk(&p, root, h)?;
            } else {
                let rel = p
                    .strip_prefix(root)
                    .unwrap_or(&p)
                    .to_string_lossy()
                    .into_owned();
                h.update(rel.as_bytes());
                h.update([0]);
                h.update(std::fs::read(&p)?);
            }
        }
        Ok(())
    }
    if path.is_dir() {
        let mut h = Sha256::new();
        walk(path, path, &mut h)?;
        return Ok(format!("{:x}", h.finalize()));
    }
    let bytes = std::fs::read(path)?;
    Ok(format!("{:x}", Sha256::digest(&bytes)))
}

/// Hash of everything in a study that changes the stored records (not its name, description
/// or analysis settings). The quantities of interest are stored with every run, so their
/// settings are part of it (a study without any keeps the hash it always had).
pub fn study_hash(study: &Study) -> String {
    let mut key = serde_json::json!({
        "seed": study.seed,
        "experiment": study.experiment,
        "method": study.method,
        "parameters": study.parameters,
        "fixed": study.fixed,
        "outputs": { "variables": study.outputs },
    });
    if !study.qoi.is_empty() {
        key["qoi"] = serde_json::json!(study.qoi);
    }
    if let Some(path) = &study.inputs {
        // The signals themselves change the records, not the file's name. An unreadable file
        // (or one that is not a regular file: a FIFO is never opened for reading) is refused
        // before any run (Interface::resolve).
        let content = in_file::read(path, crate::study::plan::inputs::MAX_INPUT_FILE_BYTES)
            .map(|b| format!("{:x}", Sha256::digest(&b)))
            .unwrap_or_default();
        key["inputs"] = serde_json::json!(content);
    }
    // Likewise the correlation: studies without one keep their hash.
    if let Some(c) = &study.correlation {
        key["correlation"] = serde_json::json!(c.pairs);
    }
    if let Some((name, value)) = study.method().hash_entry(&study.parameters) {
        key[name] = value;
    }
    format!("{:x}", Sha256::digest(key.to_string().as_bytes()))
}

/// The store manifest of `study` on `fmu` with `design`.
pub fn manifest(study: &Study, fmu: &Fmu, design: &Design) -> Result<Manifest, RunError> {
    manifest_for(study, fmu, design.len())
}

/// The store manifest of `study` on `fmu` for `n_points` points (an adaptive method: the
/// most runs it may make).
pub fn manifest_for(study: &Study, fmu: &Fmu, n_points: usize) -> Result<Manifest, RunError> {
    let iface = crate::study::plan::resolve::interface(study, fmu)?;
    let fmu_sha256 = sha256_file(fmu.path()).map_err(|source| FmuError::Io {
        path: fmu.path().to_path_buf(),
        source,
    })?;
    Ok(Manifest {
        study_hash: study_hash(study),
        fmu_sha256,
        n_points,
        n_values: iface.n_values(study.experiment.times().len()),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn changed_quantity_settings_do_not_resume_stale_records() {
        let base = crate::spec::builtin("bogie-lhs-500").unwrap();
        let study = |text: &str| Study::parse(text, "t.toml", None).unwrap();
        let a = study_hash(&study(base));
        let b = study_hash(&study(
            &base.replace("threshold = 1e-4", "threshold = 2e-4"),
        ));
        assert_ne!(a, b, "a record holds v_cr for one threshold only");
        // Name, description and analysis settings do not change the records.
        let renamed = base.replace("name = \"bogie-lhs-500\"", "name = \"renamed\"");
        let c = study_hash(&study(&format!("{renamed}\n[analysis]\npdf_grid = 50\n")));
        assert_eq!(a, c);
    }

    #[test]
    fn an_scm_whose_design_follows_the_askey_families_does_not_resume_a_hermite_store() {
        // SCM with a uniform input now runs Gauss–Legendre nodes; a store of the Gauss–Hermite
        // design the same file gave before must not be resumed, so its hash differs from the
        // hash of the same file with `chaos = "hermite"` and from the hash without the key
        // as computed before (the method serialised without `chaos`, no `scm_germ`).
        let text = |dist: &str, chaos: &str| {
            format!(
                "name = \"u\"\nfmu = \"Wheel.fmu\"\n[experiment]\nstop = 1.0\nstep = 0.01\n\
                 [[parameters]]\nname = \"K\"\n{dist}\n\
                 [outputs]\nvariables = [\"q\"]\n[method]\nkind = \"scm\"\nnodes = 3\n{chaos}"
            )
        };
        let study = |t: String| Study::parse(&t, "t.toml", None).unwrap();
        let uniform = "distribution = \"uniform\"\nlow = 90.0\nhigh = 110.0";
        let askey = study(text(uniform, ""));
        let hermite = study(text(uniform, "chaos = \"hermite\""));
        assert_ne!(study_hash(&askey), study_hash(&hermite));
        let mut old_key = serde_json::json!({
            "seed": askey.seed,
            "experiment": askey.experiment,
            "method": askey.method,
            "parameters": askey.parameters,
            "fixed": askey.fixed,
            "outputs": { "variables": askey.outputs },
        });
        let old = format!("{:x}", Sha256::digest(old_key.to_string().as_bytes()));
        assert_ne!(study_hash(&askey), old);
        // A normal input: the design is the Gauss–Hermite one either way, the hash as before.
        let normal = study(text("mean = 100.0\nstd = 10.0", ""));
        old_key["parameters"] = serde_json::json!(normal.parameters);
        old_key["seed"] = serde_json::json!(normal.seed);
        let old = format!("{:x}", Sha256::digest(old_key.to_string().as_bytes()));
        assert_eq!(study_hash(&normal), old);
    }

    #[test]
    fn studies_without_quantities_keep_their_hash() {
        // The hash of wheel-scm in the store/manifest.json that uq-driver wrote before the
        // restructuring (commit 7b51554): old result folders still resume.
        let s = Study::load("builtin:wheel-scm").unwrap();
        let expected = "9c4270a27263cfdb71ef7669728eefc88c107f891685caf239948c85fa49637a";
        assert_eq!(study_hash(&s), expected);
    }
}
