//! Loading a study: the file parsed into a [`StudyFile`], then validated in one place into a
//! [`Study`] whose parameters, quantities, method and variants all make sense together.

use std::ops::Range;
use std::path::{Path, PathBuf};
use std::sync::RwLock;

use toml::Spanned;

use super::builtins::builtin;
use super::error::{location, StudyError};
use super::file::{quantile_column, Analysis, StudyFile, Variant};
use super::parameter::{Level, ParameterSpec};
use super::study::{Study, Suite};
use crate::qoi::QoiSpec;
use crate::uq::distributions::RandomParameter;
use crate::uq::method::Evaluation;
use crate::uq::random_inputs::{Correlation, CorrelationPair};

impl Study {
    /// Loads `builtin:NAME` or a TOML file.
    pub fn load(spec: &str) -> Result<Study, StudyError> {
        Study::load_with_settings(spec, &[])
    }

    /// [`Study::load`] with `KEY=VALUE` settings written into the study's TOML first
    /// (`run --set`; see `overrides.rs` for the grammar): validated as the file's own keys,
    /// and kept in [`Study::source`].
    pub(crate) fn load_with_settings(spec: &str, sets: &[String]) -> Result<Study, StudyError> {
        let (text, base) = match spec.strip_prefix("builtin:") {
            Some(name) => (builtin(name)?.to_owned(), None),
            None => {
                let path = Path::new(spec);
                let text = std::fs::read_to_string(path).map_err(|source| StudyError::Io {
                    path: path.to_path_buf(),
                    source,
                })?;
                (text, path.parent())
            }
        };
        let changed = super::overrides::apply(&text, spec, sets)?;
        let error = match Study::parse(&changed, spec, base) {
            Ok(study) => return Ok(study),
            Err(e) if sets.is_empty() => return Err(e),
            Err(e) => e,
        };
        // The file's own error, at its place in the file; else one of the settings', whose
        // place in the rewritten text would mean nothing to the user.
        match Study::parse(&text, spec, base) {
            Err(own) if message_of(&own).is_some() && message_of(&own) == message_of(&error) => {
                Err(own)
            }
            _ => Err(match error {
                StudyError::Parse { message, .. } | StudyError::Invalid { message, .. } => {
                    StudyError::Invalid {
                        origin: format!("{spec} (with --set {})", sets.join(" --set ")),
                        at: None,
                        message,
                    }
                }
                other => other,
            }),
        }
    }

    /// Parses and validates a study; `base` is the folder relative FMU paths start from.
    pub fn parse(text: &str, origin: &str, base: Option<&Path>) -> Result<Study, StudyError> {
        let file: StudyFile = toml::from_str(text).map_err(|e| StudyError::Parse {
            origin: origin.to_owned(),
            at: super::error::parse_error_location(text, e.span(), e.message()),
            message: e.message().to_owned(),
        })?;
        study(file, origin, base, text)
    }
}

/// What a parse or validation error says, without its place.
fn message_of(e: &StudyError) -> Option<&str> {
    match e {
        StudyError::Parse { message, .. } | StudyError::Invalid { message, .. } => Some(message),
        _ => None,
    }
}

/// The folders of [`add_fmu_dir`].
static HOST_FMU_DIRS: RwLock<Vec<PathBuf>> = RwLock::new(Vec::new());

/// Adds `dir` to [`fmu_search_path`], after `$RAILUQ_FMU_DIR` and before the folders beside
/// the executable, for the rest of the process: a host that ships FMUs of its own (the
/// Python package, whose executable is the Python interpreter) makes `builtin:NAME` and
/// `fmu = "Wheel.fmu"` find them. Adding a folder twice adds it once.
pub fn add_fmu_dir(dir: impl Into<PathBuf>) {
    let dir = dir.into();
    let mut dirs = HOST_FMU_DIRS.write().unwrap_or_else(|e| e.into_inner());
    if !dirs.contains(&dir) {
        dirs.push(dir);
    }
}

/// Folders searched for an FMU named by a relative path that is not next to the study file,
/// in order: `$RAILUQ_FMU_DIR`; the folders of [`add_fmu_dir`]; beside the executable,
/// `<exe dir>/fmu` (an installed binary with its FMUs) and `<exe dir>/../share/railuq/fmu`
/// (a `PREFIX/bin` + `PREFIX/share` install); `<exe dir>/../fmu` (`target/fmu` for a cargo
/// build); `./target/fmu`.
pub fn fmu_search_path() -> Vec<PathBuf> {
    let mut dirs = Vec::new();
    if let Some(d) = std::env::var_os("RAILUQ_FMU_DIR") {
        dirs.push(PathBuf::from(d));
    }
    dirs.extend(
        HOST_FMU_DIRS
            .read()
            .unwrap_or_else(|e| e.into_inner())
            .iter()
            .cloned(),
    );
    if let Some(exe_dir) = std::env::current_exe()
        .ok()
        .and_then(|e| e.parent().map(Path::to_path_buf))
    {
        dirs.push(exe_dir.join("fmu"));
        if let Some(prefix) = exe_dir.parent() {
            dirs.push(prefix.join("share").join("railuq").join("fmu"));
            dirs.push(prefix.join("fmu"));
        }
    }
    dirs.push(PathBuf::from("target/fmu"));
    dirs
}

/// Every place a study's `fmu = "..."` is looked for, in order: as given when absolute;
/// else beside the study file, relative to the working folder, then in each folder of
/// [`fmu_search_path`].
pub fn fmu_candidates(fmu: &str, base: Option<&Path>) -> Vec<PathBuf> {
    let p = Path::new(fmu);
    if p.is_absolute() {
        return vec![p.to_path_buf()];
    }
    let mut c: Vec<PathBuf> = base.map(|b| b.join(p)).into_iter().collect();
    c.push(p.to_path_buf());
    c.extend(fmu_search_path().into_iter().map(|d| d.join(p)));
    c
}

/// Where errors point: the origin and the text the spans refer to.
struct Context<'a> {
    origin: &'a str,
    text: &'a str,
}

impl Context<'_> {
    /// An error at `span` (or at no particular place).
    fn invalid(&self, span: Option<Range<usize>>, message: impl Into<String>) -> StudyError {
        StudyError::Invalid {
            origin: self.origin.to_owned(),
            at: span.map(|s| location(self.text, s)),
            message: message.into(),
        }
    }
}

/// Validates `file` (parsed from `text`) into a study.
fn study(
    file: StudyFile,
    origin: &str,
    base: Option<&Path>,
    text: &str,
) -> Result<Study, StudyError> {
    let cx = Context { origin, text };
    let e = &file.experiment;
    e.get_ref()
        .check()
        .map_err(|err| cx.invalid(Some(e.span()), err.to_string()))?;
    let params: Vec<(Range<usize>, &ParameterSpec)> = file
        .parameters
        .iter()
        .map(|p| (p.span(), p.get_ref()))
        .collect();
    let parameters = parameters(&cx, &params, &file)?;
    let correlation = correlation(&cx, &parameters, &file)?;
    check_fixed(&cx, &file)?;
    check_quantities(&cx, &file)?;
    check_analysis(&cx, &file.analysis)?;
    let mut study = Study {
        name: file.name.clone(),
        description: file.description.clone(),
        origin: origin.to_owned(),
        source: text.to_owned(),
        base: base.map(Path::to_path_buf),
        fmu_path: None,
        seed: file.seed,
        experiment: e.get_ref().clone(),
        method: file.method.get_ref().clone(),
        parameters,
        allow_negative: params
            .iter()
            .filter(|(_, p)| p.allow_negative)
            .map(|(_, p)| p.name.clone())
            .collect(),
        correlation,
        fixed: file.fixed.clone(),
        inputs: file
            .inputs
            .as_ref()
            .map(|i| resolve_relative(&i.file, base)),
        outputs: file.outputs.variables.clone(),
        qoi: file.qoi.iter().map(|q| q.get_ref().clone()).collect(),
        analysis: file.analysis.clone(),
        system: file.system.clone(),
        suite: None,
    };
    let outer: Vec<String> = params
        .iter()
        .filter(|(_, p)| p.level == Level::Outer)
        .map(|(_, p)| p.name.clone())
        .collect();
    check_method(&cx, &mut study, &outer, file.method.span())?;
    if !matches!(study.method().evaluation(), Evaluation::Intrusive(_)) {
        let fmu = file
            .fmu
            .as_deref()
            .ok_or_else(|| cx.invalid(None, "`fmu` is required (the FMU to run)"))?;
        study.fmu_path = Some(resolve_fmu(fmu, base));
    }
    if !file.variants.is_empty() || file.reference.is_some() {
        study.suite = Some(suite(&cx, &file, base)?);
    }
    Ok(study)
}

/// The validated random parameters: at least one, distinct, not also fixed.
fn parameters(
    cx: &Context,
    specs: &[(Range<usize>, &ParameterSpec)],
    file: &StudyFile,
) -> Result<Vec<RandomParameter>, StudyError> {
    if specs.is_empty() {
        return Err(cx.invalid(
            None,
            "no random [[parameters]]: a study needs at least one (a `nominal` study runs the \
             FMU at their means); to run the FMU once at its start values, use `uq-driver \
             simulate`",
        ));
    }
    let mut out: Vec<RandomParameter> = Vec::new();
    for (span, p) in specs {
        let at = Some(span.clone());
        if out.iter().any(|q| q.name == p.name) {
            return Err(cx.invalid(at, format!("parameter '{}' is listed twice", p.name)));
        }
        if file.fixed.contains_key(&p.name) {
            return Err(cx.invalid(
                at,
                format!("parameter '{}' is both random and fixed", p.name),
            ));
        }
        let param = p
            .to_parameter()
            .map_err(|e| cx.invalid(at, format!("parameter '{}': {e}", p.name)))?;
        out.push(param);
    }
    Ok(out)
}

/// The `[[correlation]]` pairs, their Gaussian copula checked (positive definite,
/// attainable with the marginals).
fn correlation(
    cx: &Context,
    parameters: &[RandomParameter],
    file: &StudyFile,
) -> Result<Option<Correlation>, StudyError> {
    let pairs = file
        .correlation
        .iter()
        .map(|c| CorrelationPair {
            between: c.get_ref().between.clone(),
            rho: c.get_ref().rho,
        })
        .collect();
    let at = file.correlation.first().map(|c| c.span());
    Correlation::new(parameters, pairs).map_err(|e| cx.invalid(at, format!("[[correlation]]: {e}")))
}

fn check_fixed(cx: &Context, file: &StudyFile) -> Result<(), StudyError> {
    match file.fixed.iter().find(|(_, v)| !v.is_finite()) {
        Some((name, _)) => Err(cx.invalid(None, format!("fixed value of '{name}' is not finite"))),
        None => Ok(()),
    }
}

/// Something to analyse; unique names; each quantity's settings.
fn check_quantities(cx: &Context, file: &StudyFile) -> Result<(), StudyError> {
    if file.outputs.variables.is_empty() && file.qoi.is_empty() {
        return Err(cx.invalid(
            None,
            "nothing to analyse: give [outputs] variables and/or [[qoi]]",
        ));
    }
    let e = file.experiment.get_ref();
    let duration = e.stop - e.start;
    let mut names: Vec<String> = file.outputs.variables.clone();
    for q in &file.qoi {
        let (span, q): (_, &QoiSpec) = (q.span(), q.get_ref());
        for name in q.quantity_names() {
            if names.contains(&name) {
                return Err(cx.invalid(
                    Some(span.clone()),
                    format!("quantity name '{name}' is used twice"),
                ));
            }
            names.push(name);
        }
        q.validate(duration)
            .and_then(|()| q.check_grid(e.start, e.stop, e.step))
            .map_err(|e| cx.invalid(Some(span), e.to_string()))?;
    }
    let qois: Vec<QoiSpec> = file.qoi.iter().map(|q| q.get_ref().clone()).collect();
    if let Some(problem) = crate::qoi::ended::ended_value_problem(&qois, &file.outputs.variables) {
        return Err(cx.invalid(None, problem));
    }
    // Their files: two names must not write the same one (checked before any run).
    crate::text::file_name::check_distinct(&names).map_err(|m| cx.invalid(None, m))?;
    Ok(())
}

/// Checks `[analysis]`, naming the first key out of its range with its rule, e.g.
/// `analysis: pdf_times = 0: must be at least 1 (...)`.
fn check_analysis(cx: &Context, a: &Analysis) -> Result<(), StudyError> {
    let counts = [
        ("pdf_grid", a.pdf_grid, 2, "points of the density grid"),
        (
            "pdf_times",
            a.pdf_times,
            1,
            "time columns of the PDF evolution",
        ),
        (
            "surrogate_samples",
            a.surrogate_samples,
            2,
            "draws of a chaos for a scalar quantity",
        ),
        (
            "series_samples",
            a.series_samples,
            2,
            "draws of a chaos for the outputs over time",
        ),
    ];
    for (key, value, least, what) in counts {
        if value < least {
            return Err(cx.invalid(
                None,
                format!("analysis: {key} = {value}: must be at least {least} ({what})"),
            ));
        }
    }
    // A level 0 is the smallest value, 1 the largest; NaN fails the range test too.
    if let Some(q) = a.quantiles.iter().find(|q| !(0.0..=1.0).contains(*q)) {
        return Err(cx.invalid(
            None,
            format!(
                "analysis: quantiles: level {q} must be in [0, 1] (0 gives the smallest \
                 value, 1 the largest)"
            ),
        ));
    }
    // NaN fails the range test too.
    if !(a.retained_variance > 0.0 && a.retained_variance <= 1.0) {
        return Err(cx.invalid(
            None,
            format!(
                "analysis: retained_variance = {} must be in (0, 1] (the share of a series' \
                 variance its principal components keep; default 0.999999)",
                a.retained_variance
            ),
        ));
    }
    // Each level names a column of `<V>.csv`: two levels with one name would be two
    // columns that cannot be told apart.
    let names: Vec<String> = a.quantiles.iter().map(|&p| quantile_column(p)).collect();
    for (j, name) in names.iter().enumerate() {
        if let Some(i) = names[..j].iter().position(|n| n == name) {
            return Err(cx.invalid(
                None,
                format!(
                    "analysis: quantiles {} and {} both give the column '{name}': give each \
                     level once",
                    a.quantiles[i], a.quantiles[j]
                ),
            ));
        }
    }
    Ok(())
}

/// Resolves the method's files and the levels of its parameters (`outer`: the names marked
/// `level = "outer"`), then checks its settings against the study.
fn check_method(
    cx: &Context,
    study: &mut Study,
    outer: &[String],
    span: Range<usize>,
) -> Result<(), StudyError> {
    let kind = study.method().kind();
    let base = study.base.clone();
    study
        .method
        .resolve_files(base.as_deref())
        .map_err(|e| cx.invalid(Some(span.clone()), format!("method {kind}: {e}")))?;
    study
        .method
        .set_levels(outer)
        .map_err(|e| cx.invalid(Some(span.clone()), format!("method {kind}: {e}")))?;
    let times = study.times();
    study
        .method()
        .validate(&study.problem(&times))
        .map_err(|e| cx.invalid(Some(span), format!("method {}: {e}", study.method().kind())))
}

/// Each variant as a complete study: the study's method, parameters and fixed values
/// replaced by the variant's.
fn suite(cx: &Context, file: &StudyFile, base: Option<&Path>) -> Result<Suite, StudyError> {
    let mut variants: Vec<Study> = Vec::new();
    for v in &file.variants {
        let (span, v): (_, &Variant) = (v.span(), v.get_ref());
        let plain = !v.name.is_empty() && !v.name.contains(['/', '\\', '.']);
        if !plain || variants.iter().any(|s| s.name == v.name) {
            return Err(cx.invalid(
                Some(span),
                format!(
                    "variant name '{}' is empty, repeated or not a plain folder name",
                    v.name
                ),
            ));
        }
        variants.push(variant(cx, file, v, span, base)?);
    }
    let reference = match &file.reference {
        None => 0,
        Some(r) => variants.iter().position(|s| &s.name == r).ok_or_else(|| {
            cx.invalid(None, format!("reference '{r}' is not one of the variants"))
        })?,
    };
    Ok(Suite {
        variants,
        reference,
        paper: file.paper.clone(),
    })
}

fn variant(
    cx: &Context,
    file: &StudyFile,
    v: &Variant,
    span: Range<usize>,
    base: Option<&Path>,
) -> Result<Study, StudyError> {
    let mut f = file.clone();
    f.variants.clear();
    f.reference = None;
    f.paper.clear();
    f.name = v.name.clone();
    // Errors inside the variant point at the variant.
    if let Some(m) = &v.method {
        f.method = Spanned::new(span.clone(), m.clone());
    }
    if let Some(p) = &v.parameters {
        f.parameters = p
            .iter()
            .map(|p| Spanned::new(span.clone(), p.clone()))
            .collect();
    }
    for (k, x) in &v.fixed {
        f.fixed.insert(k.clone(), x.clone());
    }
    if let Some(names) = &v.quantities {
        if let Some(n) = names
            .iter()
            .find(|n| !file.qoi.iter().any(|q| q.get_ref().name() == *n))
        {
            return Err(cx.invalid(
                Some(span),
                format!(
                    "variant '{}': quantities names '{n}', which is not a [[qoi]] of the study",
                    v.name
                ),
            ));
        }
        f.qoi
            .retain(|q| names.iter().any(|n| n == q.get_ref().name()));
    }
    let origin = format!("{} (variant {})", cx.origin, v.name);
    study(f, &origin, base, cx.text)
}

/// A file named in the study: absolute, or relative to the study's folder (to the current
/// folder for a built-in study).
fn resolve_relative(file: &str, base: Option<&Path>) -> PathBuf {
    let p = Path::new(file);
    match base {
        Some(b) if p.is_relative() => b.join(p),
        _ => p.to_path_buf(),
    }
}

/// The first of [`fmu_candidates`] that exists, else the first candidate (opening it then
/// fails; the command line lists every place searched).
fn resolve_fmu(fmu: &str, base: Option<&Path>) -> PathBuf {
    let candidates = fmu_candidates(fmu, base);
    candidates
        .iter()
        .find(|c| c.exists())
        .unwrap_or(&candidates[0])
        .clone()
}
