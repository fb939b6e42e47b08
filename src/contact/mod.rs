//! Wheel–rail contact geometry: the contact table a vehicle model reads (one row per wheelset
//! lateral displacement, the format of a table file, interpolation), and its computation from
//! wheel and rail profiles.
//!
//! Pure Rust, no FMI types.
#![forbid(unsafe_code)]

pub mod table;

pub use table::{ContactTable, TableError, TableRow};
