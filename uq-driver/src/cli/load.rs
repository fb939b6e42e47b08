//! Reading a study argument: files, built-in names, warnings, the FMU search.

use std::path::{Path, PathBuf};

use anyhow::Result;

use crate::spec::{fmu_candidates, Study, BUILTINS};
use crate::suggest;

/// A study argument as `Study::load` takes it: a file, `builtin:NAME`, or a bare built-in
/// NAME when no file of that name exists; a misspelt name gets the closest built-in.
pub(crate) fn study_spec(arg: &str) -> Result<String> {
    let names = || BUILTINS.iter().map(|(n, _)| *n);
    if let Some(name) = arg.strip_prefix("builtin:") {
        if names().any(|n| n == name) {
            return Ok(arg.to_owned());
        }
        let hint = suggest::closest(name, names())
            .map(|c| format!(" (did you mean builtin:{c}?)"))
            .unwrap_or_default();
        anyhow::bail!("no built-in study '{name}'{hint}; `uq-driver list` shows them all");
    }
    let is_builtin = names().any(|n| n == arg);
    let exists = Path::new(arg).exists();
    match (exists, is_builtin) {
        (true, true) => anyhow::bail!(
            "'{arg}' is both a file here and a built-in study: write ./{arg} for the file or \
             builtin:{arg} for the built-in"
        ),
        (true, false) => Ok(arg.to_owned()),
        (false, true) => Ok(format!("builtin:{arg}")),
        (false, false) => {
            let hint = suggest::closest(arg, names())
                .map(|c| format!("; did you mean the built-in study {c}?"))
                .unwrap_or_else(|| "; `uq-driver list` shows the built-in studies".into());
            anyhow::bail!("no study file '{arg}' and no built-in study of that name{hint}")
        }
    }
}

/// Loads a study argument (file, builtin:NAME or NAME), warns about `cov` values that look
/// like percentages and checks that its FMU (and every variant's) can be found.
pub(crate) fn load_study(arg: &str) -> Result<Study> {
    load_study_with(arg, &[])
}

/// [`load_study`] with `KEY=VALUE` settings written into the study first (`run --set`).
pub(crate) fn load_study_with(arg: &str, sets: &[String]) -> Result<Study> {
    let s = Study::load_with_settings(&study_spec(arg)?, sets)?;
    super::check_study(&s)?;
    Ok(s)
}

/// `cov` is a fraction: a value above 1 is most likely a percentage.
pub(crate) fn cov_warnings(source: &str) -> Vec<String> {
    let Ok(table) = source.parse::<toml::Table>() else {
        return Vec::new();
    };
    let mut params: Vec<&toml::Value> = Vec::new();
    let arrays = |t: &toml::Table| -> Vec<toml::Value> {
        t.get("parameters")
            .and_then(|p| p.as_array())
            .cloned()
            .unwrap_or_default()
    };
    let mut all = arrays(&table);
    for v in table
        .get("variants")
        .and_then(|v| v.as_array())
        .into_iter()
        .flatten()
    {
        if let Some(t) = v.as_table() {
            all.extend(arrays(t));
        }
    }
    params.extend(all.iter());
    let mut out: Vec<String> = params
        .iter()
        .filter_map(|p| {
            let cov = p
                .get("cov")?
                .as_float()
                .or_else(|| p.get("cov").and_then(|c| c.as_integer()).map(|i| i as f64))?;
            let name = p.get("name").and_then(|n| n.as_str()).unwrap_or("?");
            (cov > 1.0).then(|| {
                format!(
                    "parameter '{name}': cov = {cov} is a coefficient of variation of {} %; \
                     `cov` is a fraction (did you mean cov = {}?)",
                    cov * 100.0,
                    cov / 100.0
                )
            })
        })
        .collect();
    out.dedup();
    out
}

/// An error listing every place searched when a study's FMU is not found.
pub(crate) fn check_fmu_found(s: &Study) -> Result<()> {
    let Some(path) = &s.fmu_path else {
        return Ok(());
    };
    if path.exists() {
        return Ok(());
    }
    let given = s
        .base
        .as_ref()
        .and_then(|b| path.strip_prefix(b).ok())
        .unwrap_or(path);
    // Each place once, as an absolute path (the study's folder and the working folder are
    // often the same).
    let mut places: Vec<PathBuf> = Vec::new();
    for p in fmu_candidates(&given.to_string_lossy(), s.base.as_deref()) {
        let p = std::path::absolute(&p).unwrap_or(p);
        if !places.contains(&p) {
            places.push(p);
        }
    }
    let list: Vec<String> = places
        .iter()
        .map(|p| format!("  {}", p.display()))
        .collect();
    anyhow::bail!(
        "{}: FMU {} not found; looked in:\n{}\n{}(set RAILUQ_FMU_DIR to the folder of the \
         FMUs, e.g. target/fmu after `make fmu`)",
        s.origin,
        given.display(),
        list.join("\n"),
        similar_fmu(&places).map_or(String::new(), |p| format!("did you mean {}? ", p.display()))
    )
}

/// The FMU, in the folders of `places`, whose name is closest to the names of `places` (a
/// misspelt file name), if one is close.
fn similar_fmu(places: &[PathBuf]) -> Option<PathBuf> {
    let wanted = places.first()?.file_name()?.to_string_lossy().into_owned();
    let mut found: Vec<PathBuf> = Vec::new();
    for dir in places.iter().filter_map(|p| p.parent()) {
        let Ok(entries) = std::fs::read_dir(dir) else {
            continue;
        };
        found.extend(
            entries
                .flatten()
                .map(|e| e.path())
                .filter(|p| p.extension().is_some_and(|e| e.eq_ignore_ascii_case("fmu"))),
        );
    }
    let names: Vec<String> = found
        .iter()
        .filter_map(|p| Some(p.file_name()?.to_string_lossy().into_owned()))
        .collect();
    let best = suggest::closest(&wanted, names.iter().map(String::as_str))?;
    found
        .into_iter()
        .find(|p| p.file_name().is_some_and(|n| n == best))
}
