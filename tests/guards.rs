//! The displacement and magnitude guards in simulation (issue 12): a press whose click is the
//! cap's travel (`moved(contact.z) >= 6 mm`) clicks on the shipped button and fails on a jammed
//! one, and a touch whose contact guard is `force_magnitude` meets a tilted table where the
//! force along the demonstrated normal alone stays below its threshold; and an `extend` in a
//! state without `move` searches (it moves the held pose). The skills are in `tests/data/`; they
//! learn from the shipped press and touch demonstrations.

use std::path::PathBuf;

use skill_runtime::exec::{bind, simulate, ExecOptions, Mode, RunLog, RunReport};
use skill_runtime::skill::{LearnOptions, Learned};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn learn(file: &str, demo: &str) -> (skill_ir::Skill, Learned) {
    let Ok((_, ir)) = skill_kit::load::load_skill(&root().join(file), None) else {
        panic!("{file} compiles")
    };
    let demo = root().join(format!("examples/demos/{demo}.csv"));
    let Ok(learned) = skill_kit::load::learn_from_files(&ir, &demo, &LearnOptions::default()) else {
        panic!("{file} learns from {}", demo.display())
    };
    (ir, learned)
}

fn run(skill: &skill_ir::Skill, learned: &Learned, scene: &str, sets: &[&str]) -> (RunReport, RunLog) {
    let sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
    let Ok(scene) = skill_kit::load::load_scene(&root().join("examples/scenes").join(scene), &sets) else {
        panic!("scene loads")
    };
    let bound = bind(skill, learned).expect("binds");
    simulate(&scene, Mode::Skill(&bound), &ExecOptions::default()).expect("runs")
}

/// The ticks of the first visit of `state`.
fn ticks_in<'l>(log: &'l RunLog, state: &str) -> Vec<&'l skill_runtime::exec::Tick> {
    let index = log
        .states
        .iter()
        .position(|name| name == state)
        .expect("the state is logged") as u32;
    log.ticks
        .iter()
        .skip_while(|tick| tick.state != index)
        .take_while(|tick| tick.state == index)
        .collect()
}

/// The tool point's travel along the compliant z between the first and the last tick of `state`.
fn travel_along_z(log: &RunLog, state: &str) -> f64 {
    let ticks = ticks_in(log, state);
    let (first, last) = (ticks.first().expect("ticks"), ticks.last().expect("ticks"));
    (0..3)
        .map(|axis| (last.measured[axis] - first.measured[axis]) * last.frame_z()[axis])
        .sum()
}

#[test]
fn a_click_guard_on_the_caps_travel_clicks_on_the_button_and_not_on_a_jammed_one() {
    let (skill, learned) = learn("tests/data/press_click.skill", "press");
    let (report, log) = run(&skill, &learned, "button.toml", &[]);
    assert_eq!(report.outcome, skill_ir::Outcome::Success, "{}", report.message);
    let travel = travel_along_z(&log, "press");
    eprintln!(
        "shipped button: clicked after {:.2} mm in {:.2} s",
        travel * 1e3,
        ticks_in(&log, "press").len() as f64 * 1e-3
    );
    // The guard fires at the tick the tool has moved 6 mm (the first logged tick of the state is
    // the one after its entry, so a little less is measured here).
    assert!((0.0059..0.0065).contains(&travel), "travel {travel} m");

    // The same cap with 0.5 mm of travel: it stops on its lower stop and never clicks.
    let (report, log) = run(&skill, &learned, "button.toml", &["button.travel=0.0005"]);
    assert_eq!(report.outcome, skill_ir::Outcome::Failure);
    assert_eq!(report.terminal.as_deref(), Some("jammed"), "{}", report.message);
    let travel = travel_along_z(&log, "press");
    eprintln!("jammed button: {:.2} mm, then {}", travel * 1e3, report.message);
    assert!(travel < 0.002, "travel {travel} m");
}

#[test]
fn a_force_magnitude_guard_fires_on_a_tilted_table_before_the_normal_component_would() {
    let (skill, learned) = learn("tests/data/touch_any_direction.skill", "touch");
    let touch = learned.thresholds.get("touch").expect("the touch threshold").value;
    // The table narrowed to 10 cm, 3 cm lower (so that its tilted top stays below the tool's
    // start) and tilted 50° about y: its normal is 50° from the demonstrated one.
    let sets = [
        "table.size=[0.1, 0.8, 0.05]",
        "table.xyz=[0.55, 0.0, 0.245]",
        "table.rpy=[0.0, 0.8726646, 0.0]",
    ];
    let (report, log) = run(&skill, &learned, "table.toml", &sets);
    assert!(
        report.visits.iter().any(|visit| visit.state == "settle"),
        "the approach ends on contact: {}",
        report.message
    );
    // Over the whole approach the force along the contact z stayed below the threshold: a
    // `force(contact.z) >= touch` guard would not have fired yet.
    let approach = ticks_in(&log, "approach");
    let most_along_z = approach.iter().map(|tick| tick.wrench_cf[2]).fold(f64::MIN, f64::max);
    let magnitude = |tick: &skill_runtime::exec::Tick| tick.wrench_base[..3].iter().map(|f| f * f).sum::<f64>().sqrt();
    let first_settle = ticks_in(&log, "settle")[0];
    let ended_s = approach.last().expect("ticks").t_s;
    eprintln!(
        "tilted table, force_magnitude: contact at {ended_s:.2} s, |F| {:.2} N, at most {most_along_z:.2} N along the contact z (threshold {touch:.2} N); {}",
        magnitude(first_settle),
        report.message
    );
    assert!(most_along_z < touch, "the z component reached {most_along_z} N");
    assert_eq!(report.outcome, skill_ir::Outcome::Success, "{}", report.message);

    // The standard touch on the same table waits for the z component: it meets the table later
    // and harder.
    let (standard, standard_learned) = learn("stdlib-skills/touch.skill", "touch");
    let (_, log) = run(&standard, &standard_learned, "table.toml", &sets);
    let approach = ticks_in(&log, "approach");
    let peak = approach.iter().map(|tick| magnitude(tick)).fold(0.0, f64::max);
    let standard_ended_s = approach.last().expect("ticks").t_s;
    eprintln!(
        "tilted table, force(contact.z): contact at {standard_ended_s:.2} s, |F| up to {peak:.2} N in the approach"
    );
    assert!(standard_ended_s > ended_s);
}

#[test]
fn an_extend_in_a_state_without_move_moves_the_held_pose_until_contact() {
    let (skill, learned) = learn("tests/data/touch_search_without_move.skill", "touch");
    // The table 5 cm lower than demonstrated: the approach ends in free space, the search finds it.
    let (report, log) = run(&skill, &learned, "table.toml", &["table.z=0.225"]);
    assert_eq!(report.outcome, skill_ir::Outcome::Success, "{}", report.message);
    let search = ticks_in(&log, "search");
    let (first, last) = (search.first().expect("ticks"), search.last().expect("ticks"));
    let down_m = first.measured[2] - last.measured[2];
    eprintln!(
        "search without move: {:.1} mm down in {:.2} s",
        down_m * 1e3,
        last.t_s - first.t_s
    );
    assert!(down_m > 0.03, "moved {down_m} m down");
    assert!(report.visits.iter().any(|visit| visit.state == "settle"));
}

#[test]
fn a_speed_guard_fires_at_the_first_tick_past_its_speed() {
    let (skill, learned) = learn("tests/data/touch_speed_guard.skill", "touch");
    let (report, log) = run(&skill, &learned, "table.toml", &[]);
    assert_eq!(report.terminal.as_deref(), Some("too_fast"), "{}", report.message);
    let ticks = ticks_in(&log, "approach");
    // The tool point's speed from its logged positions (1 ms apart).
    let speeds: Vec<f64> = ticks
        .windows(2)
        .map(|pair| {
            let d: f64 = (0..3)
                .map(|i| (pair[1].measured[i] - pair[0].measured[i]).powi(2))
                .sum();
            d.sqrt() / (pair[1].t_s - pair[0].t_s)
        })
        .collect();
    let (last, before) = speeds.split_last().expect("the approach ran");
    let fastest_before = before.iter().copied().fold(0.0, f64::max);
    eprintln!(
        "speed guard: fired at {:.1} mm/s after {:.3} s, fastest before {:.1} mm/s",
        last * 1e3,
        ticks.len() as f64 * 1e-3,
        fastest_before * 1e3
    );
    // The guard reads the controller's twist, the positions differ by one tick's integration.
    assert!(*last > 0.0078, "fired at {last} m/s");
    assert!(fastest_before < 0.0081, "already {fastest_before} m/s before");
}

#[test]
fn a_group_of_states_repeats_as_often_as_an_entered_guard_says() {
    for taps in [3u32, 4] {
        let setting = [format!("taps={taps}")];
        let Ok((_, skill)) = skill_kit::load::load_skill_with(&root().join("tests/data/taps.skill"), None, &setting)
        else {
            panic!("taps.skill compiles")
        };
        let demo = root().join("examples/demos/double_tap.csv");
        let Ok(learned) = skill_kit::load::learn_from_files(&skill, &demo, &LearnOptions::default()) else {
            panic!("learns from the double tap")
        };
        let (report, _) = run(&skill, &learned, "table.toml", &[]);
        assert_eq!(report.outcome, skill_ir::Outcome::Success, "{}", report.message);
        let tapped = report.visits.iter().filter(|visit| visit.state == "tap").count();
        let spots: Vec<[f64; 3]> = report
            .visits
            .iter()
            .filter(|visit| visit.state == "tap")
            .map(|visit| visit.enter_position_m)
            .collect();
        eprintln!("taps={taps}: tapped {tapped} times at {spots:?}");
        assert_eq!(tapped, taps as usize);
        // Each tap is a hop away from the last, on the surface.
        for pair in spots.windows(2) {
            let hop: f64 = (0..3).map(|i| (pair[1][i] - pair[0][i]).powi(2)).sum::<f64>().sqrt();
            assert!(hop > 0.02, "hop of {hop} m");
        }
    }
}

#[test]
fn what_an_extension_found_moves_the_goals_of_later_motions() {
    let (skill, learned) = learn("tests/data/touch_absolute_return.skill", "touch");
    let end_z = |sets: &[&str]| {
        let (report, log) = run(&skill, &learned, "table.toml", sets);
        assert_eq!(report.outcome, skill_ir::Outcome::Success, "{}", report.message);
        let last = log.ticks.last().expect("ticks");
        // The approach's extension: the contact's height below the demonstrated goal.
        let settle = ticks_in(&log, "settle");
        (last.measured[2], settle.first().expect("settled").measured[2])
    };
    let (end_demo, contact_demo) = end_z(&[]);
    let (end_lower, contact_lower) = end_z(&["table.z=0.225"]);
    let found = contact_demo - contact_lower;
    eprintln!(
        "table 5 cm lower: contact {:.1} mm lower, return ends {:.1} mm lower",
        found * 1e3,
        (end_demo - end_lower) * 1e3
    );
    assert!((found - 0.05).abs() < 0.005, "found {found} m");
    assert!(
        ((end_demo - end_lower) - found).abs() < 0.003,
        "ends {} m lower",
        end_demo - end_lower
    );
}
