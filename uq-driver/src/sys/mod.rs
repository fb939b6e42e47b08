//! Process-level system calls, each behind a safe function: descriptors moved and copied,
//! the C streams flushed, the process ended at once, an `atexit` handler, signal
//! dispositions, read-only file maps, free disk space, and the handler that reports a crash
//! of an in-process FMU ([`crash`]).
//!
//! With the FMI import layer ([`crate::fmu`]), the only place of the library that holds
//! `unsafe` code; every other module is `#![forbid(unsafe_code)]`.

pub mod crash;

use std::fs::File;
use std::io;
use std::os::fd::{FromRawFd, OwnedFd, RawFd};
use std::path::Path;

/// A copy of descriptor `fd` at the lowest free number at or above `min`, close-on-exec.
pub fn dup_cloexec(fd: RawFd, min: RawFd) -> io::Result<OwnedFd> {
    // SAFETY: fcntl(F_DUPFD_CLOEXEC) takes no pointers; the result is checked.
    let new = unsafe { libc::fcntl(fd, libc::F_DUPFD_CLOEXEC, min) };
    if new < 0 {
        return Err(io::Error::last_os_error());
    }
    // SAFETY: `new` is a fresh descriptor owned by nothing else.
    Ok(unsafe { OwnedFd::from_raw_fd(new) })
}

/// Makes descriptor `to` a copy of `from` (`dup2`): what was open as `to` is closed. Whoever
/// calls it must know that nothing in the process relies on `to` staying what it was.
pub fn dup2(from: RawFd, to: RawFd) -> io::Result<()> {
    // SAFETY: dup2 takes no pointers; the result is checked.
    if unsafe { libc::dup2(from, to) } < 0 {
        return Err(io::Error::last_os_error());
    }
    Ok(())
}

/// Under an address-space limit (`ulimit -v`), keeps the C allocator to 2 arenas
/// (`mallopt(M_ARENA_MAX, 2)`); without a limit it does nothing. glibc gives each thread
/// an arena that reserves 64 MiB of address space; under a limit of a few hundred MiB the
/// reservations fail and every allocation falls back to a `mmap` and `munmap` of its own:
/// a Wheel study of 400 runs of 50 001 points under `ulimit -v 250000` took 254 s (4.3
/// million `mmap` calls, 80 % of them failing) instead of 5 s. Returns whether it applied.
#[cfg(all(target_os = "linux", target_env = "gnu"))]
pub fn fewer_arenas_under_an_address_limit() -> bool {
    let mut limit = libc::rlimit {
        rlim_cur: 0,
        rlim_max: 0,
    };
    // SAFETY: getrlimit writes the rlimit it is given a valid pointer to.
    let got = unsafe { libc::getrlimit(libc::RLIMIT_AS, &mut limit) };
    if got != 0 || limit.rlim_cur == libc::RLIM_INFINITY {
        return false;
    }
    // SAFETY: mallopt takes no pointers; M_ARENA_MAX may be set at any time.
    unsafe { libc::mallopt(libc::M_ARENA_MAX, 2) == 1 }
}

/// Does nothing where the C library is not glibc.
#[cfg(not(all(target_os = "linux", target_env = "gnu")))]
pub fn fewer_arenas_under_an_address_limit() -> bool {
    false
}

/// Flushes every C stream (`fflush(NULL)`): what code in the process printed with C's stdio
/// (an FMU's `printf`) reaches its descriptor.
pub fn flush_c_streams() {
    // SAFETY: fflush(NULL) is defined to flush every open output stream.
    unsafe {
        libc::fflush(std::ptr::null_mut());
    }
}

/// Ends the process at once with `code` (`_exit`): no exit handlers, no destructors, no
/// flushing (see [`flush_c_streams`]).
pub fn exit_immediately(code: i32) -> ! {
    // SAFETY: _exit has no preconditions; it does not return.
    unsafe { libc::_exit(code) }
}

/// Keeps another thread that calls `exit()` from ending the process first: after the exit
/// handlers, glibc's `exit()` flushes the C streams under the lock of the list of streams
/// (`_IO_cleanup`), so taking that lock parks such a thread. Never released: call it only
/// right before [`exit_immediately`]. Does nothing on other C libraries.
pub fn hold_other_exits() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    {
        extern "C" {
            /// glibc: takes the (recursive) lock of the list of all `FILE` streams.
            fn _IO_list_lock();
        }
        // SAFETY: `_IO_list_lock` takes no arguments; the lock is never released because the
        // process ends with `_exit` right after (this function's contract).
        unsafe { _IO_list_lock() };
    }
}

/// Registers `handler` to run when the process calls `exit()`.
pub fn at_exit(handler: extern "C" fn()) {
    // SAFETY: `handler` is a plain function that lives as long as the program; atexit only
    // stores the pointer.
    unsafe {
        libc::atexit(handler);
    }
}

/// Ignores SIGINT in this process (a worker: its parent decides when it ends).
pub fn ignore_sigint() {
    // SAFETY: setting a signal's disposition to ignore takes no pointers.
    unsafe {
        libc::signal(libc::SIGINT, libc::SIG_IGN);
    }
}

/// Asks the kernel to kill this process (SIGKILL) when its parent dies (Linux); does nothing
/// elsewhere.
pub fn die_with_parent() {
    #[cfg(target_os = "linux")]
    // SAFETY: PR_SET_PDEATHSIG with a valid signal number; no pointers involved.
    unsafe {
        libc::prctl(libc::PR_SET_PDEATHSIG, libc::SIGKILL);
    }
}

/// The process id of this process's parent.
pub fn parent_pid() -> i32 {
    // SAFETY: getppid has no preconditions and cannot fail.
    unsafe { libc::getppid() }
}

/// A read-only map of `file`'s contents.
///
/// The map is valid only while nothing changes the file: callers map the results store of an
/// output folder while they hold the folder's lock, under which alone the store is appended
/// to, repaired or truncated, and drop the map before they write it themselves.
pub fn map_read_only(file: &File) -> io::Result<memmap2::Mmap> {
    // SAFETY: read-only map; the caller guarantees that the file does not change while the
    // map lives (see above).
    unsafe { memmap2::Mmap::map(file) }
}

/// Bytes available to this user on the file system of `path` (an existing path), from
/// `statvfs(3)`.
pub fn available_bytes(path: &Path) -> Option<f64> {
    use std::os::unix::ffi::OsStrExt;
    let c = std::ffi::CString::new(path.as_os_str().as_bytes()).ok()?;
    // SAFETY: an all-zero statvfs is a valid value of this plain C struct.
    let mut s: libc::statvfs = unsafe { std::mem::zeroed() };
    // SAFETY: a NUL-terminated path and a pointer to a local statvfs, as statvfs(3) requires.
    let rc = unsafe { libc::statvfs(c.as_ptr(), &mut s) };
    (rc == 0).then_some(s.f_bavail as f64 * s.f_frsize as f64)
}
