//! The pest grammar of `.skill` templates, kept in its own crate so that pest's slow derive is compiled once.
//!
//! Nothing but the parser lives here: `skill-compiler` turns the pest pairs into a spanned AST.

#![warn(missing_docs)]
// pest_derive generates an undocumented `Rule` enum.
#![allow(missing_docs, unreachable_pub)]

/// The pest parser for `.skill` files; start at [`Rule::file`].
#[derive(pest_derive::Parser)]
#[grammar = "skill.pest"]
pub struct SkillParser;
