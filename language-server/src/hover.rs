//! Hover texts (Markdown): a declaration's line and doc comment, a learn function's signature
//! and meaning from the checker's table, a unit's dimension, a limit's bound.

use super::engine::Analysis;
use super::index::{Kind, Occurrence, What};
use skill_compiler::ast;
use std::fmt::Write as _;

/// The hover text of an occurrence.
pub fn describe(analysis: &Analysis, occurrence: &Occurrence) -> Option<String> {
    let mut out = String::new();
    match &occurrence.what {
        What::Def(id) => {
            let def = &analysis.index.defs[*id];
            let _ = writeln!(out, "```skill\n{}\n```", def.detail);
            match def.kind {
                Kind::Param => {
                    let _ = writeln!(
                        out,
                        "\nA parameter: the default above, which a task step (`NAME: VALUE`) or `--param {}=VALUE` may set.",
                        def.name
                    );
                }
                Kind::Frame | Kind::Motion | Kind::Force | Kind::Threshold => {
                    let _ = writeln!(out, "\nA {} of the `learn` block.", def.kind.word());
                }
                Kind::Capture => {
                    let _ = writeln!(
                        out,
                        "\nThe tool's pose when the state is entered, for `move M at {}`.",
                        def.name
                    );
                }
                Kind::Skill => {
                    let params: Vec<String> = analysis
                        .index
                        .defs
                        .iter()
                        .filter(|d| d.parent == Some(*id) && d.kind == Kind::Param)
                        .map(|d| format!("`{}`", d.detail.trim_start_matches("param ")))
                        .collect();
                    if !params.is_empty() {
                        let _ = writeln!(out, "\nParameters: {}.", params.join(", "));
                    }
                    if def.file != 0 {
                        let _ = writeln!(out, "\nFrom `{}`.", analysis.compilation.files[def.file].name);
                    }
                }
                _ => {}
            }
            if !def.doc.is_empty() {
                let doc: Vec<&str> = def
                    .doc
                    .iter()
                    .map(|line| line.strip_prefix(' ').unwrap_or(line))
                    .collect();
                let _ = writeln!(out, "\n{}", doc.join("\n"));
            }
        }
        What::Function { name, kind } => {
            let table = skill_compiler::info::learn_functions();
            let function = table
                .iter()
                .find(|f| f.name == *name && f.kind == *kind)
                .or_else(|| table.iter().find(|f| f.name == *name))?;
            let params: Vec<String> = function
                .params
                .iter()
                .enumerate()
                .map(|(at, param)| {
                    if at < function.positional {
                        param.to_string()
                    } else {
                        format!("{param}: …")
                    }
                })
                .collect();
            let _ = writeln!(out, "```skill\n{}({})\n```", function.name, params.join(", "));
            let _ = writeln!(out, "\n{} function: {}.", capitalise(function.kind), function.meaning);
            if function.positional > 0 {
                let _ = writeln!(
                    out,
                    "\nThe first {} may be given without its name.",
                    if function.positional == 1 {
                        "parameter".to_string()
                    } else {
                        format!("{} parameters", function.positional)
                    }
                );
            }
            let _ = writeln!(out, "\nExample: `{}`", function.example);
        }
        What::Unit(unit) => match skill_compiler::units::lookup(unit) {
            Some((dim, factor)) => {
                let si = si_unit(dim);
                let _ = writeln!(out, "`{unit}`: {}", dim.describe());
                if (factor - 1.0).abs() > f64::EPSILON {
                    let _ = writeln!(out, "\n1 {unit} = {} {si}", trim_float(factor));
                }
                let units = skill_compiler::units::units_of(dim);
                let _ = writeln!(out, "\nUnits of {}: {}", dim.describe(), ticked(&units));
            }
            None => {
                let _ = writeln!(out, "`{unit}` is not a unit skillc knows");
            }
        },
        What::Limit(name) => {
            let spec = skill_ir::limit_spec(name)?;
            let _ = writeln!(out, "```skill\n{name}\n```\nSupervisor limit: {}.", spec.what);
            let _ = writeln!(out, "\nIn {} (SI); `inf` switches the check off.", spec.dim.si_unit());
            if let Some(value) = limit_value(analysis, occurrence) {
                let _ = writeln!(out, "\nBound here: `{value}`.");
            }
        }
        What::Guard(name) => {
            let meaning = match name.as_str() {
                "motion_done" => "true once the state's motion has reached its goal (with `repeat N`, after the last run); a state that runs no motion cannot use it",
                _ => return None,
            };
            let _ = writeln!(out, "```skill\n{name}\n```\nGuard: {meaning}.");
        }
        What::Keyword(word) => {
            let meaning = match *word {
                "watch" => "the guard watches for a limit (a safety stop) and expects no contact: it fires as any guard, but a force in it does not slow the state's motion as an approach to a contact would",
                "once" => "the capture is taken at the first entry only: while the name holds no pose yet; a loop's later passes keep it",
                "since" => "`moved since NAME` compares the tool point's distance from the position `capture NAME` kept, rather than from where the state was entered; a distance, not along an axis, and false while the run has not captured NAME",
                _ => return None,
            };
            let _ = writeln!(out, "```skill\n{word}\n```\n{meaning}.");
        }
        What::BuiltinFrame(name) => {
            let meaning = if name == "base" {
                "the robot base frame"
            } else {
                "the tool frame, moving with the tool"
            };
            let _ = writeln!(out, "```skill\nframe {name}\n```\nBuilt-in frame: {meaning}.");
        }
        What::Import(file) => {
            let file = (*file)?;
            let source = &analysis.compilation.files[file];
            let skills: Vec<&str> = analysis.asts[file]
                .skills
                .iter()
                .map(|s| s.name.name.as_str())
                .collect();
            let _ = writeln!(out, "`{}`", source.name);
            if !skills.is_empty() {
                let _ = writeln!(out, "\nSkills: {}", ticked(&skills));
            }
        }
        What::StepArg(name) => {
            let meaning = match name.as_str() {
                "demo" => "the demonstration to learn from (a path relative to this file)",
                "learned" => "a learned file to run instead of learning from a demonstration",
                "phase" => {
                    "learn from this contact phase of the demonstration (1, 2, ...), as `skillc learn --phase N` does"
                }
                "force_scale" => "multiplies every desired force and force threshold",
                "speed" => "multiplies the motion speed",
                "goal_offset" => "added to every motion goal, base frame",
                "limits" => "supervisor limits for this step only",
                "at" => "`STEP.STATE`: start where an earlier step entered that state",
                _ => return None,
            };
            let _ = writeln!(out, "```skill\n{name}\n```\nStep argument: {meaning}.");
        }
    }
    Some(out.trim_end().to_string())
}

/// The value written for the limit entry an occurrence names.
fn limit_value(analysis: &Analysis, occurrence: &Occurrence) -> Option<String> {
    let tree = &analysis.asts[occurrence.file];
    let source = &analysis.compilation.files[occurrence.file];
    let entry: Option<&ast::LimitEntry> = tree
        .skills
        .iter()
        .flat_map(|s| &s.limits)
        .find(|entry| entry.name.span == occurrence.span);
    if let Some(entry) = entry {
        return Some(source.slice(entry.value.span).to_string());
    }
    // A task step's `limits: { ... }`.
    tree.tasks
        .iter()
        .flat_map(|t| &t.steps)
        .flat_map(|s| &s.args)
        .filter_map(|arg| match &arg.value.kind {
            ast::ExprKind::Record(entries) => Some(entries),
            _ => None,
        })
        .flatten()
        .find(|entry| entry.key.as_ref().is_some_and(|k| k.span == occurrence.span))
        .map(|entry| source.slice(entry.value.span).to_string())
}

/// The SI unit of a dimension.
fn si_unit(dim: skill_compiler::units::Dim) -> &'static str {
    skill_compiler::units::UNITS
        .iter()
        .find(|(_, d, factor)| *d == dim && (*factor - 1.0).abs() < f64::EPSILON)
        .map_or("", |(unit, _, _)| unit)
}

fn trim_float(value: f64) -> String {
    let text = format!("{value:.6}");
    let text = text.trim_end_matches('0').trim_end_matches('.');
    text.to_string()
}

fn ticked(items: &[&str]) -> String {
    items.iter().map(|i| format!("`{i}`")).collect::<Vec<_>>().join(", ")
}

fn capitalise(word: &str) -> String {
    let mut chars = word.chars();
    match chars.next() {
        Some(first) => first.to_uppercase().chain(chars).collect(),
        None => String::new(),
    }
}
