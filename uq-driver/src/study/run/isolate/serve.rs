//! The worker's side (`uq-driver worker`): the protocol moved out of the FMU's way, then
//! points served one after the other as the in-process runner runs them.

use std::io::BufReader;

use super::protocol::{bytes_to_f64s, f64s_to_bytes, read_frame, write_frame};
use super::Setup;
use crate::fmu::Fmu;
use crate::study::run::instances::{ResetCheck, Slot};
use crate::study::run::point::check_reset;
use crate::study::run::point::run_point;

/// The worker's protocol descriptors are moved to this number or above, out of the way of an
/// FMU that writes to (or closes) low descriptors.
pub const PROTOCOL_FD_MIN: i32 = 100;

/// Makes the protocol channel safe from the FMU: moves the worker's stdin and stdout (the
/// pipes to the parent) to descriptors at or above [`PROTOCOL_FD_MIN`], close-on-exec, and
/// points descriptor 0 at /dev/null and descriptor 1 at stderr, so that whatever the FMU
/// prints goes to stderr, a write to a low descriptor misses the pipes and a program the FMU
/// starts does not inherit them. Returns (input, output).
#[cfg(unix)]
fn protocol_fds() -> std::io::Result<(std::fs::File, std::fs::File)> {
    use crate::sys::{dup2, dup_cloexec};
    let out = std::fs::File::from(dup_cloexec(1, PROTOCOL_FD_MIN)?);
    let input = std::fs::File::from(dup_cloexec(0, PROTOCOL_FD_MIN)?);
    // Nothing in this process relies on fd 1 staying the pipe (only `out` carries the
    // protocol), nor reads fd 0 any more (the protocol reads `input`).
    dup2(2, 1)?;
    let null = std::fs::File::open("/dev/null")?;
    dup2(std::os::fd::AsRawFd::as_raw_fd(&null), 0)?;
    Ok((input, out))
}

/// Ignores SIGINT and, on Linux, asks to be killed when the parent dies.
#[cfg(unix)]
fn detach_from_terminal_signals() {
    crate::sys::ignore_sigint();
    #[cfg(target_os = "linux")]
    {
        crate::sys::die_with_parent();
        // The parent may have died before that: then nobody reads our answers.
        let expected = std::env::var("UQ_DRIVER_PARENT_PID")
            .ok()
            .and_then(|p| p.parse::<i32>().ok());
        if expected.is_some_and(|p| p != crate::sys::parent_pid()) {
            std::process::exit(0);
        }
    }
}

/// The `uq-driver worker` subcommand: serves points until stdin closes. Returns the exit
/// status.
#[cfg(unix)]
pub fn serve() -> i32 {
    detach_from_terminal_signals();
    let (mut input, mut out) = match protocol_fds() {
        Ok((i, o)) => (BufReader::new(i), std::io::BufWriter::new(o)),
        Err(e) => {
            eprintln!("uq-driver worker: {e}");
            return 1;
        }
    };
    let setup: Setup = match read_frame(&mut input) {
        Ok(Some((b'S', payload))) => match serde_json::from_slice(&payload) {
            Ok(s) => s,
            Err(e) => {
                let _ = write_frame(&mut out, b'E', format!("bad setup: {e}").as_bytes());
                return 1;
            }
        },
        _ => {
            eprintln!("uq-driver worker: expected a setup frame on stdin");
            return 1;
        }
    };
    let fmu = match Fmu::open_extracted(&setup.fmu_root, &setup.fmu_shown) {
        Ok(f) => f,
        Err(e) => {
            let _ = write_frame(&mut out, b'E', e.to_string().as_bytes());
            return 1;
        }
    };
    if write_frame(&mut out, b'R', &[]).is_err() {
        return 1;
    }
    // The FMU's messages go to stderr, where the parent keeps the last lines.
    let mut slot = Slot::new(setup.policy, true);
    // The last point run successfully: its values and record (for the reset self-check).
    let mut last: Option<(Vec<f64>, Vec<f64>)> = None;
    while let Ok(Some((tag, payload))) = read_frame(&mut input) {
        let values = bytes_to_f64s(&payload);
        let sent = match tag {
            b'P' => {
                let result = run_point(&fmu, &mut slot, &setup.interface, &values, &setup.times);
                if let Some(why) = slot.take_reset_failure() {
                    if write_frame(&mut out, b'N', why.as_bytes()).is_err() {
                        return 1;
                    }
                }
                last = None;
                match result {
                    Ok(v) => {
                        let sent = write_frame(&mut out, b'O', &f64s_to_bytes(&v));
                        last = Some((values, v));
                        sent
                    }
                    Err(e) if fmu.is_unusable() => {
                        let _ = write_frame(&mut out, b'X', e.to_string().as_bytes());
                        return 0;
                    }
                    Err(e) => write_frame(&mut out, b'F', e.to_string().as_bytes()),
                }
            }
            b'C' => {
                let (check, _) = match &last {
                    Some((v, first)) if *v == values => {
                        check_reset(&fmu, &mut slot, &setup.interface, v, &setup.times, first)
                    }
                    _ => (ResetCheck::Failed("no run to compare with".into()), None),
                };
                let ends = fmu.is_unusable();
                let (code, why) = match check {
                    ResetCheck::Passed => (0, String::new()),
                    ResetCheck::Failed(why) => (if ends { 2 } else { 1 }, why),
                    ResetCheck::NotRun => (1, "not run".to_owned()),
                };
                let mut payload = vec![code];
                payload.extend_from_slice(why.as_bytes());
                let sent = write_frame(&mut out, b'V', &payload);
                if ends {
                    return 0;
                }
                sent
            }
            _ => {
                eprintln!("uq-driver worker: unexpected frame '{}'", char::from(tag));
                return 1;
            }
        };
        if sent.is_err() {
            return 1;
        }
    }
    0
}

/// The `uq-driver worker` subcommand (not available on this platform).
#[cfg(not(unix))]
pub fn serve() -> i32 {
    eprintln!("uq-driver worker: --isolate is supported on Unix only");
    1
}
