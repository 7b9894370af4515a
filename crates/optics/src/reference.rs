//! Slow reference (to be written)
