//! Benchmarks of segmentation: connectivity clustering (10 000 and 50 000 samples), the
//! time-feature variant and CHAMP change points, on a synthetic slide-like demonstration.
use criterion::{criterion_group, criterion_main, Criterion};
use skill_runtime::learn::segment::{
    changepoint, cluster, standardise, ChangepointConfig, ClusterConfig, Features, Linkage, Temporal,
};

/// Position and force rows of an approach / slide / retract demonstration with noise.
fn synthetic(n: usize) -> (Features, Vec<f64>) {
    let mut state = 0x1234_5678_u64;
    let mut noise = move || {
        state = state
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        ((state >> 11) as f64 / (1u64 << 53) as f64 - 0.5) * 2.0
    };
    let mut data = Vec::with_capacity(n * 6);
    let t: Vec<f64> = (0..n).map(|k| k as f64 * 1e-3).collect();
    for k in 0..n {
        let u = k as f64 / n as f64;
        let (pos, force) = if u < 0.3 {
            ([0.5, 0.0, 0.3 - 0.2 * u / 0.3], [0.0, 0.0, 0.0])
        } else if u < 0.8 {
            ([0.5 + 0.3 * (u - 0.3), 0.05 * (10.0 * u).sin(), 0.1], [1.0, 0.5, 12.0])
        } else {
            ([0.65, 0.05 * (8.0f64).sin(), 0.1 + (u - 0.8)], [0.0, 0.0, 0.0])
        };
        data.extend(pos.iter().map(|p| p + 1e-4 * noise()));
        data.extend(force.iter().map(|f| f + 0.5 * noise()));
    }
    let mut features = Features { data, dims: 6 };
    standardise(&mut features);
    (features, t)
}

fn bench(c: &mut Criterion) {
    for n in [10_000, 50_000] {
        let (features, _) = synthetic(n);
        for linkage in [Linkage::Ward, Linkage::Average] {
            let config = ClusterConfig {
                linkage,
                ..ClusterConfig::default()
            };
            c.bench_function(&format!("cluster_connectivity_{linkage:?}_{n}"), |b| {
                b.iter(|| cluster(std::hint::black_box(&features), &config).expect("valid"))
            });
        }
        let config = ClusterConfig {
            temporal: Temporal::TimeFeature {
                weight: 1.0,
                max_blocks: 1000,
            },
            ..ClusterConfig::default()
        };
        c.bench_function(&format!("cluster_time_feature_ward_{n}"), |b| {
            b.iter(|| cluster(std::hint::black_box(&features), &config).expect("valid"))
        });
    }
    let (features, t) = synthetic(10_000);
    c.bench_function("changepoint_10000", |b| {
        b.iter(|| changepoint(std::hint::black_box(&features), &t, &ChangepointConfig::default()).expect("valid"))
    });
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(20);
    targets = bench
}
criterion_main!(benches);
