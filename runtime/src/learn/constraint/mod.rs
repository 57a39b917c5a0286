//! Constraints (placeholder, filled in below).
