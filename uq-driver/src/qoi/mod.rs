//! Statistics and quantities of interest.
