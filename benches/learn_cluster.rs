//! Benchmarks of segmentation: connectivity Ward at scikit-learn's neighbourhood (k = 5, the
//! ±5 samples of `kneighbors_graph(t, 10)`) and at k = 10, for 10 000, 50 000 and 100 000
//! samples of a 6-D slide-like demonstration; average linkage and the time-feature variant at
//! 10 000; CHAMP change points on a 1-D signal of 10 000 samples with 10 true breaks (the data
//! of `benches/peers/ruptures_kernelcpd.py`) and on the 6-D demonstration.
//!
//! The data generators are mirrored in `benches/peers/` so that the peers see the same samples.
use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use skill_runtime::learn::segment::{
    changepoint, cluster, standardise, ChangepointConfig, ClusterConfig, Features, Linkage, SegmentModel, Temporal,
};

/// A 64-bit LCG giving uniform noise in `[-1, 1)` (mirrored by the peer scripts).
fn lcg(seed: u64) -> impl FnMut() -> f64 {
    let mut state = seed;
    move || {
        state = state
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        ((state >> 11) as f64 / (1u64 << 53) as f64 - 0.5) * 2.0
    }
}

/// Position and force rows of an approach / slide / retract demonstration with noise.
fn synthetic(n: usize) -> (Features, Vec<f64>) {
    let mut noise = lcg(0x1234_5678);
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

/// 10 000 samples of a piecewise-constant 1-D signal with breaks every 909 samples (10 breaks,
/// means alternating through five levels) plus uniform noise of amplitude 0.5.
fn steps_1d() -> (Features, Vec<f64>, Vec<usize>) {
    let n = 10_000;
    let breaks: Vec<usize> = (1..=10).map(|b| b * 909).collect();
    let levels = [0.0, 3.0, 1.0, 4.0, 2.0];
    let mut noise = lcg(42);
    let mut data = Vec::with_capacity(n);
    let mut piece = 0;
    for k in 0..n {
        if piece < breaks.len() && k == breaks[piece] {
            piece += 1;
        }
        data.push(levels[piece % levels.len()] + 0.5 * noise());
    }
    let t = (0..n).map(|k| k as f64 * 1e-3).collect();
    (Features { data, dims: 1 }, t, breaks)
}

fn clustering(c: &mut Criterion) {
    let mut group = c.benchmark_group("cluster_connectivity_ward");
    group.sample_size(10);
    for n in [10_000, 50_000, 100_000] {
        let (features, _) = synthetic(n);
        for k in [5, 10] {
            let config = ClusterConfig {
                temporal: Temporal::Connectivity { k },
                ..ClusterConfig::default()
            };
            group.bench_with_input(BenchmarkId::new(format!("k{k}"), n), &features, |b, features| {
                b.iter(|| cluster(std::hint::black_box(features), &config).expect("valid"))
            });
        }
    }
    group.finish();
    let (features, _) = synthetic(10_000);
    let config = ClusterConfig {
        linkage: Linkage::Average,
        temporal: Temporal::Connectivity { k: 10 },
        ..ClusterConfig::default()
    };
    c.bench_function("cluster_connectivity_average/k10/10000", |b| {
        b.iter(|| cluster(std::hint::black_box(&features), &config).expect("valid"))
    });
    let config = ClusterConfig {
        temporal: Temporal::TimeFeature {
            weight: 1.0,
            max_blocks: 1000,
        },
        ..ClusterConfig::default()
    };
    c.bench_function("cluster_time_feature_ward/10000", |b| {
        b.iter(|| cluster(std::hint::black_box(&features), &config).expect("valid"))
    });
}

fn changepoints(c: &mut Criterion) {
    let (signal, t, breaks) = steps_1d();
    // No minimum length in seconds (ruptures' `min_size` is 2): only the models' own minimum
    // lengths keep them from explaining a few samples exactly.
    for (name, models) in [
        ("constant", vec![SegmentModel::Constant]),
        ("constant_linear", vec![SegmentModel::Constant, SegmentModel::Linear]),
    ] {
        let config = ChangepointConfig {
            models,
            min_length_s: 0.0,
            ..ChangepointConfig::default()
        };
        let found = changepoint(&signal, &t, &config).expect("valid");
        let starts: Vec<usize> = found.iter().skip(1).map(|s| s.segment.start).collect();
        assert_eq!(starts, breaks, "{name}: the 10 true breaks");
        c.bench_function(&format!("changepoint_1d_10_breaks_{name}/10000"), |b| {
            b.iter(|| changepoint(std::hint::black_box(&signal), &t, &config).expect("valid"))
        });
    }
    let (features, t) = synthetic(10_000);
    c.bench_function("changepoint_6d_slide/10000", |b| {
        b.iter(|| changepoint(std::hint::black_box(&features), &t, &ChangepointConfig::default()).expect("valid"))
    });
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(20);
    targets = clustering, changepoints
}
criterion_main!(benches);
