//! Benchmarks of DMPs: fitting a 3-D DMP with 50 bases to 10 000 samples, rolling it out for
//! 10 000 steps, and the same for the quaternion DMP.
use criterion::{criterion_group, criterion_main, Criterion};
use nalgebra::{UnitQuaternion, Vector3};
use skill_runtime::dmp::{Dmp, DmpConfig, QuatDmp, Regression};

fn demo(n: usize) -> (Vec<f64>, Vec<Vector3<f64>>, Vec<UnitQuaternion<f64>>) {
    let t: Vec<f64> = (0..n).map(|k| k as f64 * 1e-3).collect();
    let tau = t[n - 1];
    let p = t
        .iter()
        .map(|&t| {
            let u = t / tau;
            let s = 10.0 * u.powi(3) - 15.0 * u.powi(4) + 6.0 * u.powi(5);
            Vector3::new(
                0.4 + 0.3 * s,
                -0.1 + 0.2 * s + 0.03 * (3.0 * std::f64::consts::PI * u).sin().powi(2),
                0.3 - 0.15 * s,
            )
        })
        .collect();
    let q = t
        .iter()
        .map(|&t| UnitQuaternion::from_euler_angles(0.3 * t / tau, -0.2 * t / tau, t / tau))
        .collect();
    (t, p, q)
}

fn bench(c: &mut Criterion) {
    let (t, p, q) = demo(10_000);
    let ridge = DmpConfig::default();
    let lwr = DmpConfig {
        regression: Regression::Lwr,
        ..DmpConfig::default()
    };
    c.bench_function("dmp_fit_3d_ridge_50_bases_10000", |b| {
        b.iter(|| Dmp::fit_points(&ridge, std::hint::black_box(&t), &p).expect("valid"))
    });
    c.bench_function("dmp_fit_3d_lwr_50_bases_10000", |b| {
        b.iter(|| Dmp::fit_points(&lwr, std::hint::black_box(&t), &p).expect("valid"))
    });
    let dmp = Dmp::fit_points(&ridge, &t, &p).expect("valid");
    let dt = dmp.tau_s / 10_000.0;
    c.bench_function("dmp_rollout_3d_10000_steps", |b| {
        b.iter(|| {
            let mut rollout = dmp.rollout();
            for _ in 0..10_000 {
                rollout.step(&dmp, dt);
            }
            std::hint::black_box(rollout.position()[0])
        })
    });
    c.bench_function("quat_dmp_fit_50_bases_10000", |b| {
        b.iter(|| QuatDmp::fit(&ridge, std::hint::black_box(&t), &q).expect("valid"))
    });
    let qdmp = QuatDmp::fit(&ridge, &t, &q).expect("valid");
    c.bench_function("quat_dmp_rollout_10000_steps", |b| {
        b.iter(|| {
            let mut rollout = qdmp.rollout();
            for _ in 0..10_000 {
                rollout.step(&qdmp, dt);
            }
            std::hint::black_box(rollout.orientation())
        })
    });
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(30);
    targets = bench
}
criterion_main!(benches);
