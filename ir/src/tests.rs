//! Tests of the serialized form: older versions read, and new fields and variants round-trip.

use crate::*;

/// A version 1 program: no limits, no approach.
fn version_1() -> serde_json::Value {
    let span = serde_json::json!({"file": "a.skill", "line": 1, "column": 1, "start": 0, "end": 1});
    serde_json::json!({
        "ir_version": 1,
        "source": "a.skill",
        "skills": [{
            "name": "s", "doc": "",
            "learn": {
                "segmentation": {"method": "none"}, "segments": 1, "lowpass_hz": null,
                "resample_hz": null, "frames": [], "motions": [], "forces": [], "thresholds": []
            },
            "initial": 0,
            "states": [{
                "id": 0, "name": "go", "doc": "",
                "kind": {
                    "kind": "active", "motion": null, "frame": {"kind": "base"},
                    "position_controlled": [true, true, true, true, true, true],
                    "stiffness": [1500.0, 1500.0, 1500.0, 150.0, 150.0, 150.0], "force": null,
                    "gains": {"kp": 0.5, "ki": 5.0, "integral_limit_n": 10.0},
                    "entry": [], "transitions": []
                },
                "span": span
            }],
            "transitions": [],
            "span": span
        }],
        "tasks": [{
            "name": "t", "doc": "",
            "steps": [{
                "name": "a", "skill": "s", "input": {"kind": "demo", "path": "d.csv"},
                "overrides": {"force_scale": 1.0, "speed_factor": 1.0, "goal_offset_m": [0.0, 0.0, 0.0]},
                "on_failure": {"policy": "abort"},
                "span": span
            }],
            "fallbacks": [],
            "span": span
        }]
    })
}

#[test]
fn a_version_1_program_reads_and_writes_back_unchanged() {
    let old = version_1();
    let program: Program = serde_json::from_value(old.clone()).expect("version 1 reads");
    let skill = &program.skills[0];
    assert!(skill.limits.is_empty());
    let StateKind::Active(active) = &skill.states[0].kind else {
        panic!("an active state")
    };
    assert_eq!(active.approach, None);
    assert_eq!(active.lift_off, None);
    assert!(program.tasks[0].steps[0].limits.is_empty());
    // Empty limits and no approach are left out, so skills that use neither serialise (and
    // hash) as before.
    assert_eq!(serde_json::to_value(&program).expect("writes"), old);
}

#[test]
fn held_guards_and_lift_offs_serialise_by_name_and_read_back() {
    let held = Guard::Held {
        guard: Box::new(Guard::ForceReached { tolerance_n: 0.5 }),
        duration_s: 0.1,
    };
    let json = serde_json::to_value(&held).expect("writes");
    assert_eq!(
        json,
        serde_json::json!({
            "kind": "held",
            "guard": {"kind": "force_reached", "tolerance_n": 0.5},
            "duration_s": 0.1
        })
    );
    assert_eq!(serde_json::from_value::<Guard>(json).expect("reads"), held);
    let lift = LiftOffSpec {
        distance_m: 0.02,
        speed_mps: 0.01,
    };
    let json = serde_json::to_value(lift).expect("writes");
    assert_eq!(json, serde_json::json!({"distance_m": 0.02, "speed_mps": 0.01}));
    assert_eq!(serde_json::from_value::<LiftOffSpec>(json).expect("reads"), lift);
}

#[test]
fn limit_names_are_unique_and_found() {
    for (index, spec) in LIMITS.iter().enumerate() {
        assert!(LIMITS[index + 1..].iter().all(|other| other.name != spec.name));
        assert_eq!(limit_spec(spec.name), Some(spec));
    }
    assert_eq!(limit_spec("forse"), None);
    let off = Limit {
        name: "force".into(),
        value_si: None,
        doc: String::new(),
        span: SourceSpan {
            file: String::new(),
            line: 1,
            column: 1,
            start: 0,
            end: 0,
        },
    };
    assert_eq!(off.value(), f64::INFINITY);
}
