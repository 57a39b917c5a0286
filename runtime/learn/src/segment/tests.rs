//! Ground-truth tests: piecewise synthetic signals with known breaks.

use nalgebra::Vector3;

use super::*;
use crate::testutil::Rng;

/// Piecewise-constant rows with the given `(end, means)` pieces plus Gaussian noise.
fn piecewise(pieces: &[(usize, [f64; 3])], noise: f64, seed: u64) -> Features {
    let mut rng = Rng::new(seed);
    let mut data = Vec::new();
    let mut start = 0;
    for (end, mean) in pieces {
        for _ in start..*end {
            data.extend(mean.iter().map(|m| m + noise * rng.normal()));
        }
        start = *end;
    }
    let mut features = Features { data, dims: 3 };
    standardise(&mut features);
    features
}

fn assert_breaks(segments: &[Segment], expected: &[usize], tolerance: usize, what: &str) {
    let found = boundaries(segments);
    assert_eq!(
        found.len(),
        expected.len(),
        "{what}: boundaries {found:?}, expected {expected:?}"
    );
    for (f, e) in found.iter().zip(expected) {
        assert!(f.abs_diff(*e) <= tolerance, "{what}: boundary {f}, expected {e}");
    }
}

const PIECES: [(usize, [f64; 3]); 3] = [
    (1000, [0.0, 0.0, 0.0]),
    (2100, [3.0, -2.0, 1.0]),
    (3000, [1.0, 2.0, -3.0]),
];

#[test]
fn connectivity_clustering_finds_breaks_with_every_linkage() {
    let features = piecewise(&PIECES, 0.2, 1);
    for linkage in [Linkage::Ward, Linkage::Complete, Linkage::Average, Linkage::Single] {
        for k in [1, 3] {
            let config = ClusterConfig {
                linkage,
                temporal: Temporal::Connectivity { k },
                ..ClusterConfig::default()
            };
            let segments = cluster(&features, &config).expect("valid input");
            assert_breaks(&segments, &[1000, 2100], 2, &format!("{linkage:?} k={k}"));
        }
    }
}

#[test]
fn connectivity_clustering_scales_to_50000_samples() {
    let pieces = [
        (17_000, [0.0, 0.0, 0.0]),
        (41_000, [2.0, -1.0, 1.0]),
        (50_000, [1.0, 2.0, -2.0]),
    ];
    let features = piecewise(&pieces, 0.3, 2);
    let segments = cluster(&features, &ClusterConfig::default()).expect("valid input");
    assert_breaks(&segments, &[17_000, 41_000], 3, "ward 50k");
}

#[test]
fn time_feature_clustering_finds_breaks_within_a_block() {
    let features = piecewise(&PIECES, 0.2, 3);
    for linkage in [Linkage::Ward, Linkage::Complete, Linkage::Average] {
        let config = ClusterConfig {
            linkage,
            temporal: Temporal::TimeFeature {
                weight: 1.0,
                max_blocks: 1000,
            },
            ..ClusterConfig::default()
        };
        let segments = cluster(&features, &config).expect("valid input");
        assert_breaks(&segments, &[1000, 2100], 3, &format!("{linkage:?} time feature"));
    }
}

#[test]
fn distance_cut_and_short_runs() {
    // A 5-sample glitch inside the first piece must not become a segment.
    let mut features = piecewise(&PIECES, 0.2, 4);
    for k in 500..505 {
        features.data[k * 3] += 4.0;
    }
    let config = ClusterConfig {
        cut: Cut::Distance { threshold: 20.0 },
        min_segment_samples: 50,
        ..ClusterConfig::default()
    };
    let segments = cluster(&features, &config).expect("valid input");
    assert_breaks(&segments, &[1000, 2100], 2, "distance cut");
}

#[test]
fn more_segments_than_blocks_still_returns_segments() {
    let features = piecewise(&PIECES, 0.2, 13);
    let config = ClusterConfig {
        temporal: Temporal::TimeFeature {
            weight: 1.0,
            max_blocks: 2,
        },
        cut: Cut::Count { segments: 3 },
        ..ClusterConfig::default()
    };
    let segments = cluster(&features, &config).expect("valid input");
    assert_eq!(segments.len(), 2, "two blocks give at most two segments");
    assert_eq!(segments[0].start, 0);
    assert_eq!(segments[segments.len() - 1].end, 3000);
}

#[test]
fn clustering_rejects_bad_input() {
    let features = Features {
        data: vec![0.0, f64::NAN, 1.0],
        dims: 1,
    };
    assert!(matches!(
        cluster(&features, &ClusterConfig::default()),
        Err(SegmentError::NonFinite { index: 1, .. })
    ));
    let features = piecewise(&PIECES, 0.2, 5);
    // No neighbour, and more neighbours than the bound (a k of 4e9 would size the link arena).
    for k in [0, skill_ir::MAX_CONNECTIVITY as usize + 1, 4_000_000_000] {
        let config = ClusterConfig {
            temporal: Temporal::Connectivity { k },
            ..ClusterConfig::default()
        };
        assert!(matches!(
            cluster(&features, &config),
            Err(SegmentError::InvalidConfig { name: "k", .. })
        ));
    }
    let short = Features {
        data: vec![0.0; 4],
        dims: 1,
    };
    let config = ClusterConfig {
        min_segment_samples: 10,
        ..ClusterConfig::default()
    };
    assert!(matches!(
        cluster(&short, &config),
        Err(SegmentError::TooFewSamples { .. })
    ));
}

fn changepoint_signal(seed: u64) -> (Features, Vec<f64>) {
    let mut rng = Rng::new(seed);
    let t: Vec<f64> = (0..3000).map(|k| k as f64 * 1e-3).collect();
    let mut data = Vec::new();
    for (k, &tk) in t.iter().enumerate() {
        let (a, b) = if k < 1000 {
            (0.0, 1.0)
        } else if k < 2000 {
            (2.0 + 3.0 * (tk - 1.0), -1.0)
        } else {
            (3.0, 0.5)
        };
        data.push(a + 0.1 * rng.normal());
        data.push(b + 0.1 * rng.normal());
    }
    (Features { data, dims: 2 }, t)
}

#[test]
fn changepoint_finds_breaks_and_models() {
    let (features, t) = changepoint_signal(6);
    let segments = changepoint(&features, &t, &ChangepointConfig::default()).expect("valid input");
    let plain: Vec<Segment> = segments.iter().map(|s| s.segment).collect();
    assert_breaks(&plain, &[1000, 2000], 3, "changepoint");
    let models: Vec<SegmentModel> = segments.iter().map(|s| s.model).collect();
    assert_eq!(
        models,
        [SegmentModel::Constant, SegmentModel::Linear, SegmentModel::Constant]
    );
}

#[test]
fn changepoint_respects_min_length_and_expected_count() {
    let (mut features, t) = changepoint_signal(7);
    // A 20 ms step inside the first piece: shorter than the 50 ms minimum.
    for k in 400..420 {
        features.data[2 * k] += 3.0;
    }
    let config = ChangepointConfig {
        min_length_s: 0.05,
        ..ChangepointConfig::default()
    };
    let segments = changepoint(&features, &t, &config).expect("valid input");
    assert!(segments.iter().all(|s| s.segment.len() >= 50), "{segments:?}");
    let config = ChangepointConfig {
        expected_segments: Some(3),
        ..config
    };
    let segments = changepoint(&features, &t, &config).expect("valid input");
    let plain: Vec<Segment> = segments.iter().map(|s| s.segment).collect();
    assert_breaks(&plain, &[1000, 2000], 3, "changepoint merged to 3");
}

#[test]
fn changepoint_with_few_particles_stays_close() {
    let (features, t) = changepoint_signal(8);
    let config = ChangepointConfig {
        max_particles: 10,
        ..ChangepointConfig::default()
    };
    let segments = changepoint(&features, &t, &config).expect("valid input");
    let plain: Vec<Segment> = segments.iter().map(|s| s.segment).collect();
    assert_breaks(&plain, &[1000, 2000], 5, "10 particles");
}

#[test]
fn touch_splits_at_the_force_peak() {
    let mut rng = Rng::new(9);
    let force: Vec<Vector3<f64>> = (0..1000)
        .map(|k| {
            let bump = 8.0 * (-((k as f64 - 612.0) / 15.0).powi(2)).exp();
            Vector3::new(0.0, 0.0, bump) + rng.vector(0.1)
        })
        .collect();
    let [approach, retract] = split_at_force_peak(&force, &TouchConfig::default()).expect("contact");
    assert!(approach.end.abs_diff(612) <= 3, "split at {}", approach.end);
    assert_eq!(retract.start, approach.end);
    let quiet: Vec<Vector3<f64>> = (0..100).map(|_| rng.vector(0.1)).collect();
    assert!(matches!(
        split_at_force_peak(&quiet, &TouchConfig::default()),
        Err(SegmentError::NoContact { .. })
    ));
}

#[test]
fn segmentation_plan_dispatches_and_checks_the_count() {
    let t_s: Vec<f64> = (0..3000).map(|k| k as f64 * 1e-3).collect();
    let mut rng = Rng::new(10);
    let demo = crate::demo::Demo {
        source: "synthetic".into(),
        position_m: t_s
            .iter()
            .map(|&t| Vector3::new(0.1 * t, 0.0, 0.3) + rng.vector(1e-4))
            .collect(),
        orientation: vec![nalgebra::UnitQuaternion::identity(); 3000],
        force_n: t_s
            .iter()
            .map(|&t| Vector3::new(0.0, 0.0, if (1.0..2.0).contains(&t) { 10.0 } else { 0.0 }) + rng.vector(0.2))
            .collect(),
        torque_nm: vec![Vector3::zeros(); 3000],
        t_s,
    };
    let plan = Segmentation::Cluster(ClusterConfig::default());
    let segments = segment_demo(&demo, &plan, Some(3)).expect("three segments");
    assert_breaks(&segments, &[1000, 2000], 5, "plan cluster");
    assert_eq!(
        segments[1].times_s(&demo.t_s),
        Some((segments[1].start as f64 * 1e-3, (segments[1].end - 1) as f64 * 1e-3))
    );
    let err = segment_demo(&demo, &plan, Some(4)).expect_err("four were expected");
    assert_eq!(err.to_string(), "found 3 segment(s), the template expects 4");
    let touch = segment_demo(&demo, &Segmentation::MaxForce(TouchConfig::default()), Some(2)).expect("two");
    assert!((1000..2000).contains(&touch[0].end));
    let json = serde_json::to_string(&plan).expect("serialisable");
    let back: Segmentation = serde_json::from_str(&json).expect("round trip");
    assert_eq!(back, plan);
    assert_eq!(segment_demo(&demo, &Segmentation::None, None).expect("one").len(), 1);
}

/// Random rows: Gaussian, or quantised to halves so that many distances tie exactly.
fn random_rows(n: usize, dims: usize, seed: u64, quantised: bool) -> Vec<f64> {
    let mut rng = Rng::new(seed);
    (0..n * dims)
        .map(|_| {
            let v = rng.normal();
            if quantised {
                (2.0 * v).round() / 2.0
            } else {
                v
            }
        })
        .collect()
}

#[test]
fn connectivity_merges_equal_the_heap_implementation_exactly() {
    for seed in 0..4 {
        for quantised in [false, true] {
            let data = random_rows(300, 3, 100 + seed, quantised);
            for linkage in [Linkage::Ward, Linkage::Complete, Linkage::Average, Linkage::Single] {
                for k in [1, 2, 5, 10] {
                    let fast = super::cluster::connectivity_merges(&data, 3, k, linkage).expect("addressable");
                    let reference = super::reference::heap_merges(&data, 3, k, linkage);
                    assert_eq!(fast.len(), 299, "{linkage:?} k={k}: a full tree");
                    assert!(
                        fast == reference,
                        "{linkage:?} k={k} seed={seed} quantised={quantised}: merges differ"
                    );
                }
            }
        }
    }
}

#[test]
fn connectivity_ward_equals_brute_force_on_random_data() {
    let n = 60;
    for seed in 0..3 {
        let data = random_rows(n, 2, 200 + seed, false);
        for k in [1, 3, 5] {
            let fast = super::cluster::connectivity_merges(&data, 2, k, Linkage::Ward).expect("addressable");
            let brute = super::reference::brute_force_ward(&data, 2, k);
            assert_eq!(fast.len(), brute.len(), "k={k}");
            // Replay the fast merges with member lists.
            let mut members: Vec<Vec<usize>> = (0..n).map(|i| vec![i]).collect();
            for (step, (&(height, a, b), (expected, x, y))) in fast.iter().zip(&brute).enumerate() {
                let moved = std::mem::take(&mut members[b]);
                let pair = [members[a].clone(), moved.clone()];
                members[a].extend(moved);
                members[a].sort_unstable();
                assert!(
                    (height - expected).abs() <= 1e-9 * expected.max(1.0),
                    "k={k} seed={seed} step {step}: height {height} vs {expected}"
                );
                assert!(
                    (&pair[0] == x && &pair[1] == y) || (&pair[0] == y && &pair[1] == x),
                    "k={k} seed={seed} step {step}: merged {pair:?}, brute force {x:?} + {y:?}"
                );
            }
        }
    }
}

/// 10 000 samples of piecewise-constant 1-D data with 10 breaks 909 samples apart, levels
/// cycling through five values, plus Gaussian noise of standard deviation `noise`.
fn steps_1d(noise: f64, seed: u64) -> (Features, Vec<f64>, Vec<usize>) {
    let breaks: Vec<usize> = (1..=10).map(|b| b * 909).collect();
    let levels = [0.0, 3.0, 1.0, 4.0, 2.0];
    let mut rng = Rng::new(seed);
    let data = (0..10_000)
        .map(|k| levels[breaks.iter().filter(|&&b| b <= k).count() % 5] + noise * rng.normal())
        .collect();
    let t = (0..10_000).map(|k| k as f64 * 1e-3).collect();
    (Features { data, dims: 1 }, t, breaks)
}

#[test]
fn changepoint_without_a_minimum_length_finds_the_true_breaks() {
    // No minimum length in seconds: only the models' own minimum lengths keep the linear model
    // from explaining 2-sample pieces exactly.
    for models in [
        vec![SegmentModel::Constant],
        vec![SegmentModel::Constant, SegmentModel::Linear],
    ] {
        for seed in 0..3 {
            let (signal, t, breaks) = steps_1d(0.5, 300 + seed);
            let config = ChangepointConfig {
                models: models.clone(),
                min_length_s: 0.0,
                ..ChangepointConfig::default()
            };
            let found = changepoint(&signal, &t, &config).expect("valid input");
            let plain: Vec<Segment> = found.iter().map(|s| s.segment).collect();
            // Exactly 10 breaks; a noisy sample next to a break may go either way.
            assert_breaks(&plain, &breaks, 2, &format!("models {models:?} seed {seed}"));
        }
    }
}
