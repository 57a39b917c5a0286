//! The pest grammar of `.skill` templates.
