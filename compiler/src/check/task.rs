//! Tasks: steps and fallbacks naming skills in scope, their inputs, overrides and limits.

use super::params::ParamSetting;
use super::{join_ticked, suggest, Checker};
use crate::ast;
use crate::diag::Code;
use crate::import::join_path;
use crate::source::Span;
use crate::units::Dim;
use skill_ir as ir;
use std::collections::HashMap;

/// The parameters one step of a task sets: the step's skill is compiled again with them.
#[derive(Debug)]
pub(crate) struct StepParams {
    /// Whether the step is a fallback.
    pub(crate) fallback: bool,
    /// The step's name.
    pub(crate) step: String,
    /// Its index among the task's steps (or fallbacks), when it lowered without error.
    pub(crate) index: Option<usize>,
    /// The skill it runs.
    pub(crate) skill: String,
    /// The values it sets.
    pub(crate) settings: Vec<ParamSetting>,
}

/// The arguments every step takes; the others name the skill's parameters.
pub(crate) const STEP_ARGS: [&str; 8] = [
    "demo",
    "learned",
    "phase",
    "force_scale",
    "speed",
    "goal_offset",
    "limits",
    "at",
];

/// What a task needs to know of a skill in scope.
#[derive(Debug, Default)]
pub(crate) struct SkillFacts<'s> {
    /// Its parameters' names.
    pub(crate) params: Vec<&'s str>,
    /// Its states' names (active and terminal).
    pub(crate) states: Vec<&'s str>,
    /// Its terminal states' names.
    pub(crate) terminals: Vec<&'s str>,
    /// Whether its first state runs a motion (`move`, not `relative`: that one starts where the
    /// tool is), whose goal `at:` places.
    pub(crate) first_moves: bool,
}

impl Checker<'_> {
    /// Checks one task against the skills in scope (with the names of their parameters) and
    /// returns its IR when it has no error, with the parameters each step sets.
    pub(crate) fn task(
        &mut self,
        task: &ast::Task,
        skills: &[&str],
        facts: &HashMap<&str, SkillFacts<'_>>,
        base_dir: &str,
    ) -> (Option<ir::Task>, Vec<StepParams>) {
        let errors_before = self.error_count();
        let mut names: HashMap<&str, (Span, bool)> = HashMap::new();
        let mut fallback_index: HashMap<&str, u32> = HashMap::new();
        for step in &task.steps {
            if let Some((earlier, _)) = names.get(step.name.name.as_str()) {
                let diag = self
                    .diag(
                        Code::DuplicateName,
                        step.name.span,
                        format!("step `{}` is declared twice", step.name.name),
                        "second declaration",
                    )
                    .label(*earlier, "first declared here")
                    .help("rename one of them");
                self.report(diag);
                continue;
            }
            names.insert(&step.name.name, (step.name.span, step.fallback));
            if step.fallback {
                let next = fallback_index.len() as u32;
                fallback_index.insert(&step.name.name, next);
            }
        }
        if !task.steps.iter().any(|step| !step.fallback) {
            let diag = self
                .diag(
                    Code::NoStates,
                    task.name.span,
                    format!("task `{}` has no step", task.name.name),
                    "nothing to run",
                )
                .help("add `step NAME = SKILL(demo: \"demo.csv\")`");
            self.report(diag);
        }
        let mut steps = Vec::new();
        let mut fallbacks = Vec::new();
        let mut step_params = Vec::new();
        for step in &task.steps {
            if !skills.contains(&step.skill.name.as_str()) {
                let help = suggest(&step.skill.name, skills.iter().copied()).unwrap_or_else(|| {
                    if skills.is_empty() {
                        "no skill is in scope: `import \"path/to/skill.skill\"`".to_string()
                    } else {
                        format!(
                            "skills in scope: {}; import others with `import \"path.skill\"`",
                            join_ticked(skills)
                        )
                    }
                });
                let diag = self
                    .diag(
                        Code::UnknownName,
                        step.skill.span,
                        format!("unknown skill `{}`", step.skill.name),
                        "no skill of this name",
                    )
                    .help(help);
                self.report(diag);
            }
            // Named arguments that name the skill's parameters set them; the rest are the step's.
            let skill_facts = facts.get(step.skill.name.as_str());
            let skill_params = skill_facts.map(|facts| &facts.params);
            let is_param = |arg: &ast::Arg| {
                arg.key.as_ref().is_some_and(|key| {
                    !STEP_ARGS.contains(&key.name.as_str())
                        && skill_params.is_some_and(|names| names.contains(&key.name.as_str()))
                })
            };
            let mut step_args: Vec<ast::Arg> = Vec::new();
            for arg in step.args.iter().filter(|arg| !is_param(arg)) {
                match &arg.key {
                    Some(key) if !STEP_ARGS.contains(&key.name.as_str()) => {
                        let mut known: Vec<&str> = STEP_ARGS.to_vec();
                        let mut declared: Vec<&str> = skill_params.into_iter().flatten().copied().collect();
                        declared.dedup();
                        known.extend(declared.iter().copied());
                        let help = suggest(&key.name, known.iter().copied()).unwrap_or_else(|| {
                            format!(
                                "a step takes {}{}",
                                join_ticked(&STEP_ARGS),
                                if declared.is_empty() {
                                    format!("; `{}` declares no parameter", step.skill.name)
                                } else {
                                    format!("; `{}`'s parameters: {}", step.skill.name, join_ticked(&declared))
                                }
                            )
                        });
                        let diag = self
                            .diag(
                                Code::BadArgument,
                                key.span,
                                format!("unknown argument `{}` of `{}`", key.name, step.skill.name),
                                "unknown argument",
                            )
                            .help(help);
                        self.report(diag);
                    }
                    _ => step_args.push(arg.clone()),
                }
            }
            // Arithmetic in a step's own arguments (`force_scale: 2 / 3`); one that does not
            // fold is reported and dropped, so that it is not reported again as ill-typed.
            step_args.retain_mut(|arg| self.fold_reporting(&mut arg.value));
            let settings: Vec<ParamSetting> = step
                .args
                .iter()
                .filter(|arg| is_param(arg))
                .filter_map(|arg| {
                    Some(ParamSetting {
                        name: arg.key.clone()?,
                        value: arg.value.clone(),
                        file: self.file,
                        source: ir::ParamSource::Step(step.name.name.clone()),
                    })
                })
                .collect();
            let bound = self.bind_args(&step.skill.name, &step_args, &STEP_ARGS, 0);
            let input = match (bound.get("demo"), bound.get("learned")) {
                (Some(demo), None) => self
                    .string(demo, "`demo`")
                    .map(|path| ir::StepInput::Demo(join_path(base_dir, &path))),
                (None, Some(learned)) => self
                    .string(learned, "`learned`")
                    .map(|path| ir::StepInput::Learned(join_path(base_dir, &path))),
                (Some(_), Some(learned)) => {
                    let diag = self
                        .diag(
                            Code::BadArgument,
                            learned.span,
                            "a step takes `demo` or `learned`, not both",
                            "second source",
                        )
                        .help("give the demonstration to learn from, or the file already learned");
                    self.report(diag);
                    None
                }
                (None, None) => {
                    let span = step.span;
                    self.missing_arg(
                        &step.skill.name,
                        "demo",
                        span,
                        &format!(
                            "{}(demo: \"demos/{}.csv\")` or `learned: \"....json\"",
                            step.skill.name, step.skill.name
                        ),
                    );
                    None
                }
            };
            // `phase: N` picks one contact phase of the demonstration; a learned file has none.
            let phase = bound.get("phase").and_then(|expr| {
                let phase = self.count(expr, "the contact phase")?;
                if bound.contains_key("learned") {
                    let diag = self
                        .diag(
                            Code::BadArgument,
                            expr.span,
                            "`phase` picks a contact phase of a demonstration; a learned file has none",
                            "with `learned`",
                        )
                        .help("learn from the recording instead: `demo: \"....csv\", phase: N`");
                    self.report(diag);
                    return None;
                }
                Some(phase)
            });
            let mut overrides = ir::Overrides::default();
            if let Some(expr) = bound.get("force_scale") {
                let value = self.plain_number(expr, "the force scale");
                if let Some(value) = self.positive(value, expr.span, "the force scale") {
                    overrides.force_scale = value;
                }
            }
            if let Some(expr) = bound.get("speed") {
                let value = self.plain_number(expr, "the speed factor");
                if let Some(value) = self.positive(value, expr.span, "the speed factor") {
                    overrides.speed_factor = value;
                }
            }
            if let Some(expr) = bound.get("goal_offset") {
                if let Some(offset) = self.vector3(expr, Dim::Length, "the goal offset") {
                    overrides.goal_offset_m = offset;
                }
            }
            let limits = bound
                .get("limits")
                .map(|expr| self.step_limits(expr))
                .unwrap_or_default();
            let at = bound
                .get("at")
                .and_then(|expr| self.anchor(expr, step, &task.steps, facts));
            let on_failure = match &step.on_failure {
                None | Some(ast::OnFailure::Abort(_)) => Some(ir::OnFailure::Abort),
                Some(ast::OnFailure::Fallback(name)) => {
                    match (fallback_index.get(name.name.as_str()), names.get(name.name.as_str())) {
                        (Some(index), _) => Some(ir::OnFailure::Fallback(*index)),
                        (None, Some((span, _))) => {
                            let diag = self
                                .diag(
                                    Code::WrongKind,
                                    name.span,
                                    format!("`{}` is a step, not a fallback", name.name),
                                    "not a fallback",
                                )
                                .label(*span, "declared as a step here")
                                .help(format!("declare it with `fallback {} = ...`", name.name));
                            self.report(diag);
                            None
                        }
                        (None, None) => {
                            let fallback_names: Vec<&str> = fallback_index.keys().copied().collect();
                            let help = suggest(&name.name, fallback_names.iter().copied()).unwrap_or_else(|| {
                                format!("declare it: `fallback {} = SKILL(demo: \"...\")`", name.name)
                            });
                            let diag = self
                                .diag(
                                    Code::UnknownName,
                                    name.span,
                                    format!("unknown fallback `{}`", name.name),
                                    "no fallback of this name",
                                )
                                .help(help);
                            self.report(diag);
                            None
                        }
                    }
                }
            };
            let mut index = None;
            if let (Some(input), Some(on_failure)) = (input, on_failure) {
                let lowered = ir::Step {
                    name: step.name.name.clone(),
                    skill: step.skill.name.clone(),
                    input,
                    overrides,
                    limits,
                    on_failure,
                    specialised: None,
                    at,
                    phase,
                    span: self.ir_span(step.span),
                };
                let list = if step.fallback { &mut fallbacks } else { &mut steps };
                index = Some(list.len());
                list.push(lowered);
            }
            if !settings.is_empty() {
                step_params.push(StepParams {
                    fallback: step.fallback,
                    step: step.name.name.clone(),
                    index,
                    skill: step.skill.name.clone(),
                    settings,
                });
            }
        }
        if self.error_count() > errors_before {
            return (None, step_params);
        }
        let lowered = ir::Task {
            name: task.name.name.clone(),
            doc: task.doc.join("\n"),
            steps,
            fallbacks,
            span: self.ir_span(task.name.span),
        };
        (Some(lowered), step_params)
    }
}

impl Checker<'_> {
    /// `at: STEP.STATE`: an earlier step of the task and a state of its skill, for a step whose
    /// skill starts with a motion.
    fn anchor(
        &mut self,
        expr: &ast::Expr,
        step: &ast::Step,
        all: &[ast::Step],
        facts: &HashMap<&str, SkillFacts<'_>>,
    ) -> Option<ir::Anchor> {
        let ast::ExprKind::Axis(reference) = &expr.kind else {
            let diag = self
                .diag(
                    Code::BadArgument,
                    expr.span,
                    "`at` takes an earlier step and a state of its skill",
                    "not `STEP.STATE`",
                )
                .help("write e.g. `at: find.settle`: where step `find` entered its state `settle`");
            self.report(diag);
            return None;
        };
        let (step_name, state_name) = (&reference.frame, &reference.axis);
        let position = all.iter().position(|s| std::ptr::eq(s, step)).unwrap_or(all.len());
        let earlier: Vec<&ast::Step> = all[..position].iter().filter(|s| !s.fallback).collect();
        let Some(found) = earlier.iter().find(|s| s.name.name == step_name.name) else {
            let names: Vec<&str> = earlier.iter().map(|s| s.name.name.as_str()).collect();
            let is_later = all.iter().any(|s| s.name.name == step_name.name);
            let help = if is_later {
                format!(
                    "`{}` runs after this step (or is a fallback): name a step that runs before it",
                    step_name.name
                )
            } else {
                suggest(&step_name.name, names.iter().copied()).unwrap_or_else(|| {
                    if names.is_empty() {
                        "the first step cannot start where another ended: there is none before it".to_string()
                    } else {
                        format!("steps before this one: {}", join_ticked(&names))
                    }
                })
            };
            let diag = self
                .diag(
                    Code::UnknownName,
                    step_name.span,
                    format!("no step `{}` runs before step `{}`", step_name.name, step.name.name),
                    "not an earlier step",
                )
                .help(help);
            self.report(diag);
            return None;
        };
        let mut ok = true;
        if let Some(found_facts) = facts.get(found.skill.name.as_str()) {
            if !found_facts.states.contains(&state_name.name.as_str()) {
                let help = suggest(&state_name.name, found_facts.states.iter().copied()).unwrap_or_else(|| {
                    format!("`{}`'s states: {}", found.skill.name, join_ticked(&found_facts.states))
                });
                let diag = self
                    .diag(
                        Code::UnknownName,
                        state_name.span,
                        format!(
                            "skill `{}` (step `{}`) has no state `{}`",
                            found.skill.name, found.name.name, state_name.name
                        ),
                        "no such state",
                    )
                    .help(help);
                self.report(diag);
                ok = false;
            } else if found_facts.terminals.contains(&state_name.name.as_str()) {
                // A terminal is entered where the step ended, not where it found anything: the
                // next step starts there anyway, and a pose found in a state before it is lost.
                let active: Vec<&str> = found_facts
                    .states
                    .iter()
                    .copied()
                    .filter(|name| !found_facts.terminals.contains(name))
                    .collect();
                let diag = self
                    .diag(
                        Code::WrongKind,
                        state_name.span,
                        format!(
                            "`{}` is a terminal state of `{}` (step `{}`): `at` takes a state the step runs",
                            state_name.name, found.skill.name, found.name.name
                        ),
                        "a terminal state",
                    )
                    .help(format!(
                        "a terminal is where step `{}` ended, where the next step starts anyway; name the state \
                         entered where the pose was found (`{}`'s active states: {})",
                        found.name.name,
                        found.skill.name,
                        join_ticked(&active)
                    ));
                self.report(diag);
                ok = false;
            }
        }
        if let Some(own) = facts.get(step.skill.name.as_str()) {
            if !own.first_moves {
                let diag = self
                    .diag(
                        Code::BadArgument,
                        expr.span,
                        format!(
                            "`{}` does not start with a motion whose goal `at` can place",
                            step.skill.name
                        ),
                        "nothing to place",
                    )
                    .help(
                        "`at` moves the goal of the first state's `move` (not a `move ... relative`, which starts \
                         where the tool is, nor a `move ... at NAME`, placed by its capture); give the first state \
                         such a `move`, or use `goal_offset`",
                    );
                self.report(diag);
                ok = false;
            }
        }
        ok.then(|| ir::Anchor {
            step: step_name.name.clone(),
            state: state_name.name.clone(),
        })
    }
}

impl<'s> SkillFacts<'s> {
    /// What a task needs to know of `skill`.
    pub(crate) fn of(skill: &'s ast::Skill) -> Self {
        let first_moves = skill
            .states
            .iter()
            .find(|state| matches!(state.body, ast::StateBody::Active(_)))
            .is_some_and(|state| match &state.body {
                ast::StateBody::Active(stmts) => stmts.iter().any(|stmt| {
                    matches!(
                        stmt.kind,
                        ast::StmtKind::Move {
                            relative: false,
                            at: None,
                            ..
                        }
                    )
                }),
                ast::StateBody::Terminal { .. } => false,
            });
        SkillFacts {
            params: skill.params.iter().map(|p| p.name.name.as_str()).collect(),
            states: skill.states.iter().map(|s| s.name.name.as_str()).collect(),
            terminals: skill
                .states
                .iter()
                .filter(|s| matches!(s.body, ast::StateBody::Terminal { .. }))
                .map(|s| s.name.name.as_str())
                .collect(),
            first_moves,
        }
    }
}
