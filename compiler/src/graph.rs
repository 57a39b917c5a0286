//! Renders compiled state machines as Graphviz dot or Mermaid, like the thesis's
//! state-sequencing figures: states as nodes, guards on the edges, terminals marked.

use skill_ir as ir;
use std::fmt::Write as _;

/// The output language of `skillc graph`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum GraphFormat {
    /// Graphviz dot.
    Dot,
    /// Mermaid `stateDiagram-v2`.
    Mermaid,
}

/// One edge of the drawing.
struct Edge<'a> {
    from: &'a str,
    to: &'a str,
    label: String,
}

fn edges(skill: &ir::Skill) -> Vec<Edge<'_>> {
    let name = |id: ir::StateId| skill.states[id.index()].name.as_str();
    let mut out = Vec::new();
    for transition in &skill.transitions {
        let from = name(transition.from);
        match &transition.action {
            ir::TransitionAction::Goto { target } => out.push(Edge {
                from,
                to: name(*target),
                label: transition.guard_text.clone(),
            }),
            ir::TransitionAction::Extend {
                along,
                speed_mps,
                max_m,
                then,
            } => {
                out.push(Edge {
                    from,
                    to: from,
                    label: format!(
                        "{} / extend goal along {}.{} at {} mm/s",
                        transition.guard_text,
                        frame_name(skill, along.frame),
                        along.axis.name(),
                        trim(speed_mps * 1000.0)
                    ),
                });
                out.push(Edge {
                    from,
                    to: name(*then),
                    label: format!(
                        "{} after {} mm of extension",
                        transition.guard_text,
                        trim(max_m * 1000.0)
                    ),
                });
            }
        }
    }
    out
}

fn frame_name(skill: &ir::Skill, frame: ir::FrameRef) -> &str {
    match frame {
        ir::FrameRef::Base => "base",
        ir::FrameRef::Tool => "tool",
        ir::FrameRef::Learned(id) => skill.learn.frames.get(id.index()).map_or("?", |f| f.name.as_str()),
    }
}

fn trim(value: f64) -> String {
    let text = format!("{value:.3}");
    text.trim_end_matches('0').trim_end_matches('.').to_string()
}

/// What a state controls, in one short line: `F z | P x y rx ry rz in surface`.
fn control_summary(skill: &ir::Skill, state: &ir::ActiveState) -> String {
    let pick = |position: bool| -> String {
        ir::Axis::ALL
            .iter()
            .filter(|axis| state.position_controlled[axis.index()] == position)
            .map(|axis| axis.name())
            .collect::<Vec<_>>()
            .join(" ")
    };
    let (position, force) = (pick(true), pick(false));
    let mut text = String::new();
    if !force.is_empty() {
        text.push_str(&format!("F {force}"));
    }
    if !position.is_empty() {
        if !text.is_empty() {
            text.push_str(" | ");
        }
        text.push_str(&format!("P {position}"));
    }
    text.push_str(&format!(" in {}", frame_name(skill, state.frame)));
    text
}

fn escape_dot(text: &str) -> String {
    text.replace('\\', "\\\\").replace('"', "\\\"")
}

fn mermaid_id(skill: &ir::Skill, state: &str) -> String {
    format!("{}__{}", skill.name, state)
}

fn escape_mermaid(text: &str) -> String {
    // Mermaid labels end at `:` boundaries and choke on some characters; keep them plain.
    text.replace(':', "꞉").replace('"', "'").replace(';', ",")
}

/// Renders every skill of a program (and its tasks as step chains).
pub fn render(program: &ir::Program, format: GraphFormat) -> String {
    match format {
        GraphFormat::Dot => dot(program),
        GraphFormat::Mermaid => mermaid(program),
    }
}

fn dot(program: &ir::Program) -> String {
    let mut out = String::new();
    let _ = writeln!(out, "digraph skills {{");
    let _ = writeln!(out, "    rankdir=LR;");
    let _ = writeln!(out, "    node [shape=box, style=rounded, fontname=\"Helvetica\"];");
    let _ = writeln!(out, "    edge [fontname=\"Helvetica\", fontsize=10];");
    for skill in &program.skills {
        let id = |state: &str| format!("\"{}.{}\"", skill.name, state);
        let _ = writeln!(out, "    subgraph \"cluster_{}\" {{", skill.name);
        let _ = writeln!(out, "        label=\"skill {}\";", skill.name);
        let _ = writeln!(out, "        \"{}.__start\" [shape=point, label=\"\"];", skill.name);
        for state in &skill.states {
            match &state.kind {
                ir::StateKind::Active(active) => {
                    let _ = writeln!(
                        out,
                        "        {} [label=\"{}\\n{}\"];",
                        id(&state.name),
                        escape_dot(&state.name),
                        escape_dot(&control_summary(skill, active))
                    );
                }
                ir::StateKind::Terminal { outcome, .. } => {
                    let color = match outcome {
                        ir::Outcome::Success => "darkgreen",
                        ir::Outcome::Failure => "firebrick",
                    };
                    let _ = writeln!(
                        out,
                        "        {} [label=\"{}\", shape=doublecircle, color={color}, fontcolor={color}];",
                        id(&state.name),
                        escape_dot(&state.name)
                    );
                }
            }
        }
        let initial = &skill.states[skill.initial.index()].name;
        let _ = writeln!(out, "        \"{}.__start\" -> {};", skill.name, id(initial));
        for edge in edges(skill) {
            let _ = writeln!(
                out,
                "        {} -> {} [label=\"{}\"];",
                id(edge.from),
                id(edge.to),
                escape_dot(&edge.label)
            );
        }
        let _ = writeln!(out, "    }}");
    }
    for task in &program.tasks {
        let _ = writeln!(out, "    subgraph \"cluster_task_{}\" {{", task.name);
        let _ = writeln!(out, "        label=\"task {}\";", task.name);
        for step in task.steps.iter().chain(&task.fallbacks) {
            let _ = writeln!(
                out,
                "        \"{}/{}\" [label=\"{}\\n{}\"];",
                task.name,
                step.name,
                escape_dot(&step.name),
                escape_dot(&step.skill)
            );
        }
        for pair in task.steps.windows(2) {
            let _ = writeln!(
                out,
                "        \"{}/{}\" -> \"{}/{}\" [label=\"success\"];",
                task.name, pair[0].name, task.name, pair[1].name
            );
        }
        for step in &task.steps {
            if let ir::OnFailure::Fallback(index) = step.on_failure {
                if let Some(fallback) = task.fallbacks.get(index as usize) {
                    let _ = writeln!(
                        out,
                        "        \"{}/{}\" -> \"{}/{}\" [label=\"failure\", style=dashed];",
                        task.name, step.name, task.name, fallback.name
                    );
                }
            }
        }
        let _ = writeln!(out, "    }}");
    }
    let _ = writeln!(out, "}}");
    out
}

fn mermaid(program: &ir::Program) -> String {
    let mut out = String::new();
    let _ = writeln!(out, "stateDiagram-v2");
    for skill in &program.skills {
        let _ = writeln!(out, "    state \"skill {}\" as {} {{", skill.name, skill.name);
        for state in &skill.states {
            let label = match &state.kind {
                ir::StateKind::Active(active) => format!("{}<br/>{}", state.name, control_summary(skill, active)),
                ir::StateKind::Terminal { outcome, .. } => format!(
                    "{} ({})",
                    state.name,
                    match outcome {
                        ir::Outcome::Success => "success",
                        ir::Outcome::Failure => "failure",
                    }
                ),
            };
            let _ = writeln!(
                out,
                "        state \"{}\" as {}",
                escape_mermaid(&label),
                mermaid_id(skill, &state.name)
            );
        }
        let initial = &skill.states[skill.initial.index()].name;
        let _ = writeln!(out, "        [*] --> {}", mermaid_id(skill, initial));
        for state in &skill.states {
            if matches!(state.kind, ir::StateKind::Terminal { .. }) {
                let _ = writeln!(out, "        {} --> [*]", mermaid_id(skill, &state.name));
            }
        }
        for edge in edges(skill) {
            let _ = writeln!(
                out,
                "        {} --> {} : {}",
                mermaid_id(skill, edge.from),
                mermaid_id(skill, edge.to),
                escape_mermaid(&edge.label)
            );
        }
        let _ = writeln!(out, "    }}");
    }
    for task in &program.tasks {
        let _ = writeln!(out, "    state \"task {}\" as task_{} {{", task.name, task.name);
        let step_id = |name: &str| format!("task_{}__{}", task.name, name);
        if let Some(first) = task.steps.first() {
            let _ = writeln!(out, "        [*] --> {}", step_id(&first.name));
        }
        for step in task.steps.iter().chain(&task.fallbacks) {
            let _ = writeln!(
                out,
                "        state \"{} ({})\" as {}",
                step.name,
                step.skill,
                step_id(&step.name)
            );
        }
        for pair in task.steps.windows(2) {
            let _ = writeln!(
                out,
                "        {} --> {} : success",
                step_id(&pair[0].name),
                step_id(&pair[1].name)
            );
        }
        if let Some(last) = task.steps.last() {
            let _ = writeln!(out, "        {} --> [*] : success", step_id(&last.name));
        }
        for step in &task.steps {
            if let ir::OnFailure::Fallback(index) = step.on_failure {
                if let Some(fallback) = task.fallbacks.get(index as usize) {
                    let _ = writeln!(
                        out,
                        "        {} --> {} : failure",
                        step_id(&step.name),
                        step_id(&fallback.name)
                    );
                }
            }
        }
        let _ = writeln!(out, "    }}");
    }
    out
}
