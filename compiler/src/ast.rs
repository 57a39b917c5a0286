//! The syntax tree of a `.skill` file: what the user wrote, every node with its byte span.
//!
//! The tree is permissive on purpose (any identifier where a frame goes, any call in a
//! learn declaration); `check` gives meaning to it and explains what is wrong.

use crate::source::Span;

/// A name as written, with where it was written.
#[derive(Debug, Clone, PartialEq)]
pub struct Ident {
    /// The identifier text.
    pub name: String,
    /// Where it was written.
    pub span: Span,
}

/// A parsed `.skill` file.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct File {
    /// `import "path"` lines, in order.
    pub imports: Vec<Import>,
    /// Skill templates, in order.
    pub skills: Vec<Skill>,
    /// Tasks, in order.
    pub tasks: Vec<Task>,
}

/// `import "../stdlib-skills/touch.skill"`.
#[derive(Debug, Clone, PartialEq)]
pub struct Import {
    /// The path as written, relative to the importing file.
    pub path: String,
    /// The span of the path string.
    pub span: Span,
}

/// `skill NAME { learn { ... } state ... terminal ... }`.
#[derive(Debug, Clone, PartialEq)]
pub struct Skill {
    /// Doc comment lines, without the `///`.
    pub doc: Vec<String>,
    /// The skill's name.
    pub name: Ident,
    /// The `param` declarations in source order.
    pub params: Vec<ParamDecl>,
    /// The `learn` blocks (one is expected; more are merged and duplicates reported).
    pub learn: Vec<LearnDecl>,
    /// The entries of the `limits` blocks, in source order (more blocks are merged).
    pub limits: Vec<LimitEntry>,
    /// States and terminals in source order.
    pub states: Vec<State>,
    /// The whole skill.
    pub span: Span,
}

/// `param hold = 2 s`: a named value the skill's body uses, settable by a task step or the
/// command line.
#[derive(Debug, Clone, PartialEq)]
pub struct ParamDecl {
    /// Doc comment lines.
    pub doc: Vec<String>,
    /// The parameter's name.
    pub name: Ident,
    /// Its default value.
    pub value: Expr,
    /// The whole declaration (after its doc comment).
    pub span: Span,
}

/// One declaration inside `learn { }`.
#[derive(Debug, Clone, PartialEq)]
pub struct LearnDecl {
    /// Doc comment lines.
    pub doc: Vec<String>,
    /// What is declared.
    pub kind: LearnKind,
    /// The declared name (`None` for `segments`, `lowpass`, `resample`).
    pub name: Option<Ident>,
    /// The right-hand side.
    pub value: Expr,
    /// `expect N` on a `segments` declaration.
    pub expect: Option<(u64, Span)>,
    /// The whole declaration.
    pub span: Span,
}

/// `force: 40 N` inside `limits { }`.
#[derive(Debug, Clone, PartialEq)]
pub struct LimitEntry {
    /// Doc comment lines.
    pub doc: Vec<String>,
    /// The limit's name as written (checked against the supervisor's table later).
    pub name: Ident,
    /// Its value.
    pub value: Expr,
    /// The whole entry.
    pub span: Span,
}

/// The keyword that starts a learn declaration.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LearnKind {
    /// `segments = ...`
    Segments,
    /// `frame NAME = ...`
    Frame,
    /// `motion NAME = ...`
    Motion,
    /// `force NAME = ...`
    Force,
    /// `threshold NAME = ...`
    Threshold,
    /// `lowpass = 20 Hz`
    Lowpass,
    /// `resample = 1000 Hz`
    Resample,
}

impl LearnKind {
    /// The keyword as written.
    pub fn keyword(self) -> &'static str {
        match self {
            LearnKind::Segments => "segments",
            LearnKind::Frame => "frame",
            LearnKind::Motion => "motion",
            LearnKind::Force => "force",
            LearnKind::Threshold => "threshold",
            LearnKind::Lowpass => "lowpass",
            LearnKind::Resample => "resample",
        }
    }
}

/// A `state` or a `terminal`.
#[derive(Debug, Clone, PartialEq)]
pub struct State {
    /// Doc comment lines.
    pub doc: Vec<String>,
    /// The state's name.
    pub name: Ident,
    /// Its body.
    pub body: StateBody,
    /// The whole state.
    pub span: Span,
}

/// What a state is.
#[derive(Debug, Clone, PartialEq)]
pub enum StateBody {
    /// `state NAME { statements }`.
    Active(Vec<Stmt>),
    /// `terminal NAME: success "message"`.
    Terminal {
        /// `success` or `failure` as written (checked later).
        outcome: Ident,
        /// An optional message for the user.
        message: Option<String>,
    },
}

/// A statement inside a state, with its doc comment.
#[derive(Debug, Clone, PartialEq)]
pub struct Stmt {
    /// Doc comment lines.
    pub doc: Vec<String>,
    /// The statement.
    pub kind: StmtKind,
    /// The whole statement.
    pub span: Span,
}

/// The statements a state may contain.
// Built once per parse and walked a few times: boxing would only add indirection.
#[allow(clippy::large_enum_variant)]
#[derive(Debug, Clone, PartialEq)]
pub enum StmtKind {
    /// `move MOTION \[from current\]`.
    Move {
        /// The motion name.
        motion: Ident,
        /// Whether `from current` was written (the default behaviour).
        from_current: bool,
        /// Whether `relative` was written: the motion moves as a whole to start at the entry
        /// pose (its goal moves by the same offset).
        relative: bool,
        /// `at NAME`: the goal is moved to the position `capture NAME` stored.
        at: Option<Ident>,
        /// `at NAME + OFFSET in FRAME`: moved on from there by `OFFSET`.
        offset: Option<AtOffset>,
    },
    /// `control force z, position x y rx ry rz in FRAME`.
    Control {
        /// The groups in order.
        groups: Vec<ControlGroup>,
        /// `in FRAME`, if given.
        frame: Option<Ident>,
    },
    /// `stiffness x y z: 2000 N/m, rx ry rz: 150 Nm/rad`.
    Stiffness(Vec<AxisValue>),
    /// `apply FORCE`.
    Apply(Ident),
    /// `gains kp: 0.3, ki: 4, limit: 10 N`.
    Gains(Vec<Arg>),
    /// `entry reset_integral, tare`.
    Entry(Vec<Expr>),
    /// `approach within 10 cm at 25 mm/s`.
    Approach {
        /// The distance from the motion's goal where the slow approach begins.
        within: Expr,
        /// The largest speed there.
        speed: Expr,
    },
    /// `lift off 2 cm at 10 mm/s`, or `lift off 0 mm`.
    LiftOff {
        /// How far to lift along the contact normal.
        distance: Expr,
        /// How fast, if written (`at V`).
        speed: Option<Expr>,
    },
    /// `repeat 4`.
    Repeat(Expr),
    /// `capture NAME`: the tool's pose at entry, kept under NAME for the rest of the run;
    /// `capture NAME once`: at the first entry only.
    Capture {
        /// The name it is kept under.
        name: Ident,
        /// `once` (where it is written): later entries keep the first capture.
        once: Option<Span>,
    },
    /// `on GUARD -> TARGET`, `on watch GUARD -> TARGET`.
    Transition {
        /// `watch` (where it is written): the guard watches for a limit and expects no contact.
        watch: Option<Span>,
        /// The guard.
        guard: Guard,
        /// Where it goes.
        target: Target,
    },
}

/// `position x y` or `force z` inside a `control` statement.
#[derive(Debug, Clone, PartialEq)]
pub struct ControlGroup {
    /// `position` or `force`.
    pub force: bool,
    /// The span of the mode keyword.
    pub mode_span: Span,
    /// The axes.
    pub axes: AxisSet,
}

/// A set of axes as written.
#[derive(Debug, Clone, PartialEq)]
pub enum AxisSet {
    /// `all`.
    All(Span),
    /// A list of axis names (validated by `check`).
    List(Vec<Ident>),
}

impl AxisSet {
    /// The span covering the whole set.
    pub fn span(&self) -> Span {
        match self {
            AxisSet::All(span) => *span,
            AxisSet::List(axes) => match (axes.first(), axes.last()) {
                (Some(first), Some(last)) => first.span.to(last.span),
                _ => Span::default(),
            },
        }
    }
}

/// `x y z: 2000 N/m` inside `stiffness`.
#[derive(Debug, Clone, PartialEq)]
pub struct AxisValue {
    /// The axes.
    pub axes: AxisSet,
    /// The value.
    pub value: Expr,
}

/// Where a transition goes.
#[allow(clippy::large_enum_variant)] // As for `StmtKind`.
#[derive(Debug, Clone, PartialEq)]
pub enum Target {
    /// `-> STATE`.
    State(Ident),
    /// `-> extend along FRAME.AXIS at SPEED, up to DISTANCE, then STATE`.
    Extend {
        /// The direction.
        axis: AxisRef,
        /// The speed of the goal.
        speed: Expr,
        /// The bound on the extension.
        max: Expr,
        /// Where to go when the bound is reached without the guard of an earlier transition firing.
        then: Ident,
        /// The whole target.
        span: Span,
    },
}

/// `FRAME.AXIS`.
#[derive(Debug, Clone, PartialEq)]
pub struct AxisRef {
    /// The frame name.
    pub frame: Ident,
    /// The axis name.
    pub axis: Ident,
    /// The whole reference.
    pub span: Span,
}

/// A transition guard.
#[derive(Debug, Clone, PartialEq)]
pub struct Guard {
    /// What the guard is.
    pub kind: GuardKind,
    /// Where it was written.
    pub span: Span,
}

/// The guard forms.
#[derive(Debug, Clone, PartialEq)]
pub enum GuardKind {
    /// `a or b or c`.
    Or(Vec<Guard>),
    /// `a and b`.
    And(Vec<Guard>),
    /// `not a`.
    Not(Box<Guard>),
    /// `a for 100 ms`: `a` has held that long without a break.
    Held {
        /// The guard that must keep holding.
        guard: Box<Guard>,
        /// How long.
        duration: Expr,
    },
    /// `force(FRAME.AXIS) OP VALUE`.
    Force {
        /// The measured axis.
        axis: AxisRef,
        /// The comparison.
        op: CmpOp,
        /// The right-hand side: a threshold or force name, or a literal.
        rhs: Expr,
    },
    /// `moved(FRAME.AXIS) OP VALUE` (the tool point's displacement along the axis since the
    /// state was entered) or, without an axis, `moved OP VALUE` (the distance).
    Moved {
        /// The axis, if written.
        axis: Option<AxisRef>,
        /// `since NAME`: measured from the pose `capture NAME` kept instead of the entry.
        since: Option<Ident>,
        /// Where the keyword `since` was written (for hover).
        since_keyword: Option<Span>,
        /// The comparison.
        op: CmpOp,
        /// The right-hand side: a length, or an angle for a rotation axis.
        rhs: Expr,
    },
    /// `force_magnitude OP VALUE` or `moment_magnitude OP VALUE`.
    Magnitude {
        /// `true` for `moment_magnitude`.
        moment: bool,
        /// The comparison.
        op: CmpOp,
        /// The right-hand side: a threshold or force name, or a literal.
        rhs: Expr,
    },
    /// `entered(STATE) OP COUNT`: how many times the run has entered a state.
    Entered {
        /// The state counted.
        state: Ident,
        /// The comparison.
        op: CmpOp,
        /// The right-hand side: a count.
        rhs: Expr,
    },
    /// `speed OP VALUE`: the tool point's measured speed.
    Speed {
        /// The comparison.
        op: CmpOp,
        /// The right-hand side: a speed.
        rhs: Expr,
    },
    /// `timeout 5 s` or `dwell 200 ms`.
    Timed {
        /// `true` for `timeout`.
        timeout: bool,
        /// The duration.
        duration: Expr,
    },
    /// `force_reached within 1 N`.
    ForceReached(Expr),
    /// A bare name: `motion_done`.
    Named(Ident),
}

/// A comparison operator.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CmpOp {
    /// `>=`
    Ge,
    /// `>`
    Gt,
    /// `<=`
    Le,
    /// `<`
    Lt,
}

impl CmpOp {
    /// The operator as written.
    pub fn as_str(self) -> &'static str {
        match self {
            CmpOp::Ge => ">=",
            CmpOp::Gt => ">",
            CmpOp::Le => "<=",
            CmpOp::Lt => "<",
        }
    }
}

/// A task: skill invocations run in sequence.
#[derive(Debug, Clone, PartialEq)]
pub struct Task {
    /// Doc comment lines.
    pub doc: Vec<String>,
    /// The task's name.
    pub name: Ident,
    /// `step` and `fallback` entries in source order.
    pub steps: Vec<Step>,
    /// The whole task.
    pub span: Span,
}

/// `step NAME = SKILL(args) [on failure abort | on failure -> FALLBACK]` or `fallback NAME = SKILL(args)`.
#[derive(Debug, Clone, PartialEq)]
pub struct Step {
    /// Doc comment lines.
    pub doc: Vec<String>,
    /// `true` for a `fallback`, which runs only when a step names it.
    pub fallback: bool,
    /// The step's name.
    pub name: Ident,
    /// The skill invoked.
    pub skill: Ident,
    /// The invocation's arguments.
    pub args: Vec<Arg>,
    /// The failure policy, if written.
    pub on_failure: Option<OnFailure>,
    /// The whole step.
    pub span: Span,
}

/// What a task does when a step fails.
#[derive(Debug, Clone, PartialEq)]
pub enum OnFailure {
    /// `on failure abort`.
    Abort(Span),
    /// `on failure -> NAME`.
    Fallback(Ident),
}

/// A call argument: `key: value` or a positional value.
#[derive(Debug, Clone, PartialEq)]
pub struct Arg {
    /// The key, for a named argument.
    pub key: Option<Ident>,
    /// The value.
    pub value: Expr,
    /// The whole argument.
    pub span: Span,
}

/// `+ [0 mm, 0 mm, 5 mm] in contact` after `move M at NAME`.
#[derive(Debug, Clone, PartialEq)]
pub struct AtOffset {
    /// The offset: three lengths.
    pub value: Expr,
    /// The frame whose axes it is given in; the base's when `None`.
    pub frame: Option<Ident>,
}

/// A value.
#[derive(Debug, Clone, PartialEq)]
pub struct Expr {
    /// What it is.
    pub kind: ExprKind,
    /// Where it was written.
    pub span: Span,
}

/// The value forms.
#[derive(Debug, Clone, PartialEq)]
pub enum ExprKind {
    /// A number with a unit: `10 mm/s`.
    Quantity {
        /// The number as written (for the formatter) and its value.
        number: Number,
        /// The unit as written.
        unit: Ident,
    },
    /// A plain number.
    Number(Number),
    /// A string literal (escapes resolved).
    Str(String),
    /// `[a, b, c]`.
    List(Vec<Expr>),
    /// `{ key: value, ... }` (a task step's `limits:`).
    Record(Vec<Arg>),
    /// `segment N` (1-based as written).
    Segment(u64),
    /// `name(args)`.
    Call {
        /// The function name.
        name: Ident,
        /// Its arguments.
        args: Vec<Arg>,
    },
    /// `frame.axis`.
    Axis(AxisRef),
    /// A bare name.
    Name(Ident),
    /// `-x`: the negation of a value.
    Neg(Box<Expr>),
    /// `a + b - c` or `a * b / c`: operators of one precedence, applied left to right. A chain
    /// is flat (not nested per operator) so that a long sum costs no depth; a sum inside a
    /// product (`(a + b) * 2`) is a chain inside a chain.
    Arith {
        /// The first operand.
        first: Box<Expr>,
        /// Each operator with the operand after it; not empty.
        rest: Vec<(BinOp, Expr)>,
    },
}

/// A binary arithmetic operator.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BinOp {
    /// `+`.
    Add,
    /// `-`.
    Sub,
    /// `*`.
    Mul,
    /// `/`.
    Div,
}

impl BinOp {
    /// The operator as written.
    pub fn symbol(self) -> &'static str {
        match self {
            BinOp::Add => "+",
            BinOp::Sub => "-",
            BinOp::Mul => "*",
            BinOp::Div => "/",
        }
    }

    /// Whether it is `+` or `-` (binding looser than `*` and `/`).
    pub fn is_additive(self) -> bool {
        matches!(self, BinOp::Add | BinOp::Sub)
    }
}

/// A number literal, kept as written so the formatter does not change `1.50` to `1.5`.
#[derive(Debug, Clone, PartialEq)]
pub struct Number {
    /// The text as written.
    pub text: String,
    /// Its value.
    pub value: f64,
}
