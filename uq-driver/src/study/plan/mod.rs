//! What is known before any run: the study resolved against its FMU (value references, the
//! input signals, the runs of `hunting_speed` quantities), the values checked against the
//! variables' declared ranges, the study's fingerprint (the hash that ties a results store to
//! its study and FMU) and its size (runs, memory, disk, time).

pub mod fingerprint;
pub mod inputs;
pub mod interface;
pub mod ranges;
pub mod resolve;
pub mod size;
