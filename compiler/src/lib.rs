//! Parse, check and lower `.skill` templates to the IR.
