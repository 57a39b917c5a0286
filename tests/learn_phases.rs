//! Demonstrations as people record them (issue 26, items 1 and 3), generated with known answers:
//! wipes of 2-4 passes with lift-offs between, each pass at its own force, learn the force of
//! the phase learned within 15 % of its applied median and say which phase; `--phase N` picks
//! another and an absent phase is refused; noisy presses (0.2 mm position noise) put the
//! contact frame within 3° of the true normal and the press's boundaries within 50 ms of the
//! truth (20 ms on average); touches put the frame within 3°.

use std::path::PathBuf;

use nalgebra::Vector3;
use skill_runtime::demo::Demo;
use skill_runtime::demogen::{generate_varied, Demonstration, StdSkill, TruthSurface, Variation};
use skill_runtime::skill::{learn_skill, LearnError, LearnOptions, Learned, LearnedForce, LearnedFrame};

fn skill(name: &str) -> skill_ir::Skill {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    match skill_kit::load::load_skill(&root.join(format!("stdlib-skills/{name}.skill")), None) {
        Ok((_, ir)) => ir,
        Err(_) => panic!("`{name}` compiles"),
    }
}

fn demo_of(generated: &Demonstration) -> Demo {
    let samples = &generated.samples;
    Demo {
        source: format!("{:?}-{}", generated.truth.skill, generated.truth.seed),
        t_s: samples.iter().map(|s| s.t_s).collect(),
        position_m: samples.iter().map(|s| s.position_m).collect(),
        orientation: samples.iter().map(|s| s.orientation).collect(),
        force_n: samples.iter().map(|s| s.force_n).collect(),
        torque_nm: samples.iter().map(|s| s.torque_nm).collect(),
    }
}

fn learn(skill: &skill_ir::Skill, generated: &Demonstration, phase: Option<usize>) -> Result<Learned, LearnError> {
    let options = LearnOptions {
        phase,
        ..LearnOptions::default()
    };
    learn_skill(skill, &demo_of(generated), &[], &options)
}

fn constant_force(learned: &Learned) -> f64 {
    learned
        .forces
        .values()
        .find_map(|f| match f {
            LearnedForce::Constant { value_n, .. } => Some(*value_n),
            _ => None,
        })
        .expect("a constant force")
}

/// The median applied normal force of the truth's `k`-th wipe segment (0-based), measured from
/// the generated samples without the sensor's bias.
fn applied_median(generated: &Demonstration, k: usize) -> f64 {
    let wipe = generated
        .truth
        .segments
        .iter()
        .filter(|s| s.label == "wipe")
        .nth(k)
        .expect("the pass");
    let bias = Vector3::from(generated.truth.sensor_bias_n);
    let mut forces: Vec<f64> = generated
        .samples
        .iter()
        .filter(|s| s.t_s >= wipe.start_s && s.t_s < wipe.end_s)
        .map(|s| (s.force_n - bias).z)
        .collect();
    forces.sort_by(f64::total_cmp);
    forces[forces.len() / 2]
}

#[test]
fn multi_pass_wipes_learn_one_phase_within_15_percent() {
    let wipe = skill("wipe");
    let mut worst: f64 = 0.0;
    for passes in 2..=4 {
        for seed in [1u64, 2, 3] {
            let variation = Variation {
                passes,
                ..Variation::default()
            };
            let generated = generate_varied(StdSkill::Wipe, 100 + seed, &variation);
            let learned = learn(&wipe, &generated, None).expect("learns");
            let phases = learned.quality.phases.as_ref().expect("phases reported");
            assert_eq!(phases.phases_s.len(), passes, "passes {passes} seed {seed}: {phases:?}");
            let spans: Vec<[f64; 2]> = learned.segments.iter().map(|s| [s.start_s, s.end_s]).collect();
            let chosen = phases
                .learned
                .unwrap_or_else(|| panic!("one phase learned: {phases:?}, segments {spans:?}"));
            assert_eq!(phases.chosen_by, "longest");
            assert!(
                learned.demo.warnings.iter().any(|w| w.contains("contact phases")),
                "the choice is said: {:?}",
                learned.demo.warnings
            );
            let median = applied_median(&generated, chosen - 1);
            let force = constant_force(&learned);
            let error = (force - median).abs() / median;
            worst = worst.max(error);
            eprintln!("passes {passes} seed {seed}: phase {chosen}, learned {force:.2} N for a median {median:.2} N ({:.1} %)", error * 100.0);
            assert!(error < 0.15, "passes {passes} seed {seed}: {force} N for {median} N");
            // The wipe segment lies on the chosen pass: its boundaries within 0.3 s of the truth's.
            let truth = generated
                .truth
                .segments
                .iter()
                .filter(|s| s.label == "wipe")
                .nth(chosen - 1)
                .expect("pass");
            let segment = &learned.segments[1];
            assert!(
                (segment.start_s - truth.start_s).abs() < 0.3,
                "start {} for {}",
                segment.start_s,
                truth.start_s
            );
            assert!(
                (segment.end_s - truth.end_s).abs() < 0.3,
                "end {} for {}",
                segment.end_s,
                truth.end_s
            );
        }
    }
    eprintln!("worst force error {:.1} %", worst * 100.0);
}

#[test]
fn a_chosen_phase_is_learned_and_an_absent_one_refused() {
    let wipe = skill("wipe");
    let generated = generate_varied(
        StdSkill::Wipe,
        7,
        &Variation {
            passes: 3,
            ..Variation::default()
        },
    );
    for phase in 1..=3 {
        let learned = learn(&wipe, &generated, Some(phase)).expect("learns");
        let report = learned.quality.phases.as_ref().expect("phases");
        assert_eq!(report.learned, Some(phase));
        let median = applied_median(&generated, phase - 1);
        let force = constant_force(&learned);
        assert!(
            (force - median).abs() < 0.15 * median,
            "phase {phase}: {force} N for {median} N"
        );
    }
    let err = learn(&wipe, &generated, Some(5)).expect_err("there is no fifth phase");
    let text = err.to_string();
    assert!(
        text.contains("`--phase 5`") && text.contains("3 contact phase"),
        "{text}"
    );
}

fn normal_of(generated: &Demonstration) -> Vector3<f64> {
    match &generated.truth.surface {
        TruthSurface::Plane { normal, .. } => Vector3::from(*normal),
        TruthSurface::Cylinder { .. } => panic!("a plane"),
    }
}

fn frame_error_deg(learned: &Learned, generated: &Demonstration) -> f64 {
    let Some(LearnedFrame::Constant(pose)) = learned.frames.get("contact") else {
        panic!("a constant contact frame")
    };
    let z = pose.isometry().rotation * Vector3::z();
    // z points into the surface, the truth's normal out of it.
    z.dot(&-normal_of(generated)).clamp(-1.0, 1.0).acos().to_degrees()
}

#[test]
fn noisy_presses_have_their_frame_within_3_degrees_and_boundaries_within_50_ms() {
    const SEEDS: u64 = 32;
    let press = skill("press");
    let (mut worst_angle, mut worst_boundary, mut boundary_sum): (f64, f64, f64) = (0.0, 0.0, 0.0);
    for seed in 0..SEEDS {
        let variation = Variation {
            position_noise_m: 0.0002,
            tilt_rad: [0.0, 0.1, -0.15, 0.2][seed as usize % 4],
            ..Variation::default()
        };
        let generated = generate_varied(StdSkill::Press, 300 + seed, &variation);
        let learned = learn(&press, &generated, None).expect("learns");
        let angle = frame_error_deg(&learned, &generated);
        let truth = &generated.truth.segments;
        let errors = [
            (learned.segments[1].start_s - truth[1].start_s).abs(),
            (learned.segments[2].start_s - truth[2].start_s).abs(),
        ];
        eprintln!(
            "press seed {seed}: frame {angle:.2}°, boundaries off by {:.0} and {:.0} ms",
            errors[0] * 1e3,
            errors[1] * 1e3
        );
        worst_angle = worst_angle.max(angle);
        worst_boundary = worst_boundary.max(errors[0]).max(errors[1]);
        boundary_sum += errors[0] + errors[1];
        let window = learned
            .quality
            .onset_frames
            .get("contact")
            .expect("the window is reported");
        assert!(window.samples >= 5 && window.scatter_deg.is_finite());
    }
    eprintln!(
        "presses: worst frame {worst_angle:.2}°, worst boundary {:.0} ms",
        worst_boundary * 1e3
    );
    assert!(worst_angle < 3.0, "frame {worst_angle}°");
    // The press's force rises as a minimum-jerk curve from zero (8 N·10u³ is 7 mN 40 ms in),
    // which the onset fit's minimum-jerk shapes extrapolate back to (docs/method.md §3); a power
    // law alone put these boundaries 34 ms off on average and 100 ms at worst. Seed 19's wrench
    // was read as sensor axes (the button's travel along the tool's axis taken for sliding) and
    // its frame was 10.7° off.
    let mean_boundary = boundary_sum / (2.0 * SEEDS as f64);
    assert!(mean_boundary < 0.02, "mean boundary error {mean_boundary} s");
    assert!(worst_boundary < 0.05, "boundary {worst_boundary} s");
}

#[test]
fn noisy_touches_have_their_frame_within_3_degrees() {
    let touch = skill("touch");
    let mut worst: f64 = 0.0;
    for seed in 0..32u64 {
        let variation = Variation {
            position_noise_m: 0.0002,
            rate_hz: if seed % 2 == 0 { 1000.0 } else { 250.0 },
            ..Variation::default()
        };
        let generated = generate_varied(StdSkill::Touch, 400 + seed, &variation);
        let learned = learn(&touch, &generated, None).expect("learns");
        let angle = frame_error_deg(&learned, &generated);
        eprintln!("touch seed {seed}: frame {angle:.2}°");
        worst = worst.max(angle);
    }
    assert!(worst < 3.0, "frame {worst}°");
}

#[test]
fn learn_prints_the_phases_and_the_one_it_learned() {
    let generated = generate_varied(
        StdSkill::Wipe,
        9,
        &Variation {
            passes: 3,
            ..Variation::default()
        },
    );
    let dir = std::env::temp_dir().join(format!("skillc-phases-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let demo = dir.join("three_passes.csv");
    std::fs::write(&demo, skill_runtime::demogen::to_csv(&generated)).expect("write");
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let run = |extra: &[&str]| {
        std::process::Command::new(env!("CARGO_BIN_EXE_skillc"))
            .arg("learn")
            .arg(root.join("stdlib-skills/wipe.skill"))
            .arg(&demo)
            .arg("-o")
            .arg(dir.join("wipe.learned.json"))
            .args(extra)
            .output()
            .expect("skillc runs")
    };
    let out = run(&[]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(stdout.contains("3 contact phases: "), "{stdout}");
    assert!(stdout.contains("(the longest; --phase N picks another)"), "{stdout}");
    let out = run(&["--phase", "1"]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(stdout.contains("learned phase 1 (--phase)"), "{stdout}");
    let out = run(&["--phase", "4"]);
    assert_eq!(out.status.code(), Some(1));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("`--phase 4`") && stderr.contains("three_passes.csv"),
        "{stderr}"
    );
    std::fs::remove_dir_all(&dir).expect("clean up");
}

#[test]
fn a_task_learns_each_step_from_its_own_phase_of_one_recording() {
    let generated = generate_varied(
        StdSkill::Wipe,
        9,
        &Variation {
            passes: 3,
            ..Variation::default()
        },
    );
    let dir = std::env::temp_dir().join(format!("skillc-step-phases-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    std::fs::write(dir.join("three_passes.csv"), skill_runtime::demogen::to_csv(&generated)).expect("write");
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let import = root.join("stdlib-skills/wipe.skill");
    let task = |phases: [&str; 2]| {
        format!(
            "import \"{}\"\n\ntask wipe_first_and_last {{\n    step first = wipe(demo: \"three_passes.csv\"{})\n    \
             step last = wipe(demo: \"three_passes.csv\"{})\n}}\n",
            import.display(),
            phases[0],
            phases[1]
        )
    };
    let path = dir.join("task.skill");
    std::fs::write(&path, task([", phase: 1", ", phase: 3"])).expect("write task");
    let program = skill_kit::load::load_program_with(&path, &[]).expect("the task compiles");
    let steps = &program.tasks[0].steps;
    assert_eq!(steps.iter().map(|s| s.phase).collect::<Vec<_>>(), [Some(1), Some(3)]);
    // Each step learns its own pass's force: the passes are at different forces, so learning
    // the other pass (or the longest) would miss by more than the bound.
    let mut learned_n = Vec::new();
    for (step, pass) in steps.iter().zip([0usize, 2]) {
        let skill_ir::StepInput::Demo(demo) = &step.input else {
            panic!("a demonstration step")
        };
        let learned = skill_kit::load::learn_from_files(
            step.skill_in(&program).expect("the skill"),
            std::path::Path::new(demo),
            &skill_kit::load::step_learn_options(step),
        )
        .expect("the step learns");
        let phases = learned.quality.phases.as_ref().expect("phases reported");
        assert_eq!(phases.learned, Some(pass + 1));
        let force = constant_force(&learned);
        let median = applied_median(&generated, pass);
        eprintln!(
            "step `{}`: phase {}, {force:.2} N for a median {median:.2} N",
            step.name,
            pass + 1
        );
        assert!(
            (force - median).abs() / median < 0.15,
            "step `{}`: {force} N for {median} N",
            step.name
        );
        learned_n.push(force);
    }
    // Each step's force is nearer its own pass's median than the other's: the steps did not
    // learn the same pass.
    let [first, third] = [applied_median(&generated, 0), applied_median(&generated, 2)];
    assert!(
        (learned_n[0] - first).abs() < (learned_n[0] - third).abs()
            && (learned_n[1] - third).abs() < (learned_n[1] - first).abs(),
        "learned {learned_n:?} N for passes at {first} N and {third} N"
    );
    // A phase the recording does not have fails before anything runs, naming the step.
    std::fs::write(&path, task([", phase: 1", ", phase: 4"])).expect("write task");
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_skillc"))
        .arg("run")
        .arg(&path)
        .arg("--scene")
        .arg(root.join("examples/scenes/table.toml"))
        .output()
        .expect("skillc runs");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains("step `last`")
            && stderr.contains("no contact phase 4")
            && stderr.contains("has 3 contact phase(s)"),
        "{stderr}"
    );
    // `phase` with a learned file is a checker error; `phase: 0` is out of range.
    for (args, expected) in [
        (", phase: 0", "the contact phase must be between 1"),
        (", phase: 2 s", "the contact phase must be a whole number"),
    ] {
        std::fs::write(&path, task([args, ""])).expect("write task");
        let err = skill_kit::load::load_program_with(&path, &[]).expect_err("refused");
        assert!(format!("{err:?}").contains(expected), "{args}: {err:?}");
    }
    std::fs::write(
        &path,
        format!(
            "import \"{}\"\n\ntask t {{\n    step s = wipe(learned: \"w.json\", phase: 2)\n}}\n",
            import.display()
        ),
    )
    .expect("write task");
    let err = skill_kit::load::load_program_with(&path, &[]).expect_err("refused");
    assert!(format!("{err:?}").contains("a learned file has none"), "{err:?}");
    // The whole task runs: both steps wipe the table and the run says so.
    std::fs::write(&path, task([", phase: 1", ", phase: 3"])).expect("write task");
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_skillc"))
        .arg("run")
        .arg(&path)
        .arg("--scene")
        .arg(root.join("examples/scenes/table.toml"))
        .output()
        .expect("skillc runs");
    let stdout = String::from_utf8_lossy(&out.stdout);
    eprintln!("{stdout}{}", String::from_utf8_lossy(&out.stderr));
    assert!(out.status.success(), "{stdout}");
    assert!(stdout.contains("step `first` learned contact phase 1 of 3"), "{stdout}");
    assert!(stdout.contains("step `last` learned contact phase 3 of 3"), "{stdout}");
    assert_eq!(stdout.matches("success: reached `done`").count(), 2, "{stdout}");
    std::fs::remove_dir_all(&dir).expect("clean up");
}
