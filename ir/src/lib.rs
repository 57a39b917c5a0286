//! The serde state-machine IR shared by the compiler and the runtime.
