//! The error type of FMU import, and the FMI status codes it reports.

use std::fmt;
use std::path::{Path, PathBuf};

use super::description::DescriptionError;

/// The status returned by an FMI 2.0 function (`fmi2Status`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Status {
    /// `fmi2OK` (0): all well.
    Ok,
    /// `fmi2Warning` (1): things are not quite right, but the computation can continue.
    Warning,
    /// `fmi2Discard` (2): the call was not carried out (for `fmi2DoStep`: the step was not completed).
    Discard,
    /// `fmi2Error` (3): the instance is unusable until `fmi2Reset` or a stored FMU state is restored.
    Error,
    /// `fmi2Fatal` (4): the computations of all instances of this FMU are irreparably corrupted.
    Fatal,
    /// `fmi2Pending` (5): an asynchronous `fmi2DoStep` is still running.
    Pending,
    /// A value outside the FMI 2.0 range, returned by a misbehaving FMU.
    Unknown(i32),
}

impl Status {
    /// Converts a raw `fmi2Status` value.
    pub fn from_raw(raw: i32) -> Status {
        match raw {
            0 => Status::Ok,
            1 => Status::Warning,
            2 => Status::Discard,
            3 => Status::Error,
            4 => Status::Fatal,
            5 => Status::Pending,
            other => Status::Unknown(other),
        }
    }

    /// Whether a call that returned this status succeeded (`OK` or `Warning`).
    pub fn is_success(self) -> bool {
        matches!(self, Status::Ok | Status::Warning)
    }
}

impl fmt::Display for Status {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Status::Ok => f.write_str("OK"),
            Status::Warning => f.write_str("Warning"),
            Status::Discard => f.write_str("Discard"),
            Status::Error => f.write_str("Error"),
            Status::Fatal => f.write_str("Fatal"),
            Status::Pending => f.write_str("Pending"),
            Status::Unknown(raw) => write!(f, "invalid status {raw}"),
        }
    }
}

/// One message that an FMU sent through the logger callback.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct LogMessage {
    /// The status the FMU attached to the message.
    pub status: Status,
    /// The log category (for example `logStatusError`); empty if the FMU gave none.
    pub category: String,
    /// The formatted message text.
    pub message: String,
}

impl fmt::Display for LogMessage {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.category.is_empty() {
            write!(f, "[{}] {}", self.status, self.message)
        } else {
            write!(f, "[{}] {}: {}", self.status, self.category, self.message)
        }
    }
}

/// Formats the FMU's log lines for an error message; `logging_on`: whether the instance was
/// asked to log (many FMUs send nothing otherwise, not even at fmi2Error or fmi2Fatal).
fn log_lines(messages: &[LogMessage], logging_on: bool) -> String {
    if messages.is_empty() && logging_on {
        return " (the FMU logged nothing)".to_string();
    }
    if messages.is_empty() {
        return " (the FMU logged nothing; many FMUs log only when instantiated with loggingOn = \
                true: run again with --fmu-logging)"
            .to_string();
    }
    let mut out = String::from("; FMU log:");
    for m in messages {
        out.push_str("\n    ");
        out.push_str(&m.to_string());
    }
    out
}

/// Everything that can go wrong when opening, loading or running an FMU.
///
/// Each variant names the file (or instance) concerned, so that its `Display` is a complete,
/// user-facing message.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum FmuError {
    /// The file is not a zip archive.
    #[error("{}: not a zip archive ({reason})", .path.display())]
    NotAZip {
        /// The `.fmu` file.
        path: PathBuf,
        /// What the zip reader reported.
        reason: String,
    },
    /// The zip archive is corrupt or uses a feature that is not supported (encryption, a
    /// compression method other than stored or deflate).
    #[error("{}: cannot read archive entry '{entry}' ({reason})", .path.display())]
    Archive {
        /// The `.fmu` file.
        path: PathBuf,
        /// The entry's name as stored in the archive.
        entry: String,
        /// What went wrong.
        reason: String,
    },
    /// An archive entry would be written outside the extraction folder, or is a link or device.
    #[error("{}: refusing unsafe archive entry '{entry}': {reason}", .path.display())]
    UnsafeEntry {
        /// The `.fmu` file.
        path: PathBuf,
        /// The entry's name as stored in the archive.
        entry: String,
        /// Why it is refused.
        reason: String,
    },
    /// The archive exceeds the extraction limits (a zip bomb, or simply far too large).
    #[error("{}: archive too large: {reason}", .path.display())]
    ArchiveTooLarge {
        /// The `.fmu` file.
        path: PathBuf,
        /// Which limit was exceeded.
        reason: String,
    },
    /// An I/O operation on a file failed.
    #[error("{}: {source}", .path.display())]
    Io {
        /// The file or folder concerned.
        path: PathBuf,
        /// The underlying error.
        #[source]
        source: std::io::Error,
    },
    /// The archive has no `modelDescription.xml` at its top level.
    #[error("{}: no modelDescription.xml at the top level of the FMU", .path.display())]
    MissingModelDescription {
        /// The `.fmu` file.
        path: PathBuf,
    },
    /// `modelDescription.xml` is not well-formed XML.
    #[error("{}: malformed modelDescription.xml at line {line}, column {column}: {reason}", .path.display())]
    MalformedXml {
        /// The `.fmu` file.
        path: PathBuf,
        /// 1-based line of the error.
        line: usize,
        /// 1-based column (in bytes) of the error.
        column: usize,
        /// What the XML reader reported.
        reason: String,
    },
    /// The FMU is not an FMI 2.0 FMU.
    #[error("{}: unsupported FMI version \"{found}\"; uq-driver imports FMI 2.0 FMUs only", .path.display())]
    UnsupportedFmiVersion {
        /// The `.fmu` file.
        path: PathBuf,
        /// The `fmiVersion` attribute found.
        found: String,
    },
    /// The FMU does not implement Co-Simulation.
    #[error(
        "{}: the FMU does not support Co-Simulation ({}); uq-driver needs an FMI 2.0 Co-Simulation FMU",
        .path.display(),
        if *.model_exchange_present { "it is a Model Exchange FMU only" } else { "no CoSimulation element" }
    )]
    NoCoSimulation {
        /// The `.fmu` file.
        path: PathBuf,
        /// Whether the description has a `ModelExchange` element.
        model_exchange_present: bool,
    },
    /// `modelDescription.xml` is well-formed but violates FMI 2.0.
    #[error("{}: invalid modelDescription.xml: {source}", .path.display())]
    InvalidDescription {
        /// The `.fmu` file.
        path: PathBuf,
        /// The violation.
        #[source]
        source: Box<DescriptionError>,
    },
    /// There is no binary for this platform.
    #[error(
        "{}: no binary for this platform: expected {} in the FMU{}",
        .path.display(),
        .expected,
        if .available.is_empty() { String::from(" (its binaries/ folder is empty or missing)") }
        else { format!(" (binaries/ has: {})", .available.join(", ")) }
    )]
    MissingBinary {
        /// The `.fmu` file.
        path: PathBuf,
        /// The path of the expected binary inside the FMU, e.g. `binaries/linux64/Wheel.so`.
        expected: String,
        /// The platform folders present under `binaries/`.
        available: Vec<String>,
    },
    /// The platform is not one for which FMI 2.0 defines a binary folder.
    #[error("FMI 2.0 defines no binary folder for this platform ({os}/{arch})")]
    UnsupportedPlatform {
        /// `std::env::consts::OS`.
        os: &'static str,
        /// `std::env::consts::ARCH`.
        arch: &'static str,
    },
    /// The shared library could not be loaded.
    #[error("{}: cannot load the FMU binary: {reason}", .path.display())]
    Load {
        /// The shared library.
        path: PathBuf,
        /// What the dynamic loader reported.
        reason: String,
    },
    /// The shared library does not export a function that FMI 2.0 Co-Simulation requires.
    #[error("{}: the FMU binary does not export the required function {symbol}", .path.display())]
    MissingSymbol {
        /// The shared library.
        path: PathBuf,
        /// The missing function.
        symbol: &'static str,
    },
    /// The binary is not an FMI 2.0 binary for the default platform types.
    #[error("{}: incompatible FMU binary: {reason}", .path.display())]
    IncompatibleBinary {
        /// The shared library.
        path: PathBuf,
        /// What does not match.
        reason: String,
    },
    /// `fmi2Instantiate` returned no instance, or the instance could not be created.
    #[error("{}: cannot instantiate '{instance}': {reason}{}", .path.display(), log_lines(.messages, *.logging_on))]
    InstantiateFailed {
        /// The `.fmu` file.
        path: PathBuf,
        /// The instance name.
        instance: String,
        /// Why.
        reason: String,
        /// What the FMU logged meanwhile.
        messages: Vec<LogMessage>,
        /// Whether the instance was asked to log (`loggingOn`).
        logging_on: bool,
    },
    /// An FMI function returned a status other than OK or Warning.
    #[error(
        "{}: {function} returned {status} for instance '{instance}'{}",
        .path.display(), log_lines(.messages, *.logging_on)
    )]
    Call {
        /// The `.fmu` file.
        path: PathBuf,
        /// The instance name.
        instance: String,
        /// The FMI function, e.g. `fmi2DoStep`.
        function: &'static str,
        /// The status it returned.
        status: Status,
        /// The messages the FMU logged during the call (or, if none, its last messages).
        messages: Vec<LogMessage>,
        /// Whether the instance was asked to log (`loggingOn`).
        logging_on: bool,
    },
    /// The FMU returned something that breaks the FMI 2.0 contract (e.g. a null string).
    #[error("{}: {function} of instance '{instance}' misbehaved: {reason}", .path.display())]
    Protocol {
        /// The `.fmu` file.
        path: PathBuf,
        /// The instance name.
        instance: String,
        /// The FMI function.
        function: &'static str,
        /// What was wrong.
        reason: String,
    },
    /// An earlier call returned `fmi2Fatal`: no FMI function of this FMU may be called again.
    #[error("{}: cannot call {function}: an earlier call returned Fatal, so FMI 2.0 forbids any further call to this FMU", .path.display())]
    Unusable {
        /// The `.fmu` file.
        path: PathBuf,
        /// The function that was not called.
        function: &'static str,
    },
    /// The FMU declares that it does not support the requested capability.
    #[error("{}: {function} is not supported: the FMU declares {declaration}", .path.display())]
    Unsupported {
        /// The `.fmu` file.
        path: PathBuf,
        /// The function that was not called.
        function: &'static str,
        /// The capability attribute in modelDescription.xml, e.g. `canGetAndSetFMUstate="false"`.
        declaration: &'static str,
    },
    /// An argument passed by the caller is invalid (length mismatch, interior NUL, ...).
    #[error("{function}: invalid argument: {reason}")]
    InvalidArgument {
        /// The function called.
        function: &'static str,
        /// What is wrong.
        reason: String,
    },
    /// No variable of this name exists in the model description.
    #[error("no variable named '{name}' in the model")]
    UnknownVariable {
        /// The name asked for.
        name: String,
    },
    /// The variable exists but has another type.
    #[error("variable '{name}' is of type {found}, not {expected}")]
    WrongType {
        /// The variable.
        name: String,
        /// The type asked for.
        expected: &'static str,
        /// The declared type.
        found: &'static str,
    },
    /// The variable may not be set now (FMI 2.0 rules on causality, variability and initial).
    #[error("variable '{name}' cannot be set: {why}")]
    NotSettable {
        /// The variable.
        name: String,
        /// Why not.
        why: String,
    },
}

impl FmuError {
    /// Attaches the `.fmu` path to an error from [`ModelDescription::parse`](super::ModelDescription::parse).
    pub fn from_description(path: &Path, error: DescriptionError) -> FmuError {
        let path = path.to_path_buf();
        match error {
            DescriptionError::Malformed {
                line,
                column,
                reason,
            } => FmuError::MalformedXml {
                path,
                line,
                column,
                reason,
            },
            DescriptionError::UnsupportedFmiVersion { found } => {
                FmuError::UnsupportedFmiVersion { path, found }
            }
            DescriptionError::NoCoSimulation {
                model_exchange_present,
            } => FmuError::NoCoSimulation {
                path,
                model_exchange_present,
            },
            source => FmuError::InvalidDescription {
                path,
                source: Box::new(source),
            },
        }
    }

    /// The messages the FMU logged, for the errors that carry them.
    pub fn fmu_messages(&self) -> &[LogMessage] {
        match self {
            FmuError::Call { messages, .. } | FmuError::InstantiateFailed { messages, .. } => {
                messages
            }
            _ => &[],
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn status_round_trip() {
        for raw in 0..6 {
            assert_ne!(Status::from_raw(raw), Status::Unknown(raw));
        }
        assert_eq!(Status::from_raw(42), Status::Unknown(42));
        assert!(Status::Warning.is_success());
        assert!(!Status::Discard.is_success());
    }

    #[test]
    fn call_error_lists_the_fmu_log() {
        let e = FmuError::Call {
            path: PathBuf::from("/x/Model.fmu"),
            instance: "w0".into(),
            function: "fmi2DoStep",
            status: Status::Error,
            messages: vec![LogMessage {
                status: Status::Error,
                category: "logStatusError".into(),
                message: "step size must be positive".into(),
            }],
            logging_on: false,
        };
        let text = e.to_string();
        assert!(text.starts_with("/x/Model.fmu: fmi2DoStep returned Error for instance 'w0'"));
        assert!(text.contains("[Error] logStatusError: step size must be positive"));
    }

    /// An FMU that logs only with loggingOn gave "the FMU logged nothing" and no way
    /// out; the message names --fmu-logging unless logging was on.
    #[test]
    fn an_empty_log_names_fmu_logging_when_logging_was_off() {
        let call = |logging_on| {
            FmuError::Call {
                path: PathBuf::from("/x/Model.fmu"),
                instance: "w0".into(),
                function: "fmi2DoStep",
                status: Status::Fatal,
                messages: Vec::new(),
                logging_on,
            }
            .to_string()
        };
        let off = call(false);
        assert!(off.contains("(the FMU logged nothing; "), "{off}");
        assert!(off.contains("run again with --fmu-logging)"), "{off}");
        let on = call(true);
        assert!(on.ends_with("(the FMU logged nothing)"), "{on}");
    }
}
