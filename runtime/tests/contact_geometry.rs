//! The geometric contact suite (issue 25, item 1): the LWR-IV's probe (a 10 mm sphere on an
//! 8 mm shaft) driven by a Cartesian impedance over box edges, steps, slots, seams, tilted boxes,
//! cylinders and a button in the rapier plant; every tick of every run is checked against the
//! analytic distance between the sphere and the scene's shapes: no force while the sphere is
//! more than 1 mm from every object, never deeper than the contact's compliance explains.

use std::path::PathBuf;

use nalgebra::{Isometry3, Matrix6xX, Point3, Translation3, UnitQuaternion, Vector3, Vector6};
use skill_runtime::plant::{Observation, Plant};
use skill_runtime::robot::{Robot, RobotData};
use skill_runtime::sim::{RapierPlant, Scene};

/// The probe tip's radius, m (`examples/robots/lwr4.urdf`).
const TIP_RADIUS: f64 = 0.01;
/// The probe shaft's radius, m, and its extent along the tip's z axis from the tip centre
/// (the shaft runs from 0.01 m to 0.11 m behind the tip centre).
const SHAFT_RADIUS: f64 = 0.008;
const SHAFT_FROM: f64 = 0.01;
const SHAFT_TO: f64 = 0.11;
/// The scene's contact stiffness (the default), N/m.
const CONTACT_STIFFNESS: f64 = 5e4;
/// How far from every object the tool may still feel a force, m (the bound).
const FORCE_FREE_BEYOND: f64 = 1e-3;
/// The largest force counted as none, N.
const NO_FORCE: f64 = 1e-6;
/// The impedance's vertical stiffness, N/m: the probe's set point lies `PRESS / KZ` below the
/// surface, so it presses with about `PRESS` newtons.
const KZ: f64 = 1000.0;
const PRESS: f64 = 10.0;
/// Joint damping of the probe's controller, N m s/rad (light at the wrist: its inertia is
/// about 1e-3 kg m², and damping beyond 2 I / dt is unstable at 1 kHz).
const JOINT_DAMPING: [f64; 7] = [2.0, 2.0, 1.0, 1.0, 0.2, 0.1, 0.02];
/// The path's speed, m/s.
const SPEED: f64 = 0.03;

/// A scene object as the suite knows it: the same numbers go into the scene file and into the
/// analytic distance.
#[derive(Debug, Clone, Copy)]
enum Shape {
    /// A box of full `size`.
    Box { size: [f64; 3] },
    /// A cylinder along its local z.
    Cylinder { radius: f64, length: f64 },
    /// A button: its cap is a cylinder along the local z, pressed in along −z.
    Button { radius: f64, height: f64 },
}

#[derive(Debug, Clone, Copy)]
struct Object {
    name: &'static str,
    shape: Shape,
    xyz: [f64; 3],
    rpy: [f64; 3],
}

impl Object {
    fn cuboid(name: &'static str, center: [f64; 3], size: [f64; 3]) -> Self {
        Object {
            name,
            shape: Shape::Box { size },
            xyz: center,
            rpy: [0.0; 3],
        }
    }

    fn pose(&self, button_depth: f64) -> Isometry3<f64> {
        let rotation = UnitQuaternion::from_euler_angles(self.rpy[0], self.rpy[1], self.rpy[2]);
        let pressed = rotation * Vector3::new(0.0, 0.0, -button_depth);
        Isometry3::from_parts(Translation3::from(Vector3::from(self.xyz) + pressed), rotation)
    }

    fn toml(&self, friction: f64) -> String {
        let head = format!(
            "[objects.{}]\nxyz = {:?}\nrpy = {:?}\nfriction = {friction}\n",
            self.name, self.xyz, self.rpy
        );
        let body = match self.shape {
            Shape::Box { size } => format!("kind = \"box\"\nsize = {size:?}\n"),
            Shape::Cylinder { radius, length } => {
                format!("kind = \"cylinder\"\nradius = {radius}\nlength = {length}\n")
            }
            Shape::Button { radius, height } => format!(
                "kind = \"button\"\nradius = {radius}\nheight = {height}\nmass = 0.02\nstiffness = 400.0\n\
                 preload_n = 2.0\ndamping = 2.0\ntravel = 0.008\n"
            ),
        };
        head + &body
    }

    /// The signed distance from `point` to this object's surface (negative inside), m.
    fn signed_distance(&self, point: &Point3<f64>, button_depth: f64) -> f64 {
        let local = self.pose(button_depth).inverse_transform_point(point);
        match self.shape {
            Shape::Box { size } => {
                let q = Vector3::new(
                    local.x.abs() - size[0] / 2.0,
                    local.y.abs() - size[1] / 2.0,
                    local.z.abs() - size[2] / 2.0,
                );
                q.map(|c| c.max(0.0)).norm() + q.max().min(0.0)
            }
            Shape::Cylinder { radius, length } => disc_distance(&local, radius, length / 2.0),
            Shape::Button { radius, height } => disc_distance(&local, radius, height / 2.0),
        }
    }
}

/// The signed distance from `local` to a cylinder along z of `radius` and half-length `half`.
fn disc_distance(local: &Point3<f64>, radius: f64, half: f64) -> f64 {
    let radial = (local.x * local.x + local.y * local.y).sqrt() - radius;
    let axial = local.z.abs() - half;
    radial.max(0.0).hypot(axial.max(0.0)) + radial.max(axial).min(0.0)
}

/// The outward normal at the tip centre of the object nearest to it (the gradient of its
/// signed distance, by central differences).
fn nearest_normal(
    objects: &[Object],
    plant: &RapierPlant,
    tip: &Isometry3<f64>,
    depth_of: &dyn Fn(&RapierPlant, &Object) -> f64,
) -> Vector3<f64> {
    let centre = Point3::from(tip.translation.vector);
    let nearest = objects
        .iter()
        .min_by(|a, b| {
            let da = a.signed_distance(&centre, depth_of(plant, a));
            let db = b.signed_distance(&centre, depth_of(plant, b));
            da.total_cmp(&db)
        })
        .expect("every case has an object");
    let depth = depth_of(plant, nearest);
    let h = 1e-6;
    let gradient = Vector3::from_fn(|axis, _| {
        let mut step = Vector3::zeros();
        step[axis] = h;
        (nearest.signed_distance(&(centre + step), depth) - nearest.signed_distance(&(centre - step), depth))
            / (2.0 * h)
    });
    gradient.normalize()
}

/// One run: the objects, and the tip centre's path as straight pieces between way points
/// (the first is reached from the start high above, the set point's z is the way point's).
struct Case {
    name: &'static str,
    objects: Vec<Object>,
    path: Vec<[f64; 3]>,
    /// Whether the tip must touch, and whether it must leave contact again after touching.
    touches: bool,
    leaves: bool,
    /// The objects' friction coefficient.
    friction: f64,
}

/// The set point's height for a tip resting on a surface at `top`.
fn pressing(top: f64) -> f64 {
    top + TIP_RADIUS - PRESS / KZ
}

/// What a run showed.
#[derive(Debug, Default)]
struct Outcome {
    ticks: usize,
    contact_ticks: usize,
    /// Ticks in contact followed later by ticks without.
    lost_after_contact: bool,
    peak_n: f64,
    deepest_m: f64,
    /// The largest force while the sphere was more than 1 mm from every object (before and after the step).
    force_when_clear_n: f64,
    /// The worst excess of penetration over `F / k + 1 mm`, m.
    excess_depth_m: f64,
    closest_shaft_m: f64,
    arm_contact_n: f64,
    /// Every tick's tip centre and contact force on the tool (base frame).
    trace: Vec<(Vector3<f64>, Vector3<f64>)>,
}

fn scene_for(case: &Case) -> Scene {
    let mut text = String::from(
        "[robot]\nurdf = \"../robots/lwr4.urdf\"\ntool = \"probe_tip\"\nsensor = \"lwr_flange\"\n\
         q0 = [0.0, -0.5, 0.0, 1.5, 0.0, -1.1415926535897931, 0.0]\n\
         tool_start = { xyz = [0.5466, 0.0, 0.345], rpy = [3.14159265358979, 0.0, 3.14159265358979] }\n\
         [sim]\ndt = 0.001\n[sensor]\nnoise_force_n = 0.0\nnoise_torque_nm = 0.0\n",
    );
    for object in &case.objects {
        text += &object.toml(case.friction);
    }
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../examples/scenes");
    Scene::from_toml(&text, case.name, &dir).expect("the suite's scene is valid")
}

/// The tip's set point at time `t`: the path followed at [`SPEED`] from the start pose, then held.
fn set_point(start: &Vector3<f64>, path: &[[f64; 3]], t: f64) -> Vector3<f64> {
    let mut from = *start;
    let mut left = t * SPEED;
    for way in path {
        let to = Vector3::from(*way);
        let length = (to - from).norm();
        if left <= length {
            return from + (to - from) * (left / length.max(1e-12));
        }
        left -= length;
        from = to;
    }
    from
}

fn run(case: &Case) -> Outcome {
    let scene = scene_for(case);
    let mut plant = RapierPlant::from_scene(&scene).expect("the suite's scene builds");
    let robot: Robot = plant.robot().clone();
    let mut data: RobotData = robot.data();
    let n = robot.dof();
    let mut jacobian = Matrix6xX::zeros(n);
    let mut gravity = vec![0.0; n];
    let mut tau = vec![0.0; n];
    let mut obs = Observation::zeros(n);
    plant.observe_into(&mut obs);
    robot.forward_kinematics(&mut data, obs.q.as_slice());
    let start = robot.tool_in_base(&data);
    let omega_squared = CONTACT_STIFFNESS
        / robot
            .tool_effective_mass(obs.q.as_slice(), &Vector3::z())
            .expect("the start is not singular");
    let (start_xyz, orientation) = (start.translation.vector, start.rotation);
    let mut total = 0.0;
    let mut from = start_xyz;
    for way in &case.path {
        total += (Vector3::from(*way) - from).norm();
        from = Vector3::from(*way);
    }
    let duration = total / SPEED + 0.5;
    let button_depth = |plant: &RapierPlant, object: &Object| match object.shape {
        Shape::Button { .. } => plant.button_depth(object.name).unwrap_or(0.0),
        _ => 0.0,
    };
    let distances = |plant: &RapierPlant, tip: &Isometry3<f64>| -> (f64, f64) {
        let centre = Point3::from(tip.translation.vector);
        let axis = tip.rotation * Vector3::z();
        let mut sphere = f64::INFINITY;
        let mut shaft = f64::INFINITY;
        for object in &case.objects {
            let depth = button_depth(plant, object);
            sphere = sphere.min(object.signed_distance(&centre, depth) - TIP_RADIUS);
            // The shaft as points along its axis less its radius: a lower bound of its distance.
            for step in 0..=40 {
                let along = SHAFT_FROM + (SHAFT_TO - SHAFT_FROM) * f64::from(step) / 40.0;
                let point = centre - axis * along;
                shaft = shaft.min(object.signed_distance(&point, depth) - SHAFT_RADIUS);
            }
        }
        (sphere, shaft)
    };
    let mut outcome = Outcome {
        closest_shaft_m: f64::INFINITY,
        ..Outcome::default()
    };
    let (mut before, _) = distances(&plant, &start);
    let ticks = (duration / 1e-3) as usize;
    for tick in 0..ticks {
        plant.observe_into(&mut obs);
        robot.forward_kinematics(&mut data, obs.q.as_slice());
        robot.tool_jacobian(&data, &mut jacobian);
        robot.gravity_torques(&mut data, &mut gravity);
        let pose = robot.tool_in_base(&data);
        let velocity = &jacobian * &obs.qd;
        let goal = set_point(&start_xyz, &case.path, tick as f64 * 1e-3);
        let error = goal - pose.translation.vector;
        let turn = (orientation * pose.rotation.inverse()).scaled_axis();
        let force = Vector3::new(3000.0 * error.x, 3000.0 * error.y, KZ * error.z) - 60.0 * velocity.fixed_rows::<3>(0);
        let moment = 20.0 * turn - 0.2 * velocity.fixed_rows::<3>(3);
        let push = jacobian.transpose() * Vector6::new(force.x, force.y, force.z, moment.x, moment.y, moment.z);
        for idx in 0..n {
            tau[idx] = gravity[idx] + push[idx] - JOINT_DAMPING[idx] * obs.qd[idx];
        }
        plant.apply(&tau).expect("seven torques");
        plant.step(1e-3).expect("finite state");
        plant.observe_into(&mut obs);
        robot.forward_kinematics(&mut data, obs.q.as_slice());
        let tip = robot.tool_in_base(&data);
        let (after, shaft) = distances(&plant, &tip);
        let wrench = plant.ideal_wrench_base();
        let force_n = wrench.fixed_rows::<3>(0).norm();
        outcome
            .trace
            .push((tip.translation.vector, wrench.fixed_rows::<3>(0).into_owned()));
        outcome.ticks += 1;
        outcome.peak_n = outcome.peak_n.max(force_n);
        outcome.deepest_m = outcome.deepest_m.max(-after);
        outcome.closest_shaft_m = outcome.closest_shaft_m.min(shaft);
        outcome.arm_contact_n = outcome.arm_contact_n.max(obs.arm_contact_n);
        if force_n > NO_FORCE {
            outcome.contact_ticks += 1;
        } else if outcome.contact_ticks > 0 {
            outcome.lost_after_contact = true;
        }
        if before.min(after) > FORCE_FREE_BEYOND {
            if force_n > outcome.force_when_clear_n {
                eprintln!(
                    "{}: t {:.3} s force {force_n:.3} N with the sphere {:.2} mm clear at {:?}",
                    case.name,
                    tick as f64 * 1e-3,
                    before.min(after) * 1e3,
                    tip.translation.vector.as_slice()
                );
            }
            outcome.force_when_clear_n = outcome.force_when_clear_n.max(force_n);
        }
        // rapier's contact is a spring of stiffness m ω² for the arm's effective mass m along
        // the contact normal (ω set once from the mass along the base z at the start, see
        // `RapierPlant`): the compliance along the sphere's normal at the nearest object.
        let allowed = if -after > FORCE_FREE_BEYOND {
            let normal = nearest_normal(&case.objects, &plant, &tip, &button_depth);
            let mass = robot
                .tool_effective_mass(obs.q.as_slice(), &normal)
                .expect("the suite's poses are not singular");
            force_n / (omega_squared * mass) + FORCE_FREE_BEYOND
        } else {
            FORCE_FREE_BEYOND
        };
        outcome.excess_depth_m = outcome.excess_depth_m.max(-after - allowed);
        before = after;
    }
    outcome
}

/// The table of the standard scene, 0.6 m long, top at z = 0.300 m, its far edge at x = 0.65 m.
fn table(name: &'static str, x_from: f64, x_to: f64, top: f64) -> Object {
    Object::cuboid(
        name,
        [(x_from + x_to) / 2.0, 0.0, top - 0.025],
        [x_to - x_from, 0.4, 0.05],
    )
}

fn cases() -> Vec<Case> {
    let top = 0.300;
    let z = pressing(top);
    let mut cases = vec![
        Case {
            name: "off_the_end",
            objects: vec![table("table", 0.35, 0.58, top)],
            path: vec![[0.52, 0.0, z], [0.62, 0.0, z]],
            touches: true,
            leaves: true,
            friction: 0.4,
        },
        Case {
            name: "off_the_side",
            objects: vec![Object::cuboid("table", [0.55, -0.1, top - 0.025], [0.3, 0.2, 0.05])],
            path: vec![[0.55, -0.04, z], [0.55, 0.04, z]],
            touches: true,
            leaves: true,
            friction: 0.4,
        },
        Case {
            name: "step_down",
            objects: vec![table("upper", 0.35, 0.56, top), table("lower", 0.56, 0.75, top - 0.005)],
            path: vec![[0.52, 0.0, z], [0.60, 0.0, z]],
            touches: true,
            leaves: false,
            friction: 0.4,
        },
        Case {
            name: "step_up",
            objects: vec![table("lower", 0.35, 0.56, top - 0.004), table("upper", 0.56, 0.75, top)],
            path: vec![[0.52, 0.0, z], [0.60, 0.0, z]],
            touches: true,
            leaves: false,
            friction: 0.4,
        },
        Case {
            name: "slot_narrower_than_the_sphere",
            objects: vec![table("near", 0.35, 0.55, top), table("far", 0.562, 0.75, top)],
            path: vec![[0.52, 0.0, z], [0.60, 0.0, z]],
            touches: true,
            leaves: false,
            friction: 0.4,
        },
        Case {
            name: "slot_wider_than_the_sphere",
            objects: vec![
                table("near", 0.35, 0.55, top),
                table("floor", 0.55, 0.58, top - 0.004),
                table("far", 0.58, 0.75, top),
            ],
            path: vec![[0.52, 0.0, z], [0.61, 0.0, z]],
            touches: true,
            leaves: false,
            friction: 0.4,
        },
        Case {
            name: "seam_one_mm_down",
            objects: vec![table("upper", 0.35, 0.56, top), table("lower", 0.56, 0.75, top - 0.001)],
            path: vec![[0.52, 0.0, z], [0.60, 0.0, z], [0.52, 0.0, z]],
            touches: true,
            leaves: false,
            friction: 0.4,
        },
        Case {
            name: "past_a_side_1_5_mm_clear",
            objects: vec![table("block", 0.35, 0.55, top)],
            path: vec![[0.5615, 0.0, 0.33], [0.5615, 0.0, 0.26], [0.5615, 0.0, 0.33]],
            touches: false,
            leaves: false,
            friction: 0.4,
        },
        Case {
            name: "past_a_button_1_5_mm_clear",
            objects: vec![Object {
                name: "button",
                shape: Shape::Button {
                    radius: 0.02,
                    height: 0.02,
                },
                xyz: [0.55, 0.0, 0.29],
                rpy: [0.0; 3],
            }],
            path: vec![[0.5815, 0.0, 0.33], [0.5815, 0.0, 0.27], [0.5815, 0.0, 0.33]],
            touches: false,
            leaves: false,
            friction: 0.4,
        },
        Case {
            name: "over_a_button",
            objects: vec![Object {
                name: "button",
                shape: Shape::Button {
                    radius: 0.02,
                    height: 0.02,
                },
                xyz: [0.55, 0.0, 0.29],
                rpy: [0.0; 3],
            }],
            path: vec![[0.53, 0.0, 0.305], [0.60, 0.0, 0.305]],
            touches: true,
            leaves: true,
            friction: 0.4,
        },
    ];
    // A box tilted about y (its top rising along x) and about x, off its far edge.
    let tilt = 0.15_f64;
    let tilted = Object {
        name: "tilted",
        shape: Shape::Box { size: [0.2, 0.3, 0.05] },
        xyz: [0.50, 0.0, top - 0.025],
        rpy: [0.1, -tilt, 0.0],
    };
    let normal = tilted.pose(0.0).rotation * Vector3::z();
    let surface = |x: f64| top - 0.025 + (0.025 - normal.x * (x - 0.50)) / normal.z;
    cases.push(Case {
        name: "tilted_box_off_its_edge",
        objects: vec![tilted],
        path: vec![
            [0.53, 0.0, pressing(surface(0.53))],
            [0.62, 0.0, pressing(surface(0.62))],
        ],
        touches: true,
        leaves: true,
        friction: 0.4,
    });
    // A drum along y (the shipped cylinder scene's), crossed along x over its crown, and a
    // drum along x slid along its top and off its end.
    let crown = 0.300;
    let across = Object {
        name: "drum",
        shape: Shape::Cylinder {
            radius: 0.15,
            length: 0.3,
        },
        xyz: [0.55, 0.0, crown - 0.15],
        rpy: [std::f64::consts::FRAC_PI_2, 0.0, 0.0],
    };
    let over = |x: f64| (0.15_f64.powi(2) - (x - 0.55).powi(2)).sqrt() + crown - 0.15;
    cases.push(Case {
        name: "across_a_drum",
        objects: vec![across],
        path: (0..=10)
            .map(|step| {
                let x = 0.50 + 0.01 * f64::from(step);
                [x, 0.0, pressing(over(x))]
            })
            .collect(),
        touches: true,
        leaves: false,
        friction: 0.4,
    });
    let along = Object {
        name: "drum",
        shape: Shape::Cylinder {
            radius: 0.05,
            length: 0.2,
        },
        xyz: [0.48, 0.0, crown - 0.05],
        rpy: [0.0, std::f64::consts::FRAC_PI_2, 0.0],
    };
    cases.push(Case {
        name: "along_a_drum_off_its_end",
        objects: vec![along],
        // 1 cm off the crown: the sphere meets the curved side.
        path: vec![
            [
                0.52,
                0.01,
                pressing(crown - 0.05 + (0.05_f64.powi(2) - 0.01_f64.powi(2)).sqrt()),
            ],
            [
                0.62,
                0.01,
                pressing(crown - 0.05 + (0.05_f64.powi(2) - 0.01_f64.powi(2)).sqrt()),
            ],
        ],
        touches: true,
        leaves: true,
        friction: 0.4,
    });
    cases
}

#[test]
fn contact_force_only_where_the_geometry_touches() {
    let mut failures = Vec::new();
    for case in cases() {
        let outcome = run(&case);
        eprintln!(
            "{:32} ticks {:5} in contact {:5} peak {:6.2} N deepest {:5.2} mm force when clear {:.3e} N \
             excess depth {:6.2} mm shaft {:5.1} mm arm {:.2} N lost {}",
            case.name,
            outcome.ticks,
            outcome.contact_ticks,
            outcome.peak_n,
            outcome.deepest_m * 1e3,
            outcome.force_when_clear_n,
            outcome.excess_depth_m * 1e3,
            outcome.closest_shaft_m * 1e3,
            outcome.arm_contact_n,
            outcome.lost_after_contact
        );
        let mut wrong = Vec::new();
        if outcome.force_when_clear_n > NO_FORCE {
            wrong.push(format!(
                "{:.3} N with the sphere more than 1 mm from every object",
                outcome.force_when_clear_n
            ));
        }
        if outcome.excess_depth_m > 0.0 {
            wrong.push(format!(
                "sank {:.2} mm deeper than F/k + 1 mm",
                outcome.excess_depth_m * 1e3
            ));
        }
        if case.touches && outcome.contact_ticks < 200 {
            wrong.push(format!("touched for {} ticks only", outcome.contact_ticks));
        }
        if !case.touches && outcome.contact_ticks > 0 {
            wrong.push(format!("touched for {} ticks", outcome.contact_ticks));
        }
        if case.leaves && !outcome.lost_after_contact {
            wrong.push("never left the contact".into());
        }
        // The suite is about the tip: the shaft and the arm must stay clear, or their
        // contacts would be counted against the sphere's distance.
        if outcome.closest_shaft_m < 2e-3 {
            wrong.push(format!("the shaft came {:.2} mm near", outcome.closest_shaft_m * 1e3));
        }
        if outcome.arm_contact_n > 0.0 {
            wrong.push(format!("an arm link met an object ({:.2} N)", outcome.arm_contact_n));
        }
        if !wrong.is_empty() {
            failures.push(format!("{}: {}", case.name, wrong.join("; ")));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// Where the contact is lost after the last tick of force above 0.5 N (the force's magnitude,
/// or with `horizontal` its x component: an edge's push), and the mean force on the flat
/// (x in [0.53, 0.55] m, the tip lower than a radius above the top).
fn witness_figures(trace: &[(Vector3<f64>, Vector3<f64>)], horizontal: bool) -> (Option<f64>, f64) {
    let (mut touched, mut lost) = (false, None);
    for (tip, force) in trace {
        let value = if horizontal { force.x.abs() } else { force.norm() };
        if value > 0.5 {
            (touched, lost) = (true, None);
        } else if touched && lost.is_none() {
            lost = Some(tip.x);
        }
    }
    let flat: Vec<f64> = trace
        .iter()
        .filter(|(tip, _)| (0.53..=0.55).contains(&tip.x) && tip.z < 0.300 + TIP_RADIUS)
        .map(|(_, force)| force.norm())
        .collect();
    (lost, flat.iter().sum::<f64>() / flat.len().max(1) as f64)
}

/// The cases `benches/peers/mujoco_edge_step.py` runs in MuJoCo, frictionless: the figures it
/// compares (benches/README.md has the table). Geometry alone bounds them here: the tip leaves
/// the table's end between the edge and a radius past it, the step's edge before the tip is over
/// the lower top by a radius, and the flat carries the impedance's 10 N within 5 %.
#[test]
fn witness_cases_lose_contact_where_the_geometry_ends() {
    let z = pressing(0.300);
    let cases = [
        (
            Case {
                name: "witness_off_the_end",
                objects: vec![table("table", 0.35, 0.58, 0.300)],
                path: vec![[0.52, 0.0, z], [0.62, 0.0, z]],
                touches: true,
                leaves: true,
                friction: 0.0,
            },
            false,
            0.58,
        ),
        (
            Case {
                name: "witness_step_down",
                objects: vec![table("upper", 0.35, 0.56, 0.300), table("lower", 0.56, 0.75, 0.295)],
                path: vec![[0.52, 0.0, z], [0.60, 0.0, z]],
                touches: true,
                leaves: false,
                friction: 0.0,
            },
            true,
            0.56,
        ),
    ];
    for (case, horizontal, edge) in cases {
        let outcome = run(&case);
        let (lost, flat) = witness_figures(&outcome.trace, horizontal);
        let lost = lost.expect("the contact is lost");
        eprintln!(
            "{:20} contact lost at x = {lost:.4} m, steady force {flat:.3} N",
            case.name
        );
        assert!(
            lost > edge && lost < edge + TIP_RADIUS,
            "{}: lost at {lost:.4} m",
            case.name
        );
        assert!(
            (flat - PRESS).abs() < 0.05 * PRESS,
            "{}: {flat:.3} N on the flat",
            case.name
        );
        assert!(outcome.force_when_clear_n <= NO_FORCE, "{}", case.name);
    }
}
