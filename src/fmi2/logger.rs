//! Logging through the importer's variadic logger, always as `logger(env, name, status,
//! category, "%s", message)` so that no '%' in a message is ever interpreted.

use std::ffi::CString;

use super::types::{Fmi2CallbackFunctions, Fmi2Status, FMI2_ERROR, FMI2_FATAL, FMI2_WARNING};

/// The log categories declared in every modelDescription.xml.
pub const LOG_CATEGORIES: [(&str, &str); 4] = [
    (
        "logStatusWarning",
        "Warnings (e.g. a parameter value that makes the model unstable)",
    ),
    ("logStatusError", "Errors (always reported to the logger)"),
    (
        "logStatusFatal",
        "Fatal errors (always reported to the logger)",
    ),
    ("logCalls", "A line for every successful fmi2 function call"),
];

/// Index of a category in [`LOG_CATEGORIES`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Category {
    /// logStatusWarning
    Warning = 0,
    /// logStatusError
    Error = 1,
    /// logStatusFatal
    Fatal = 2,
    /// logCalls
    Calls = 3,
}

impl Category {
    /// The category of a status.
    pub fn of_status(status: Fmi2Status) -> Category {
        match status {
            FMI2_WARNING => Category::Warning,
            FMI2_FATAL => Category::Fatal,
            FMI2_ERROR => Category::Error,
            _ => Category::Calls,
        }
    }
}

/// An instance's logger: the importer's callbacks and the debug-logging settings.
#[derive(Clone)]
pub struct Logger {
    callbacks: Option<Fmi2CallbackFunctions>,
    name: CString,
    enabled: [bool; LOG_CATEGORIES.len()],
}

impl std::fmt::Debug for Logger {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Logger")
            .field("name", &self.name)
            .field("enabled", &self.enabled)
            .finish()
    }
}

// SAFETY: the logger holds the importer's callback pointers and environment pointer, which
// the FMI standard lets the FMU call from whichever thread calls the FMU (one at a time per
// instance); the instance is moved between threads only as a whole.
unsafe impl Send for Logger {}

impl Logger {
    /// A logger for instance `name`; `callbacks` None means silent. As in the FMI fmuTemplate,
    /// `logging_on` (fmi2Instantiate's loggingOn) switches every category on or off.
    pub fn new(callbacks: Option<Fmi2CallbackFunctions>, name: &str, logging_on: bool) -> Self {
        let name = CString::new(name.replace('\0', "?")).unwrap_or_default();
        Logger {
            callbacks,
            name,
            enabled: [logging_on; LOG_CATEGORIES.len()],
        }
    }

    /// fmi2SetDebugLogging: `categories` empty means all categories; otherwise only the listed
    /// categories change.
    pub fn set_debug_logging(&mut self, on: bool, categories: &[String]) -> Result<(), String> {
        if categories.is_empty() {
            self.enabled = [on; LOG_CATEGORIES.len()];
            return Ok(());
        }
        let mut idx = Vec::with_capacity(categories.len());
        for c in categories {
            match LOG_CATEGORIES.iter().position(|(n, _)| n == c) {
                Some(i) => idx.push(i),
                None => {
                    let known: Vec<_> = LOG_CATEGORIES.iter().map(|(n, _)| *n).collect();
                    return Err(format!(
                        "unknown log category '{c}' (known: {})",
                        known.join(", ")
                    ));
                }
            }
        }
        for i in idx {
            self.enabled[i] = on;
        }
        Ok(())
    }

    /// Whether a message of this category and status would reach the importer.
    pub fn would_log(&self, status: Fmi2Status, category: Category) -> bool {
        if self.callbacks.and_then(|c| c.logger).is_none() {
            return false;
        }
        matches!(status, FMI2_ERROR | FMI2_FATAL) || self.enabled[category as usize]
    }

    /// Sends a message (errors always; others if their category is enabled).
    pub fn log(&self, status: Fmi2Status, category: Category, message: &str) {
        if !self.would_log(status, category) {
            return;
        }
        let Some(cb) = self.callbacks else { return };
        let Some(logger) = cb.logger else { return };
        let cat = CString::new(LOG_CATEGORIES[category as usize].0).unwrap_or_default();
        let msg = CString::new(message.replace('\0', "?")).unwrap_or_default();
        // SAFETY: `logger` is the importer's fmi2CallbackLogger, called with the environment
        // it gave us, NUL-terminated strings that live across the call, and the format "%s"
        // with exactly one string argument, so no format directive in `msg` is interpreted.
        unsafe {
            logger(
                cb.component_environment,
                self.name.as_ptr(),
                status,
                cat.as_ptr(),
                c"%s".as_ptr(),
                msg.as_ptr(),
            );
        }
    }
}
