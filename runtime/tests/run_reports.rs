//! Runs that report what happened (issue 25, item 3): a reflex's reported peak is the run's
//! true peak, the ticks of the damped stop included; a task step that ends in a reflex runs its
//! `on failure` step.

mod support;

use skill_ir as ir;
use skill_runtime::exec::{bind, simulate_task, ExecOptions, RunLog, TaskStep};
use support::{learn, run, span, table, Touch};

/// The largest force the log records, N.
fn logged_peak(log: &RunLog) -> f64 {
    log.ticks
        .iter()
        .map(|tick| {
            let f = &tick.wrench_base;
            (f[0] * f[0] + f[1] * f[1] + f[2] * f[2]).sqrt()
        })
        .fold(0.0, f64::max)
}

fn tight_force(value: f64) -> ExecOptions {
    let mut options = ExecOptions {
        limits: vec![("force".into(), value)],
        ..ExecOptions::default()
    };
    // Three times as fast: the tool lands at speed, so the force rises steeply at the crossing.
    options.overrides.speed_factor = 3.0;
    options
}

#[test]
fn a_reflex_reports_the_peak_of_its_damped_stop() {
    let skill = support::touch(Touch::default());
    let learned = learn(&skill);
    // The touch presses about 5 N: a 3 N limit is crossed as it lands, and the force goes on
    // rising while the arm is stopped.
    let (report, log) = run(&skill, &learned, &tight_force(3.0));
    let violation = report.reflex.as_ref().expect("the 3 N limit stops the touch");
    let peak = logged_peak(&log);
    assert!(
        peak > violation.measured,
        "the log's peak {peak:.2} N should lie beyond the crossing {:.2} N",
        violation.measured
    );
    assert!(
        report.safety.peak_force_n >= peak,
        "reported peak {:.2} N, the log reached {peak:.2} N",
        report.safety.peak_force_n
    );
}

#[test]
fn a_step_that_ends_in_a_reflex_runs_its_fallback() {
    let skill = support::touch(Touch::default());
    let learned = learn(&skill);
    let step = |name: &str, limits: Vec<ir::Limit>, on_failure| ir::Step {
        name: name.into(),
        skill: "touch".into(),
        input: ir::StepInput::Demo("touch.csv".into()),
        overrides: ir::Overrides::default(),
        limits,
        on_failure,
        specialised: None,
        at: None,
        phase: None,
        span: span(),
    };
    let tight = vec![ir::Limit {
        name: "force".into(),
        value_si: Some(3.0),
        doc: String::new(),
        span: span(),
    }];
    let find = step("find", tight, ir::OnFailure::Fallback(0));
    let back_off = step("back_off", Vec::new(), ir::OnFailure::Abort);
    let steps = [TaskStep {
        step: &find,
        bound: bind(&skill, &learned).expect("binds"),
    }];
    let fallbacks = [TaskStep {
        step: &back_off,
        bound: bind(&skill, &learned).expect("binds"),
    }];
    let run = simulate_task(&table(), &steps, &fallbacks, &ExecOptions::default()).expect("runs");
    assert_eq!(run.outcome, ir::Outcome::Failure);
    let first = &run.steps[0];
    assert!(first.report.reflex.is_some(), "{}", first.report.message);
    let names: Vec<(&str, bool)> = run.steps.iter().map(|s| (s.step.as_str(), s.fallback)).collect();
    assert_eq!(names, [("find", false), ("back_off", true)]);
    assert!(!run.steps[1].log.ticks.is_empty(), "the fallback ran no tick");
}
