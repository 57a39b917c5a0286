//! Benchmark of the whole slide template on a 10 s, 1 kHz synthetic demonstration: clustering
//! into approach / slide / retract, plane fit of the slide, constant normal force, and position
//! and quaternion DMPs of every segment.
use criterion::{criterion_group, criterion_main, Criterion};
use nalgebra::{UnitQuaternion, Vector3};
use skill_runtime::demo::Demo;
use skill_runtime::dmp::{Dmp, DmpConfig, QuatDmp};
use skill_runtime::learn::constraint::{fit_constraints, ConstraintConfig};
use skill_runtime::learn::force::{constant_normal_force, profile_along_axis, ConstantForceConfig};
use skill_runtime::learn::segment::{cluster_demo, ClusterConfig};

fn slide_demo() -> Demo {
    let mut state = 0x9e37_79b9_u64;
    let mut noise = move || {
        state = state
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        ((state >> 11) as f64 / (1u64 << 53) as f64 - 0.5) * 2.0
    };
    let n = 10_001;
    let t_s: Vec<f64> = (0..n).map(|k| k as f64 * 1e-3).collect();
    let normal_out = Vector3::new(0.1, -0.05, 1.0).normalize();
    let u = normal_out.cross(&Vector3::x()).normalize();
    let contact = Vector3::new(0.5, 0.0, 0.2);
    let mut demo = Demo {
        source: "synthetic slide".into(),
        t_s: t_s.clone(),
        position_m: Vec::with_capacity(n),
        orientation: Vec::with_capacity(n),
        force_n: Vec::with_capacity(n),
        torque_nm: vec![Vector3::zeros(); n],
    };
    for &t in &t_s {
        let smooth = |x: f64| {
            let x = x.clamp(0.0, 1.0);
            10.0 * x.powi(3) - 15.0 * x.powi(4) + 6.0 * x.powi(5)
        };
        let (p, f) = if t < 3.0 {
            (contact + normal_out * (0.15 * (1.0 - smooth(t / 3.0))), 0.0)
        } else if t < 8.0 {
            (contact + u * (0.2 * smooth((t - 3.0) / 5.0)), 12.0)
        } else {
            (contact + u * 0.2 + normal_out * (0.15 * smooth((t - 8.0) / 2.0)), 0.0)
        };
        demo.position_m.push(p + Vector3::new(noise(), noise(), noise()) * 2e-4);
        demo.orientation
            .push(UnitQuaternion::from_euler_angles(3.1, 0.05 * t, 0.3));
        demo.force_n
            .push(normal_out * f + Vector3::new(noise(), noise(), noise()) * 0.5);
    }
    demo
}

fn learn_slide(demo: &Demo) -> f64 {
    let segments = cluster_demo(
        demo,
        &ClusterConfig {
            min_segment_samples: 200,
            ..ClusterConfig::default()
        },
    )
    .expect("segments");
    let slide = segments[1].range();
    let report = fit_constraints(
        &demo.position_m[slide.clone()],
        &demo.orientation[slide.clone()],
        &demo.force_n[slide.clone()],
        &ConstraintConfig::default(),
    )
    .expect("constraint");
    let frame = report.chosen().frame;
    let profile = profile_along_axis(&demo.force_n[slide.clone()], &frame.z_axis());
    let force = constant_normal_force(&demo.t_s[slide], &profile, &ConstantForceConfig::default()).expect("force");
    let config = DmpConfig::default();
    for segment in &segments {
        let range = segment.range();
        Dmp::fit_points(&config, &demo.t_s[range.clone()], &demo.position_m[range.clone()]).expect("position dmp");
        QuatDmp::fit(&config, &demo.t_s[range.clone()], &demo.orientation[range]).expect("orientation dmp");
    }
    force.value_n
}

fn bench(c: &mut Criterion) {
    let demo = slide_demo();
    let value = learn_slide(&demo);
    assert!((value - 12.0).abs() < 0.3, "learned {value} N");
    c.bench_function("learn_slide_template_10s_1khz", |b| {
        b.iter(|| learn_slide(std::hint::black_box(&demo)))
    });
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(20);
    targets = bench
}
criterion_main!(benches);
