//! Completion: what may be written at a place, from the text before it (read lexically, so it
//! works in a file that does not parse while it is typed) and the names the index declares.

use super::engine::Analysis;
use super::index::{Def, Kind};
use lsp_types::{CompletionItem, CompletionItemKind, Documentation, InsertTextFormat};

/// The block a place is in, innermost last.
#[derive(Debug, Clone, PartialEq)]
enum Block {
    Skill(String),
    Learn,
    Limits,
    State,
    Task(String),
    /// A call's parentheses; the name before them.
    Call(String),
    /// A `{ }` or `[ ]` value, or a block the scan does not know.
    Other,
}

/// The completions at byte `offset` of `text`.
pub fn complete(text: &str, offset: usize, analysis: Option<&Analysis>) -> Vec<CompletionItem> {
    let mut offset = offset.min(text.len());
    while !text.is_char_boundary(offset) {
        offset -= 1;
    }
    let Some(blocks) = scan(&text[..offset]) else {
        return Vec::new(); // In a comment or a string.
    };
    let line_start = text[..offset].rfind('\n').map_or(0, |at| at + 1);
    let prefix = &text[line_start..offset];
    let word_start = prefix
        .char_indices()
        .rev()
        .take_while(|(_, c)| c.is_ascii_alphanumeric() || *c == '_')
        .last()
        .map_or(prefix.len(), |(at, _)| at);
    let before = prefix[..word_start].trim_end();
    let skill = blocks.iter().rev().find_map(|b| match b {
        Block::Skill(name) => Some(name.clone()),
        _ => None,
    });
    let task = blocks.iter().rev().find_map(|b| match b {
        Block::Task(name) => Some(name.clone()),
        _ => None,
    });
    let scope = Scope { analysis, skill };
    let innermost = blocks.last().cloned();
    let last_word = before
        .rsplit(|c: char| !(c.is_ascii_alphanumeric() || c == '_'))
        .next()
        .unwrap_or("");
    let ends_with_word = |word: &str| last_word == word && !before.ends_with(')');

    if ends_with_number(before) && !prefix[word_start..].starts_with(|c: char| c.is_ascii_digit()) {
        return units();
    }
    if let Some(task) = task {
        return in_task(&scope, &task, before, &blocks);
    }
    if before.ends_with("->") {
        let mut items = scope.names(&[Kind::State, Kind::Terminal]);
        items.push(snippet(
            "extend along",
            "extend along ${1:frame}.${2:z} at ${3:20 mm/s}, up to ${4:100 mm}, then ${5:state}",
            "move the goal on along a frame axis until a bound, then go to a state",
        ));
        return items;
    }
    if before.ends_with("force(")
        || before.ends_with("moved(")
        || before.ends_with("along:")
        || ends_with_word("in")
        || ends_with_word("along")
    {
        let mut items = scope.names(&[Kind::Frame]);
        for (name, doc) in [("base", "the robot base frame"), ("tool", "the tool frame")] {
            items.push(item(name, CompletionItemKind::STRUCT, "built-in frame", doc));
        }
        return items;
    }
    if ends_with_word("entry") || (before.trim_start().starts_with("entry ") && before.ends_with(',')) {
        return keywords(&[
            (
                "reset_integral",
                "reset_integral",
                "reset the force controller's integral",
            ),
            ("tare", "tare", "zero the force sensor at entry"),
            (
                "shift_goal",
                "shift_goal",
                "move the motion's goal by where the state starts",
            ),
        ]);
    }
    if ends_with_word("control") || (before.trim_start().starts_with("control ") && before.ends_with(',')) {
        return keywords(&[
            ("position", "position ${1:all}", "position-controlled axes"),
            ("force", "force ${1:z}", "force-controlled axes"),
        ]);
    }
    if before.trim_start().starts_with("terminal ") && before.ends_with(':') {
        return keywords(&[
            ("success", "success", "the skill succeeded"),
            ("failure", "failure \"${1:why}\"", "the skill failed, with a message"),
        ]);
    }
    if before.ends_with("entered(") {
        return scope.names(&[Kind::State]);
    }
    if ends_with_word("move") {
        return scope.names(&[Kind::Motion]);
    }
    if ends_with_word("apply") {
        return scope.names(&[Kind::Force]);
    }
    if ends_with_word("at") && before.trim_start().starts_with("move ") {
        return scope.names(&[Kind::Capture]);
    }
    match innermost {
        None if before.is_empty() => keywords(&[
            (
                "skill",
                "skill ${1:name} {\n\tlearn {\n\t\t$2\n\t}\n}",
                "a skill template",
            ),
            (
                "task",
                "task ${1:name} {\n\tstep ${2:first} = ${3:skill}(demo: \"$4\")\n}",
                "skills run in sequence",
            ),
            (
                "import",
                "import \"${1:../stdlib-skills/touch.skill}\"",
                "another file's skills",
            ),
        ]),
        Some(Block::Skill(_)) if before.is_empty() => keywords(&[
            (
                "param",
                "param ${1:name} = ${2:2 s}",
                "a value a task step or `--param` may set",
            ),
            ("learn", "learn {\n\t$1\n}", "what is learned from the demonstration"),
            (
                "limits",
                "limits {\n\t${1:force}: ${2:40 N}\n}",
                "the safety supervisor's limits",
            ),
            (
                "state",
                "state ${1:name} {\n\t$2\n}",
                "a state of the machine (the first is the initial one)",
            ),
            (
                "terminal",
                "terminal ${1:done}: ${2|success,failure|}",
                "a terminal state",
            ),
        ]),
        Some(Block::Learn) if before.is_empty() => keywords(&[
            (
                "segments",
                "segments = ${1:max_force}",
                "how the demonstration is cut into segments",
            ),
            (
                "frame",
                "frame ${1:name} = ${2:force_aligned(at: end(segment 1))}",
                "a learned frame",
            ),
            ("motion", "motion ${1:name} = dmp(segment ${2:1})", "a learned motion"),
            ("force", "force ${1:name} = ${2:dmp(segment 2)}", "a learned force"),
            (
                "threshold",
                "threshold ${1:name} = ${2:force_at(end(segment 1), along: contact.z, scale: 0.5)}",
                "a learned threshold",
            ),
            ("lowpass", "lowpass = ${1:20 Hz}", "low-pass filter the demonstration"),
            ("resample", "resample = ${1:1 kHz}", "resample the demonstration"),
        ]),
        Some(Block::Learn) if before.ends_with('=') => {
            let kind = before.split_whitespace().next().unwrap_or("");
            learn_functions(if kind == "segments" { "segments" } else { kind })
        }
        Some(Block::Call(name))
            if matches!(
                name.as_str(),
                "end" | "start" | "peak_force" | "force_aligned" | "force_at"
            ) || before.ends_with("at:") =>
        {
            let mut items = learn_functions("point");
            items.push(snippet("segment", "segment ${1:1}", "a segment, counted from 1"));
            items
        }
        Some(Block::Call(name)) if name == "cluster" && before.ends_with("cut:") => learn_functions("cut"),
        Some(Block::Limits) if before.is_empty() || before.ends_with(',') => limits(),
        Some(Block::State) if before.is_empty() => statements(),
        Some(Block::State) | Some(Block::Call(_))
            if ["on", "or", "and", "not"].iter().any(|w| ends_with_word(w)) || before.ends_with('(') =>
        {
            guards()
        }
        _ if [">=", "<=", ">", "<"].iter().any(|op| before.ends_with(op))
            || ["within", "for", "timeout", "dwell"].iter().any(|w| ends_with_word(w)) =>
        {
            scope.names(&[Kind::Threshold, Kind::Force, Kind::Param])
        }
        _ => scope.names(&[
            Kind::Param,
            Kind::Frame,
            Kind::Motion,
            Kind::Force,
            Kind::Threshold,
            Kind::State,
            Kind::Terminal,
            Kind::Capture,
        ]),
    }
}

/// Completions inside a task.
fn in_task(scope: &Scope<'_>, task: &str, before: &str, blocks: &[Block]) -> Vec<CompletionItem> {
    let Some(analysis) = scope.analysis else {
        return Vec::new();
    };
    let index = &analysis.index;
    let task_id = index.lookup(None, task, &[Kind::Task]);
    if before.is_empty() && matches!(blocks.last(), Some(Block::Task(_))) {
        return keywords(&[
            ("step", "step ${1:name} = ${2:skill}(demo: \"$3\")", "run a skill"),
            (
                "fallback",
                "fallback ${1:name} = ${2:skill}(demo: \"$3\")",
                "a step run when another fails",
            ),
        ]);
    }
    if before.ends_with("->") {
        return index
            .defs
            .iter()
            .filter(|d| d.parent == task_id && d.kind == Kind::Step && d.detail.starts_with("fallback"))
            .map(def_item)
            .collect();
    }
    if before.ends_with('=') {
        return index
            .defs
            .iter()
            .filter(|d| d.kind == Kind::Skill)
            .map(|d| {
                let mut item = def_item(d);
                item.insert_text = Some(format!("{}(demo: \"$1\")", d.name));
                item.insert_text_format = Some(InsertTextFormat::SNIPPET);
                item
            })
            .collect();
    }
    if let Some(Block::Call(skill)) = blocks.last() {
        if before.ends_with('(') || before.ends_with(',') {
            let mut items: Vec<CompletionItem> = [
                ("demo", "demo: \"$1\"", "the demonstration to learn from"),
                ("learned", "learned: \"$1\"", "a learned file to run"),
                (
                    "phase",
                    "phase: ${1:1}",
                    "learn from this contact phase of the demonstration",
                ),
                (
                    "force_scale",
                    "force_scale: ${1:1.0}",
                    "multiplies every desired force and threshold",
                ),
                ("speed", "speed: ${1:1.0}", "multiplies the motion speed"),
                (
                    "goal_offset",
                    "goal_offset: [${1:0 mm}, ${2:0 mm}, ${3:0 mm}]",
                    "added to every motion goal",
                ),
                (
                    "limits",
                    "limits: { ${1:force}: ${2:40 N} }",
                    "supervisor limits for this step",
                ),
                (
                    "at",
                    "at: ${1:step}.${2:state}",
                    "start where an earlier step entered a state",
                ),
            ]
            .iter()
            .map(|(label, text, doc)| snippet(label, text, doc))
            .collect();
            if let Some(skill) = index.lookup(None, skill, &[Kind::Skill]) {
                for def in index
                    .defs
                    .iter()
                    .filter(|d| d.parent == Some(skill) && d.kind == Kind::Param)
                {
                    let mut item = def_item(def);
                    item.insert_text = Some(format!("{}: ${{1}}", def.name));
                    item.insert_text_format = Some(InsertTextFormat::SNIPPET);
                    items.push(item);
                }
            }
            return items;
        }
    }
    if ends_with_number(before) {
        return units();
    }
    Vec::new()
}

/// The declarations of the enclosing skill.
struct Scope<'a> {
    analysis: Option<&'a Analysis>,
    skill: Option<String>,
}

impl Scope<'_> {
    fn names(&self, kinds: &[Kind]) -> Vec<CompletionItem> {
        let (Some(analysis), Some(skill)) = (self.analysis, &self.skill) else {
            return Vec::new();
        };
        let index = &analysis.index;
        let Some(skill) = index
            .defs
            .iter()
            .position(|d| d.kind == Kind::Skill && d.file == 0 && d.name == *skill)
        else {
            return Vec::new();
        };
        let mut items: Vec<CompletionItem> = Vec::new();
        for kind in kinds {
            for def in index.defs.iter().filter(|d| d.parent == Some(skill) && d.kind == *kind) {
                if !items.iter().any(|i| i.label == def.name) {
                    items.push(def_item(def));
                }
            }
        }
        items
    }
}

fn def_item(def: &Def) -> CompletionItem {
    let kind = match def.kind {
        Kind::Skill => CompletionItemKind::CLASS,
        Kind::Task => CompletionItemKind::MODULE,
        Kind::Step => CompletionItemKind::FUNCTION,
        Kind::Param => CompletionItemKind::CONSTANT,
        Kind::Frame => CompletionItemKind::STRUCT,
        Kind::Motion => CompletionItemKind::METHOD,
        Kind::Force | Kind::Threshold => CompletionItemKind::FIELD,
        Kind::State | Kind::Terminal => CompletionItemKind::ENUM_MEMBER,
        Kind::Capture => CompletionItemKind::VARIABLE,
    };
    let doc = def.doc.iter().map(|l| l.trim()).collect::<Vec<_>>().join(" ");
    item(&def.name, kind, &def.detail, &doc)
}

fn item(label: &str, kind: CompletionItemKind, detail: &str, doc: &str) -> CompletionItem {
    CompletionItem {
        label: label.to_string(),
        kind: Some(kind),
        detail: Some(detail.to_string()),
        documentation: (!doc.is_empty()).then(|| Documentation::String(doc.to_string())),
        ..CompletionItem::default()
    }
}

fn snippet(label: &str, text: &str, doc: &str) -> CompletionItem {
    CompletionItem {
        label: label.to_string(),
        kind: Some(CompletionItemKind::SNIPPET),
        detail: Some(doc.to_string()),
        insert_text: Some(text.to_string()),
        insert_text_format: Some(InsertTextFormat::SNIPPET),
        ..CompletionItem::default()
    }
}

fn keywords(list: &[(&str, &str, &str)]) -> Vec<CompletionItem> {
    list.iter()
        .map(|(label, text, doc)| {
            let mut item = snippet(label, text, doc);
            item.kind = Some(CompletionItemKind::KEYWORD);
            item
        })
        .collect()
}

fn statements() -> Vec<CompletionItem> {
    keywords(&[
        (
            "move",
            "move ${1:motion}",
            "run a learned motion from the pose at entry",
        ),
        (
            "control",
            "control ${1:position all} in ${2:frame}",
            "which axes are position- or force-controlled, in a frame",
        ),
        (
            "stiffness",
            "stiffness x y z: ${1:2000 N/m}, rx ry rz: ${2:150 Nm/rad}",
            "the impedance of position-controlled axes",
        ),
        (
            "apply",
            "apply ${1:force}",
            "the desired force of force-controlled axes",
        ),
        (
            "gains",
            "gains kp: ${1:0.5}, ki: ${2:8}, limit: ${3:10 N}",
            "the force controller's gains",
        ),
        (
            "entry",
            "entry ${1:reset_integral}",
            "actions when the state is entered",
        ),
        (
            "approach",
            "approach within ${1:10 cm} at ${2:25 mm/s}",
            "slow down near the motion's goal",
        ),
        (
            "lift off",
            "lift off ${1:1 cm} at ${2:25 mm/s}",
            "leave the contact along its normal first",
        ),
        ("repeat", "repeat ${1:4}", "run the motion N times"),
        (
            "capture",
            "capture ${1:name}",
            "keep the tool's pose at entry under a name",
        ),
        (
            "capture once",
            "capture ${1:name} once",
            "keep the tool's pose at the first entry only",
        ),
        ("on", "on ${1:motion_done} -> ${2:state}", "a transition"),
    ])
}

fn guards() -> Vec<CompletionItem> {
    keywords(&[
        ("motion_done", "motion_done", "the state's motion reached its goal"),
        (
            "force",
            "force(${1:frame}.${2:z}) >= ${3:threshold}",
            "a force along a frame axis",
        ),
        (
            "force_magnitude",
            "force_magnitude >= ${1:20 N}",
            "the applied force's length",
        ),
        (
            "moment_magnitude",
            "moment_magnitude >= ${1:2 Nm}",
            "the applied moment's length",
        ),
        (
            "force_reached",
            "force_reached within ${1:1 N}",
            "the desired force is reached",
        ),
        (
            "moved",
            "moved >= ${1:5 cm}",
            "the tool point's displacement since entry",
        ),
        (
            "moved since",
            "moved since ${1:found} >= ${2:3 mm}",
            "the tool point's distance from a captured pose",
        ),
        (
            "watch",
            "watch ${1:force_magnitude >= 30 N}",
            "a safety stop: fires, but expects no contact",
        ),
        ("speed", "speed < ${1:5 mm/s}", "the tool point's measured speed"),
        (
            "entered",
            "entered(${1:state}) >= ${2:2}",
            "how many times the run entered a state",
        ),
        ("timeout", "timeout ${1:5 s}", "time since entry (a failure path)"),
        ("dwell", "dwell ${1:200 ms}", "time since entry"),
        ("not", "not ${1:motion_done}", "the opposite of a guard"),
    ])
}

fn units() -> Vec<CompletionItem> {
    skill_compiler::units::UNITS
        .iter()
        .map(|(unit, dim, _)| item(unit, CompletionItemKind::UNIT, dim.describe(), ""))
        .collect()
}

fn limits() -> Vec<CompletionItem> {
    skill_ir::LIMITS
        .iter()
        .map(|spec| {
            let mut item = snippet(spec.name, &format!("{}: $1", spec.name), spec.what);
            item.kind = Some(CompletionItemKind::PROPERTY);
            item
        })
        .collect()
}

/// The learn functions that produce `kind`, each inserted as its example call.
fn learn_functions(kind: &str) -> Vec<CompletionItem> {
    skill_compiler::info::learn_functions()
        .into_iter()
        .filter(|f| f.kind == kind)
        .map(|f| {
            let params = f.params.join(", ");
            let example = f.example.split('`').next().unwrap_or(f.example);
            CompletionItem {
                label: f.name.to_string(),
                kind: Some(CompletionItemKind::FUNCTION),
                detail: Some(format!("{}({params})", f.name)),
                documentation: Some(Documentation::String(format!(
                    "{}. Example: `{}`",
                    f.meaning, f.example
                ))),
                insert_text: Some(example.to_string()),
                ..CompletionItem::default()
            }
        })
        .collect()
}

/// Whether text ends in a number (with spaces after it): where a unit goes.
fn ends_with_number(before: &str) -> bool {
    let trimmed = before.trim_end_matches([' ', '\t']);
    let digits = trimmed.trim_end_matches(|c: char| c.is_ascii_digit() || c == '.');
    if digits.len() == trimmed.len() {
        return false;
    }
    // Not part of a name (`segment2`) or a `segment N` reference.
    !digits.ends_with(|c: char| c.is_ascii_alphabetic() || c == '_') && !digits.trim_end().ends_with("segment")
}

/// The blocks open at the end of `text`, or `None` when it ends in a comment or a string.
fn scan(text: &str) -> Option<Vec<Block>> {
    let bytes = text.as_bytes();
    let mut blocks = Vec::new();
    let mut words: Vec<&str> = Vec::new();
    let mut at = 0;
    while at < bytes.len() {
        let byte = bytes[at];
        match byte {
            b'/' if bytes.get(at + 1) == Some(&b'/') => match text[at..].find('\n') {
                Some(end) => at += end,
                None => return None,
            },
            b'"' => {
                let mut end = at + 1;
                while end < bytes.len() && bytes[end] != b'"' && bytes[end] != b'\n' {
                    end += if bytes[end] == b'\\' { 2 } else { 1 };
                }
                if end >= bytes.len() {
                    return None;
                }
                at = end + 1;
                continue;
            }
            b'{' | b'(' | b'[' => {
                let block = match (byte, words.as_slice()) {
                    (b'{', [.., "skill", name]) => Block::Skill(name.to_string()),
                    (b'{', [.., "task", name]) => Block::Task(name.to_string()),
                    (b'{', [.., "state", _]) => Block::State,
                    (b'{', [.., "learn"]) => Block::Learn,
                    (b'{', [.., "limits"]) if !text[..at].trim_end().ends_with(':') => Block::Limits,
                    (b'(', [.., name]) if text[..at].ends_with(name) => Block::Call(name.to_string()),
                    _ => Block::Other,
                };
                blocks.push(block);
                words.clear();
            }
            b'}' | b')' | b']' => {
                blocks.pop();
                words.clear();
            }
            b'\n' => words.clear(),
            c if c.is_ascii_alphabetic() || c == b'_' => {
                let start = at;
                while at < bytes.len() && (bytes[at].is_ascii_alphanumeric() || bytes[at] == b'_') {
                    at += 1;
                }
                words.push(&text[start..at]);
                continue;
            }
            _ => {}
        }
        at += 1;
    }
    Some(blocks)
}
