//! Study files, runner and results store.
