//! The wrench's frame, bias and sign settled before learning, and fitted plane normals checked
//! against the applied force (issue 11, items 2 and 3), on synthetic demonstrations whose true
//! forces, bias and surface are known.

use nalgebra::{Rotation3, Unit, UnitQuaternion, Vector3};
use skill_ir as ir;
use skill_runtime::demo::{
    prepare_wrench, BiasFinding, Demo, ForceSign, FrameStatistic, Origin, WrenchDeclaration, WrenchFrame, WrenchOptions,
};
use skill_runtime::rng::SplitMix64;
use skill_runtime::skill::{learn_skill, LearnOptions, Learned, LearnedForce};
use support::span;

mod support;

const RATE_HZ: f64 = 500.0;

/// The path of the tool while in contact.
#[derive(Clone, Copy, PartialEq)]
enum Path {
    /// One lap of an ellipse 12 cm by 8 cm: every direction of travel in the plane.
    Ellipse,
    /// 20 cm along x with a sideways bulge of 5 cm (out and back, symmetric in time).
    Sway,
    /// No sliding: the tool presses in place.
    Press,
}

/// A demonstration: still in the air, down onto the table (top at z = 0), a push of `force_n`
/// while following `path`, up again, still.
#[derive(Clone, Copy)]
struct Spec {
    /// The tool's tilt from pointing straight down \[°\].
    tilt_deg: f64,
    /// Amplitude of a slow rocking of the tool about the tilt axis (period 2.5 s) \[°\].
    rock_deg: f64,
    /// The force on the tool leans this far from the table's normal, towards +y \[°\].
    force_tilt_deg: f64,
    /// Coulomb friction against the direction of travel.
    friction: f64,
    /// The sensor's bias in its own axes \[N\].
    bias_n: [f64; 3],
    /// The axes the file's wrench is written in.
    frame: WrenchFrame,
    /// For a sensor-frame file: the sensor's axes are the flange's turned this far about z \[°\].
    turn_deg: f64,
    /// Which wrench the file stores.
    sign: ForceSign,
    path: Path,
    /// The normal force \[N\].
    force_n: f64,
}

impl Default for Spec {
    fn default() -> Self {
        Spec {
            tilt_deg: 0.0,
            rock_deg: 0.0,
            force_tilt_deg: 0.0,
            friction: 0.3,
            bias_n: [0.0; 3],
            frame: WrenchFrame::Base,
            turn_deg: 0.0,
            sign: ForceSign::OnTool,
            path: Path::Ellipse,
            force_n: 12.0,
        }
    }
}

/// A generated demonstration and the true force on the tool in the base frame per sample.
struct Generated {
    demo: Demo,
    true_force_n: Vec<Vector3<f64>>,
}

fn min_jerk(u: f64) -> f64 {
    let u = u.clamp(0.0, 1.0);
    u * u * u * (10.0 - 15.0 * u + 6.0 * u * u)
}

fn generate(spec: &Spec, seed: u64) -> Generated {
    let mut rng = SplitMix64::new(seed);
    let start = Vector3::new(0.5, 0.0, 0.05);
    let table = Vector3::new(0.5, 0.0, 0.0);
    // Phase ends [s]: still, down, force up, slide, force down, up, still.
    let ends = [0.5, 1.5, 1.7, 4.7, 4.9, 5.9, 6.4];
    let slide_s = ends[3] - ends[2];
    let path = |u: f64| -> Vector3<f64> {
        let s = min_jerk(u);
        let offset = match spec.path {
            Path::Ellipse => {
                let phase = 2.0 * std::f64::consts::PI * s;
                Vector3::new(0.06 * (phase.cos() - 1.0), 0.04 * phase.sin(), 0.0)
            }
            Path::Sway => Vector3::new(0.2 * s, 0.025 * (1.0 - (2.0 * std::f64::consts::PI * s).cos()), 0.0),
            Path::Press => Vector3::zeros(),
        };
        table + offset
    };
    let tilt_axis = Unit::new_normalize(Vector3::new(1.0, -0.5, 0.0));
    let down = UnitQuaternion::from_axis_angle(&Vector3::x_axis(), std::f64::consts::PI);
    let normal = Rotation3::from_axis_angle(&Vector3::x_axis(), -spec.force_tilt_deg.to_radians()) * Vector3::z();
    let bias = Vector3::from(spec.bias_n);
    let n = (ends[6] * RATE_HZ).round() as usize;
    let mut demo = Demo {
        source: "synthetic.csv".into(),
        t_s: Vec::new(),
        position_m: Vec::new(),
        orientation: Vec::new(),
        force_n: Vec::new(),
        torque_nm: Vec::new(),
    };
    let mut true_force_n = Vec::new();
    for k in 0..n {
        let t = k as f64 / RATE_HZ;
        let (position, normal_force, velocity) = if t < ends[0] {
            (start, 0.0, Vector3::zeros())
        } else if t < ends[1] {
            (
                start + (table - start) * min_jerk((t - ends[0]) / (ends[1] - ends[0])),
                0.0,
                Vector3::zeros(),
            )
        } else if t < ends[2] {
            (
                table,
                spec.force_n * (t - ends[1]) / (ends[2] - ends[1]),
                Vector3::zeros(),
            )
        } else if t < ends[3] {
            let u = (t - ends[2]) / slide_s;
            let h = 1e-4;
            let velocity = (path(u + h) - path(u - h)) / (2.0 * h * slide_s);
            (path(u), spec.force_n, velocity)
        } else if t < ends[4] {
            (
                path(1.0),
                spec.force_n * (ends[4] - t) / (ends[4] - ends[3]),
                Vector3::zeros(),
            )
        } else if t < ends[5] {
            let lift = start - table;
            (
                path(1.0) + lift * min_jerk((t - ends[4]) / (ends[5] - ends[4])),
                0.0,
                Vector3::zeros(),
            )
        } else {
            (path(1.0) + (start - table), 0.0, Vector3::zeros())
        };
        let angle = spec.tilt_deg + spec.rock_deg * (2.0 * std::f64::consts::PI * t / 2.5).sin();
        let orientation = UnitQuaternion::from_axis_angle(&tilt_axis, angle.to_radians()) * down;
        let speed = velocity.norm();
        let friction = if speed > 1e-3 {
            -velocity / speed * spec.friction * normal_force
        } else {
            Vector3::zeros()
        };
        let on_tool = normal * normal_force + friction;
        let noise = Vector3::new(rng.normal(), rng.normal(), rng.normal()) * 0.1;
        let signed = match spec.sign {
            ForceSign::OnTool => on_tool,
            ForceSign::Applied => -on_tool,
        };
        let (force, torque) = match spec.frame {
            WrenchFrame::Base => (signed + orientation * bias + noise, Vector3::zeros()),
            WrenchFrame::Sensor => {
                let sensor =
                    orientation * UnitQuaternion::from_axis_angle(&Vector3::z_axis(), spec.turn_deg.to_radians());
                (
                    sensor.inverse_transform_vector(&signed) + bias + noise,
                    Vector3::zeros(),
                )
            }
        };
        demo.t_s.push(t);
        demo.position_m.push(position);
        demo.orientation.push(orientation);
        demo.force_n.push(force);
        demo.torque_nm.push(torque);
        true_force_n.push(on_tool);
    }
    Generated { demo, true_force_n }
}

/// The largest distance between the settled forces and the generator's true ones \[N\].
fn worst_error(settled: &Demo, generated: &Generated) -> f64 {
    settled
        .force_n
        .iter()
        .zip(&generated.true_force_n)
        .map(|(f, truth)| (f - truth).norm())
        .fold(0.0, f64::max)
}

/// `spec`'s demonstration written in base axes is detected as base, not as a sensor frame.
fn assert_detected_as_base(spec: &Spec, seed: u64) {
    let base = Spec {
        frame: WrenchFrame::Base,
        ..*spec
    };
    let (_, report) = detect(&generate(&base, seed).demo);
    assert_eq!(report.frame.frame, WrenchFrame::Base, "{}", report.frame);
    assert_eq!(report.frame.origin, Origin::Detected, "{}", report.frame);
}

/// The slide's learning plan without its motions: three segments clustered on the force
/// magnitude, a plane fitted to the second, the constant force along its normal.
fn slide_plan() -> ir::Skill {
    ir::Skill {
        name: "slide".into(),
        doc: String::new(),
        learn: ir::LearnPlan {
            segmentation: ir::Segmentation::Cluster {
                linkage: ir::Linkage::Ward,
                temporal: ir::Temporal::Connectivity { k: 10 },
                cut: ir::Cut::Count(3),
                min_length_s: 0.2,
                features: ir::SegmentFeatures {
                    position: false,
                    force: false,
                    force_magnitude: true,
                },
            },
            segments: 3,
            lowpass_hz: None,
            resample_hz: None,
            frames: vec![ir::FrameDecl {
                name: "surface".into(),
                source: ir::FrameSource::Constraint {
                    segment: ir::SegmentIdx(1),
                    candidates: vec![ir::ConstraintModel::Planar],
                },
                span: span(),
            }],
            motions: Vec::new(),
            forces: vec![ir::ForceDecl {
                name: "push".into(),
                source: ir::ForceSource::Constant {
                    segment: ir::SegmentIdx(1),
                    along: ir::FrameAxis {
                        frame: ir::FrameRef::Learned(ir::FrameId(0)),
                        axis: ir::Axis::Z,
                    },
                },
                span: span(),
            }],
            thresholds: Vec::new(),
        },
        initial: ir::StateId(0),
        states: Vec::new(),
        transitions: Vec::new(),
        limits: Vec::new(),
        params: Vec::new(),
        span: span(),
    }
}

fn learn(demo: &Demo, options: &LearnOptions) -> Learned {
    learn_skill(&slide_plan(), demo, &[], options).expect("the synthetic slide is learnable")
}

/// The learned plane's z and the learned constant force.
fn plane_and_force(learned: &Learned) -> (Vector3<f64>, f64) {
    let z = learned.frames["surface"].at(0.0).rotation * Vector3::z();
    let LearnedForce::Constant { value_n, .. } = learned.forces["push"] else {
        panic!("`push` is a constant force");
    };
    (z, value_n)
}

fn angle_deg(a: &Vector3<f64>, b: &Vector3<f64>) -> f64 {
    (a.dot(b) / (a.norm() * b.norm())).clamp(-1.0, 1.0).acos().to_degrees()
}

fn detect(demo: &Demo) -> (Demo, skill_runtime::demo::WrenchReport) {
    prepare_wrench(demo, &WrenchOptions::default())
}

const BIAS_N: [f64; 3] = [0.8, -0.5, 1.2];

#[test]
fn a_sensor_bias_is_found_in_the_still_start_and_removed() {
    let spec = Spec {
        bias_n: BIAS_N,
        ..Spec::default()
    };
    let generated = generate(&spec, 1);
    let (settled, report) = detect(&generated.demo);
    let BiasFinding::Removed {
        force_n,
        first,
        last,
        t_s,
        ..
    } = report.bias
    else {
        panic!("a still start carries the bias: {}", report.bias);
    };
    for axis in 0..3 {
        assert!(
            (force_n[axis] - BIAS_N[axis]).abs() < 0.03,
            "bias {force_n:?}, true {BIAS_N:?}"
        );
    }
    assert_eq!(first, 0);
    // The descent starts slowly: its first 0.1 s move less than 1 cm/s.
    assert!(
        t_s[1] > 0.4 && t_s[1] < 0.65,
        "the still start lasts 0.5 s: {t_s:?} (samples ..{last})"
    );
    // What remains is the true force plus noise.
    let error: f64 = settled
        .force_n
        .iter()
        .zip(&generated.true_force_n)
        .map(|(f, truth)| (f - truth).norm())
        .sum::<f64>()
        / settled.len() as f64;
    assert!(
        error < 0.25,
        "mean error {error} N after removing the bias (noise 0.1 N per axis)"
    );

    // Learned: the bias (1.2 N along the tool, which points down) no longer shifts the force.
    let (z, removed) = plane_and_force(&learn(&generated.demo, &LearnOptions::default()));
    let kept = plane_and_force(&learn(
        &generated.demo,
        &LearnOptions {
            keep_bias: true,
            ..LearnOptions::default()
        },
    ))
    .1;
    assert!(angle_deg(&z, &-Vector3::z()) < 1.0, "plane z {z}");
    assert!(
        (removed - spec.force_n).abs() < 0.15,
        "learned {removed} N, true {} N",
        spec.force_n
    );
    assert!((kept - spec.force_n).abs() > 1.0, "with the bias kept: {kept} N");
}

#[test]
fn without_a_still_period_or_with_a_frozen_one_the_bias_is_not_removed() {
    let spec = Spec {
        bias_n: BIAS_N,
        ..Spec::default()
    };
    let generated = generate(&spec, 2);
    // Cut inside the descent and the ascent: the flange moves from the first to the last sample.
    let moving = generated.demo.slice((0.8 * RATE_HZ) as usize..(5.5 * RATE_HZ) as usize);
    let (settled, report) = detect(&moving);
    let BiasFinding::NotRemoved { reason } = &report.bias else {
        panic!("nothing is still: {}", report.bias);
    };
    assert!(reason.contains("no still, contact-free period"), "{reason}");
    assert_eq!(settled.force_n, moving.force_n, "base-frame forces are left as read");

    // A sensor that stopped streaming repeats its last value: no bias can be read from it.
    let mut frozen = generated.demo.clone();
    let still = (0.5 * RATE_HZ) as usize;
    let n = frozen.len();
    for k in (0..still).chain(n - still..n) {
        frozen.force_n[k] = Vector3::new(2.0, -1.0, -12.0);
    }
    let (_, report) = detect(&frozen);
    let BiasFinding::NotRemoved { reason } = &report.bias else {
        panic!("a frozen signal is no bias: {}", report.bias);
    };
    assert!(reason.contains("not streaming"), "{reason}");
}

#[test]
fn a_tilted_tool_sliding_with_the_wrench_in_sensor_axes_is_detected_and_rotated() {
    let spec = Spec {
        tilt_deg: 35.0,
        rock_deg: 5.0,
        bias_n: BIAS_N,
        frame: WrenchFrame::Sensor,
        ..Spec::default()
    };
    let generated = generate(&spec, 3);
    let (settled, report) = detect(&generated.demo);
    assert_eq!(report.frame.frame, WrenchFrame::Sensor, "{}", report.frame);
    assert_eq!(report.frame.origin, Origin::Detected);
    let evidence = report.frame.evidence.expect("detected from evidence");
    assert_eq!(evidence.statistic, FrameStatistic::LeanSpread);
    assert!(evidence.sensor_deg[0] < 0.5 * evidence.base_deg, "{}", report.frame);
    assert_eq!(
        (report.frame.turn_deg, report.frame.turn_origin),
        (0.0, Origin::Detected),
        "{}",
        report.frame
    );
    assert!(matches!(report.bias, BiasFinding::Removed { .. }), "{}", report.bias);
    assert_eq!(report.sign.sign, ForceSign::OnTool, "{}", report.sign);
    let worst = worst_error(&settled, &generated);
    assert!(
        worst < 0.8,
        "rotated and debiased forces are the true base-frame forces (worst {worst} N)"
    );

    let (z, force) = plane_and_force(&learn(&generated.demo, &LearnOptions::default()));
    assert!(angle_deg(&z, &-Vector3::z()) < 2.0, "plane z {z}");
    assert!((force - spec.force_n).abs() < 0.02 * spec.force_n, "learned {force} N");

    // Read as base axes, the same file puts the force 35° off: what the detection buys.
    let declared = LearnOptions {
        wrench: WrenchDeclaration {
            frame: Some(WrenchFrame::Base),
            ..WrenchDeclaration::default()
        },
        ..LearnOptions::default()
    };
    let (wrong_z, _) = plane_and_force(&learn(&generated.demo, &declared));
    let wrong = angle_deg(&wrong_z, &-Vector3::z());
    assert!(wrong > 20.0, "declared base: z {wrong_z} is {wrong}° off");

    // The same demonstration written in base axes is not taken for a sensor-frame file.
    assert_detected_as_base(&spec, 3);
}

#[test]
fn a_sensor_turned_half_a_turn_about_the_tool_axis_is_detected() {
    // x and y of the sensor point the other way than the flange's: read without the turn,
    // friction would push the tool along its motion, and the force would lean 2 × 20° off.
    let spec = Spec {
        tilt_deg: 20.0,
        rock_deg: 5.0,
        bias_n: BIAS_N,
        frame: WrenchFrame::Sensor,
        turn_deg: 180.0,
        ..Spec::default()
    };
    let generated = generate(&spec, 8);
    let (settled, report) = detect(&generated.demo);
    assert_eq!(
        (report.frame.frame, report.frame.turn_deg, report.frame.turn_origin),
        (WrenchFrame::Sensor, 180.0, Origin::Detected),
        "{}",
        report.frame
    );
    let worst = worst_error(&settled, &generated);
    assert!(worst < 0.8, "worst error {worst} N");
    let (z, force) = plane_and_force(&learn(&generated.demo, &LearnOptions::default()));
    assert!(angle_deg(&z, &-Vector3::z()) < 2.0, "plane z {z}");
    assert!((force - spec.force_n).abs() < 0.02 * spec.force_n, "learned {force} N");
    // A declared turn is used as it is (and here it is wrong).
    let declared = LearnOptions {
        wrench: WrenchDeclaration {
            frame: Some(WrenchFrame::Sensor),
            sensor_turn_deg: Some(0.0),
            ..WrenchDeclaration::default()
        },
        ..LearnOptions::default()
    };
    let learned = learn(&generated.demo, &declared);
    let frame = learned.quality.wrench.as_ref().expect("reported").frame;
    assert_eq!((frame.turn_deg, frame.turn_origin), (0.0, Origin::Declared));
    let (wrong_z, _) = plane_and_force(&learned);
    assert!(angle_deg(&wrong_z, &-Vector3::z()) > 5.0, "z {wrong_z}");
}

#[test]
fn a_tilted_tool_pressing_in_place_with_the_wrench_in_sensor_axes_is_detected_by_its_direction() {
    let spec = Spec {
        tilt_deg: 25.0,
        rock_deg: 10.0,
        friction: 0.0,
        frame: WrenchFrame::Sensor,
        path: Path::Press,
        ..Spec::default()
    };
    let (settled, report) = detect(&generate(&spec, 4).demo);
    assert_eq!(report.frame.frame, WrenchFrame::Sensor, "{}", report.frame);
    let evidence = report.frame.evidence.expect("detected from evidence");
    assert_eq!(evidence.statistic, FrameStatistic::DirectionSpread, "{}", report.frame);
    let peak = settled
        .force_n
        .iter()
        .max_by(|a, b| a.norm().total_cmp(&b.norm()))
        .expect("samples");
    assert!(
        angle_deg(peak, &Vector3::z()) < 3.0,
        "the pressing force is vertical: {peak}"
    );
    assert_detected_as_base(&spec, 4);
}

#[test]
fn an_applied_wrench_in_sensor_axes_gets_both_decisions_right() {
    let spec = Spec {
        tilt_deg: 30.0,
        rock_deg: 5.0,
        bias_n: BIAS_N,
        frame: WrenchFrame::Sensor,
        sign: ForceSign::Applied,
        ..Spec::default()
    };
    let generated = generate(&spec, 5);
    let (settled, report) = detect(&generated.demo);
    assert_eq!(
        (report.frame.frame, report.sign.sign, report.sign.origin),
        (WrenchFrame::Sensor, ForceSign::Applied, Origin::Detected),
        "{report}"
    );
    let contact = settled
        .force_n
        .iter()
        .zip(&generated.true_force_n)
        .filter(|(_, truth)| truth.norm() > 1.0);
    for (found, truth) in contact {
        assert!((found - truth).norm() < 0.8, "{found} against {truth}");
    }
    // A declaration wins over detection.
    let (_, declared) = prepare_wrench(
        &generated.demo,
        &WrenchOptions {
            declared: WrenchDeclaration {
                frame: Some(WrenchFrame::Base),
                sign: Some(ForceSign::OnTool),
                sensor_turn_deg: None,
            },
            keep_bias: false,
        },
    );
    assert_eq!(
        (declared.frame.frame, declared.frame.origin, declared.sign.sign),
        (WrenchFrame::Base, Origin::Declared, ForceSign::OnTool)
    );
}

/// Base-frame forces, known sign: only the normal check is under test.
fn declared_base() -> LearnOptions {
    LearnOptions {
        wrench: WrenchDeclaration {
            frame: Some(WrenchFrame::Base),
            sign: Some(ForceSign::OnTool),
            sensor_turn_deg: None,
        },
        ..LearnOptions::default()
    }
}

#[test]
fn a_plane_normal_40_degrees_off_the_force_is_flagged_and_replaced() {
    // Friction (µ = 0.3 against a slide mostly along x) leans the mean force further; the
    // replacement leaves it out.
    let spec = Spec {
        force_tilt_deg: 40.0,
        friction: 0.3,
        path: Path::Sway,
        ..Spec::default()
    };
    let learned = learn(&generate(&spec, 6).demo, &declared_base());
    let check = &learned.quality.normals["surface"];
    assert!(check.replaced, "{check:?}");
    assert!(check.angle_deg > 40.0 && check.angle_deg < 50.0, "{check:?}");
    assert!((check.friction - 0.3).abs() < 0.05, "{check:?}");
    assert!((check.cone_deg - 0.5f64.atan().to_degrees()).abs() < 1e-9);
    let warning = learned
        .demo
        .warnings
        .iter()
        .find(|w| w.contains("friction cone"))
        .expect("a warning names the disagreement");
    assert!(
        warning.contains("frame `surface`") && warning.contains("segment 2"),
        "{warning}"
    );
    let applied = -(Rotation3::from_axis_angle(&Vector3::x_axis(), -40f64.to_radians()) * Vector3::z());
    let (z, force) = plane_and_force(&learned);
    assert!(
        angle_deg(&z, &applied) < 3.0,
        "z {z} follows the applied force {applied}"
    );
    assert!(
        force > 0.97 * spec.force_n,
        "the force along it is the whole push: {force} N"
    );

    // A larger friction coefficient widens the cone (atan 1 = 45°) and keeps the plane.
    let learned = learn(
        &generate(&spec, 6).demo,
        &LearnOptions {
            friction_mu: Some(1.0),
            ..declared_base()
        },
    );
    assert!(!learned.quality.normals["surface"].replaced);
    let (z, _) = plane_and_force(&learned);
    assert!(angle_deg(&z, &-Vector3::z()) < 1.0, "z {z}");
}

#[test]
fn a_plane_normal_10_degrees_off_the_force_is_kept() {
    let spec = Spec {
        force_tilt_deg: 10.0,
        friction: 0.0,
        path: Path::Sway,
        ..Spec::default()
    };
    let learned = learn(&generate(&spec, 7).demo, &declared_base());
    let check = &learned.quality.normals["surface"];
    assert!(!check.replaced, "{check:?}");
    assert!((check.angle_deg - 10.0).abs() < 2.0, "{check:?}");
    assert!(!learned.demo.warnings.iter().any(|w| w.contains("friction cone")));
    let (z, force) = plane_and_force(&learned);
    assert!(angle_deg(&z, &-Vector3::z()) < 1.0, "z {z}");
    let along = spec.force_n * 10f64.to_radians().cos();
    assert!(
        (force - along).abs() < 0.02 * along,
        "{force} N, the push along the normal is {along} N"
    );
}
