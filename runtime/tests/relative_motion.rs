//! `move M relative`: a motion moved as a whole to start where its state began; and the default,
//! which runs from there to the demonstrated goal moved by what earlier extensions found. The
//! standard touch (written out as IR, tests/support) meets a table 3 cm lower than demonstrated
//! (its approach extends 3 cm); its return ends 3 cm lower than on the demonstrated table both
//! ways: relative, because it starts 3 cm lower; by default, because the extension's finding
//! moves its goal.

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
    let demonstrated = support::table();
    let mut lower = support::table();
    let centre_z = lower.spec().objects["table"].xyz[2];
    lower
        .set("table.z", &format!("{}", centre_z - 0.03))
        .expect("the table moves");
    let mut ends = Vec::new();
    for (skill, scene) in [(&absolute, &demonstrated), (&absolute, &lower), (&relative, &lower)] {
        let learned = learn(skill);
        let bound = bind(skill, &learned).expect("binds");
        let (report, log) = simulate(scene, Mode::Skill(&bound), &ExecOptions::default()).expect("runs");
        assert_eq!(report.outcome, ir::Outcome::Success, "{}", report.message);
        ends.push(retract_ends(&log));
    }
    let ((entry_demo, end_demo), (entry_abs, end_abs), (entry_rel, end_rel)) = (ends[0], ends[1], ends[2]);
    // Both returns on the lowered table start on it, 3 cm below the demonstrated contact.
    assert!(
        (entry_abs[2] - entry_rel[2]).abs() < 1e-3,
        "{entry_abs:?} vs {entry_rel:?}"
    );
    assert!(
        ((entry_demo[2] - entry_abs[2]) - 0.03).abs() < 2e-3,
        "{entry_demo:?} vs {entry_abs:?}"
    );
    // Both end 3 cm below the demonstrated return's end (within the 1-2 mm the contacts and the
    // final tracking differ by), the same in x and y.
    for (name, end) in [("default", end_abs), ("relative", end_rel)] {
        let drop = end_demo[2] - end[2];
        assert!((drop - 0.03).abs() < 2e-3, "the {name} return ends {drop} m lower");
        for axis in 0..2 {
            assert!(
                (end_demo[axis] - end[axis]).abs() < 2e-3,
                "{name}, axis {axis}: {end_demo:?} vs {end:?}"
            );
        }
    }
}
