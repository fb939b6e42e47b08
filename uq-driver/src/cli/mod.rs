//! The `uq-driver` command line: arguments, and the commands that are more than a call into
//! the library.

pub(crate) mod args;
pub(crate) mod cluster;
pub(crate) mod load;
pub(crate) mod print;
pub(crate) mod tools;
