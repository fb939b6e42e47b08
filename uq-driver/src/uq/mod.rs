//! Uncertainty-quantification numerics.
