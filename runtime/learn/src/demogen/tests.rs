//! Tests of the generator: determinism, the tip on the surface under force, the ground truth's
//! segments.

use nalgebra::Vector3;

use super::*;

#[test]
fn generation_is_deterministic_and_seed_dependent() {
    let a = generate(StdSkill::Slide, 5);
    let b = generate(StdSkill::Slide, 5);
    let c = generate(StdSkill::Slide, 6);
    assert_eq!(to_csv(&a), to_csv(&b));
    assert_ne!(to_csv(&a), to_csv(&c));
}

#[test]
fn the_tip_stays_on_the_surface_while_the_force_is_on() {
    for skill in StdSkill::ALL {
        let demo = generate(skill, skill.default_seed());
        let tip_offset = Vector3::from(demo.truth.tip_in_flange_m);
        for sample in &demo.samples {
            let tip = sample.position_m + sample.orientation * tip_offset;
            let normal_force = (sample.force_n - Vector3::from(demo.truth.sensor_bias_n)).norm();
            let gap = match &demo.truth.surface {
                TruthSurface::Plane { point_m, normal } => {
                    (tip - Vector3::from(*point_m)).dot(&Vector3::from(*normal)) - TIP_RADIUS_M
                }
                TruthSurface::Cylinder {
                    axis_point_m, radius_m, ..
                } => {
                    let d = tip - Vector3::from(*axis_point_m);
                    (d.x * d.x + d.z * d.z).sqrt() - radius_m - TIP_RADIUS_M
                }
            };
            assert!(
                gap > -0.0085,
                "{skill:?}: the tip goes {gap} m into the surface at {}",
                sample.t_s
            );
            if normal_force > 3.0 && skill != StdSkill::Press {
                assert!(
                    gap.abs() < 1e-3,
                    "{skill:?}: pressing {normal_force} N while {gap} m away at {}",
                    sample.t_s
                );
            }
        }
    }
}

#[test]
fn ground_truth_segments_cover_the_demonstration_in_order() {
    for skill in StdSkill::ALL {
        let demo = generate(skill, skill.default_seed());
        let segments = &demo.truth.segments;
        let expected = match skill {
            StdSkill::GuardedMove => 2,
            StdSkill::SlideThenPress => 4,
            StdSkill::DoubleTap => 5,
            _ => 3,
        };
        assert_eq!(segments.len(), expected, "{skill:?}");
        assert_eq!(segments[0].start_s, 0.0);
        for pair in segments.windows(2) {
            assert!((pair[0].end_s - pair[1].start_s).abs() < 1e-9);
        }
        let last = demo.samples.last().expect("samples").t_s;
        assert!((segments[segments.len() - 1].end_s - last).abs() < 1e-9);
    }
}
