//! railuq
