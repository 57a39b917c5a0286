//! Free flight against rapier (`runtime/sim/src/free_flight.rs`): the steps the plant integrates
//! itself from the robot model move the arm as rapier's own steps do, the plant takes them far
//! from everything and never in contact, near a joint limit or in a scene with a moving object,
//! the handover into contact gives rapier's first contact force, and the wrist sensor reads in
//! free flight what it reads under rapier.
//!
//! **The tolerance.** Free flight and rapier are both semi-implicit Euler on the same equations
//! of motion, but rapier treats the Coriolis and gyroscopic terms semi-implicitly (their
//! derivative in q̇, times dt, in the mass matrix it solves with) and free flight explicitly:
//! the two differ at first order in dt, as each differs from the exact motion. So each run is
//! also made with rapier at a sixteenth of the step (the torques held over the tick), the
//! converged motion to within about a sixteenth of the full step's error (first order), and the
//! test asserts that free flight is as close to it as rapier's own full step is (within 25 %),
//! and that the two differ by at most twice rapier's error. A model error does not shrink with
//! dt, so it fails that.
//! Checked by changing the code by hand: link 4 made 2 % heavier in free flight's model only
//! fails the open-loop run (2.5e-2 rad from the converged motion against rapier's 1.8e-3), the
//! circle (1.1e-3 against 3.1e-4), the fall (1.3e-2 against 7.2e-3) and the descent; the position
//! update taken with the velocity before the step (explicit Euler) fails the open-loop run (3.9e-3
//! rad from rapier), the fall and the descent, while the circle's feedback absorbs it; velocities
//! written back into rapier 1e-5 short fail the landing checks.

use std::path::PathBuf;

use nalgebra::{DMatrix, Isometry3, Matrix6xX, Translation3, UnitQuaternion, Vector3, Vector6};
use skill_runtime::control::{Command, ControllerGains, HybridController};
use skill_runtime::plant::{Observation, Plant};
use skill_runtime::robot::{Robot, RobotData};
use skill_runtime::sim::{RapierOptions, RapierPlant, Scene};

const DT: f64 = 1e-3;

/// How many steps of `DT / FINE` the converged reference takes per tick.
const FINE: usize = 16;

/// Free flight may be this much farther from the converged motion than rapier's own step.
const ACCURACY_RATIO: f64 = 1.25;

fn scene(name: &str) -> Scene {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../examples/scenes")
        .join(name);
    Scene::from_file(&path).expect("example scene loads")
}

/// table.toml with the table moved `drop_m` down (the probe tip starts 1 mm above its top).
fn table(drop_m: f64) -> Scene {
    let mut scene = scene("table.toml");
    scene.set("table.z", &(0.275 - drop_m).to_string()).expect("valid z");
    scene
}

fn plant(scene: &Scene, free: bool) -> RapierPlant {
    plant_with(scene, free, RapierOptions::default())
}

fn plant_with(scene: &Scene, free: bool, options: RapierOptions) -> RapierPlant {
    let mut plant = RapierPlant::from_scene_with(scene, options).expect("scene builds");
    plant.set_free_flight(free);
    plant
}

/// The joint state after a tick.
#[derive(Debug, Clone)]
struct Sample {
    q: Vec<f64>,
    qd: Vec<f64>,
    /// Whether the plant took the tick's (last) step in free flight.
    free: bool,
}

/// The largest joint position difference between two runs, rad.
fn max_difference(a: &[Sample], b: &[Sample]) -> f64 {
    a.iter()
        .zip(b)
        .flat_map(|(x, y)| x.q.iter().zip(&y.q).map(|(u, v)| (u - v).abs()))
        .fold(0.0, f64::max)
}

/// Runs `ticks` ticks of `torques(tick, observation)`, each held over `substeps` plant steps of
/// `DT / substeps`, and records the joint state after each.
fn run(
    plant: &mut RapierPlant,
    ticks: usize,
    substeps: usize,
    mut torques: impl FnMut(usize, &Observation) -> Vec<f64>,
) -> Vec<Sample> {
    let mut obs = plant.observe();
    let mut trace = Vec::with_capacity(ticks);
    for tick in 0..ticks {
        plant.observe_into(&mut obs);
        let tau = torques(tick, &obs);
        let mut free = false;
        for _ in 0..substeps {
            plant.apply(&tau).expect("7 torques");
            let before = plant.step_counts().free;
            plant.step(DT / substeps as f64).expect("finite state");
            free = plant.step_counts().free > before;
        }
        plant.observe_into(&mut obs);
        trace.push(Sample {
            q: obs.q.as_slice().to_vec(),
            qd: obs.qd.as_slice().to_vec(),
            free,
        });
    }
    trace
}

/// The same torque law run with free flight, with rapier forced on every step, and with rapier
/// at a sixteenth of the step; checks free flight against both and returns the figures.
#[derive(Debug)]
struct Agreement {
    /// Largest joint difference between free flight and rapier, rad.
    free_vs_rapier: f64,
    /// Largest joint difference of free flight and of rapier from the converged motion, rad.
    free_error: f64,
    rapier_error: f64,
    /// The share of the ticks taken in free flight.
    free_share: f64,
}

fn agreement<F>(scene: &Scene, ticks: usize, options: RapierOptions, torques: impl Fn() -> F) -> Agreement
where
    F: FnMut(usize, &Observation) -> Vec<f64>,
{
    let free = run(&mut plant_with(scene, true, options), ticks, 1, torques());
    let mut forced = plant_with(scene, false, options);
    let rapier = run(&mut forced, ticks, 1, torques());
    assert_eq!(forced.step_counts().free, 0, "forced rapier flew free");
    let converged = run(&mut plant_with(scene, false, options), ticks, FINE, torques());
    Agreement {
        free_vs_rapier: max_difference(&free, &rapier),
        free_error: max_difference(&free, &converged),
        rapier_error: max_difference(&rapier, &converged),
        free_share: free.iter().filter(|sample| sample.free).count() as f64 / ticks as f64,
    }
}

fn assert_as_accurate_as_rapier(what: &str, found: &Agreement) {
    eprintln!("{what}: {found:?}");
    assert!(
        found.free_error <= ACCURACY_RATIO * found.rapier_error,
        "{what}: free flight is {:.3e} rad from the converged motion, rapier's step {:.3e} rad ({found:?})",
        found.free_error,
        found.rapier_error
    );
    // Both first-order errors of the same size: their difference is within their sum.
    assert!(
        found.free_vs_rapier <= 2.0 * found.rapier_error,
        "{what}: free flight and rapier differ by {:.3e} rad ({found:?})",
        found.free_vs_rapier
    );
}

/// Joint damping of the open-loop torques, N m s/rad (the wrist is light: M₇₇ ≈ 8e-4 kg m²).
const DAMPING: [f64; 7] = [8.0, 8.0, 4.0, 4.0, 1.0, 0.5, 0.1];

/// Gravity compensation, joint damping and a cosine on every joint, each at its own frequency,
/// of an amplitude that swings the joint about ±`swing_rad` (`|−M_ii ω² + i D_i ω| swing`).
fn gravity_and_cosines(robot: &Robot, q0: &[f64], swing_rad: f64) -> impl FnMut(usize, &Observation) -> Vec<f64> {
    let robot = robot.clone();
    let mut data: RobotData = robot.data();
    let n = robot.dof();
    let mut mass = DMatrix::zeros(n, n);
    robot.forward_kinematics(&mut data, q0);
    robot.mass_matrix(&mut data, &mut mass);
    let omegas: Vec<f64> = (0..n)
        .map(|idx| 2.0 * std::f64::consts::PI * (0.7 + 0.23 * idx as f64))
        .collect();
    let amps: Vec<f64> = (0..n)
        .map(|idx| swing_rad * (mass[(idx, idx)] * omegas[idx].powi(2)).hypot(DAMPING[idx] * omegas[idx]))
        .collect();
    let mut gravity = vec![0.0; n];
    move |tick, obs| {
        let t = tick as f64 * DT;
        robot.forward_kinematics(&mut data, obs.q.as_slice());
        robot.gravity_torques(&mut data, &mut gravity);
        (0..n)
            .map(|idx| gravity[idx] - DAMPING[idx] * obs.qd[idx] + amps[idx] * (omegas[idx] * t).cos())
            .collect()
    }
}

fn start_of(scene: &Scene) -> (Robot, Vec<f64>) {
    let plant = plant(scene, false);
    (plant.robot().clone(), plant.observe().q.as_slice().to_vec())
}

#[test]
fn open_loop_torques_move_the_arm_as_under_rapier() {
    let scene = table(5.0);
    let (robot, q0) = start_of(&scene);
    let found = agreement(&scene, 2000, RapierOptions::default(), || {
        gravity_and_cosines(&robot, &q0, 0.2)
    });
    assert_as_accurate_as_rapier("gravity, damping and cosines for 2 s", &found);
    // Far from everything every step but the first (rapier's: it sets its masses up) is free.
    assert!(found.free_share > 0.999, "free share {}", found.free_share);
}

/// The hybrid controller tracking a 6 cm circle (and 2 cm up and down) in free space.
fn track_circle(robot: &Robot, q0: &[f64]) -> impl FnMut(usize, &Observation) -> Vec<f64> {
    let mut controller =
        HybridController::new(robot.clone(), "lwr_flange", q0, ControllerGains::default()).expect("controller");
    let mut start: Option<Isometry3<f64>> = None;
    let omega = 2.0 * std::f64::consts::PI / 1.5;
    move |tick, obs| {
        controller.observe(obs);
        let start = *start.get_or_insert(controller.state().tool);
        let t = tick as f64 * DT;
        // The circle's radius grows over the first half second.
        let radius = 0.06 * (t / 0.5).min(1.0);
        let phase = omega * t;
        let offset = Vector3::new(radius * (phase.cos() - 1.0), radius * phase.sin(), 0.02 * phase.sin());
        let pose = Isometry3::from_parts(Translation3::from(start.translation.vector + offset), start.rotation);
        let mut cmd = Command::hold(pose, [2000.0, 2000.0, 2000.0, 150.0, 150.0, 150.0]);
        cmd.frame = Isometry3::from_parts(controller.state().tool.translation, UnitQuaternion::identity());
        controller.torques(obs, &cmd, DT).to_vec()
    }
}

#[test]
fn the_hybrid_controller_moves_the_arm_as_under_rapier() {
    let scene = table(5.0);
    let (robot, q0) = start_of(&scene);
    let found = agreement(&scene, 3000, RapierOptions::default(), || track_circle(&robot, &q0));
    assert_as_accurate_as_rapier("hybrid controller, 3 s circle", &found);
    assert!(found.free_share > 0.999, "free share {}", found.free_share);
}

/// The arm's energy `½ q̇ᵀ M q̇ + V(q)`, J.
fn energy(robot: &Robot, sample: &Sample) -> f64 {
    let n = robot.dof();
    let mut data = robot.data();
    robot.forward_kinematics(&mut data, &sample.q);
    let mut mass = DMatrix::zeros(n, n);
    robot.mass_matrix(&mut data, &mut mass);
    let qd = nalgebra::DVector::from_column_slice(&sample.qd);
    let kinetic = 0.5 * qd.dot(&(&mass * &qd));
    let potential: f64 = robot
        .links()
        .iter()
        .enumerate()
        .map(|(idx, link)| {
            let com = robot.link_in_base(&data, idx) * nalgebra::Point3::from(link.inertial.com);
            -link.inertial.mass * robot.gravity().dot(&com.coords)
        })
        .sum();
    kinetic + potential
}

#[test]
fn without_torques_the_arm_falls_as_under_rapier() {
    // 0.35 s of falling from the table's start: every joint still inside its limits (A2 reaches
    // its stop at about 0.39 s), joint speeds up to about 5 rad/s.
    let scene = table(5.0);
    let ticks = 350;
    let zeros = || |_: usize, _: &Observation| vec![0.0; 7];
    let found = agreement(&scene, ticks, RapierOptions::default(), zeros);
    assert_as_accurate_as_rapier("falling without torques, 0.35 s", &found);
    assert!(found.free_share > 0.99, "free share {}", found.free_share);
    // Energy: both integrators are first order and neither conserves it exactly; free flight's
    // drift stays that of rapier's step.
    let robot = plant(&scene, false).robot().clone();
    let drift = |free: bool| {
        let trace = run(&mut plant(&scene, free), ticks, 1, zeros());
        let start = energy(&robot, &trace[0]);
        trace
            .iter()
            .map(|sample| (energy(&robot, sample) - start).abs())
            .fold(0.0, f64::max)
    };
    let (free_drift, rapier_drift) = (drift(true), drift(false));
    let kinetic = {
        let trace = run(&mut plant(&scene, false), ticks, 1, zeros());
        let at_rest = Sample {
            qd: vec![0.0; 7],
            ..trace[ticks - 1].clone()
        };
        energy(&robot, &trace[ticks - 1]) - energy(&robot, &at_rest)
    };
    eprintln!(
        "energy drift over the fall: free flight {free_drift:.3e} J, rapier {rapier_drift:.3e} J (of {kinetic:.1} J turned kinetic)"
    );
    assert!(
        free_drift <= 2.0 * rapier_drift + 1e-6,
        "free flight's energy drifts {free_drift} J, rapier's {rapier_drift} J"
    );
}

/// τ = g(q) + Jᵀ f − D q̇: pushes the tool with a force (N, base frame), damped.
struct Push {
    robot: Robot,
    data: RobotData,
    jacobian: Matrix6xX<f64>,
    gravity: Vec<f64>,
}

impl Push {
    fn new(robot: &Robot) -> Self {
        Push {
            robot: robot.clone(),
            data: robot.data(),
            jacobian: Matrix6xX::zeros(robot.dof()),
            gravity: vec![0.0; robot.dof()],
        }
    }

    fn torques(&mut self, obs: &Observation, force: Vector3<f64>) -> Vec<f64> {
        self.robot.forward_kinematics(&mut self.data, obs.q.as_slice());
        self.robot.tool_jacobian(&self.data, &mut self.jacobian);
        self.robot.gravity_torques(&mut self.data, &mut self.gravity);
        let push = self.jacobian.transpose() * Vector6::new(force.x, force.y, force.z, 0.0, 0.0, 0.0);
        (0..self.robot.dof())
            .map(|idx| self.gravity[idx] + push[idx] - DAMPING[idx] * obs.qd[idx])
            .collect()
    }
}

/// One tick of a descent onto the table.
#[derive(Debug, Clone)]
struct Tick {
    free: bool,
    /// The noise-free contact force on the tool, N.
    contact_n: f64,
    arm_contact_n: f64,
    tip_z: f64,
    tip_vz: f64,
    q: Vec<f64>,
    /// How far the step's acceleration is from the robot model's, relative to it.
    model_error: f64,
}

/// Pushes the probe down with `force_n` for `ticks` ticks.
fn descend(plant: &mut RapierPlant, force_n: f64, ticks: usize) -> Vec<Tick> {
    let robot = plant.robot().clone();
    let mut push = Push::new(&robot);
    let mut data = robot.data();
    let mut jacobian = Matrix6xX::zeros(robot.dof());
    let mut obs = plant.observe();
    let mut out = Vec::with_capacity(ticks);
    let mut bias = vec![0.0; robot.dof()];
    let mut mass = DMatrix::zeros(robot.dof(), robot.dof());
    for _ in 0..ticks {
        plant.observe_into(&mut obs);
        let tau = push.torques(&obs, Vector3::new(0.0, 0.0, -force_n));
        robot.forward_kinematics(&mut data, obs.q.as_slice());
        robot.inverse_dynamics(&mut data, obs.qd.as_slice(), &[0.0; 7], &mut bias);
        robot.mass_matrix(&mut data, &mut mass);
        let rhs = nalgebra::DVector::from_iterator(7, tau.iter().zip(&bias).map(|(t, b)| t - b));
        let model = mass.clone().cholesky().expect("positive definite").solve(&rhs);
        let qd_before = obs.qd.clone();
        plant.apply(&tau).expect("7 torques");
        let before = plant.step_counts().free;
        plant.step(DT).expect("finite state");
        plant.observe_into(&mut obs);
        let acc = (&obs.qd - qd_before) / DT;
        let model_error = (acc - &model).norm() / model.norm();
        robot.forward_kinematics(&mut data, obs.q.as_slice());
        robot.tool_jacobian(&data, &mut jacobian);
        out.push(Tick {
            free: plant.step_counts().free > before,
            contact_n: plant.ideal_wrench_base().fixed_rows::<3>(0).norm(),
            arm_contact_n: obs.arm_contact_n,
            tip_z: robot.tool_in_base(&data).translation.vector.z,
            tip_vz: (&jacobian * &obs.qd)[2],
            q: obs.q.as_slice().to_vec(),
            model_error,
        });
    }
    out
}

#[test]
fn a_descent_onto_the_table_hands_over_to_rapier_with_its_contact_force() {
    // The probe starts 5 cm above the table and is pushed down: with 10 N it arrives at
    // 0.36 m/s (an impact), with 2 N at 0.09 m/s.
    let scene = table(0.05);
    let robot = plant(&scene, false).robot().clone();
    for force_n in [10.0, 2.0] {
        let ticks = 1500;
        let mut free_plant = plant(&scene, true);
        let free = descend(&mut free_plant, force_n, ticks);
        let rapier = descend(&mut plant(&scene, false), force_n, ticks);
        let first_contact = |trace: &[Tick]| trace.iter().position(|tick| tick.contact_n > 0.0);
        let touch = first_contact(&free).expect("the probe reaches the table");
        assert_eq!(
            Some(touch),
            first_contact(&rapier),
            "{force_n} N: first contact at another tick"
        );
        // (b) Free flight until the probe nears the table, none from the first contact on (the
        // probe then stays on it), and every free step without contact.
        let free_before = free[..touch].iter().filter(|tick| tick.free).count();
        assert!(
            free_before as f64 > 0.8 * touch as f64,
            "{force_n} N: {free_before} of {touch} ticks before contact free"
        );
        assert!(
            free[touch..].iter().all(|tick| !tick.free),
            "{force_n} N: a free step in contact"
        );
        assert!(free
            .iter()
            .filter(|tick| tick.free)
            .all(|tick| tick.contact_n == 0.0 && tick.arm_contact_n == 0.0));
        // The landing: the first rapier step after the flight starts from free flight's state, so
        // its acceleration departs from the model's (free steps: by rounding) as the rapier steps
        // after it do, by rapier's semi-implicit Coriolis term, which changes smoothly from step to
        // step; a state written back wrong would show as a jump.
        let flight = free.iter().position(|tick| tick.free).expect("a free step");
        let land = flight + free[flight..].iter().position(|tick| !tick.free).expect("a landing");
        let (jump, next) = (
            (free[land].model_error - free[land + 1].model_error).abs(),
            (free[land + 1].model_error - free[land + 2].model_error).abs(),
        );
        assert!(
            free[flight..land].iter().all(|tick| tick.model_error < 1e-12),
            "{force_n} N: a free step off the model"
        );
        assert!(
            jump <= 10.0 * next + 1e-9,
            "{force_n} N: the landing's acceleration jumps by {jump:.3e} (then {next:.3e})"
        );
        // (c) The first contact tick's force is rapier's step from the state it starts in: the
        // solver removes the approach speed beyond what the gap allows, so the force moves with the
        // gap by m/dt² and with the speed by m/dt (m the tool's effective mass along z). The
        // difference of the two runs at the tick before contact bounds the force's.
        let (a, b) = (&free[touch - 1], &rapier[touch - 1]);
        let m_eff = robot.tool_effective_mass(&a.q, &Vector3::z()).expect("not singular");
        let (gap_diff, speed_diff) = ((a.tip_z - b.tip_z).abs(), (a.tip_vz - b.tip_vz).abs());
        let bound = m_eff / DT.powi(2) * gap_diff + m_eff / DT * speed_diff + 1e-6;
        let force_diff = (free[touch].contact_n - rapier[touch].contact_n).abs();
        let peak = |trace: &[Tick]| {
            trace[touch..touch + 200]
                .iter()
                .map(|t| t.contact_n)
                .fold(0.0, f64::max)
        };
        let (peak_free, peak_rapier) = (peak(&free), peak(&rapier));
        let (rest_free, rest_rapier) = (free[ticks - 1].contact_n, rapier[ticks - 1].contact_n);
        eprintln!(
            "{force_n} N: {free_before} of {touch} ticks before contact free ({:?}); at contact the tip is \
             {gap_diff:.2e} m and {speed_diff:.2e} m/s apart; first contact force {:.4} N free, {:.4} N rapier \
             (bound on the difference {bound:.3} N); peak {peak_free:.4} / {peak_rapier:.4} N; at rest \
             {rest_free:.6} / {rest_rapier:.6} N",
            free_plant.step_counts(),
            free[touch].contact_n,
            rapier[touch].contact_n
        );
        assert!(
            force_diff <= bound,
            "{force_n} N: first contact force differs by {force_diff} N, more than {bound} N"
        );
        assert!(
            (peak_free - peak_rapier).abs() <= 0.01 * peak_rapier,
            "{force_n} N: peaks {peak_free} / {peak_rapier} N"
        );
        assert!(
            (rest_free - rest_rapier).abs() < 1e-3,
            "at rest {rest_free} / {rest_rapier} N"
        );
    }
}

#[test]
fn a_scene_with_a_moving_object_never_flies_free() {
    // A button's cap is a body rapier moves: free flight is off for the whole run, even with the
    // button out of reach (what decides is the body, not the object's name or distance).
    let mut far_button = scene("button.toml");
    far_button.set("button.z", "-5").expect("valid z");
    far_button.set("base.z", "-5").expect("valid z");
    let mut far_table = table(5.0);
    far_table
        .set("robot.q0", "[0.0, -0.5, 0.0, 1.5, 0.0, -1.1415926535897931, 0.0]")
        .expect("q0");
    for (name, scene, flies) in [("button", far_button, false), ("table", far_table, true)] {
        let (robot, q0) = start_of(&scene);
        let mut plant = plant(&scene, true);
        run(&mut plant, 300, 1, gravity_and_cosines(&robot, &q0, 0.1));
        let counts = plant.step_counts();
        eprintln!("{name}: {counts:?}");
        assert_eq!(counts.free > 0, flies, "{name}: {counts:?}");
    }
}

#[test]
fn joint_limits_are_left_to_rapier() {
    // The arm falls without torques onto its joint limits (rapier's drive friction lets it come
    // to rest there): every step that starts or ends with a joint at or beyond a limit is rapier's.
    let scene = table(5.0);
    let options = RapierOptions { joint_damping: 0.5 };
    let mut plant = plant_with(&scene, true, options);
    let robot = plant.robot().clone();
    let limits: Vec<(f64, f64)> = robot.position_limits().collect();
    let inside = |q: &[f64]| q.iter().zip(&limits).all(|(q, (lower, upper))| q > lower && q < upper);
    let mut before = plant.observe().q.as_slice().to_vec();
    let trace = run(&mut plant, 4000, 1, |_, _| vec![0.0; 7]);
    let mut at_limit = 0;
    for sample in &trace {
        if !inside(&before) || !inside(&sample.q) {
            at_limit += 1;
            assert!(
                !sample.free,
                "a free step with a joint at a limit: {:?} -> {:?}",
                before, sample.q
            );
        }
        before.clone_from(&sample.q);
    }
    let counts = plant.step_counts();
    eprintln!("falling onto the limits: {at_limit} ticks at a limit, {counts:?}");
    assert!(at_limit > 100, "the arm never reached a limit");
    assert!(counts.free > 100, "no free flight before the limits: {counts:?}");
    // Where the arm comes to rest is rapier's: both runs end at the same stops.
    let rapier = run(&mut plant_with(&scene, false, options), 4000, 1, |_, _| vec![0.0; 7]);
    let (end_free, end_rapier) = (&trace[3999].q, &rapier[3999].q);
    for (idx, (lower, upper)) in limits.iter().enumerate() {
        let stop = |q: f64| {
            if (q - lower).abs() < 0.05 {
                -1
            } else if (q - upper).abs() < 0.05 {
                1
            } else {
                0
            }
        };
        assert_eq!(
            stop(end_free[idx]),
            stop(end_rapier[idx]),
            "joint {idx}: {end_free:?} / {end_rapier:?}"
        );
    }
}

#[test]
fn in_free_flight_the_sensor_reads_what_it_reads_under_rapier() {
    // The sensor reads contact wrenches only (no inertial load): in free flight a zero wrench
    // through the same bias, noise and filter. A bias shows the frame: the base-frame reading
    // turns with the sensor, so it may differ by the runs' orientation difference, which the sum
    // of the joint differences bounds.
    let mut scene = table(5.0);
    scene
        .set("sensor.bias", "[1.0, -2.0, 3.0, 0.1, -0.2, 0.3]")
        .expect("valid bias");
    let (robot, q0) = start_of(&scene);
    let mut free = plant(&scene, true);
    let mut rapier = plant(&scene, false);
    let (mut torques_free, mut torques_rapier) = (
        gravity_and_cosines(&robot, &q0, 0.2),
        gravity_and_cosines(&robot, &q0, 0.2),
    );
    let (mut obs_free, mut obs_rapier) = (free.observe(), rapier.observe());
    let mut worst_base: f64 = 0.0;
    for tick in 0..1000 {
        free.observe_into(&mut obs_free);
        rapier.observe_into(&mut obs_rapier);
        let tau = torques_free(tick, &obs_free);
        free.apply(&tau).expect("7 torques");
        free.step(DT).expect("finite");
        let tau = torques_rapier(tick, &obs_rapier);
        rapier.apply(&tau).expect("7 torques");
        rapier.step(DT).expect("finite");
        free.observe_into(&mut obs_free);
        rapier.observe_into(&mut obs_rapier);
        assert_eq!(free.ideal_wrench_base(), Vector6::zeros());
        assert_eq!(rapier.ideal_wrench_base(), Vector6::zeros());
        assert_eq!(obs_free.wrench_sensor, obs_rapier.wrench_sensor, "tick {tick}");
        let turned: f64 = (&obs_free.q - &obs_rapier.q).abs().sum();
        let reading =
            obs_rapier.wrench_base.fixed_rows::<3>(0).norm() + obs_rapier.wrench_base.fixed_rows::<3>(3).norm();
        let base_diff = (obs_free.wrench_base - obs_rapier.wrench_base).abs().max();
        assert!(
            base_diff <= turned * reading + 1e-12,
            "tick {tick}: {base_diff} for {turned} rad"
        );
        worst_base = worst_base.max(base_diff);
    }
    eprintln!(
        "sensor: identical in the sensor frame, base frame within {worst_base:.2e}; {:?}",
        free.step_counts()
    );
    assert!(free.step_counts().free > 990);
}

#[test]
fn landing_writes_the_flight_state_back_into_rapier() {
    // A zero-length step lands the flight (with free flight switched off) and moves nothing:
    // rapier's state is then free flight's.
    let scene = table(5.0);
    let (robot, q0) = start_of(&scene);
    let mut plant = plant(&scene, true);
    run(&mut plant, 500, 1, gravity_and_cosines(&robot, &q0, 0.2));
    assert_eq!(plant.step_counts().free, 499);
    let flying = plant.observe();
    plant.set_free_flight(false);
    plant.step(0.0).expect("finite");
    let landed = plant.observe();
    let (dq, dqd) = (
        (&landed.q - &flying.q).abs().max(),
        (&landed.qd - &flying.qd).abs().max(),
    );
    eprintln!("landing: rapier's state {dq:.3e} rad, {dqd:.3e} rad/s from free flight's");
    // The positions go back as displacements from rapier's last state: rounding only.
    assert!(dq <= 1e-12 && dqd <= 1e-12, "landed {dq} rad, {dqd} rad/s off");
    assert!(
        landed
            .q
            .iter()
            .zip(q0.iter())
            .any(|(q, start)| (q - start).abs() > 0.01),
        "the arm never moved"
    );
}
