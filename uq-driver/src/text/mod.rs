//! Text the other modules share, at the bottom of the library (it uses none of them): CSV
//! fields and numbers, and the file names derived from variable names.

#![forbid(unsafe_code)]

pub mod csv;
pub mod file_name;
