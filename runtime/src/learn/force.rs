//! Forces (placeholder, filled in below).
