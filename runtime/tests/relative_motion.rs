//! `move M relative`: a motion moved as a whole to start where its state began, against the
//! default that runs from there to the demonstrated goal. The standard touch (written out as IR,
//! tests/support) meets a table 3 cm lower than demonstrated; its return, made relative, ends
//! 3 cm lower than the demonstrated return does.

mod support;

use skill_ir as ir;
use skill_runtime::exec::{bind, simulate, ExecOptions, Mode, RunLog};
use support::{learn, Touch};

/// The measured tool point of the last tick and of the first tick of `retract`.
fn retract_ends(log: &RunLog) -> ([f64; 3], [f64; 3]) {
    let state = log.states.iter().position(|s| s == "retract").expect("the retract ran") as u32;
    let first = log
        .ticks
        .iter()
        .find(|tick| tick.state == state)
        .expect("retract ticks");
    let last = log.ticks.last().expect("ticks");
    let point = |p: &[f64; 7]| [p[0], p[1], p[2]];
    (point(&first.measured), point(&last.measured))
}

#[test]
fn a_relative_return_keeps_the_demonstrated_shape_from_where_it_starts() {
    let absolute = support::touch(Touch::default());
    let mut relative = absolute.clone();
    for state in &mut relative.states {
        if state.name == "retract" {
            match &mut state.kind {
                ir::StateKind::Active(active) => active.motion_relative = true,
                _ => panic!("retract is active"),
            }
        }
    }
    let mut lower = support::table();
    let centre_z = lower.spec().objects["table"].xyz[2];
    lower
        .set("table.z", &format!("{}", centre_z - 0.03))
        .expect("the table moves");
    let mut ends = Vec::new();
    for skill in [&absolute, &relative] {
        let learned = learn(skill);
        let bound = bind(skill, &learned).expect("binds");
        let (report, log) = simulate(&lower, Mode::Skill(&bound), &ExecOptions::default()).expect("runs");
        assert_eq!(report.outcome, ir::Outcome::Success, "{}", report.message);
        ends.push(retract_ends(&log));
    }
    let ((entry_abs, end_abs), (entry_rel, end_rel)) = (ends[0], ends[1]);
    // Both returns start on the lowered table, 3 cm below the demonstrated contact.
    assert!(
        (entry_abs[2] - entry_rel[2]).abs() < 1e-3,
        "{entry_abs:?} vs {entry_rel:?}"
    );
    // The default one ends at the demonstrated goal; the relative one 3 cm lower (within the
    // 1 mm the two contacts and the final tracking differ by).
    let drop = end_abs[2] - end_rel[2];
    assert!((drop - 0.03).abs() < 2e-3, "the relative return ends {drop} m lower");
    for axis in 0..2 {
        assert!(
            (end_abs[axis] - end_rel[axis]).abs() < 2e-3,
            "axis {axis}: {end_abs:?} vs {end_rel:?}"
        );
    }
}
