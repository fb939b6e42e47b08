//! The logger and memory callbacks handed to `fmi2Instantiate`.
//!
//! `fmi2CallbackLogger` is variadic; the C shim `csrc/logger_shim.c` formats the message and
//! calls [`uq_driver_log`] with the finished text. `componentEnvironment` points to the
//! instance's boxed [`LogSink`], which keeps the recent messages (for error reports) and echoes
//! them to stderr on request.

use std::collections::VecDeque;
use std::ffi::{c_char, c_int, c_void};
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Mutex, MutexGuard};

use super::error::{LogMessage, Status};

/// How many messages an instance keeps.
const CAPACITY: usize = 256;
/// The longest message kept (bytes of UTF-8): the rest is cut, and said so.
pub(crate) const MAX_MESSAGE_BYTES: usize = 4096;
/// The longest instance name or category kept (bytes).
const MAX_NAME_BYTES: usize = 256;
/// The most bytes of message text an instance keeps: older messages are forgotten first (the
/// newest is always kept), so an FMU that logs a lot costs little memory, and an error,
/// which carries the messages of the failing call, stays small in `points.csv` and the store.
const MAX_KEPT_BYTES: usize = 64 * 1024;
/// How many of the last messages an error carries when the failing call itself logged none.
const FALLBACK: usize = 8;

extern "C" {
    /// The variadic `fmi2CallbackLogger` of `csrc/logger_shim.c`.
    fn uq_driver_fmi2_logger(
        env: *mut c_void,
        instance_name: *const c_char,
        status: c_int,
        category: *const c_char,
        message: *const c_char,
        ...
    );
}

/// `fmi2CallbackLogger`.
type LoggerFn =
    unsafe extern "C" fn(*mut c_void, *const c_char, c_int, *const c_char, *const c_char, ...);

/// The Rust function the C shim calls with the formatted message.
type SinkFn = extern "C" fn(*mut c_void, *const c_char, c_int, *const c_char, *const c_char);

/// `fmi2CallbackFunctions`. FMI 2.0.0 FMUs may keep the pointer, so it must live as long as the
/// instance (the instance boxes it).
#[repr(C)]
pub(crate) struct CallbackFunctions {
    logger: LoggerFn,
    allocate_memory: unsafe extern "C" fn(usize, usize) -> *mut c_void,
    free_memory: unsafe extern "C" fn(*mut c_void),
    step_finished: Option<unsafe extern "C" fn(*mut c_void, c_int)>,
    component_environment: *mut c_void,
}

impl CallbackFunctions {
    /// Callbacks that log into `sink`, which must outlive the FMU instance.
    pub(crate) fn new(sink: &LogSink) -> Box<CallbackFunctions> {
        Box::new(CallbackFunctions {
            logger: uq_driver_fmi2_logger,
            allocate_memory: libc::calloc,
            free_memory: libc::free,
            step_finished: None,
            component_environment: sink as *const LogSink as *mut c_void,
        })
    }
}

/// Per-instance destination of the FMU's log messages.
#[repr(C)]
pub(crate) struct LogSink {
    /// Read by the C shim through `componentEnvironment`: must stay the first field.
    sink: SinkFn,
    echo: AtomicBool,
    /// Sequence number of the next message.
    next: AtomicU64,
    messages: Mutex<Kept>,
}

/// The kept messages with their sequence numbers, and the bytes of their text.
#[derive(Default)]
struct Kept {
    messages: VecDeque<(u64, LogMessage)>,
    bytes: usize,
}

impl Kept {
    fn iter(&self) -> impl Iterator<Item = &(u64, LogMessage)> {
        self.messages.iter()
    }

    fn len(&self) -> usize {
        self.messages.len()
    }
}

/// Bytes a message counts against [`MAX_KEPT_BYTES`].
fn kept_bytes(m: &LogMessage) -> usize {
    m.message.len() + m.category.len()
}

impl LogSink {
    /// A new, empty sink; `echo` copies every message to stderr.
    pub(crate) fn new(echo: bool) -> Box<LogSink> {
        Box::new(LogSink {
            sink: uq_driver_log,
            echo: AtomicBool::new(echo),
            next: AtomicU64::new(0),
            messages: Mutex::new(Kept::default()),
        })
    }

    fn lock(&self) -> MutexGuard<'_, Kept> {
        self.messages.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// Turns copying messages to stderr on or off.
    pub(crate) fn set_echo(&self, echo: bool) {
        self.echo.store(echo, Ordering::Relaxed);
    }

    /// A mark to pass to [`LogSink::since`].
    pub(crate) fn mark(&self) -> u64 {
        self.next.load(Ordering::Acquire)
    }

    /// The messages logged since `mark`, or if there are none, the last few.
    pub(crate) fn since(&self, mark: u64) -> Vec<LogMessage> {
        let messages = self.lock();
        let new: Vec<LogMessage> = messages
            .iter()
            .filter(|(seq, _)| *seq >= mark)
            .map(|(_, m)| m.clone())
            .collect();
        if !new.is_empty() {
            return new;
        }
        let skip = messages.len().saturating_sub(FALLBACK);
        messages.iter().skip(skip).map(|(_, m)| m.clone()).collect()
    }

    /// All messages kept (the last 256).
    pub(crate) fn all(&self) -> Vec<LogMessage> {
        self.lock().iter().map(|(_, m)| m.clone()).collect()
    }

    /// Forgets all messages.
    pub(crate) fn clear(&self) {
        let mut kept = self.lock();
        kept.messages.clear();
        kept.bytes = 0;
    }

    fn push(&self, instance: &str, message: LogMessage) {
        if self.echo.load(Ordering::Relaxed) {
            eprintln!("[fmu {instance}] {message}");
        }
        let mut kept = self.lock();
        kept.bytes += kept_bytes(&message);
        let seq = self.next.load(Ordering::Relaxed);
        kept.messages.push_back((seq, message));
        while kept.messages.len() > CAPACITY
            || (kept.bytes > MAX_KEPT_BYTES && kept.messages.len() > 1)
        {
            if let Some((_, old)) = kept.messages.pop_front() {
                kept.bytes -= kept_bytes(&old);
            }
        }
        self.next.store(seq + 1, Ordering::Release);
    }
}

/// The text of an FMU's C string made safe to keep and show: at most `max` bytes (cut on a
/// character boundary, with `… (N bytes cut)`), invalid UTF-8 replaced, and control characters
/// other than tab and newline (terminal escapes, carriage returns, NUL-like bytes) written as
/// `\u{1b}`, so they reach neither the terminal nor a CSV file raw.
pub(crate) fn clean_text(bytes: &[u8], max: usize) -> String {
    let mut end = bytes.len().min(max);
    if end < bytes.len() {
        // Back to the start of a UTF-8 sequence (at most 3 continuation bytes).
        let floor = end.saturating_sub(3);
        while end > floor && (bytes[end] & 0b1100_0000) == 0b1000_0000 {
            end -= 1;
        }
    }
    let text = String::from_utf8_lossy(&bytes[..end]);
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        if c.is_control() && c != '\t' && c != '\n' {
            out.push_str(&format!("\\u{{{:x}}}", u32::from(c)));
        } else {
            out.push(c);
        }
    }
    if end < bytes.len() {
        out.push_str(&format!("… ({} bytes cut)", bytes.len() - end));
    }
    out
}

/// [`clean_text`] of a C string, `None` if null.
///
/// # Safety
/// `ptr` must be null or point to a NUL-terminated string valid for the duration of the call.
unsafe fn clean_c_string(ptr: *const c_char, max: usize) -> Option<String> {
    if ptr.is_null() {
        return None;
    }
    // SAFETY: non-null, and NUL-terminated and valid per this function's contract.
    let s = unsafe { std::ffi::CStr::from_ptr(ptr) };
    Some(clean_text(s.to_bytes(), max))
}

/// Receives a formatted message from the C shim and stores it in the [`LogSink`] at `env`.
extern "C" fn uq_driver_log(
    env: *mut c_void,
    instance: *const c_char,
    status: c_int,
    category: *const c_char,
    message: *const c_char,
) {
    // A panic must not unwind into the FMU's C code.
    let _ = catch_unwind(AssertUnwindSafe(|| {
        if env.is_null() {
            return;
        }
        // SAFETY: `env` is the componentEnvironment we passed to fmi2Instantiate: a `LogSink`
        // boxed by the instance, alive until after fmi2FreeInstance. Only shared access is used.
        let sink = unsafe { &*(env as *const LogSink) };
        // SAFETY: the shim passes NUL-terminated strings from the FMU (or its own buffer), valid
        // during this call, or null.
        let (instance, category, text) = unsafe {
            (
                clean_c_string(instance, MAX_NAME_BYTES),
                clean_c_string(category, MAX_NAME_BYTES),
                clean_c_string(message, MAX_MESSAGE_BYTES),
            )
        };
        sink.push(
            instance.as_deref().unwrap_or(""),
            LogMessage {
                status: Status::from_raw(status),
                category: category.unwrap_or_default(),
                message: text.unwrap_or_default(),
            },
        );
    }));
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::ffi::CString;

    #[test]
    fn shim_formats_variadic_messages_into_the_sink() {
        let sink = LogSink::new(false);
        let callbacks = CallbackFunctions::new(&sink);
        let name = CString::new("inst").unwrap();
        let cat = CString::new("logStatusError").unwrap();
        let fmt = CString::new("value %d is %s").unwrap();
        let arg = CString::new("bad").unwrap();
        let long = "y".repeat(5000);
        let long_c = CString::new(long.clone()).unwrap();
        let fmt_s = CString::new("%s!").unwrap();
        let mark = sink.mark();
        // SAFETY: calling the shim the way an FMU does: valid strings and matching varargs, and
        // an environment that is the live sink.
        unsafe {
            (callbacks.logger)(
                callbacks.component_environment,
                name.as_ptr(),
                3,
                cat.as_ptr(),
                fmt.as_ptr(),
                42 as c_int,
                arg.as_ptr(),
            );
            (callbacks.logger)(
                callbacks.component_environment,
                std::ptr::null(),
                0,
                std::ptr::null(),
                fmt_s.as_ptr(),
                long_c.as_ptr(),
            );
            (callbacks.logger)(
                std::ptr::null_mut(),
                name.as_ptr(),
                0,
                cat.as_ptr(),
                fmt_s.as_ptr(),
                arg.as_ptr(),
            );
        }
        let got = sink.since(mark);
        assert_eq!(got.len(), 2);
        assert_eq!(got[0].message, "value 42 is bad");
        assert_eq!(got[0].status, Status::Error);
        assert_eq!(got[0].category, "logStatusError");
        // 5001 bytes: cut to the first 4096, and said so.
        assert_eq!(
            got[1].message,
            format!("{}… (905 bytes cut)", &long[..MAX_MESSAGE_BYTES])
        );
        assert_eq!(got[1].category, "");
        assert_eq!(
            sink.since(sink.mark()).len(),
            2,
            "falls back to the last messages"
        );
        sink.clear();
        assert!(sink.all().is_empty());
    }

    #[test]
    fn huge_messages_are_cut_on_a_character_boundary_and_say_how_much() {
        // "é" is 2 bytes: 4095 'a' then 'é' straddles the 4096-byte limit.
        let text = format!(
            "{}é{}",
            "a".repeat(MAX_MESSAGE_BYTES - 1),
            "b".repeat(5_000_000)
        );
        let cut = clean_text(text.as_bytes(), MAX_MESSAGE_BYTES);
        assert_eq!(
            cut,
            format!(
                "{}… ({} bytes cut)",
                "a".repeat(MAX_MESSAGE_BYTES - 1),
                text.len() - (MAX_MESSAGE_BYTES - 1)
            )
        );
        assert_eq!(clean_text(b"short", MAX_MESSAGE_BYTES), "short");
    }

    #[test]
    fn terminal_escapes_and_control_characters_are_escaped_tabs_and_newlines_kept() {
        let raw = b"\x1b[31mred\x1b[0m\tcol\nline\rback\x07\x7f\xff";
        assert_eq!(
            clean_text(raw, MAX_MESSAGE_BYTES),
            "\\u{1b}[31mred\\u{1b}[0m\tcol\nline\\u{d}back\\u{7}\\u{7f}\u{fffd}"
        );
    }

    #[test]
    fn a_flood_of_large_messages_keeps_a_bounded_number_of_bytes() {
        let sink = LogSink::new(false);
        let big = "m".repeat(MAX_MESSAGE_BYTES);
        let mark = sink.mark();
        for _ in 0..1000 {
            sink.push(
                "x",
                LogMessage {
                    status: Status::Warning,
                    category: "c".into(),
                    message: big.clone(),
                },
            );
        }
        let bytes: usize = sink.all().iter().map(kept_bytes).sum();
        assert!(bytes <= MAX_KEPT_BYTES, "{bytes}");
        assert_eq!(sink.all().len(), MAX_KEPT_BYTES / (MAX_MESSAGE_BYTES + 1));
        // An error carries what is kept of the failing call's messages: as bounded.
        let since: usize = sink.since(mark).iter().map(kept_bytes).sum();
        assert!(since <= MAX_KEPT_BYTES, "{since}");
        sink.clear();
        assert!(sink.all().is_empty());
    }

    #[test]
    fn sink_keeps_only_the_last_messages() {
        let sink = LogSink::new(false);
        for i in 0..(CAPACITY + 10) {
            sink.push(
                "x",
                LogMessage {
                    status: Status::Ok,
                    category: String::new(),
                    message: i.to_string(),
                },
            );
        }
        let all = sink.all();
        assert_eq!(all.len(), CAPACITY);
        assert_eq!(all[0].message, "10");
        assert_eq!(sink.since(sink.mark() - 1).len(), 1);
    }
}
