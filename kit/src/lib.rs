//! What skillc's commands and its eval harness share: compiling `.skill` files and loading
//! demonstrations, learned files and scenes ([`load`], [`frontend`]), writing outputs all or
//! nothing ([`atomic`]), the built-in copies of the standard files ([`defaults`]), bounds on the
//! numbers a user gives ([`limits`]), printing ([`out`], [`render`]) and plots ([`plot`],
//! [`scene_view`], [`profile`]).
//!
//! A crate of its own so that the eval harness (`skill-eval`) and the command line (`skillc`)
//! both build on it without importing each other.

pub mod atomic;
pub mod defaults;
pub mod frontend;
pub mod limits;
pub mod load;
pub mod out;
pub mod plot;
pub mod profile;
pub mod render;
pub mod scene_view;
