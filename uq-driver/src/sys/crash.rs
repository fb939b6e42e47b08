//! A crash of an FMU running in-process (SIGSEGV, SIGBUS, SIGILL, SIGFPE, SIGABRT) takes the
//! driver with it; this handler at least says so. The text, naming the study and its running
//! points, is prepared as they start and finish ([`prepare`]); the handler only copies it to
//! file descriptor 2 with `write(2)` (no allocation, no lock), then re-raises the signal with
//! its default action, so the exit status stays that of the signal. A fault next to the
//! stack pointer (a stack overflow: the thread's guard page) is left to the handler that was
//! there before (Rust's "has overflowed its stack"), and so is everything while no study is
//! in progress.

use std::sync::atomic::{AtomicBool, AtomicU8, AtomicUsize, Ordering};
use std::sync::{Once, OnceLock};

/// Longest prepared text (bytes); a longer one is cut.
const CAPACITY: usize = 2048;
/// The signals handled.
#[cfg(unix)]
const SIGNALS: [i32; 5] = [
    libc::SIGSEGV,
    libc::SIGBUS,
    libc::SIGILL,
    libc::SIGFPE,
    libc::SIGABRT,
];

#[allow(clippy::declare_interior_mutable_const)]
const ZERO: AtomicU8 = AtomicU8::new(0);
/// Two buffers: the one being written is not the one a handler reads.
static TEXT: [[AtomicU8; CAPACITY]; 2] = [[ZERO; CAPACITY], [ZERO; CAPACITY]];
static LEN: [AtomicUsize; 2] = [AtomicUsize::new(0), AtomicUsize::new(0)];
static CURRENT: AtomicUsize = AtomicUsize::new(0);
/// Set once a signal has been passed on to the previous handler (whose own abort must not be
/// reported as the FMU's).
static PASSED_ON: AtomicBool = AtomicBool::new(false);
static INSTALL: Once = Once::new();
#[cfg(unix)]
static PREVIOUS: OnceLock<Vec<(i32, libc::sigaction)>> = OnceLock::new();

/// Prepares the text the handler prints: `what` is running (a study, its points); `None`:
/// nothing is. Callers serialize (the study registry's lock).
pub fn prepare(what: Option<&str>) {
    let text = what.map_or_else(String::new, |what| {
        format!(
            " during {what}: an FMU running in-process crashed and took the process with it. \
             Finished points are kept in the results store of the output folder. Run again \
             with --isolate to run each point in its own process (a crash then fails only its \
             point).\n"
        )
    });
    let mut n = text.len().min(CAPACITY);
    while !text.is_char_boundary(n) {
        n -= 1;
    }
    let next = 1 - CURRENT.load(Ordering::Acquire);
    for (cell, b) in TEXT[next].iter().zip(&text.as_bytes()[..n]) {
        cell.store(*b, Ordering::Relaxed);
    }
    LEN[next].store(n, Ordering::Release);
    CURRENT.store(next, Ordering::Release);
}

/// Installs the handler (once per process).
pub fn install() {
    #[cfg(unix)]
    INSTALL.call_once(|| {
        let mut previous = Vec::new();
        for sig in SIGNALS {
            // SAFETY: a zeroed sigaction is a valid value to fill; `on_crash` has the
            // SA_SIGINFO signature and lives for the whole program; `old` receives the
            // previous action, kept for the handler to pass signals on.
            unsafe {
                let mut act: libc::sigaction = std::mem::zeroed();
                act.sa_sigaction = on_crash as *const () as usize;
                act.sa_flags = libc::SA_SIGINFO | libc::SA_ONSTACK;
                libc::sigemptyset(&mut act.sa_mask);
                let mut old: libc::sigaction = std::mem::zeroed();
                if libc::sigaction(sig, &act, &mut old) == 0 {
                    previous.push((sig, old));
                }
            }
        }
        let _ = PREVIOUS.set(previous);
    });
}

#[cfg(unix)]
fn signal_text(sig: i32) -> &'static [u8] {
    match sig {
        libc::SIGSEGV => b"SIGSEGV (a segmentation fault)",
        libc::SIGBUS => b"SIGBUS (a bus error)",
        libc::SIGILL => b"SIGILL (an illegal instruction)",
        libc::SIGFPE => b"SIGFPE (an arithmetic fault)",
        libc::SIGABRT => b"SIGABRT (abort())",
        _ => b"a signal",
    }
}

/// Writes all of `bytes` to fd 2 (async-signal-safe).
#[cfg(unix)]
fn write_err(mut bytes: &[u8]) {
    while !bytes.is_empty() {
        // SAFETY: write(2) from a valid buffer of the given length.
        let n = unsafe { libc::write(2, bytes.as_ptr().cast(), bytes.len()) };
        if n <= 0 {
            return;
        }
        bytes = &bytes[n as usize..];
    }
}

/// Whether the fault at `info`'s address is next to the interrupted stack pointer: a stack
/// overflow into the guard page, which the previous (Rust's) handler reports.
#[cfg(unix)]
fn near_stack_pointer(info: *mut libc::siginfo_t, ctx: *mut libc::c_void) -> bool {
    if info.is_null() || ctx.is_null() {
        return false;
    }
    // SAFETY: the kernel passes a valid siginfo_t to an SA_SIGINFO handler.
    let addr = unsafe { (*info).si_addr() } as usize;
    #[cfg(all(target_os = "linux", target_arch = "x86_64"))]
    // SAFETY: on x86_64 Linux `ctx` is the interrupted context, a ucontext_t.
    let sp = unsafe { (*ctx.cast::<libc::ucontext_t>()).uc_mcontext.gregs[libc::REG_RSP as usize] }
        as usize;
    #[cfg(all(target_os = "linux", target_arch = "aarch64"))]
    // SAFETY: on aarch64 Linux `ctx` is the interrupted context, a ucontext_t.
    let sp = unsafe { (*ctx.cast::<libc::ucontext_t>()).uc_mcontext.sp } as usize;
    #[cfg(not(all(
        target_os = "linux",
        any(target_arch = "x86_64", target_arch = "aarch64")
    )))]
    let sp = addr.wrapping_add(usize::MAX / 2);
    (addr <= sp && sp - addr < 1 << 20) || (addr > sp && addr - sp < 4096)
}

/// Passes `sig` on to the handler that was there before: restores it and returns (a fault
/// happens again; glibc's abort() raises again). A previous default action gets the signal
/// again at once (it is blocked until this handler returns), so that a signal sent by
/// `raise` or `kill` ends the process as it would have.
#[cfg(unix)]
fn pass_on(sig: i32) {
    PASSED_ON.store(true, Ordering::Release);
    let Some((_, act)) = PREVIOUS
        .get()
        .and_then(|p| p.iter().find(|(s, _)| *s == sig))
    else {
        // SAFETY: the default action for this signal, then the signal again (see above).
        unsafe {
            libc::signal(sig, libc::SIG_DFL);
            libc::raise(sig);
        }
        return;
    };
    // SAFETY: restores an action the kernel gave us for this signal; raise as above.
    unsafe {
        libc::sigaction(sig, act, std::ptr::null_mut());
        if act.sa_sigaction == libc::SIG_DFL {
            libc::raise(sig);
        }
    }
}

#[cfg(unix)]
extern "C" fn on_crash(sig: i32, info: *mut libc::siginfo_t, ctx: *mut libc::c_void) {
    let cur = CURRENT.load(Ordering::Acquire);
    let len = LEN[cur].load(Ordering::Acquire);
    let overflow = (sig == libc::SIGSEGV || sig == libc::SIGBUS) && near_stack_pointer(info, ctx);
    if len == 0 || overflow || PASSED_ON.load(Ordering::Acquire) {
        pass_on(sig);
        return;
    }
    write_err(b"uq-driver: error: the process was killed by ");
    write_err(signal_text(sig));
    let mut chunk = [0u8; 256];
    let mut at = 0;
    while at < len {
        let n = (len - at).min(chunk.len());
        for (c, cell) in chunk.iter_mut().zip(&TEXT[cur][at..at + n]) {
            *c = cell.load(Ordering::Relaxed);
        }
        write_err(&chunk[..n]);
        at += n;
    }
    // SAFETY: the default action for this signal, then the signal again: it is blocked while
    // this handler runs, so it is delivered (and ends the process with its status) on return.
    unsafe {
        libc::signal(sig, libc::SIG_DFL);
        libc::raise(sig);
    }
}
