//! Segments the real LASA rim-wiping demonstrations (KUKA LWR IV, ~100 Hz) and compares the
//! boundaries with the authors' manual labels (approach / wipe / retract).
//!
//! The data is not part of the repository (SimPL-2.0); pass its folder, by default
//! `../shared/data/lasa_wiping_lwr4/csv`:
//!
//! ```text
//! cargo run --release -p skill-runtime --example learn_rim -- /path/to/lasa_wiping_lwr4/csv
//! ```
#![allow(clippy::print_stdout)] // An example reports on stdout.

use std::path::{Path, PathBuf};

use skill_runtime::demo::{preprocess, read_csv, Demo, FilterOrder, PreprocessConfig, ReadOptions};
use skill_runtime::learn::segment::{
    boundaries, changepoint_demo, cluster_demo, ChangepointConfig, ClusterConfig, Cut, FeatureSet, LengthPrior,
    Linkage, Segment, Temporal,
};

/// Manual boundaries (0-based first sample of each segment after the first) per file.
fn read_labels(dir: &Path, file: &str) -> Result<Vec<usize>, String> {
    let path = dir.join("segment_labels.csv");
    let text = std::fs::read_to_string(&path).map_err(|e| format!("cannot read `{}`: {e}", path.display()))?;
    let mut starts = Vec::new();
    for line in text.lines().filter(|l| !l.starts_with('#') && !l.starts_with("file,")) {
        let fields: Vec<&str> = line.split(',').collect();
        if fields.len() == 4 && fields[0] == file {
            let first: usize = fields[1]
                .trim()
                .parse()
                .map_err(|e| format!("bad label row `{line}`: {e}"))?;
            starts.push(first - 1);
        }
    }
    starts.sort_unstable();
    Ok(starts.into_iter().skip(1).collect())
}

/// A segmentation method under test.
type Segmenter = Box<dyn Fn(&Demo) -> Result<Vec<Segment>, String>>;

struct Method {
    name: &'static str,
    run: Segmenter,
}

fn methods() -> Vec<Method> {
    let cluster_with = |linkage: Linkage, temporal: Temporal, features: FeatureSet| {
        move |demo: &Demo| {
            let min_segment_samples = (0.5 / demo.mean_dt_s()) as usize;
            let config = ClusterConfig {
                linkage,
                temporal,
                cut: Cut::Count { segments: 3 },
                min_segment_samples,
                features,
            };
            cluster_demo(demo, &config).map_err(|e| e.to_string())
        }
    };
    let pos_force = FeatureSet::default();
    let pos_mag = FeatureSet {
        position: true,
        force: false,
        force_magnitude: true,
    };
    let conn = Temporal::Connectivity { k: 1 };
    let time = Temporal::TimeFeature {
        weight: 1.0,
        max_blocks: 1000,
    };
    vec![
        Method {
            name: "ward, connectivity, pos+force",
            run: Box::new(cluster_with(Linkage::Ward, conn, pos_force)),
        },
        Method {
            name: "ward, connectivity, pos+|force|",
            run: Box::new(cluster_with(Linkage::Ward, conn, pos_mag)),
        },
        Method {
            name: "average, connectivity, pos+force",
            run: Box::new(cluster_with(Linkage::Average, conn, pos_force)),
        },
        Method {
            name: "complete, connectivity, pos+force",
            run: Box::new(cluster_with(Linkage::Complete, conn, pos_force)),
        },
        Method {
            name: "ward, time feature, pos+force",
            run: Box::new(cluster_with(Linkage::Ward, time, pos_force)),
        },
        Method {
            name: "ward, time feature, pos+|force|",
            run: Box::new(cluster_with(Linkage::Ward, time, pos_mag)),
        },
        Method {
            name: "changepoint, pos+force, expect 3",
            run: Box::new(|demo: &Demo| {
                let config = ChangepointConfig {
                    min_length_s: 0.5,
                    length_prior: LengthPrior::Geometric { mean_s: 4.0 },
                    noise_floor: 0.05,
                    expected_segments: Some(3),
                    ..ChangepointConfig::default()
                };
                changepoint_demo(demo, &config)
                    .map(|s| s.iter().map(|m| m.segment).collect())
                    .map_err(|e| e.to_string())
            }),
        },
        Method {
            name: "changepoint, pos+|force|, expect 3",
            run: Box::new(|demo: &Demo| {
                let config = ChangepointConfig {
                    min_length_s: 0.5,
                    length_prior: LengthPrior::Geometric { mean_s: 4.0 },
                    noise_floor: 0.05,
                    expected_segments: Some(3),
                    features: FeatureSet {
                        position: true,
                        force: false,
                        force_magnitude: true,
                    },
                    ..ChangepointConfig::default()
                };
                changepoint_demo(demo, &config)
                    .map(|s| s.iter().map(|m| m.segment).collect())
                    .map_err(|e| e.to_string())
            }),
        },
    ]
}

fn main() {
    let dir = std::env::args()
        .nth(1)
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from("../shared/data/lasa_wiping_lwr4/csv"));
    let methods = methods();
    // Per method: absolute boundary errors [s].
    let mut errors: Vec<Vec<f64>> = vec![Vec::new(); methods.len()];
    for idx in 1..=5 {
        let file = format!("rim_{idx:02}.csv");
        let loaded = match read_csv(&dir.join(&file), &ReadOptions { min_samples: 100 }) {
            Ok(loaded) => loaded,
            Err(err) => {
                println!("{file}: {err}");
                continue;
            }
        };
        for warning in &loaded.warnings {
            println!("{file}: warning: {warning}");
        }
        let demo = match preprocess(
            &loaded.demo,
            &PreprocessConfig {
                resample_hz: None,
                lowpass_cutoff_hz: Some(5.0),
                lowpass_order: FilterOrder::Second,
            },
        ) {
            Ok(demo) => demo,
            Err(err) => {
                println!("{file}: {err}");
                continue;
            }
        };
        let truth = match read_labels(&dir, &file) {
            Ok(truth) => truth,
            Err(err) => {
                println!("{err}");
                continue;
            }
        };
        let dt = demo.mean_dt_s();
        println!(
            "{file}: {} samples, dt {:.4} s, manual boundaries {truth:?}",
            demo.len(),
            dt
        );
        for (method, errs) in methods.iter().zip(&mut errors) {
            let started = std::time::Instant::now();
            match (method.run)(&demo) {
                Ok(segments) => {
                    let found = boundaries(&segments);
                    let elapsed_ms = started.elapsed().as_secs_f64() * 1e3;
                    let diffs: Vec<String> = if found.len() == truth.len() {
                        found
                            .iter()
                            .zip(&truth)
                            .map(|(f, t)| {
                                let err_samples = *f as i64 - *t as i64;
                                errs.push((err_samples as f64 * dt).abs());
                                format!("{err_samples:+} ({:+.2} s)", err_samples as f64 * dt)
                            })
                            .collect()
                    } else {
                        vec![format!("{} boundaries, expected {}", found.len(), truth.len())]
                    };
                    println!(
                        "  {:<36} {found:?}  errors {}  [{elapsed_ms:.1} ms]",
                        method.name,
                        diffs.join(", ")
                    );
                }
                Err(err) => println!("  {:<36} error: {err}", method.name),
            }
        }
    }
    println!("\nmean / max absolute boundary error over rim_01..05 (10 boundaries):");
    for (method, errs) in methods.iter().zip(&errors) {
        if errs.is_empty() {
            continue;
        }
        let mean = errs.iter().sum::<f64>() / errs.len() as f64;
        let max = errs.iter().copied().fold(0.0, f64::max);
        println!(
            "  {:<36} mean {mean:.2} s, max {max:.2} s (n = {})",
            method.name,
            errs.len()
        );
    }
}
