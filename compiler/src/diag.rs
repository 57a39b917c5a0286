//! Diagnostics as data: every problem the front end can report, with its code, spans and help.
//!
//! STYLE.md suggests one `thiserror` + `miette::Diagnostic` enum per phase. We keep the
//! codes in one registry ([`Code`]) and the problems in one plain struct ([`Diag`]) instead:
//! the JSON output for editors, the miette rendering for people, and the corpus test that
//! demands one example file per code all read the same table, so a new code cannot be added
//! without its message shape, severity and corpus file.

use crate::source::{SourceFile, Span};
use std::fmt;

/// How bad a diagnostic is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum Severity {
    /// Legal but suspicious; `--deny-warnings` turns it into an error.
    Warning,
    /// The file does not compile.
    Error,
}

impl Severity {
    /// `"error"` or `"warning"`.
    pub fn as_str(self) -> &'static str {
        match self {
            Severity::Warning => "warning",
            Severity::Error => "error",
        }
    }
}

macro_rules! codes {
    ($($(#[doc = $doc:literal])* $variant:ident => $code:literal, $severity:ident;)*) => {
        /// Every diagnostic code. The doc comment on each says when it fires and shows a
        /// minimal `.skill` fragment that triggers it; `compiler/tests/corpus/err/` holds one
        /// file per code.
        #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
        #[non_exhaustive]
        pub enum Code {
            $($(#[doc = $doc])* $variant,)*
        }

        impl Code {
            /// All codes, in declaration order.
            pub const ALL: &'static [Code] = &[$(Code::$variant,)*];

            /// The code as shown to users: `skill::check::unknown_name`.
            pub fn as_str(self) -> &'static str {
                match self { $(Code::$variant => $code,)* }
            }

            /// The severity this code always has.
            pub fn severity(self) -> Severity {
                match self { $(Code::$variant => Severity::$severity,)* }
            }
        }
    };
}

codes! {
    /// The file is not valid UTF-8 (for example a binary file).
    InvalidUtf8 => "skill::syntax::invalid_utf8", Error;
    /// The file is larger than a template can reasonably be (see [`crate::MAX_SOURCE_BYTES`]).
    FileTooLarge => "skill::syntax::file_too_large", Error;
    /// Brackets, braces and `not`s nested deeper than [`crate::MAX_NESTING`]: `[[[[[[...`,
    /// `on not not not ... motion_done`.
    TooDeep => "skill::syntax::too_deep", Error;
    /// A character the grammar cannot take outside strings and comments, named by code point
    /// and what it looks like: a no-break space in `on\u{a0}motion_done`, a Cyrillic `а`; or a
    /// NUL anywhere.
    UnexpectedCharacter => "skill::syntax::unexpected_character", Error;
    /// The text does not follow the grammar: `skill { }` (a name is missing).
    Unexpected => "skill::syntax::unexpected", Error;
    /// A name declared twice in one scope: two `state approach` in a skill.
    DuplicateName => "skill::check::duplicate_name", Error;
    /// A name that is not declared: `move aproach` when the motion is `approach`.
    UnknownName => "skill::check::unknown_name", Error;
    /// A name of the wrong kind: `move contact` where `contact` is a frame, not a motion.
    WrongKind => "skill::check::wrong_kind", Error;
    /// An unknown learning function: `frame f = plan(segment 2)`.
    UnknownFunction => "skill::check::unknown_function", Error;
    /// A missing, unknown or ill-typed argument: `dmp(basis: 50)` with no segment.
    BadArgument => "skill::check::bad_argument", Error;
    /// A unit skillc does not know: `10 lbs`.
    UnknownUnit => "skill::check::unknown_unit", Error;
    /// A quantity of the wrong dimension: `timeout 5 mm`.
    UnitMismatch => "skill::check::unit_mismatch", Error;
    /// A physical value written without a unit: `timeout 5`.
    MissingUnit => "skill::check::missing_unit", Error;
    /// Arithmetic that has no value: a product or quotient of two quantities (`2 mm * 3 mm`), a
    /// division by zero, or arithmetic on a name that is not a parameter (`2 * contact`).
    BadArithmetic => "skill::check::bad_arithmetic", Error;
    /// A value outside its valid range: `dmp(segment 1, basis: 0)`.
    OutOfRange => "skill::check::out_of_range", Error;
    /// A segment beyond what the segmentation yields: `segment 3` with `segments = max_force`.
    SegmentOutOfRange => "skill::check::segment_out_of_range", Error;
    /// Segments are referenced but their count is not known: `changepoint(...)` without `expect N`.
    SegmentCountUnknown => "skill::check::segment_count_unknown", Error;
    /// `expect N` disagrees with what the method yields: `segments = max_force expect 3`.
    ExpectMismatch => "skill::check::expect_mismatch", Error;
    /// A statement that may appear once appears twice: two `move` in a state.
    DuplicateStatement => "skill::check::duplicate_statement", Error;
    /// Not an axis: `control position x y w`.
    UnknownAxis => "skill::check::unknown_axis", Error;
    /// An axis named twice in one `control` or `stiffness`: `control position x x y z rx ry rz`.
    RepeatedAxis => "skill::check::repeated_axis", Error;
    /// A `control` that leaves axes unassigned: `control position x y z`.
    MissingAxis => "skill::check::missing_axis", Error;
    /// Force-controlled axes with no `apply`: `control force z, position x y rx ry rz` alone.
    MissingForceSource => "skill::check::missing_force_source", Error;
    /// A zero or negative stiffness: `stiffness x: 0 N/m`.
    NonPositiveStiffness => "skill::check::non_positive_stiffness", Error;
    /// A negative force gain or integral limit: `gains kp: -1`.
    NegativeGain => "skill::check::negative_gain", Error;
    /// An unknown guard: `on motion_dne -> next`.
    UnknownGuard => "skill::check::unknown_guard", Error;
    /// A terminal whose outcome is neither `success` nor `failure`.
    UnknownOutcome => "skill::check::unknown_outcome", Error;
    /// A skill with no state to run.
    NoStates => "skill::check::no_states", Error;
    /// A state no transition leads to from the initial state.
    UnreachableState => "skill::check::unreachable_state", Error;
    /// A state from which no terminal state can be reached.
    NoTerminalPath => "skill::check::no_terminal_path", Error;
    /// A non-terminal state with no outgoing transition: it would run forever.
    DeadEnd => "skill::check::dead_end", Error;
    /// A transition whose guard can never be true when it is evaluated.
    NeverFires => "skill::check::never_fires", Error;
    /// A transition whose guard repeats an earlier one in the same state.
    DuplicateGuard => "skill::check::duplicate_guard", Error;
    /// Files that import each other.
    ImportCycle => "skill::check::import_cycle", Error;
    /// An imported file that cannot be read.
    MissingImport => "skill::check::missing_import", Error;
    /// A limit the safety supervisor does not have: `limits { forse: 40 N }`.
    UnknownLimit => "skill::check::unknown_limit", Error;
    /// A limit set twice in one skill's `limits` or one step's `limits:`:
    /// `limits { force: 40 N  force: 50 N }`.
    DuplicateLimit => "skill::check::duplicate_limit", Error;
    /// A zero or negative limit: `limits { speed: 0 mm/s }` (`inf` switches a check off).
    NonPositiveLimit => "skill::check::non_positive_limit", Error;
    /// `approach within 5 cm at 10 mm/s` in a state without `move`: there is no motion to slow.
    ApproachWithoutMove => "skill::check::approach_without_move", Error;
    /// `lift off 2 cm at 10 mm/s` in a state without `move`: only a state that leaves a contact
    /// on a learned path lifts off.
    LiftOffWithoutMove => "skill::check::lift_off_without_move", Error;
    /// `repeat 3` in a state without `move`: there is no motion to repeat.
    RepeatWithoutMove => "skill::check::repeat_without_move", Error;
    /// `for` on a guard that only counts time since entry: `on dwell 100 ms for 50 ms -> next`
    /// (that is `dwell 150 ms`).
    ForOnTimedGuard => "skill::check::for_on_timed_guard", Error;
    /// `move back at found` when no state of the skill has `capture found`.
    UnknownCapture => "skill::check::unknown_capture", Error;
    /// `move back relative at found`: `relative` starts the motion's shape at the entry pose,
    /// `at` ends it at a captured pose; a move takes one of them.
    RelativeAndAt => "skill::check::relative_and_at", Error;
    /// A force-controlled axis whose PI integral has no limit: it can wind up.
    NoIntegralLimit => "skill::lint::no_integral_limit", Warning;
    /// A state that only waits for contact, with no timeout, motion or dwell to leave it.
    ContactWaitWithoutTimeout => "skill::lint::contact_wait_without_timeout", Warning;
    /// A learned feature that no state uses.
    Unused => "skill::lint::unused", Warning;
    /// `apply` in a state with no force-controlled axis: the force is ignored.
    ForceWithoutForceAxes => "skill::lint::force_without_force_axes", Warning;
    /// `approach within 5 cm at 10 mm/s` in a state no force guard leaves: it slows down for
    /// a contact nothing waits for.
    ApproachWithoutForceGuard => "skill::lint::approach_without_force_guard", Warning;
    /// `extend along base.z`: a search along an axis the checker knows points up (the base's z,
    /// or a literal frame's axis more than 30° above the horizontal) moves the goal away from a
    /// surface below.
    ExtendUpwards => "skill::lint::extend_upwards", Warning;
    /// `frame table = fixed(origin: [0 m, 0 m, 5 cm])`: a literal frame whose origin lies within
    /// 10 cm of the robot base (origins are in the base frame, metres), or that gives none.
    FrameAtBase => "skill::lint::frame_at_base", Warning;
    /// `lift off 2 cm at 10 mm/s` in a state that never lifts off: one that force-controls an
    /// axis, or approaches a contact (`approach`, or a force guard).
    LiftOffIgnored => "skill::lint::lift_off_ignored", Warning;
    /// `capture found` that no `move ... at found` uses.
    UnusedCapture => "skill::lint::unused_capture", Warning;
    /// `move back at found` (or a guard `moved since found ...`) in a state the run can reach from
    /// the initial state without passing through a state with `capture found`: the run fails
    /// there if it does (the guard is false there).
    AtBeforeCapture => "skill::lint::at_before_capture", Warning;
    /// `on timeout 0 s -> next` (or `dwell 0 s`, alone or in an `or`) in a state that moves or
    /// force-controls an axis: the state is left at its entry, before its motion or force runs.
    EndsOnEntry => "skill::lint::ends_on_entry", Warning;
    /// `// allow(NAME): REASON` that names no lint, names an error, gives no reason, or silences
    /// nothing on its line (or, alone on a line, the next line with code).
    UnusedAllow => "skill::lint::unused_allow", Warning;
}

impl fmt::Display for Code {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}

/// A labelled span in a diagnostic.
#[derive(Debug, Clone, PartialEq)]
pub struct Label {
    /// Where.
    pub span: Span,
    /// What to say there (in the user's terms).
    pub text: String,
}

/// One problem found in one file.
#[derive(Debug, Clone, PartialEq)]
pub struct Diag {
    /// The code, which fixes the severity.
    pub code: Code,
    /// Index of the file in the [`crate::Compilation`]'s file table.
    pub file: usize,
    /// The message: lowercase, no trailing period, names items in backticks.
    pub message: String,
    /// The primary label first, then related ones (such as an earlier declaration).
    pub labels: Vec<Label>,
    /// A concrete fix, when one exists.
    pub help: Option<String>,
}

impl Diag {
    /// A diagnostic with a primary label.
    pub fn new(code: Code, file: usize, span: Span, message: impl Into<String>, label: impl Into<String>) -> Self {
        Diag {
            code,
            file,
            message: message.into(),
            labels: vec![Label {
                span,
                text: label.into(),
            }],
            help: None,
        }
    }

    /// Adds a help line.
    pub fn help(mut self, help: impl Into<String>) -> Self {
        self.help = Some(help.into());
        self
    }

    /// Adds a help line when there is one.
    pub fn maybe_help(mut self, help: Option<String>) -> Self {
        self.help = help;
        self
    }

    /// Adds a secondary label.
    pub fn label(mut self, span: Span, text: impl Into<String>) -> Self {
        self.labels.push(Label {
            span,
            text: text.into(),
        });
        self
    }

    /// The severity of its code.
    pub fn severity(&self) -> Severity {
        self.code.severity()
    }

    /// The primary span.
    pub fn span(&self) -> Span {
        self.labels.first().map(|label| label.span).unwrap_or_default()
    }

    /// Pairs the diagnostic with its source so that miette can render it.
    pub fn with_source<'a>(&'a self, source: &'a SourceFile) -> Rendered<'a> {
        Rendered {
            diag: self,
            source: CharColumns {
                name: source.name.clone(),
                text: source.text.clone(),
            },
        }
    }
}

/// A file's text for miette, with columns counted in characters: miette's own count is in
/// bytes, which put `skillc check`'s `file:line:column` six columns right of the JSON output's
/// (and the editor's) on a line with `é`, `µ`, `°` and an emoji before the problem.
#[derive(Debug)]
struct CharColumns {
    name: String,
    text: std::sync::Arc<str>,
}

impl miette::SourceCode for CharColumns {
    fn read_span<'a>(
        &'a self,
        span: &miette::SourceSpan,
        context_lines_before: usize,
        context_lines_after: usize,
    ) -> Result<Box<dyn miette::SpanContents<'a> + 'a>, miette::MietteError> {
        let contents = self.text.read_span(span, context_lines_before, context_lines_after)?;
        let start = contents.span().offset();
        let line_start = self.text[..start].rfind('\n').map_or(0, |n| n + 1);
        let column = self.text[line_start..start].chars().count();
        Ok(Box::new(miette::MietteSpanContents::new_named(
            self.name.clone(),
            contents.data(),
            *contents.span(),
            contents.line(),
            column,
            contents.line_count(),
        )))
    }
}

/// A diagnostic with its source text, implementing [`miette::Diagnostic`].
#[derive(Debug)]
pub struct Rendered<'a> {
    diag: &'a Diag,
    source: CharColumns,
}

impl fmt::Display for Rendered<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.diag.message)
    }
}

impl std::error::Error for Rendered<'_> {}

impl miette::Diagnostic for Rendered<'_> {
    fn code<'a>(&'a self) -> Option<Box<dyn fmt::Display + 'a>> {
        Some(Box::new(self.diag.code.as_str()))
    }

    fn severity(&self) -> Option<miette::Severity> {
        Some(match self.diag.severity() {
            Severity::Error => miette::Severity::Error,
            Severity::Warning => miette::Severity::Warning,
        })
    }

    fn help<'a>(&'a self) -> Option<Box<dyn fmt::Display + 'a>> {
        self.diag
            .help
            .as_ref()
            .map(|help| Box::new(help) as Box<dyn fmt::Display>)
    }

    fn source_code(&self) -> Option<&dyn miette::SourceCode> {
        Some(&self.source)
    }

    fn labels(&self) -> Option<Box<dyn Iterator<Item = miette::LabeledSpan> + '_>> {
        Some(Box::new(self.diag.labels.iter().enumerate().map(|(at, label)| {
            let text = (!label.text.is_empty()).then(|| label.text.clone());
            if at == 0 {
                miette::LabeledSpan::new_primary_with_span(text, label.span)
            } else {
                miette::LabeledSpan::new_with_span(text, label.span)
            }
        })))
    }
}

/// The closest candidate to `name` by edit distance, if it is close enough to be a likely typo.
pub fn did_you_mean<'a>(name: &str, candidates: impl IntoIterator<Item = &'a str>) -> Option<&'a str> {
    let limit = (name.chars().count() / 3).max(1);
    candidates
        .into_iter()
        .filter(|candidate| *candidate != name)
        .map(|candidate| (edit_distance(name, candidate), candidate))
        .filter(|(distance, _)| *distance <= limit)
        .min_by_key(|(distance, _)| *distance)
        .map(|(_, candidate)| candidate)
}

/// Levenshtein distance over characters.
fn edit_distance(a: &str, b: &str) -> usize {
    let b: Vec<char> = b.chars().collect();
    let mut row: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.chars().enumerate() {
        let mut diagonal = row[0];
        row[0] = i + 1;
        for (j, cb) in b.iter().enumerate() {
            let substitution = diagonal + usize::from(ca != *cb);
            diagonal = row[j + 1];
            row[j + 1] = substitution.min(row[j] + 1).min(row[j + 1] + 1);
        }
    }
    row[b.len()]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn did_you_mean_finds_close_names_only() {
        let names = ["approach", "retract", "press"];
        assert_eq!(did_you_mean("aproach", names), Some("approach"));
        assert_eq!(did_you_mean("pres", names), Some("press"));
        assert_eq!(did_you_mean("zzz", names), None);
    }

    #[test]
    fn every_code_is_namespaced_and_unique() {
        let mut seen = std::collections::HashSet::new();
        for code in Code::ALL {
            assert!(code.as_str().starts_with("skill::"), "{code}");
            assert!(seen.insert(code.as_str()), "duplicate code {code}");
        }
    }
}
