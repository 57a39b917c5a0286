//! Learning from noisy, slow and irregularly sampled demonstrations (issue 11): synthetic
//! demonstrations from `demogen` with known noise-free paths, learned through the driver.

use nalgebra::Vector3;
use skill_ir as ir;
use skill_runtime::demo::Demo;
use skill_runtime::demogen::{generate, StdSkill};
use skill_runtime::rng::SplitMix64;
use skill_runtime::skill::{learn_skill, LearnError, LearnOptions, Learned};
use support::span;

mod support;

/// A skill that splits at the force peak and learns a motion on each side.
fn two_motions() -> ir::Skill {
    let motion = |name: &str, segment| ir::MotionDecl {
        name: name.into(),
        segment: ir::SegmentIdx(segment),
        basis: 50,
        strokes: None,
        span: span(),
    };
    ir::Skill {
        name: "two_motions".into(),
        doc: String::new(),
        learn: ir::LearnPlan {
            segmentation: ir::Segmentation::MaxForce,
            segments: 2,
            lowpass_hz: None,
            resample_hz: None,
            frames: Vec::new(),
            motions: vec![motion("before", 0), motion("after", 1)],
            forces: Vec::new(),
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

/// The generated demonstration of `skill`, every `stride`-th sample.
fn demo(skill: StdSkill, stride: usize) -> Demo {
    let generated = generate(skill, skill.default_seed());
    let samples: Vec<_> = generated.samples.iter().step_by(stride).collect();
    Demo {
        source: format!("{}.csv", skill.name()),
        t_s: samples.iter().map(|s| s.t_s).collect(),
        position_m: samples.iter().map(|s| s.position_m).collect(),
        orientation: samples.iter().map(|s| s.orientation).collect(),
        force_n: samples.iter().map(|s| s.force_n).collect(),
        torque_nm: samples.iter().map(|s| s.torque_nm).collect(),
    }
}

/// `demo` with white noise of `sigma_m` on every position coordinate.
fn with_noise(demo: &Demo, sigma_m: f64, seed: u64) -> Demo {
    let mut rng = SplitMix64::new(seed);
    let mut out = demo.clone();
    for p in &mut out.position_m {
        *p += Vector3::new(rng.normal(), rng.normal(), rng.normal()) * sigma_m;
    }
    out
}

fn learn(demo: &Demo, lowpass_hz: Option<f64>) -> Result<Learned, LearnError> {
    let options = LearnOptions {
        lowpass_hz,
        resample_hz: None,
        ..LearnOptions::default()
    };
    learn_skill(&two_motions(), demo, &[], &options)
}

/// Per motion: the RMS distance \[m\] of its rollout (from the learned start, at the
/// demonstration's times) from `clean`, the rollout's peak speed and `clean`'s \[m/s\].
fn against(learned: &Learned, clean: &Demo) -> Vec<(String, f64, f64, f64)> {
    learned
        .motions
        .iter()
        .map(|(name, motion)| {
            let segment = learned.segments[motion.segment];
            let range = segment.start_index..segment.end_index;
            let t = &clean.t_s[range.clone()];
            let path = &clean.position_m[range];
            let mut rollout = motion.position.rollout();
            let (mut sum, mut peak, mut clean_peak) = (0.0, 0.0f64, 0.0f64);
            let mut velocity = [0.0; 3];
            for k in 0..t.len() {
                if k > 0 {
                    rollout.step(&motion.position, t[k] - t[k - 1]);
                }
                // The demonstrated speed over ±5 ms: the generator's path steps by 0.16 mm
                // where the tremor's normal part stops at touch-down, which is not speed.
                // (at least the neighbours at slower rates).
                let (a, b) = (
                    t.partition_point(|&x| x < t[k] - 0.005).min(k.saturating_sub(1)),
                    (t.partition_point(|&x| x <= t[k] + 0.005) - 1).max((k + 1).min(t.len() - 1)),
                );
                if b > a {
                    clean_peak = clean_peak.max((path[b] - path[a]).norm() / (t[b] - t[a]));
                }
                sum += (Vector3::from_column_slice(rollout.position()) - path[k]).norm_squared();
                rollout.velocity_into(&mut velocity);
                peak = peak.max(Vector3::from(velocity).norm());
            }
            (name.clone(), (sum / t.len() as f64).sqrt(), peak, clean_peak)
        })
        .collect()
}

/// Every sample of `demo` kept with steps of 5 to 15 samples at random (about a tenth).
fn irregular(demo: &Demo, seed: u64) -> Demo {
    let mut rng = SplitMix64::new(seed);
    let mut keep = Vec::new();
    let mut k = 0;
    while k < demo.len() {
        keep.push(k);
        k += 5 + (rng.uniform() * 10.0) as usize;
    }
    Demo {
        source: demo.source.clone(),
        t_s: keep.iter().map(|&k| demo.t_s[k]).collect(),
        position_m: keep.iter().map(|&k| demo.position_m[k]).collect(),
        orientation: keep.iter().map(|&k| demo.orientation[k]).collect(),
        force_n: keep.iter().map(|&k| demo.force_n[k]).collect(),
        torque_nm: keep.iter().map(|&k| demo.torque_nm[k]).collect(),
    }
}

const SKILLS: [StdSkill; 4] = [StdSkill::Touch, StdSkill::Press, StdSkill::Slide, StdSkill::Contour];

#[test]
fn noise_of_a_fifth_of_a_millimetre_at_1_khz_is_smoothed_away() {
    // Before motions were smoothed by default this moved rollouts by 26-43 mm RMS and started
    // them at up to 614 mm/s.
    for skill in [StdSkill::Touch, StdSkill::Slide] {
        let clean = demo(skill, 1);
        let noisy = with_noise(&clean, 0.2e-3, 5);
        let learned = learn(&noisy, None).expect("learns with the default smoothing");
        let noise = learned.quality.position_noise_m.expect("estimated");
        assert!((noise - 0.2e-3).abs() < 0.02e-3, "{skill:?}: noise estimate {noise}");
        assert!(
            learned.quality.smoothing.contains("20 Hz"),
            "{}",
            learned.quality.smoothing
        );
        for (name, rms, peak, clean_peak) in against(&learned, &clean) {
            assert!(rms <= 1e-3, "{skill:?} {name}: {rms} m RMS from the noise-free path");
            assert!(
                peak <= 1.2 * clean_peak,
                "{skill:?} {name}: peak {peak} m/s, demonstrated {clean_peak} m/s"
            );
        }
        assert!(learned.demo.warnings.is_empty(), "{:?}", learned.demo.warnings);
    }
}

#[test]
fn unsmoothed_noise_is_refused_with_advice() {
    let noisy = with_noise(&demo(StdSkill::Touch, 1), 0.2e-3, 5);
    let err = learn(&noisy, Some(0.0)).expect_err("smoothing switched off");
    let text = err.to_string();
    assert!(matches!(err, LearnError::Implausible { .. }), "{text}");
    assert!(text.contains("peak speed") && text.contains("--lowpass"), "{text}");
    // A little noise without smoothing is learned, with a warning.
    let slightly = with_noise(&demo(StdSkill::Touch, 1), 0.03e-3, 5);
    let learned = learn(&slightly, Some(0.0)).expect("learns");
    assert!(
        learned.demo.warnings.iter().any(|w| w.contains("not smoothed")),
        "{:?}",
        learned.demo.warnings
    );
}

#[test]
fn slow_and_irregular_rates_keep_their_accuracy() {
    for skill in SKILLS {
        for (label, clean) in [
            ("100 Hz", demo(skill, 10)),
            ("irregular", irregular(&demo(skill, 1), 3)),
        ] {
            let smoothed = against(&learn(&clean, None).expect("learns"), &clean);
            let unsmoothed = against(&learn(&clean, Some(0.0)).expect("learns"), &clean);
            for ((name, rms, peak, clean_peak), (_, before, _, _)) in smoothed.iter().zip(&unsmoothed) {
                assert!(
                    *rms <= 1.1 * before + 0.02e-3,
                    "{skill:?} {label} {name}: {rms} m RMS, {before} m without smoothing"
                );
                assert!(*peak <= 1.2 * clean_peak, "{skill:?} {label} {name}: peak {peak} m/s");
            }
        }
    }
}

#[test]
fn a_gap_in_time_is_an_error_naming_its_rows() {
    let mut gap = demo(StdSkill::Touch, 1);
    gap.t_s[2000..].iter_mut().for_each(|t| *t += 10.0);
    let text = learn(&gap, None).expect_err("a 10 s gap").to_string();
    assert!(
        text.contains("gap") && text.contains("data rows 2000 and 2001"),
        "{text}"
    );
}

#[test]
fn time_in_microseconds_is_an_error_naming_the_unit() {
    let mut micro = demo(StdSkill::Touch, 1);
    micro.t_s.iter_mut().for_each(|t| *t *= 1e6);
    let text = learn(&micro, None).expect_err("microseconds").to_string();
    assert!(text.contains("wrong unit") && text.contains("microseconds"), "{text}");
}

/// The wipe's plan written out: three segments by the force magnitude, the contact learned as
/// strokes (stdlib-skills/wipe.skill's learn block, without frames and forces).
fn wiping_strokes() -> ir::Skill {
    let mut skill = two_motions();
    skill.name = "strokes".into();
    skill.learn.segmentation = ir::Segmentation::Cluster {
        linkage: ir::Linkage::Ward,
        temporal: ir::Temporal::Connectivity { k: 10 },
        cut: ir::Cut::Count(3),
        min_length_s: 0.2,
        features: ir::SegmentFeatures {
            position: false,
            force: false,
            force_magnitude: true,
        },
    };
    skill.learn.segments = 3;
    skill.learn.motions = vec![ir::MotionDecl {
        name: "strokes".into(),
        segment: ir::SegmentIdx(1),
        basis: 40,
        strokes: Some(ir::Strokes { min_length_s: 0.15 }),
        span: span(),
    }];
    skill
}

#[test]
fn strokes_survive_noise_of_a_fifth_of_a_millimetre() {
    let clean = demo(StdSkill::Wipe, 1);
    let truth = generate(StdSkill::Wipe, StdSkill::Wipe.default_seed()).truth.turns_s;
    let noisy = with_noise(&clean, 0.2e-3, 9);
    let learned = learn_skill(&wiping_strokes(), &noisy, &[], &LearnOptions::default()).expect("learns");
    let motion = &learned.motions["strokes"];
    let times = &learned.quality.motions["strokes"].strokes_s;
    assert_eq!(motion.strokes.len(), 4, "{times:?}");
    for (stroke, turn) in times.iter().zip(&truth) {
        assert!(
            (stroke[1] - turn).abs() < 0.06,
            "turn at {} s, truth {turn} s",
            stroke[1]
        );
    }
    // Each stroke's rollout against the noise-free path over its own samples.
    for (stroke, [start_s, end_s]) in motion.strokes.iter().zip(times) {
        let first = clean.t_s.partition_point(|&t| t < start_s - 1e-9);
        let last = clean.t_s.partition_point(|&t| t <= end_s + 1e-9);
        let (t, path) = (&clean.t_s[first..last], &clean.position_m[first..last]);
        let mut rollout = stroke.position.rollout();
        let mut sum = 0.0;
        for k in 0..t.len() {
            if k > 0 {
                rollout.step(&stroke.position, t[k] - t[k - 1]);
            }
            sum += (Vector3::from_column_slice(rollout.position()) - path[k]).norm_squared();
        }
        let rms = (sum / t.len() as f64).sqrt();
        assert!(
            rms <= 1e-3,
            "stroke {start_s:.2}-{end_s:.2} s: {rms} m RMS from the noise-free path"
        );
    }
}
