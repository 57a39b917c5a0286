//! End-to-end tests of the front end on holds (`for`), lift-offs and timeouts: the values they
//! take, the guards that can never fire beside them, and how graphs print them.

mod support;

use skill_compiler::Code;
use support::{codes_of, compile_with, with_state};

#[test]
fn lift_off_values_are_checked_by_dimension_and_sign() {
    let ok = with_state("control force z, position x y rx ry rz in c apply f on timeout 1 s -> e } state e { move q lift off 5 mm at 1 cm/s on motion_done -> d");
    assert_eq!(codes_of(&ok), Vec::<Code>::new());
    let lift = |stmt: &str| {
        with_state(&format!(
            "control force z, position x y rx ry rz in c apply f on timeout 1 s -> e }} state e {{ move q {stmt} on motion_done -> d"
        ))
    };
    assert_eq!(codes_of(&lift("lift off -1 cm at 10 mm/s")), [Code::OutOfRange]);
    assert_eq!(codes_of(&lift("lift off 2 cm at 0 mm/s")), [Code::OutOfRange]);
    assert_eq!(codes_of(&lift("lift off 2 cm")), [Code::BadArgument]);
    assert_eq!(codes_of(&lift("lift off 2 s at 10 mm/s")), [Code::UnitMismatch]);
    assert_eq!(codes_of(&lift("lift off 2 cm at 10 mm")), [Code::UnitMismatch]);
    assert_eq!(
        codes_of(&lift("lift off 2 cm at 10 mm/s lift off 0 mm")),
        [Code::DuplicateStatement]
    );
    // No lift, no lint: `lift off 0 mm` in a state that would not lift anyway.
    assert_eq!(
        codes_of(&with_state(
            "move q lift off 0 mm on force(c.z) >= t -> d on timeout 1 s -> d"
        )),
        Vec::<Code>::new()
    );
    // A force-controlled state never lifts off.
    assert_eq!(
        codes_of(&with_state(
            "move q control force z, position x y rx ry rz in c apply f lift off 1 cm at 5 mm/s on motion_done -> d"
        )),
        [Code::LiftOffIgnored]
    );
}

#[test]
fn hold_times_are_positive_durations_and_not_on_timed_guards() {
    let on = |guard: &str| with_state(&format!("move q on {guard} -> d on timeout 9 s -> d"));
    assert_eq!(codes_of(&on("force(c.z) < t for 100 ms")), Vec::<Code>::new());
    assert_eq!(codes_of(&on("force(c.z) < t for 0 ms")), [Code::OutOfRange]);
    assert_eq!(codes_of(&on("force(c.z) < t for 100")), [Code::MissingUnit]);
    assert_eq!(codes_of(&on("force(c.z) < t for 100 mm")), [Code::UnitMismatch]);
    assert_eq!(codes_of(&on("timeout 1 s for 500 ms")), [Code::ForOnTimedGuard]);
    assert_eq!(
        codes_of(&on("(dwell 1 s or timeout 2 s) for 500 ms")),
        [Code::ForOnTimedGuard]
    );
    // `not dwell 1 s for 50 ms` holds from 50 ms to 1 s: a meaning of its own.
    assert_eq!(codes_of(&on("not dwell 1 s for 50 ms")), Vec::<Code>::new());
    let compiled = skill_compiler::compile_str("f.skill", &on("timeout 1 s for 500 ms"));
    assert_eq!(compiled.diags[0].help.as_deref(), Some("write `timeout 1.5 s` instead"));
}

#[test]
fn a_hold_never_fires_after_an_earlier_timeout_or_beside_a_transition_on_its_guard() {
    let state = |transitions: &str| with_state(&format!("move q {transitions}"));
    assert_eq!(
        codes_of(&state("on timeout 1 s -> d on force(c.z) < t for 2 s -> d")),
        [Code::NeverFires]
    );
    assert_eq!(
        codes_of(&state(
            "on force(c.z) < t -> d on force(c.z) < t for 100 ms -> d on timeout 1 s -> d"
        )),
        [Code::NeverFires]
    );
    // The other way round the plain guard fires as soon as it holds, before it held 100 ms...
    assert_eq!(
        codes_of(&state(
            "on force(c.z) < t for 100 ms -> d on force(c.z) < t -> d on timeout 1 s -> d"
        )),
        [Code::NeverFires]
    );
    assert_eq!(
        codes_of(&state(
            "on (force(c.z) < t and motion_done) for 100 ms -> d on timeout 1 s -> d on force(c.z) < t -> d"
        )),
        [Code::NeverFires]
    );
    // ... unless it only starts a search, which keeps the state, or needs more than the held guard.
    assert_eq!(
        codes_of(&state(
            "on force(c.z) < t for 100 ms -> d on force(c.z) < t -> extend along c.z at 1 cm/s, up to 1 cm, then d on timeout 1 s -> d"
        )),
        Vec::<Code>::new()
    );
    assert_eq!(
        codes_of(&state(
            "on force(c.z) < t for 100 ms -> d on force(c.z) < t and motion_done -> d on timeout 1 s -> d"
        )),
        Vec::<Code>::new()
    );
    assert_eq!(
        codes_of(&state(
            "on force(c.z) < t for 100 ms and not force(c.z) < t -> d on timeout 1 s -> d"
        )),
        [Code::NeverFires]
    );
    assert_eq!(
        codes_of(&state("on motion_done -> d on force(c.z) >= t for 20 ms -> d")),
        Vec::<Code>::new(),
        "a held force guard still needs contact but has a way out"
    );
    assert_eq!(
        codes_of(&state("on force(c.z) >= t for 20 ms -> d")),
        [Code::ContactWaitWithoutTimeout]
    );
}

#[test]
fn graphs_print_hold_times_on_their_edges() {
    let program = skill_compiler::compile_str(
        "f.skill",
        &with_state("move q on force(c.z) < t for 100 ms -> d on timeout 1 s -> d"),
    )
    .program
    .expect("compiles");
    for format in [
        skill_compiler::graph::GraphFormat::Dot,
        skill_compiler::graph::GraphFormat::Mermaid,
    ] {
        let drawn = skill_compiler::graph::render(&program, format);
        assert!(drawn.contains("force(c.z) < t for 100 ms"), "{drawn}");
    }
}

#[test]
fn a_hold_longer_than_a_later_timeout_is_refused_also_when_a_parameter_sets_it() {
    let text = with_state("move q on force(c.z) < t for hold -> d on timeout 4 s -> d")
        .replace("skill s {", "skill s { param hold = 2 s");
    let compile = |params: &[&str]| compile_with(&text, params);
    assert_eq!(compile(&[]).diags, Vec::new());
    let refused = compile(&["hold=5s"]);
    assert_eq!(
        refused.diags.iter().map(|d| d.code).collect::<Vec<_>>(),
        [Code::NeverFires]
    );
    assert!(refused.program.is_none());
    // Written the other way round, the hold after the timeout, it was refused already.
    assert_eq!(
        codes_of(&with_state("move q on force(c.z) < t for 5 s -> d on timeout 4 s -> d")),
        [Code::NeverFires]
    );
    assert_eq!(
        codes_of(&with_state("move q on force(c.z) < t for 4 s -> d on timeout 4 s -> d")),
        Vec::<Code>::new(),
        "a hold as long as the timeout fires if the force held from the entry"
    );
    // An `extend` before the timeout keeps the state, so the timeout may not come first.
    assert_eq!(
        codes_of(&with_state(
            "move q on force(c.z) < t for 5 s -> d on motion_done -> extend along c.z at 1 cm/s, up to 1 cm, then d on timeout 4 s -> d"
        )),
        Vec::<Code>::new()
    );
}

#[test]
fn a_zero_timeout_warns_only_where_a_motion_or_force_would_be_cut() {
    assert_eq!(
        codes_of(&with_state("move q on motion_done -> d on timeout 0 s -> d")),
        [Code::EndsOnEntry]
    );
    assert_eq!(
        codes_of(&with_state("move q on motion_done or dwell 0 ms -> d")),
        [Code::EndsOnEntry]
    );
    // A pass-through state, and a search started at once, are meant.
    let pass_through = codes_of(&with_state("capture here on dwell 0 s -> d"));
    assert!(
        !pass_through.is_empty() && !pass_through.contains(&Code::EndsOnEntry),
        "{pass_through:?}"
    );
    assert_eq!(
        codes_of(&with_state(
            "move q on force(c.z) >= t -> d on dwell 0 s -> extend along c.z at 1 cm/s, up to 1 cm, then d on timeout 5 s -> d"
        )),
        Vec::<Code>::new()
    );
}
