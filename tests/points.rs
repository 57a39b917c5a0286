//! `peak_force(segment N)` (issue 12, item 4): the sample of largest force within one segment,
//! as a point for `force_at` (a force or a threshold) and `force_aligned` (a frame). On the
//! shipped slide-then-press demonstration (ground truth: slide 5 N, press 15 N peak) the slide's
//! peak lies between the slide's force and the press's, and the whole demonstration's is the
//! press's.

use std::path::PathBuf;

use skill_runtime::skill::LearnOptions;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

#[test]
fn the_peak_within_a_segment_is_the_slides_and_the_peak_overall_the_press() {
    let Ok((_, skill)) = skill_kit::load::load_skill(&root().join("tests/data/peak_points.skill"), None) else {
        panic!("the skill compiles")
    };
    let demo = root().join("examples/demos/slide_then_press.csv");
    let Ok(learned) = skill_kit::load::learn_from_files(&skill, &demo, &LearnOptions::default()) else {
        panic!("learns")
    };
    let slide = learned.forces["slide_peak"].value_n().expect("a constant force");
    let press = learned.forces["press_peak"].value_n().expect("a constant force");
    let threshold = learned.thresholds["half_slide_peak"].value;
    eprintln!("slide peak {slide:.2} N, press peak {press:.2} N, threshold {threshold:.2} N");
    // The slide is pressed at 5 N; the learned slide segment ends 0.2 s after the true boundary,
    // in the press's rise, so its peak is that of the rise's first 0.2 s (9.1 N measured): above
    // the slide's force, well below the press's.
    assert!(
        slide > 5.0 && slide < press - 3.0,
        "slide peak {slide} N, press peak {press} N"
    );
    assert!((14.0..17.0).contains(&press), "press peak {press} N");
    assert!((threshold - 0.5 * slide).abs() < 1e-9, "threshold {threshold} N");
}
