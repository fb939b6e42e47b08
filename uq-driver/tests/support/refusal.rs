//! The check of a refusal (of a study too large, a grid too fine, ...).

use std::process::Output;

/// A refusal: exit status 1 (an error, not an abort), each of `needles` in standard error,
/// no panic. Returns standard error.
pub fn assert_refused(o: &Output, needles: &[&str]) -> String {
    let err = String::from_utf8_lossy(&o.stderr).into_owned();
    assert_eq!(o.status.code(), Some(1), "{err}");
    for n in needles {
        assert!(err.contains(n), "missing '{n}' in: {err}");
    }
    assert!(!err.contains("panicked"), "{err}");
    err
}
